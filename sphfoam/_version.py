"""The version of sphfoam (a leaf module: it imports nothing)."""

__version__ = "0.1.0"
