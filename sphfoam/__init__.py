"""sphfoam: weakly-compressible SPH for free-surface water flows, driven like an OpenFOAM case."""

__version__ = "0.1.0"
