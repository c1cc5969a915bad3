"""Particle generation from ``system/particleDict`` (the analogue of blockMesh).

Fluid particles sit at the centres of a square lattice of spacing dx, so a block of fluid
holds exactly its area / dx^2 particles and its surface lies dx/2 beyond the outermost row.
Wall particles sit at the centres of the lattice cells *behind* the wall line, ``layers``
rows deep, so the first wall row is dx/2 behind the wall and dx from the first fluid row.
The initial state is hydrostatic: p = rho0 g_down (eta - y) with g_down = -g_y and eta the
local free surface above each particle, and rho from the inverse of the equation of state. Masses are rho dx^2.
A box of fluid or a tank whose sides are not whole numbers of dx is fitted to its faces
(sphfoam.case.geometry.fitted_sites), masses rho times the cell's area.
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as MplPath
from scipy.spatial import cKDTree

from sphfoam.case.schemas import BlockWalls, BoxRegion, BoxWalls, ParticleDict
from sphfoam.engine.state import FLUID, WALL, ParticleState
from sphfoam.models.mirror import line_distance, segment_array
from sphfoam.case.geometry import (LATTICE_TOLERANCE, distance_to_walls, fitted_sites,
                                   fluid_side, lattice_count, lattice_offsets, off_lattice,
                                   tank_sites,
                                   polylines_of, segments_of, wall_metadata)
from sphfoam.setup.waves import fields as wave_fields
from sphfoam.setup.waves import surface as wave_surface
from sphfoam.setup.waves import wave_columns


def _lattice(lo, hi, dx):
    """Cell centres of the dx-lattice anchored at ``lo`` that lie inside [lo, hi]."""
    nx = lattice_count(hi[0] - lo[0], dx)
    ny = lattice_count(hi[1] - lo[1], dx)
    xs = lo[0] + dx * (np.arange(nx) + 0.5)
    ys = lo[1] + dx * (np.arange(ny) + 0.5)
    X, Y = np.meshgrid(xs, ys)
    return X.ravel(), Y.ravel()


def _rotated_lattice(lo, hi, dx, origin, angle):
    """Cell centres origin + (i + 1/2) dx t + (j + 1/2) dx n of the square lattice whose rows
    run at ``angle`` degrees (t = (cos a, sin a), n = (-sin a, cos a)) that fall in the box
    [lo, hi] (T §5.3.4: the grid parallel to a slope)."""
    a = np.radians(angle)
    t = np.array([np.cos(a), np.sin(a)])
    n = np.array([-np.sin(a), np.cos(a)])
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    rel = corners - np.asarray(origin, float)
    s, q = rel @ t / dx - 0.5, rel @ n / dx - 0.5
    i = np.arange(np.floor(s.min()), np.ceil(s.max()) + 1)
    j = np.arange(np.floor(q.min()), np.ceil(q.max()) + 1)
    I, J = np.meshgrid(i, j)
    x = origin[0] + dx * ((I + 0.5) * t[0] + (J + 0.5) * n[0])
    y = origin[1] + dx * ((I + 0.5) * t[1] + (J + 0.5) * n[1])
    x, y = x.ravel(), y.ravel()
    # half-open bounds, as the usual grid's cells: a centre on the far edge belongs outside
    eps = 1e-9 * dx
    inside = (x >= lo[0] - eps) & (x < hi[0] - eps) & (y >= lo[1] - eps) & (y < hi[1] - eps)
    return x[inside], y[inside]


def _fitted_box(lo, hi, dx):
    """Cell centres filling a box whose sides are not whole numbers of dx to its faces
    (sphfoam.case.geometry.fitted_sites), and their spacing across x and along y."""
    (xs, sx), (ys, sy) = (fitted_sites(a, b, dx) for a, b in zip(lo, hi))
    X, Y = np.meshgrid(xs, ys)
    return X.ravel(), Y.ravel(), sx, sy


def fluid_points(region, dx):
    """Particles of a fluid region: the cell centres of its lattice (the usual grid anchored
    at its lower-left corner, or its ``grid``) inside it (a box whose sides are not whole
    numbers of dx: ``_fitted_box``, in ``generate``)."""
    grid = getattr(region, "grid", None)
    if isinstance(region, BoxRegion):
        if grid is None:
            return _lattice(region.min, region.max, dx)
        return _rotated_lattice(region.min, region.max, dx, grid.origin, grid.angle)
    pts = np.asarray(region.points, dtype=float)
    lo = pts.min(axis=0)
    if grid is None:
        x, y = _lattice(lo, pts.max(axis=0), dx)
    else:
        x, y = _rotated_lattice(lo, pts.max(axis=0), dx, grid.origin, grid.angle)
    inside = MplPath(pts).contains_points(np.column_stack([x, y]))
    return x[inside], y[inside]


def seam_keep(x, y, region, r):
    """Mask thinning the seams between fluid regions: of two particles of different regions
    closer than ``r``, the one of the later region goes (T §5.3.4, Fig 5.2: "some particles
    lying above the toe of the slope were removed to ensure that no two particles were placed
    too close together")."""
    keep = np.ones(x.size, bool)
    if x.size < 2:
        return keep
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(r, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        cross = region[i] != region[j]
        i, j = i[cross], j[cross]
        keep[np.where(region[i] > region[j], i, j)] = False
    return keep


def _tank_sites(tank, dx):
    """Sites of a tank whose sides are not whole numbers of dx (``tank_sites``: its rows
    ``layers`` deep behind every closed side; the lattice anchored at the corner put the far
    sides' first row less than dx behind them and dropped the last), with each site's area."""
    n = [[0 if end in tank.open else tank.layers for end in ends]
         for ends in (("left", "right"), ("bottom", "top"))]
    axes, spacing = tank_sites(tank.min, tank.max, dx, [n[0][0], n[1][0]], [n[0][1], n[1][1]])
    X, Y = np.meshgrid(*axes)
    SX, SY = np.meshgrid(*spacing)
    return X.ravel(), Y.ravel(), (SX * SY).ravel()


def wall_points(region, dx, areas: bool = False):
    """Rows of wall particles behind a wall entry (``layers`` deep, cell centred). With
    ``areas``, also each particle's area, or None where it is dx^2."""
    if isinstance(region, BoxWalls):
        L = region.layers * dx
        (x0, y0), (x1, y1) = region.min, region.max
        lo = (x0 - (0 if "left" in region.open else L), y0 - (0 if "bottom" in region.open else L))
        hi = (x1 + (0 if "right" in region.open else L), y1 + (0 if "top" in region.open else L))
        a = None
        if off_lattice(region.min, region.max, dx):
            x, y, a = _tank_sites(region, dx)
        else:
            x, y = _lattice(lo, hi, dx)
        out = ~((x > x0) & (x < x1) & (y > y0) & (y < y1))
        if not areas:
            return x[out], y[out]
        return x[out], y[out], None if a is None else a[out]
    xs, ys = [], []
    for pts, side in polylines_of(region):
        x, y = polyline_points(np.asarray(pts, float), dx, region.layers, side)
        xs.append(x)
        ys.append(y)
    x, y = np.concatenate(xs), np.concatenate(ys)
    return (x, y, None) if areas else (x, y)


def polyline_points(pts, dx, layers, side):
    """Rows of wall particles behind each segment; ``side`` is where the solid lies."""
    xs, ys = [], []
    sgn = -1.0 if side == "right" else 1.0
    for p0, p1 in zip(pts[:-1], pts[1:]):
        seg = p1 - p0
        length = float(np.hypot(*seg))
        if length == 0:
            continue
        t = seg / length
        nrm = sgn * np.array([-t[1], t[0]])      # unit normal pointing into the solid
        n = max(1, int(round(length / dx)))
        s = (np.arange(n) + 0.5) * (length / n)
        for k in range(layers):
            off = (k + 0.5) * dx
            xs.append(p0[0] + s * t[0] + off * nrm[0])
            ys.append(p0[1] + s * t[1] + off * nrm[1])
    x, y = np.concatenate(xs), np.concatenate(ys)
    # drop near-duplicates where segments meet (inside corners)
    keep = np.ones(x.size, bool)
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(0.5 * dx, output_type="ndarray")
    keep[pairs[:, 1]] = False          # i < j in every pair: keep the first of each
    return x[keep], y[keep]


def local_surface(xf, yf, dx):
    """Free-surface height above each fluid particle: top of its lattice column + dx/2."""
    col = np.floor((xf - xf.min()) / dx + 0.5).astype(np.int64)
    top = np.full(col.max() + 1, -np.inf)
    np.maximum.at(top, col, yf)
    return top[col] + 0.5 * dx


#: the per-wall-particle fields the set-up can write (sphfoam.case.geometry.wall_metadata)
WALL_METADATA = ("nx", "ny", "wallDist", "corner", "nFull", "ghostX", "ghostY")


def generate(pd: ParticleDict, ctx, eos, boundary=None, support_radius: float | None = None,
             moving: bool = False, waves=(), fields=()) -> ParticleState:
    """Particles of a case at rest in hydrostatic equilibrium.

    ``boundary`` (the selected boundary model) decides where wall particles go
    (``wall_placement``: rows behind the walls or none; ``wall_layers``: how many) and which
    per-wall-particle fields are stored (``wall_fields``: normal, distance behind the wall, corner
    flag, fully-wet pair count ``nFull`` for a support of ``support_radius``). ``moving``
    adds the wall entry index ``patch`` and the initial positions ``x0, y0`` that prescribed
    motions displace. ``waves`` (pairs of InitialWave and theory model, from
    ``constant/waveProperties``) put solitary waves on every box of still water, with their
    velocity and pressure (sphfoam.setup.waves). ``fields``: further per-wall-particle fields
    other selected models read (e.g. the normal ``nx``, ``ny`` of the turbulent wall law;
    ``lineDist``, every particle's signed distance to the nearest wall line, of the mixing
    length).
    """
    dx = pd.dx
    placement = getattr(boundary, "wall_placement", "rows")
    segs = segments_of(pd)
    gmag = float(np.hypot(*ctx.g))
    pieces, areas = [], []
    for name, r in pd.fluid.items():
        if waves and isinstance(r, BoxRegion) and r.grid is not None:
            from sphfoam.case.errors import CaseError
            raise CaseError.single("system/particleDict", f"fluid.{name}.grid", (
                "a box carrying the initial waves of constant/waveProperties is filled column "
                "by column on the usual grid: remove its grid (or the waves)"))
        area = np.nan                     # NaN: the area is dx dy, the mass as before
        if waves and isinstance(r, BoxRegion):
            x_, y_, dy_ = wave_columns(r, dx, waves, gmag)
            pieces.append((x_, y_, dy_, r))
        elif isinstance(r, BoxRegion) and r.grid is None and off_lattice(r.min, r.max, dx):
            x_, y_, sx, sy = _fitted_box(r.min, r.max, dx)   # filled to its faces
            pieces.append((x_, y_, np.full(x_.size, sy), None))
            area = sx * sy
        else:
            x_, y_ = fluid_points(r, dx)
            pieces.append((x_, y_, np.full(x_.size, dx), None))
        if r.clipToWalls and segs:
            x_, y_, dy_, w_ = pieces[-1]
            ok = fluid_side(segs, x_, y_, dx)
            pieces[-1] = (x_[ok], y_[ok], dy_[ok], w_)
        areas.append(np.full(pieces[-1][0].size, area))
    xf = np.concatenate([q[0] for q in pieces])
    yf = np.concatenate([q[1] for q in pieces])
    dyf = np.concatenate([q[2] for q in pieces])
    af = np.concatenate(areas)
    regf = np.concatenate([np.full(q[0].size, i) for i, q in enumerate(pieces)])
    ok = seam_keep(xf, yf, regf, pd.minSpacing * dx)
    xf, yf, dyf, regf, af = xf[ok], yf[ok], dyf[ok], regf[ok], af[ok]
    walls = list(pd.walls.values())
    if walls and placement != "none":
        layers = getattr(boundary, "wall_layers", None)
        wall_pieces = [wall_points(r if layers is None else r.model_copy(update={"layers": layers}),
                                   dx, areas=True) for r in walls]
        xw = np.concatenate([p[0] for p in wall_pieces])
        yw = np.concatenate([p[1] for p in wall_pieces])
        aw = np.concatenate([np.full(len(p[0]), np.nan) if p[2] is None else p[2]
                             for p in wall_pieces])
        pw = np.concatenate([np.full(len(p[0]), i) for i, p in enumerate(wall_pieces)])
        keep = _first_of_duplicates(xw, yw, 0.5 * dx)
        xw, yw, pw, aw = xw[keep], yw[keep], pw[keep], aw[keep]
        vel = np.array([tuple(getattr(w, "velocity", (0.0, 0.0))) for w in walls],
                       float).reshape(len(walls), 2)
        uw, vw = vel[pw, 0], vel[pw, 1]
    else:
        xw = yw = uw = vw = aw = np.zeros(0)
        pw = np.zeros(0, dtype=np.int64)
    if xw.size and xf.size:
        # fluid never overlaps walls: drop fluid particles closer than dx/2 to a wall particle
        # only whether a wall particle is nearer than dx/2: a bounded search (inf beyond)
        d, _ = cKDTree(np.column_stack([xw, yw])).query(np.column_stack([xf, yf]),
                                                         distance_upper_bound=0.5 * dx,
                                                         workers=-1)
        ok = d >= 0.5 * dx * (1 - LATTICE_TOLERANCE)
        xf, yf, dyf, regf, af = xf[ok], yf[ok], dyf[ok], regf[ok], af[ok]
    for r in walls:                       # nor inside a solid block (beyond its rows)
        if isinstance(r, BlockWalls) and xf.size:
            m = 0.5 * dx * (1 - LATTICE_TOLERANCE)
            ok = ~((xf > r.min[0] - m) & (xf < r.max[0] + m) & (yf > r.min[1] - m)
                   & (yf < r.max[1] + m))
            xf, yf, dyf, regf, af = xf[ok], yf[ok], dyf[ok], regf[ok], af[ok]
    if segs and xf.size:
        # ... or to a wall line (walls without particles, e.g. mirrored ghosts). A wave's
        # column (sphfoam.setup.waves.wave_columns) holds n = round((d + eta)/dx) particles
        # dy = (d + eta)/n apart from dy/2 above the bed: where n rounds up, dy < dx and the
        # bottom particle is closer than dx/2 to the bed. Dropping it (as before) left a hole
        # a particle high at the bed under each such column (20-29 % of the wave's volume
        # at d/dx = 8-20 for A/d = 0.3) that the column above fell into: the crest
        # "breathed" by 8-9 % at the column's acoustic period (docs/low-dissipation.md).
        # Each particle keeps half its own spacing, min(dx, dy), from the wall lines instead
        # (the wall rows of particle boundaries lie dx/2 behind the line: no change there).
        # (a fitted box's particles keep half their spacing across, area / dy)
        sxf = np.where(np.isnan(af), dx, af / dyf)
        ok = (distance_to_walls(segs, xf, yf)
              >= 0.5 * np.minimum(sxf, dyf) * (1 - LATTICE_TOLERANCE))
        xf, yf, dyf, regf, af = xf[ok], yf[ok], dyf[ok], regf[ok], af[ok]
    if xf.size == 0:
        raise ValueError("system/particleDict: fluid regions produce no particles at this dx")
    gdown = max(-float(ctx.g[1]), 0.0)   # hydrostatic along -y only (a body force along x,
    eta_f = local_surface(xf, yf, dx)     # e.g. a channel's driving force, adds no pressure)
    uf = np.zeros(xf.size)
    vf = np.zeros(xf.size)
    pf = None
    if waves:
        pf = ctx.rho0 * gdown * np.maximum(eta_f - yf, 0.0)
        for i, (_, _, _, r) in enumerate(pieces):
            if r is None:
                continue
            sel = regf == i
            bed, top = r.min[1], r.max[1]
            uf[sel], vf[sel], pf[sel] = wave_fields(xf[sel], yf[sel], bed, top - bed, waves,
                                                    gmag, ctx.rho0)
            eta_f[sel] = top + wave_surface(xf[sel], top - bed, waves, gmag)
    if xw.size:
        _, nearest = cKDTree(np.column_stack([xf, yf])).query(np.column_stack([xw, yw]),
                                                              workers=-1)
        eta_w = eta_f[nearest]
    else:
        eta_w = np.zeros(0)
    x = np.concatenate([xf, xw])
    y = np.concatenate([yf, yw])
    eta = np.concatenate([eta_f, eta_w])
    p = ctx.rho0 * gdown * np.maximum(eta - y, 0.0)
    if pf is not None:
        p[:xf.size] = pf
        if xw.size:
            p[xf.size:] = wall_pressure(pf, yf, yw, nearest, ctx.rho0 * gdown)
    rho = eos.density(p, ctx)
    kind = np.concatenate([np.full(xf.size, FLUID), np.full(xw.size, WALL)])
    u = np.concatenate([uf, uw])
    v = np.concatenate([vf, vw])
    dy = np.concatenate([dyf, np.full(xw.size, dx)])
    extra = {}
    # the distance behind the wall is always written: it records how the walls were set up
    wanted = set(boundary.fields_in(2) if boundary is not None else ()) | {"wallDist"} | \
        {f for f in fields if f in WALL_METADATA}
    if wanted and xw.size:
        nx, ny, dist, corner, _ = wall_metadata(segs, xw, yw, dx)
        # the ghost node (mDBC): the mirror image across the nearest wall point
        meta = {"nx": nx, "ny": ny, "wallDist": dist, "corner": corner,
                "ghostX": 2.0 * dist * nx, "ghostY": 2.0 * dist * ny}
        if "nFull" in wanted:
            meta["nFull"] = full_pairs(segs, xw, yw, dx, support_radius)
        for k in wanted:
            extra[k] = np.concatenate([np.zeros(xf.size), meta[k]])
    if "lineDist" in fields:
        # signed distance to the nearest wall line (the mixing length's wall distance)
        dist = np.zeros(x.size)
        line_distance(x, y, segment_array(segs), dist)
        extra["lineDist"] = dist
    if moving:
        extra["patch"] = np.concatenate([np.full(xf.size, -1.0), pw.astype(float)])
        extra["x0"] = x.copy()
        extra["y0"] = y.copy()
    mass = rho * dx * dy
    area = np.concatenate([af, aw])
    fit = ~np.isnan(area)
    mass[fit] = rho[fit] * area[fit]     # fitted boxes and tanks: rho times the cell's area
    return ParticleState(x, y, u, v, rho, mass, kind, extra=extra)


def wall_pressure(pf, yf, yw, nearest, rho_g):
    """Pressure of wall particles beside a wave: the nearest fluid particle's (the wave
    theory's, non-hydrostatic) continued hydrostatically to the wall particle,
    p_w = p_f + rho0 g (y_f - y_w), p_w >= 0.

    Under a solitary wave the bed's pressure is not the hydrostatic rho0 g (d + eta) of the
    local surface: it is the theory's, 5.2 kPa (0.53 m of water, 18 % of A) lower under the
    crest of the exact wave at A/d = 0.3 (Dw/Dt < 0 there). The vertical pressure gradient at
    a flat bed is hydrostatic (w = 0 on it, so Dw/Dt = 0), so the continuation is exact to
    O(dy^2) for the bed's rows; beside a vertical wall it is the fluid particle's own pressure
    (y_f ~ y_w). In still water it is rho0 g (eta - y_w), as without waves.
    """
    return np.maximum(pf[nearest] + rho_g * (yf[nearest] - yw), 0.0)


def _first_of_duplicates(x, y, r):
    """Mask keeping the first of any points closer than ``r`` (walls of two entries that
    meet, e.g. a slope starting on a tank's bed)."""
    keep = np.ones(x.size, bool)
    if x.size == 0:
        return keep
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(r, output_type="ndarray")
    for i, j in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))] if len(pairs) else ():
        if keep[i]:
            keep[j] = False
    return keep


def full_pairs(segs, xw, yw, dx, support_radius):
    """Pairs a wall particle would form with fluid if submerged: the lattice sites inside
    its kernel support on the fluid side of the walls (fewer in a corner, T §3.9)."""
    if support_radius is None:
        raise ValueError("full_pairs needs the kernel support radius")
    off = lattice_offsets(support_radius / dx) * dx
    sx = (xw[:, None] + off[None, :, 0]).ravel()
    sy = (yw[:, None] + off[None, :, 1]).ravel()
    wet = fluid_side(segs, sx, sy, dx).reshape(xw.size, len(off))
    return wet.sum(axis=1).astype(float)
