"""sphfoam: weakly-compressible SPH for free-surface water flows, driven like an OpenFOAM case.

The Python API (see docs/user-guide.md, "Python API"): :class:`Case`, :func:`run`,
:func:`clone_case`, :func:`setup_case`, :func:`times`, :func:`read_time`,
:func:`export_vtk`. They are imported on first use, so ``import sphfoam`` does not load
numba, pydantic or VTK.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from sphfoam._version import __version__
from sphfoam.cachedir import use_numba_cache_dir
from sphfoam.engine.threads import prefer_omp


use_numba_cache_dir()       # numba's cache per version of these sources (see sphfoam.cachedir)
prefer_omp()                # numba's OpenMP layer first (see sphfoam.engine.threads)

__all__ = ["Case", "clone_case", "run", "setup_case", "times", "read_time", "export_vtk", "__version__"]

if TYPE_CHECKING:
    from sphfoam.api import clone_case, export_vtk, read_time, run, setup_case, times
    from sphfoam.case.case import Case


def __getattr__(name: str):
    if name == "Case":
        from sphfoam.case.case import Case

        return Case
    if name in ("clone_case", "run", "setup_case", "times", "read_time", "export_vtk"):
        from sphfoam import api

        return getattr(api, name)
    raise AttributeError(f"module 'sphfoam' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
