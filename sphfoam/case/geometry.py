"""Wall geometry of ``system/particleDict`` as straight segments with normals.

Every wall entry (a tank ``box``, a ``polyline``, a ``slope`` or the lines of a ``mesh`` file,
sphfoam.case.meshwalls) becomes a list of
:class:`Segment` s whose unit normal points *into the fluid*. The boundary models use them in
two ways: particle boundaries (repulsive, stationary ghosts, hybrid) place wall particles along
them and store, per wall particle, the normal of the nearest wall point, its distance behind
the wall and whether that point is a corner; mirrored ghosts (T(3.77)-(3.80)) reflect fluid
particles across the segments themselves, every step. :func:`default_domain` is the box
the geometry spans (set-up, assembly and the ParaView mesh share it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sphfoam.case.schemas import (BlockWalls, BoxRegion, BoxWalls, MeshWalls, ParticleDict,
                                  SlopeWalls)

#: how far short of a whole number of spacings (in spacings) a length may fall and still get
#: its last particle: a dx typed with a few digits (0.4166667 for d/24) makes a 200 m box
#: 479.99995 spacings long, and flooring that left a column-wide gap at the far wall
LATTICE_TOLERANCE = 1e-3


def lattice_count(length: float, dx: float) -> int:
    """Number of whole dx-spacings in ``length`` (within ``LATTICE_TOLERANCE`` of one)."""
    return max(0, int(math.floor(length / dx + LATTICE_TOLERANCE)))


def whole_spacings(length: float, dx: float) -> bool:
    """Whether ``length`` is a whole number of dx (within ``LATTICE_TOLERANCE``)."""
    n = length / dx
    return abs(n - round(n)) <= LATTICE_TOLERANCE


def off_lattice(lo, hi, dx: float) -> bool:
    """Whether a box's sides are not all whole numbers of dx: the set-up fills it with
    ``fitted_sites`` (a box of fluid) or ``tank_sites`` (a tank)."""
    return not all(whole_spacings(b - a, dx) for a, b in zip(lo, hi))


def tank_sites(lo, hi, dx: float, before, after) -> tuple[list, list]:
    """Per axis k, a tank's sites and each site's spacing: ``before[k]`` wall layers dx/2,
    3dx/2, ... below ``lo[k]``, the ``fitted_sites`` that fill [lo[k], hi[k]], and
    ``after[k]`` layers above ``hi[k]``."""
    axes, spacing = [], []
    for a, b, n0, n1 in zip(lo, hi, before, after):
        inner, s = fitted_sites(a, b, dx)
        axes.append(np.concatenate([a - dx * (np.arange(n0)[::-1] + 0.5), inner,
                                    b + dx * (np.arange(n1) + 0.5)]))
        spacing.append(np.concatenate([np.full(n0, dx), np.full(inner.size, s),
                                       np.full(n1, dx)]))
    return axes, spacing


def fitted_boxes(pd: ParticleDict, waves: bool = False) -> list[str]:
    """What the set-up fits (``fitted_sites``): each box of fluid, each tank and each 3-D
    block whose sides are not all whole numbers of dx, with its particles' count and spacing
    per axis (a box carrying waves is laid out in columns along x and up: only across is
    fitted in 3-D; a 2-D block's rows follow each face, sphfoam.setup.particles)."""
    notes = []
    entries = [("fluid", n, r) for n, r in pd.fluid.items()
               if isinstance(r, BoxRegion) and getattr(r, "grid", None) is None]
    entries += [("walls", n, w) for n, w in pd.walls.items() if isinstance(w, BoxWalls)
                or (isinstance(w, BlockWalls) and len(w.min) == 3)]
    for kind, name, r in entries:
        axes = range(len(r.min))
        if waves and kind == "fluid":
            axes = [1] if len(r.min) == 3 else []
        if not off_lattice([r.min[a] for a in axes], [r.max[a] for a in axes], pd.dx):
            continue
        sites = [fitted_sites(r.min[a], r.max[a], pd.dx) for a in axes]
        what = "particles" if kind == "fluid" else "sites along its faces" \
            if isinstance(r, BoxWalls) else "sites"
        notes.append(f"{kind}.{name} is not a whole number of dx = {pd.dx:g} m along every "
                     f"side: {' x '.join(str(q.size) for q, _ in sites)} {what}, spaced "
                     f"({' '.join(f'{sp:.6g}' for _, sp in sites)}) m, filled to its faces")
    return notes


def fitted_sites(lo: float, hi: float, dx: float) -> tuple[np.ndarray, float]:
    """Cell centres that fill [lo, hi] along one axis, and their spacing s. A length of whole
    dx keeps the lattice (lo + (i + 1/2) dx, s = dx); any other length holds n = round(L/dx)
    cells of s = L/n (|s - dx| <= dx/2n), so a box is filled to its faces, with its volume,
    where the lattice left a gap of up to dx at the far face (SPHERIC's MARIN reservoir,
    1.228 m, is 66.98 spacings of 0.55/30: 66 columns held 1.5 % less water)."""
    length = hi - lo
    if whole_spacings(length, dx):
        return lo + dx * (np.arange(lattice_count(length, dx)) + 0.5), dx
    n = int(round(length / dx))
    if n < 1:
        return np.zeros(0), dx
    s = length / n
    return lo + s * (np.arange(n) + 0.5), s


@dataclass(frozen=True)
class Segment:
    """A straight piece of wall from ``p0`` to ``p1``; ``normal`` points into the fluid."""

    p0: tuple[float, float]
    p1: tuple[float, float]
    normal: tuple[float, float]
    patch: int                 # index of the particleDict wall entry it belongs to

    @property
    def length(self) -> float:
        return math.hypot(self.p1[0] - self.p0[0], self.p1[1] - self.p0[1])

    @property
    def tangent(self) -> tuple[float, float]:
        L = self.length
        return ((self.p1[0] - self.p0[0]) / L, (self.p1[1] - self.p0[1]) / L)


def polylines_of(region) -> list[tuple[list[tuple[float, float]], str]]:
    """A wall entry as polylines (vertex lists) and the side their solid lies on."""
    if isinstance(region, BoxWalls):
        (x0, y0), (x1, y1) = region.min, region.max
        # counter-clockwise from the bottom-left corner: the solid lies on the right
        loop = [("bottom", (x0, y0), (x1, y0)), ("right", (x1, y0), (x1, y1)),
                ("top", (x1, y1), (x0, y1)), ("left", (x0, y1), (x0, y0))]
        if not region.open:
            return [([a for _, a, _ in loop] + [loop[0][1]], "right")]
        k = next(i for i, s in enumerate(loop) if s[0] in region.open)
        loop = loop[k + 1:] + loop[:k + 1]          # start just after an open side
        chains, cur = [], []
        for name, a, b in loop:
            if name in region.open:
                if cur:
                    chains.append(cur)
                cur = []
            else:
                cur = cur or [a]
                cur.append(b)
        if cur:
            chains.append(cur)
        return [(c, "right") for c in chains]
    if isinstance(region, BlockWalls):
        (x0, y0), (x1, y1) = region.min, region.max
        # counter-clockwise around the block: the solid lies on the left
        return [([(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)], "left")]
    if isinstance(region, SlopeWalls):
        ang = math.radians(region.angle)
        x0, y0 = region.start
        return [([(x0, y0), (x0 + region.length * math.cos(ang),
                             y0 + region.length * math.sin(ang))], "right")]
    if isinstance(region, MeshWalls):
        return [(list(pts), region.side) for pts in region.polylines]
    return [([tuple(p) for p in region.points], region.side)]


@dataclass(frozen=True)
class Plane:
    """A plane face of a 3-D ``box`` tank: the plane x_k = ``position`` (k = ``axis``) with
    the fluid on the side of ``sign`` (its normal into the fluid is sign e_k), bounded by
    ``extent`` (lo, hi along axis k+1, lo, hi along axis k+2, mod 3)."""

    axis: int
    position: float
    sign: float
    extent: tuple[float, float, float, float]
    velocity: tuple[float, float, float]
    patch: int


def planes_of(pd: ParticleDict) -> list[Plane]:
    """The closed faces of a 3-D case's ``box`` tanks as planes (the walls mirrored ghosts
    reflect across in 3-D); none in 2-D. Other 3-D walls have no plane form: a boundary
    that needs one refuses them (``sphfoam.setup.particles3d``)."""
    from sphfoam.case.solids import FACE_AXES

    out: list[Plane] = []
    if pd.dimension != 3:
        return out
    for patch, w in enumerate(pd.walls.values()):
        if not isinstance(w, BoxWalls):
            continue
        lo, hi = [float(v) for v in w.min], [float(v) for v in w.max]
        vel = tuple(float(v) for v in (tuple(w.velocity) + (0.0, 0.0, 0.0))[:3])
        for face, (k, side) in FACE_AXES.items():
            if face in w.open:
                continue
            k1, k2 = (k + 1) % 3, (k + 2) % 3
            out.append(Plane(k, hi[k] if side else lo[k], -1.0 if side else 1.0,
                             (lo[k1], hi[k1], lo[k2], hi[k2]), vel, patch))
    return out


def segments_of(pd: ParticleDict) -> list[Segment]:
    """All wall segments of a 2-D case, normals into the fluid (none in 3-D: its walls are
    layers of particles, sphfoam.case.solids)."""
    segs: list[Segment] = []
    if pd.dimension == 3:
        return segs
    for patch, region in enumerate(pd.walls.values()):
        for pts, side in polylines_of(region):
            # the normal into the solid is the left normal (-ty, tx) if the solid is on the left
            sgn = 1.0 if side == "left" else -1.0
            for a, b in zip(pts[:-1], pts[1:]):
                if a == b:
                    continue
                L = math.hypot(b[0] - a[0], b[1] - a[1])
                tx, ty = (b[0] - a[0]) / L, (b[1] - a[1]) / L
                segs.append(Segment(tuple(a), tuple(b), (sgn * ty, -sgn * tx), patch))
    return segs


def _closest(segs: list[Segment], x: np.ndarray, y: np.ndarray,
             exposed: np.ndarray | None = None, tol: float = 0.0,
             skip: np.ndarray | None = None):
    """Nearest point on any segment: distance, point, segment index (-1 for none), whether
    it is an end. With ``exposed`` (per segment), only the exposed segments whose line each
    point lies behind or on (within ``tol``) are candidates for it; ``skip`` (per point) a
    segment index the point may not take."""
    best = np.full(x.size, np.inf)
    qx = np.zeros(x.size)
    qy = np.zeros(x.size)
    which = np.full(x.size, -1)
    at_end = np.zeros(x.size, bool)
    for i, s in enumerate(segs):
        if exposed is not None and not exposed[i]:
            continue
        tx, ty = s.tangent
        L = s.length
        t = (x - s.p0[0]) * tx + (y - s.p0[1]) * ty
        tc = np.clip(t, 0.0, L)
        px, py = s.p0[0] + tc * tx, s.p0[1] + tc * ty
        d = np.hypot(x - px, y - py)
        better = d < best - 1e-12 * max(L, 1.0)
        if exposed is not None:
            better &= (x - s.p0[0]) * s.normal[0] + (y - s.p0[1]) * s.normal[1] <= tol
        if skip is not None:
            better &= skip != i
        best = np.where(better, d, best)
        qx = np.where(better, px, qx)
        qy = np.where(better, py, qy)
        which = np.where(better, i, which)
        at_end = np.where(better, (tc <= 1e-9 * L) | (tc >= L * (1 - 1e-9)), at_end)
    return best, qx, qy, which, at_end


def distance_to_walls(segs: list[Segment], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest wall segment."""
    return _closest(segs, x, y)[0]


def split_at_junctions(segs: list[Segment], tol: float) -> list[Segment]:
    """The segments cut where another segment ends on their interior (a block standing on
    the bed cuts the bed at its feet), so that the piece a block covers can be told from
    the pieces the fluid reaches. Each piece keeps its segment's normal and patch."""
    ends = np.array([p for s in segs for p in (s.p0, s.p1)], float).reshape(-1, 2)
    out: list[Segment] = []
    for s in segs:
        tx, ty = s.tangent
        rx, ry = ends[:, 0] - s.p0[0], ends[:, 1] - s.p0[1]
        t = rx * tx + ry * ty
        on = (t > tol) & (t < s.length - tol) & (np.abs(rx * ty - ry * tx) <= tol)
        if not on.any():
            out.append(s)
            continue
        cuts: dict[int, tuple[float, float]] = {}
        for k in np.flatnonzero(on):
            cuts.setdefault(int(round(t[k] / tol)), (float(ends[k, 0]), float(ends[k, 1])))
        pts = [s.p0] + [cuts[k] for k in sorted(cuts)] + [s.p1]
        out += [Segment(a, b, s.normal, s.patch) for a, b in zip(pts[:-1], pts[1:])]
    return out


def vertex_normals(segs: list[Segment], tol: float) -> dict[tuple[float, float], tuple]:
    """Pseudo-normal (normalised sum of the adjacent normals) at every segment end, and
    whether the end is a corner (two segments meeting at an angle)."""
    ends: dict[tuple[float, float], list] = {}
    for s in segs:
        for p in (s.p0, s.p1):
            key = (round(p[0] / tol) * tol, round(p[1] / tol) * tol)
            ends.setdefault(key, []).append(s.normal)
    out = {}
    for key, normals in ends.items():
        nx = sum(n[0] for n in normals)
        ny = sum(n[1] for n in normals)
        L = math.hypot(nx, ny) or 1.0
        corner = len(normals) > 1 and any(
            abs(n[0] * normals[0][1] - n[1] * normals[0][0]) > 1e-6 for n in normals[1:])
        out[key] = ((nx / L, ny / L), corner)
    return out


def _exposed(segs: list[Segment], dx: float) -> np.ndarray:
    """Per segment, whether the fluid can reach it: a face whose midpoint, stepped off it
    along its normal, lies behind another segment touching it (a block's bottom face on the
    bed) is covered."""
    if len(segs) < 2:
        return np.ones(len(segs), bool)
    eps = 1e-3 * dx
    mx = np.array([0.5 * (s.p0[0] + s.p1[0]) + eps * s.normal[0] for s in segs])
    my = np.array([0.5 * (s.p0[1] + s.p1[1]) + eps * s.normal[1] for s in segs])
    d, qx, qy, j, _ = _closest(segs, mx, my, skip=np.arange(len(segs)))
    nx = np.array([s.normal[0] for s in segs])[j]
    ny = np.array([s.normal[1] for s in segs])[j]
    return ~((d < 0.5 * dx) & ((mx - qx) * nx + (my - qy) * ny < 0.0))


def wall_metadata(segs: list[Segment], x: np.ndarray, y: np.ndarray, dx: float):
    """Per wall particle: unit normal into the fluid (nx, ny), distance behind the wall,
    corner flag (nearest wall point is a corner vertex) and patch index.

    A wall particle takes the nearest segment it lies behind (on the solid side of its
    line) among the faces open to the fluid (``_exposed``): the rows of a block standing
    on the bed lie in front of the bed's line and behind the block's bottom face, which
    the bed covers; neither is their wall. The bed is cut at the block's feet
    (``split_at_junctions``) and the piece under the block is covered too: the bed's rows
    under the block lie behind the corner the block's face makes with the bed, the fluid's
    concave corner, as the rows behind a tank's corner do."""
    segs = split_at_junctions(segs, 1e-6 * dx)
    exposed = _exposed(segs, dx)
    d, qx, qy, which, at_end = _closest(segs, x, y, exposed, 1e-6 * dx)
    none = which < 0                      # behind no exposed line: the nearest of all
    if none.any():
        d[none], qx[none], qy[none], which[none], at_end[none] = _closest(
            segs, x[none], y[none])
    nx = np.zeros(x.size)
    ny = np.zeros(x.size)
    corner = np.zeros(x.size)
    vnorm = vertex_normals([s for s, e in zip(segs, exposed) if e], 1e-6 * dx)
    tol = 1e-6 * dx
    for k in range(x.size):
        s = segs[which[k]]
        if at_end[k]:
            key = (round(qx[k] / tol) * tol, round(qy[k] / tol) * tol)
            (vx, vy), is_corner = vnorm.get(key, (s.normal, False))
            corner[k] = 1.0 if is_corner else 0.0
            if d[k] > 1e-9 * dx and is_corner:
                # behind a corner: the direction to the corner (the bisector in the limit)
                nx[k], ny[k] = (qx[k] - x[k]) / d[k], (qy[k] - y[k]) / d[k]
                continue
            if is_corner:
                nx[k], ny[k] = vx, vy
                continue
        nx[k], ny[k] = s.normal
    patch = np.array([segs[i].patch for i in which], dtype=float)
    return nx, ny, d, corner, patch


def lattice_offsets(radius_in_dx: float, dim: int = 2) -> np.ndarray:
    """Offsets (i, j[, k]), in units of dx, of the lattice sites other than the centre closer
    than ``radius``: the pairs a particle forms inside a lattice-filled support."""
    n = int(math.ceil(radius_in_dx)) + 1
    axes = np.meshgrid(*[np.arange(-n, n + 1)] * dim)
    r2 = sum(a * a for a in axes)
    inside = (r2 > 0) & (r2 < radius_in_dx ** 2 - 1e-9)
    return np.column_stack([a[inside] for a in axes]).astype(float)


def fluid_side(segs: list[Segment], x: np.ndarray, y: np.ndarray, dx: float) -> np.ndarray:
    """Whether each point could hold a fluid particle: at least dx/2 from every wall and on
    the fluid side of the nearest one (by its normal, or at a corner the pseudo-normal)."""
    d, qx, qy, which, at_end = _closest(segs, x, y)
    nx = np.array([segs[i].normal[0] for i in which])
    ny = np.array([segs[i].normal[1] for i in which])
    tol = 1e-6 * dx
    vnorm = vertex_normals(segs, tol)
    for k in np.flatnonzero(at_end):
        key = (round(qx[k] / tol) * tol, round(qy[k] / tol) * tol)
        (vx, vy), corner = vnorm.get(key, ((nx[k], ny[k]), False))
        if corner:
            nx[k], ny[k] = vx, vy
    side = (x - qx) * nx + (y - qy) * ny
    return (d >= 0.5 * dx * (1 - 1e-6)) & (side > 0)


def default_domain(pd: ParticleDict):
    """The box outside which particles are removed (see ``ParticleDict.domain``).

    Computed from the geometry in particleDict alone, so a restart sees the same grid.
    """
    if pd.domain is not None:
        return pd.domain.min, pd.domain.max
    if pd.dimension == 3:
        from sphfoam.case.solids import bounds

        boxes = [bounds(r) for r in pd.fluid.values()]
        for w in pd.walls.values():
            lo, hi = bounds(w)
            boxes.append((lo - w.layers * pd.dx, hi + w.layers * pd.dx))
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        margin = 10 * pd.dx
        top = hi[2] + 0.5 * (hi[2] - lo[2]) + margin
        return (tuple(float(v) for v in lo - margin),
                (float(hi[0] + margin), float(hi[1] + margin), float(top)))
    pts = []
    for r in pd.fluid.values():
        pts += [r.min, r.max] if isinstance(r, BoxRegion) else list(r.points)
    for w in pd.walls.values():
        L = w.layers * pd.dx
        corners = [w.min, w.max] if isinstance(w, BoxWalls) else \
            [p for pts, _ in polylines_of(w) for p in pts]
        pts += [(c[0] + sx * L, c[1] + sy * L) for c in corners for sx in (-1, 1) for sy in (-1, 1)]
    pts = np.asarray(pts, float)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    margin = 10 * pd.dx
    return (lo[0] - margin, lo[1] - margin), (hi[0] + margin, hi[1] + 0.5 * (hi[1] - lo[1]) + margin)


def vertical_extent(region, dim: int = 2) -> float:
    """Height of a fluid region along the vertical (y in 2-D, z in 3-D), for the v_max
    estimates of the equation of state."""
    if dim == 3:
        from sphfoam.case.solids import bounds

        lo, hi = bounds(region)
        return float(hi[2] - lo[2])
    ys = [region.min[1], region.max[1]] if isinstance(region, BoxRegion) else \
        [p[1] for p in region.points]
    return max(ys) - min(ys)
