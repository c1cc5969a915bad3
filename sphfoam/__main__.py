"""``python -m sphfoam``: the same as the ``sphfoam`` command."""

from sphfoam.cli import main

if __name__ == "__main__":
    main()
