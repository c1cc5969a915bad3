"""Set-up of a case (``sphfoam setup``): the particles of ``system/particleDict`` written as
``0/``.

* :mod:`~sphfoam.setup.settling` — :func:`setup_case`, the entry point (also
  ``sphfoam.setup_case``), and the settling run controlDict ``settling`` asks for;
* :mod:`~sphfoam.setup.initial` — the generated state written as ``0/`` (with the ParaView
  mesh);
* :mod:`~sphfoam.setup.particles` — the particle lattice, walls and hydrostatic state;
* :mod:`~sphfoam.setup.waves`, :mod:`~sphfoam.setup.channel` — waves and channel flows in
  the initial state;
* :mod:`~sphfoam.setup.sanity` — checks of the geometry before anything is generated.

The wall geometry the set-up shares with the assembly is :mod:`sphfoam.case.geometry`.
:func:`setup_case` is imported on first use, so ``import sphfoam.setup.particles`` stays
light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from sphfoam.setup.settling import setup_case

__all__ = ["setup_case"]


def __getattr__(name: str):
    if name == "setup_case":
        from sphfoam.setup.settling import setup_case

        return setup_case
    raise AttributeError(f"module 'sphfoam.setup' has no attribute {name!r}")
