"""Geometry sanity of system/particleDict, checked before any particle is allocated.

* every fluid region holds at least one particle row (its extent is at least dx, a polygon
  has an area);
* a fluid region lies inside the tank (a box wall entry) it is in, on every closed side;
* fluid regions do not overlap by more than a particle's area (they may meet along a line,
  e.g. the usual grid over a flat bed and a rotated one over a slope, T §5.3.4: only the seam
  is thinned);
* the fluid lies inside ``domain`` when one is given (particles outside it would be removed
  at the first step);
* a particle budget: the particle count the spacing gives (fluid area / dx^2 plus wall rows)
  and the cells of the neighbour grid over the domain, with an estimate of the memory they
  need, against the memory of this machine (``dx 1e-7`` is refused here, not by the kernel's
  out-of-memory killer).
"""

from __future__ import annotations

import math
import os

import numpy as np

from sphfoam.case.errors import Problem
from sphfoam.case.schemas import BoxRegion, BoxWalls, ParticleDict

#: memory per particle (bytes) the estimate uses: the state (~20 float64 fields), the
#: integrator's copies, the generated pipeline's per-particle scratch and the neighbour
#: lists' share, rounded up
BYTES_PER_PARTICLE = 2048
#: memory per cell of the neighbour grid (bytes): head and count arrays
BYTES_PER_CELL = 16
#: the fraction of this machine's memory a case may plan to use
MEMORY_FRACTION = 0.8


def _bbox(region):
    if isinstance(region, BoxRegion):
        return np.asarray(region.min, float), np.asarray(region.max, float)
    pts = np.asarray(region.points, float)
    return pts.min(axis=0), pts.max(axis=0)


def _area(region) -> float:
    if isinstance(region, BoxRegion):
        (x0, y0), (x1, y1) = region.min, region.max
        return (x1 - x0) * (y1 - y0)
    p = np.asarray(region.points, float)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _wall_length(w) -> float:
    from sphfoam.case.geometry import polylines_of

    total = 0.0
    for pts, _side in polylines_of(w):
        p = np.asarray(pts, float)
        total += float(np.hypot(*np.diff(p, axis=0).T).sum())
    return total


def machine_memory() -> int | None:
    """Physical memory of this machine in bytes (None where the OS does not say)."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _size(nbytes: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if nbytes < 1024 or unit == "PiB":
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1024
    return f"{nbytes:.3g} PiB"


def estimate(pd: ParticleDict, support: float = 2.0, hdx: float = 1.3) -> tuple[float, float]:
    """(particles, cells) the particleDict gives: fluid area / dx^2 + wall length x layers
    / dx, and the neighbour-grid cells of side ``support * hdx * dx`` over the domain."""
    from sphfoam.case.geometry import default_domain

    dx = pd.dx
    n = sum(_area(r) for r in pd.fluid.values()) / dx / dx
    n += sum(_wall_length(w) * w.layers / dx for w in pd.walls.values())
    lo, hi = default_domain(pd)
    cell = support * hdx * dx
    # Python floats: a fuzzed domain's product is inf (refused by the caller), not a warning
    cells = (max(float(hi[0] - lo[0]), cell) / cell + 1) * \
        (max(float(hi[1] - lo[1]), cell) / cell + 1)
    return n, cells


def geometry_problems(pd: ParticleDict, file: str = "system/particleDict", support: float = 2.0,
                      hdx: float = 1.3, memory: int | None = None) -> list[Problem]:
    """What is wrong with the geometry of ``pd`` (empty when it makes sense)."""
    if pd.dimension == 3:
        return _problems_3d(pd, file, support, hdx, memory)
    problems: list[Problem] = []
    dx = pd.dx
    for name, r in pd.fluid.items():
        lo, hi = _bbox(r)
        ext = float(min(hi - lo))
        if ext < dx * (1 - 1e-9):
            problems.append(Problem(file, f"fluid.{name}", f"is {ext:g} m across, less than "
                                    f"dx = {dx:g} m: it holds no row of particles"))
        elif not isinstance(r, BoxRegion) and _area(r) < dx * dx:
            problems.append(Problem(file, f"fluid.{name}.points", "the polygon encloses "
                                    "(almost) no area: it holds no particle"))
    tanks = {n: w for n, w in pd.walls.items() if isinstance(w, BoxWalls)}
    tol = 1e-9 * max(1.0, dx)
    for name, r in pd.fluid.items():
        lo, hi = _bbox(r)
        if tanks:
            out = []
            for wname, w in tanks.items():
                sides = []
                if "left" not in w.open and lo[0] < w.min[0] - tol:
                    sides.append(f"left of x = {w.min[0]:g}")
                if "right" not in w.open and hi[0] > w.max[0] + tol:
                    sides.append(f"right of x = {w.max[0]:g}")
                if "bottom" not in w.open and lo[1] < w.min[1] - tol:
                    sides.append(f"below y = {w.min[1]:g}")
                if "top" not in w.open and hi[1] > w.max[1] + tol:
                    sides.append(f"above y = {w.max[1]:g}")
                overlaps = (lo[0] < w.max[0] and hi[0] > w.min[0] and lo[1] < w.max[1]
                            and hi[1] > w.min[1])
                if not sides and overlaps:
                    out = []
                    break
                out.append(f"walls.{wname} ({', '.join(sides) if sides else 'no overlap'})")
            if out:
                problems.append(Problem(file, f"fluid.{name}", "lies (partly) outside the "
                                        "tank: " + "; ".join(out)
                                        + ". Its particles would start inside or behind the "
                                        "wall rows, or outside the tank"))
        if pd.domain is not None:
            dlo, dhi = pd.domain.min, pd.domain.max
            if lo[0] < dlo[0] or lo[1] < dlo[1] or hi[0] > dhi[0] or hi[1] > dhi[1]:
                problems.append(Problem(file, f"fluid.{name}", f"reaches outside domain "
                                        f"{tuple(dlo)}..{tuple(dhi)}: its particles there "
                                        "would be removed at the first step"))
    problems += _overlaps(pd, file)
    if problems:
        return problems
    try:
        n, cells = estimate(pd, support, hdx)
        need = n * BYTES_PER_PARTICLE + cells * BYTES_PER_CELL
    except (ZeroDivisionError, OverflowError):
        n = cells = need = math.inf
    return problems + _budget(file, dx, n, cells, need, memory)


def _budget(file: str, dx: float, n: float, cells: float, need: float,
            memory: int | None) -> list[Problem]:
    """The memory budget: ``need`` bytes for ``n`` particles and ``cells`` grid cells
    against MEMORY_FRACTION of the machine's memory (both dimensions)."""
    memory = machine_memory() if memory is None else memory
    if math.isfinite(need) and (memory is None or need <= MEMORY_FRACTION * memory):
        return []
    have = f"this machine has {_size(memory)}" if memory else "more than is available"
    return [Problem(file, "dx", f"dx = {dx:g} m gives about {n:.3g} particles and "
                    f"{cells:.3g} neighbour-grid cells, needing about {_size(need)} of "
                    f"memory; {have}. Use a larger dx (or a smaller domain)")]


_FACE_WORDS = {"left": (0, 0, "x <"), "right": (0, 1, "x >"), "front": (1, 0, "y <"),
               "back": (1, 1, "y >"), "bottom": (2, 0, "z <"), "top": (2, 1, "z >")}


def _problems_3d(pd: ParticleDict, file: str, support: float, hdx: float,
                 memory: int | None) -> list[Problem]:
    """The 3-D geometry's problems: a fluid region thinner than dx or outside its tank's
    closed sides or the domain, and the particle and memory budget (particles: fluid
    volume / dx^3 plus the walls' surface x layers / dx^2, from their boxes)."""
    from sphfoam.case.geometry import default_domain
    from sphfoam.case.solids import bounds

    problems: list[Problem] = []
    dx = pd.dx
    tol = 1e-9 * max(1.0, dx)
    tanks = {n: w for n, w in pd.walls.items() if isinstance(w, BoxWalls)}
    n = 0.0
    for name, r in pd.fluid.items():
        lo, hi = bounds(r)
        try:
            n += float(np.prod(hi - lo)) / dx ** 3
        except (ZeroDivisionError, OverflowError):
            n = math.inf
        if float(min(hi - lo)) < dx * (1 - 1e-9):
            problems.append(Problem(file, f"fluid.{name}", f"is {float(min(hi - lo)):g} m "
                                    f"across, less than dx = {dx:g} m: it holds no particle"))
        for wname, w in tanks.items():
            sides = [f"{word} {(w.min, w.max)[hi_side][axis]:g}"
                     for face, (axis, hi_side, word) in _FACE_WORDS.items()
                     if face not in w.open and (hi[axis] > w.max[axis] + tol if hi_side
                                                else lo[axis] < w.min[axis] - tol)]
            if sides:
                problems.append(Problem(file, f"fluid.{name}", "lies (partly) outside the "
                                        f"tank walls.{wname}: {', '.join(sides)}. Its "
                                        "particles would start inside or behind the wall "
                                        "layers"))
        if pd.domain is not None:
            dlo, dhi = np.asarray(pd.domain.min), np.asarray(pd.domain.max)
            if np.any(lo < dlo) or np.any(hi > dhi):
                problems.append(Problem(file, f"fluid.{name}", f"reaches outside domain "
                                        f"{tuple(dlo)}..{tuple(dhi)}: its particles there "
                                        "would be removed at the first step"))
    if problems:
        return problems
    try:
        for w in pd.walls.values():
            lo, hi = bounds(w)
            e = hi - lo
            n += 2.0 * (e[0] * e[1] + e[1] * e[2] + e[0] * e[2]) * w.layers / dx ** 2
        lo, hi = default_domain(pd)
        cell = support * hdx * dx
        cells = float(np.prod([max(b - a, cell) / cell + 1 for a, b in zip(lo, hi)]))
        need = n * BYTES_PER_PARTICLE + cells * BYTES_PER_CELL
    except (ZeroDivisionError, OverflowError):
        n = cells = need = math.inf
    return problems + _budget(file, dx, n, cells, need, memory)


def _inside(region, x, y):
    if isinstance(region, BoxRegion):
        (x0, y0), (x1, y1) = region.min, region.max
        return (x > x0) & (x < x1) & (y > y0) & (y < y1)
    from matplotlib.path import Path as MplPath

    return MplPath(np.asarray(region.points, float)).contains_points(np.column_stack([x, y]))


def _overlaps(pd: ParticleDict, file: str) -> list[Problem]:
    """Fluid regions that overlap by more than a particle's area: only the seam between them
    is thinned (``minSpacing``), so the overlap would hold the particles of both at twice
    the density. Measured on a dx/2 grid over the intersection of their boxes."""
    out = []
    dx = pd.dx
    names = list(pd.fluid)
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            ra, rb = pd.fluid[names[a]], pd.fluid[names[b]]
            (la, ha), (lb, hb) = _bbox(ra), _bbox(rb)
            lo, hi = np.maximum(la, lb), np.minimum(ha, hb)
            if np.any(hi - lo <= 0.5 * dx) or np.prod((hi - lo) / (0.5 * dx)) > 4e6:
                continue        # no overlap wider than a seam (or too big to sample: rare)
            xs = np.arange(lo[0] + 0.25 * dx, hi[0], 0.5 * dx)
            ys = np.arange(lo[1] + 0.25 * dx, hi[1], 0.5 * dx)
            X, Y = (g.ravel() for g in np.meshgrid(xs, ys))
            area = np.count_nonzero(_inside(ra, X, Y) & _inside(rb, X, Y)) * 0.25 * dx * dx
            if area > dx * dx:
                out.append(Problem(file, f"fluid.{names[b]}", (
                    f"overlaps fluid.{names[a]} by about {area:.3g} m^2 ({area / dx / dx:.0f} "
                    f"dx^2): both would fill the overlap with particles. Make the regions "
                    f"meet along a line (e.g. the vertical through the toe of a slope)")))
    return out


def check_geometry(case) -> None:
    """The geometry of a validated case's system/particleDict (fluid inside the walls, a
    non-empty domain, dx against the domain and the particle and memory budget); one
    CaseError listing every problem. Run by ``sphfoam check``, by set-up before anything
    is allocated, and for every run of a study."""
    from sphfoam.case.case import FILES
    from sphfoam.case.errors import CaseError

    kernel = case.models.sph["kernel"]
    problems = geometry_problems(case.particles, FILES["particleDict"][0], kernel.support,
                                 kernel.coeffs.hdx)
    problems += periodic_problems(case)
    if problems:
        raise CaseError(problems)


def periodic_problems(case) -> list[Problem]:
    """A periodic axis shorter than three neighbour cells (the cell walk would list a
    neighbour twice through the seam)."""
    from sphfoam.case.case import FILES

    pd = case.particles
    if pd.domain is None or not pd.domain.periodic:
        return []
    cell = case.schemes.neighbourSearch.cellSizeFactor * case.context.support
    out = []
    for axis in pd.domain.periodic:
        k = "xyz".index(axis)
        length = pd.domain.max[k] - pd.domain.min[k]
        if length < 3 * cell:
            out.append(Problem(FILES["particleDict"][0], "domain.periodic", (
                f"the periodic length in {axis}, {length:g} m, is less than three neighbour "
                f"cells ({3 * cell:.4g} m = 3 x cellSizeFactor x the kernel support): make the "
                f"domain at least that long in {axis}")))
    return out
