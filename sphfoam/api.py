"""The Python API: load a case, run it, read its results as numpy arrays.

Reached through the package (``import sphfoam``; the names load on first use, so a
bare ``import sphfoam`` stays cheap)::

    import sphfoam

    case = sphfoam.Case("tutorials/damBreak")        # read and validated lazily
    report = sphfoam.run(case, end_time=0.1)         # sets up first if 0/ is empty
    print(sphfoam.times(case))                       # [0.0, 0.05, 0.1]
    f = sphfoam.read_time(case)                      # latest time: {name: ndarray}
    x, y = f["positions"].T
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from sphfoam.case.case import Case
    from sphfoam.timeloop import RunReport

__all__ = ["clone_case", "run", "setup_case", "times", "read_time", "export_vtk"]


def _path(case: "Case | str | Path") -> Path:
    return Path(getattr(case, "path", case))


def _case(case: "Case | str | Path") -> "Case":
    from sphfoam.case.case import Case

    return case if isinstance(case, Case) else Case(case)


def clone_case(src: "Case | str | Path", dst: str | Path, edits: dict | None = None) -> "Case":
    """A copy of case ``src``'s dictionaries (no results) at ``dst``, with edits
    ``{"system/particleDict:dx": 0.01, "system/controlDict:endTime": 1}`` applied."""
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case as _clone

    return Case(_clone(_path(src), Path(dst), edits))


def setup_case(case: "Case | str | Path") -> "Case":
    """``sphfoam setup --force``: particles from ``system/particleDict`` into ``0/`` (and
    the one-cell mesh and ``CASE.foam`` for ParaView). (``sphfoam.setup`` is the
    package of the set-up code, hence the longer name.)"""
    from sphfoam.setup.settling import setup_case as _setup_case

    c = _case(case)
    _setup_case(c, log=lambda msg: None)
    return c


def run(case: "Case | str | Path", *, end_time: float | None = None, progress: bool = False,
        echo=None, threads: "int | str | None" = None) -> "RunReport":
    """``sphfoam run``: run the case (setting it up first if ``0/`` holds no particles).

    ``end_time`` overrides ``controlDict.endTime``; ``threads`` (a number >= 1 or
    ``"auto"``) overrides controlDict ``threads``; ``echo`` (e.g. ``print``) receives the
    log lines, which always go to ``log.sphfoam``. Returns the run's report (steps,
    particles, timings, written times, and ``failure`` if the blow-up detector stopped it).
    """
    from sphfoam.timeloop import run_case

    return run_case(_case(case), progress=progress, echo=echo, end_time=end_time,
                    threads=threads)


def times(case: "Case | str | Path") -> list[float]:
    """The times of the case's time directories that hold particles, ascending."""
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import has_particles

    return [t for t, d in list_times(_path(case)) if has_particles(d)]


def read_time(case: "Case | str | Path", time: float | str | None = None) -> dict[str, np.ndarray]:
    """The particle fields of one time directory as ``{name: ndarray}``.

    ``time`` is a time value (matched to a directory to 1e-9 relative), a directory name,
    or ``None``/``"latestTime"`` for the latest. Fields: ``positions`` and ``U`` (N, 2),
    ``rho``, ``p``, ``mass`` (N,), ``type`` (0 fluid, 1 wall) and ``origId`` (int64), plus
    the extra fields the models keep; bit-exact as written.
    """
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import has_particles, read_state

    root = _path(case)
    have = [(t, d) for t, d in list_times(root) if has_particles(d)]
    if not have:
        raise FileNotFoundError(f"{root}: no time directory holds particles "
                                "(run 'sphfoam setup' or 'sphfoam run' first)")
    if time is None or time == "latestTime":
        return read_state(have[-1][1])
    if isinstance(time, str):
        for _, d in have:
            if d.name == time:
                return read_state(d)
        time = float(time)
    for t, d in have:
        if math.isclose(t, float(time), rel_tol=1e-9, abs_tol=1e-12):
            return read_state(d)
    raise FileNotFoundError(f"{root}: no time directory with particles at {time:g}; have: "
                            + ", ".join(d.name for _, d in have))


def export_vtk(case: "Case | str | Path", times: list[float] | None = None) -> Path:
    """``sphfoam export vtk``: write ``VTK/<case>.pvd`` (see :mod:`sphfoam.io.vtk`)."""
    from sphfoam.io.vtk import export_case

    return export_case(_path(case), times=times)


def prepare_case(case_dir: "Case | str | Path") -> tuple[Path, list[str]]:
    """Make an existing case open in ParaView (``sphfoam export foam``): the one-cell mesh
    and ``CASE.foam`` for the domain of its ``system/particleDict``, and every time
    directory written by an earlier sphfoam rewritten in the cloud layout (values
    unchanged). Returns the ``.foam`` path and the names of the rewritten times."""
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import has_particles, upgrade_state
    from sphfoam.io.polymesh import write_foam_files
    from sphfoam.case.geometry import default_domain

    case = _case(case_dir)
    foam = write_foam_files(case.path, *default_domain(case.particles), case.particles.dx)
    upgraded = [d.name for _, d in list_times(case.path) if has_particles(d) and upgrade_state(d)]
    return foam, upgraded
