"""Particle generation in three dimensions (``system/particleDict`` ``dimension 3``; z up).

As in 2-D (sphfoam.setup.particles): fluid particles sit at the centres of a cubic lattice
of spacing dx, so a block holds its volume / dx^3 particles and its surface lies dx/2 beyond
the outermost layer; wall particles sit at the lattice centres ``layers`` deep behind a
wall (outside a tank's closed sides; inside a solid's surface: a block, a cylinder, an
extruded section, a closed surface mesh, sphfoam.case.solids; behind an open surface mesh's
faces), DualSPHysics' layout of boundary particles. Fluid
keeps dx/2 from every wall particle and from every solid's surface. The initial state is
hydrostatic: p = rho0 g_down (eta - z), eta the top of each (x, y) column plus dx/2 (wall
particles: their nearest fluid particle's), rho from the inverse of the equation of state;
masses rho dx^3. A box of fluid or a tank whose sides are not whole numbers of dx is fitted
to its faces (sphfoam.case.geometry.fitted_sites: round(L/dx) sites spaced L/n along such a
side; a tank's layers dx/2, 3dx/2, ... behind every closed side), masses rho times the
cell's volume. Solitary waves (``constant/waveProperties``) on a box of still water are
the 2-D flume's columns (sphfoam.setup.waves) in the x-z plane, repeated across y.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from sphfoam.case.errors import CaseError
from sphfoam.case.geometry import (LATTICE_TOLERANCE, fitted_sites, lattice_count,
                                   lattice_offsets, off_lattice, tank_sites)
from sphfoam.case.schemas import BlockWalls, BoxRegion, BoxWalls, MeshWalls, ParticleDict
from sphfoam.case.solids import FACE_AXES, bounds, signed_distance, tank_wall_depth
from sphfoam.engine.state import FLUID, WALL, ParticleState
from sphfoam.setup.particles import wall_pressure
from sphfoam.setup.waves import fields as wave_fields
from sphfoam.setup.waves import surface as wave_surface
from sphfoam.setup.waves import wave_columns

PD = "system/particleDict"


def lattice(lo, hi, dx, anchor=None) -> np.ndarray:
    """Cell centres anchor + (i + 1/2) dx of the cubic lattice that lie in [lo, hi] (n, 3);
    ``anchor`` defaults to ``lo``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    a = lo if anchor is None else np.asarray(anchor, float)
    first = np.ceil((lo - a) / dx - 0.5 - LATTICE_TOLERANCE)
    axes = []
    for k in range(3):
        n = lattice_count(hi[k] - (a[k] + first[k] * dx), dx)
        axes.append(a[k] + dx * (first[k] + np.arange(n) + 0.5))
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


def case_anchor(pd: ParticleDict) -> np.ndarray:
    """Where the case's lattice is anchored: the first tank's corner, else the first box of
    fluid's, else the origin (cylinders and extruded sections are filled on it)."""
    for w in pd.walls.values():
        if isinstance(w, BoxWalls):
            return np.asarray(w.min, float)
    for r in pd.fluid.values():
        if isinstance(r, BoxRegion):
            return np.asarray(r.min, float)
    return np.zeros(3)


def _grid(axes) -> np.ndarray:
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])


def fluid_points(region, dx, anchor, volumes: bool = False):
    """Lattice centres inside a fluid region (a box on its own lattice, as in 2-D; a box whose
    sides are not whole numbers of dx filled to its faces, ``fitted_sites``). With
    ``volumes``, also each particle's volume (None where it is dx^3) and the least spacing."""
    vol, least = None, dx
    if isinstance(region, BoxRegion):
        if not off_lattice(region.min, region.max, dx):
            p = lattice(region.min, region.max, dx)
        else:
            sites = [fitted_sites(a, b, dx) for a, b in zip(region.min, region.max)]
            p = _grid([q for q, _ in sites])
            vol = np.full(len(p), float(np.prod([s for _, s in sites])))
            least = min(s for _, s in sites)
    else:
        lo, hi = bounds(region)
        p = lattice(lo - dx, hi + dx, dx, anchor)   # lattice() keeps whole cells: pad by one
        p = p[signed_distance(region, p) < 0.0]
    return (p, vol, least) if volumes else p


def wall_points(wall, dx, anchor, volumes: bool = False):
    """Wall particles of a wall entry ``layers`` deep and their distance behind the wall
    surface. A tank whose sides are not whole numbers of dx has its layers dx/2, 3dx/2, ...
    behind every closed face and the sites along each face fitted to its length (the lattice
    anchored at the tank's corner put the far faces' first layer less than dx behind them and
    dropped the last); a block's, ``layers`` deep inside each face. With ``volumes``, also
    each particle's volume, or None where it is dx^3."""
    L = wall.layers * dx
    if isinstance(wall, BoxWalls):
        lo, hi = np.asarray(wall.min, float), np.asarray(wall.max, float)
        vol = None
        if not off_lattice(lo, hi, dx):
            p = lattice(lo - L, hi + L, dx, anchor=lo)
        else:          # layers behind every side: tank_wall_depth drops the open ones
            axes, spacing = tank_sites(lo, hi, dx, [wall.layers] * 3, [wall.layers] * 3)
            p = _grid(axes)
            vol = np.prod(_grid(spacing), axis=1)
        d = tank_wall_depth(wall, p)
        keep = (d > 0.0) & (d < np.inf)
        p, d = p[keep], d[keep]
        if vol is not None:
            vol = vol[keep]
        return (p, d, vol) if volumes else (p, d)
    if isinstance(wall, BlockWalls) and off_lattice(wall.min, wall.max, dx):
        # a block whose sides are not whole numbers of dx: its sites fitted to its faces,
        # ``layers`` deep behind each (the lattice anchored at its corner put the far faces'
        # first layer up to dx behind them)
        sites = [fitted_sites(a, b, dx) for a, b in zip(wall.min, wall.max)]
        index = np.stack(np.meshgrid(*[np.arange(q.size) for q, _ in sites],
                                     indexing="ij"), -1).reshape(-1, 3)
        n = np.array([q.size for q, _ in sites])
        keep = ((index < wall.layers) | (index >= n - wall.layers)).any(axis=1)
        p = _grid([q for q, _ in sites])[keep]
        vol = np.full(len(p), float(np.prod([sp for _, sp in sites])))
        d = -signed_distance(wall, p)
        return (p, d, vol) if volumes else (p, d)
    lo, hi = bounds(wall)
    if isinstance(wall, MeshWalls):      # behind an open sheet, outside a container
        lo, hi = lo - L, hi + L
    anchor = np.asarray(wall.min, float) if hasattr(wall, "min") else anchor
    p = lattice(lo - dx, hi + dx, dx, anchor)   # lattice() keeps whole cells: pad by one
    d = -signed_distance(wall, p)
    keep = (d > 0.0) & (d <= L * (1 + LATTICE_TOLERANCE))
    return (p[keep], d[keep], None) if volumes else (p[keep], d[keep])


def _first_of_duplicates(p: np.ndarray, r: float) -> np.ndarray:
    """Mask keeping the first of any points closer than ``r`` (walls of two entries)."""
    keep = np.ones(len(p), bool)
    if len(p) == 0:
        return keep
    pairs = cKDTree(p).query_pairs(r, output_type="ndarray")
    for i, j in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))] if len(pairs) else ():
        if keep[i]:
            keep[j] = False
    return keep


def seam_keep(p: np.ndarray, region: np.ndarray, r: float) -> np.ndarray:
    """Of two particles of different regions closer than ``r``, the later region's goes."""
    keep = np.ones(len(p), bool)
    if len(p) < 2:
        return keep
    pairs = cKDTree(p).query_pairs(r, output_type="ndarray")
    if len(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        cross = region[i] != region[j]
        i, j = i[cross], j[cross]
        keep[np.where(region[i] > region[j], i, j)] = False
    return keep


def local_surface(p: np.ndarray, dx: float) -> np.ndarray:
    """Free-surface height above each fluid particle: top of its (x, y) column + dx/2."""
    key = np.floor((p[:, :2] - p[:, :2].min(axis=0)) / dx + 0.5).astype(np.int64)
    col = np.unique(key, axis=0, return_inverse=True)[1].ravel()
    top = np.full(col.max() + 1, -np.inf)
    np.maximum.at(top, col, p[:, 2])
    return top[col] + 0.5 * dx


#: the wall fields the 3-D set-up writes for axis-aligned walls (``wall_geometry``)
GEOMETRY_FIELDS = ("nx", "ny", "nz", "corner", "nFull", "ghostX", "ghostY", "ghostZ")


def _refuse(boundary, fields, walls=()) -> None:
    """What the 3-D set-up cannot make, refused by name."""
    if getattr(boundary, "wall_placement", "rows") == "none":
        if 3 not in getattr(boundary, "hook_dims", (2,)):
            raise CaseError.single("constant/sphProperties", "boundary.type", (
                f"{boundary.name} has no 3-D form (its walls are lines to mirror across): "
                "use stationaryGhosts"))
        for name, w in walls:
            if not isinstance(w, BoxWalls):
                raise CaseError.single(PD, f"walls.{name}.type", (
                    f"{boundary.name} in 3-D mirrors across the plane faces of box tanks "
                    f"only, not a {w.type}: use stationaryGhosts or adami"))
        return
    wanted = set(getattr(boundary, "wall_fields", ())) | set(fields)
    lacking = wanted - {"wallDist"} - set(GEOMETRY_FIELDS)
    if lacking:
        raise CaseError.single("constant/sphProperties", "boundary.type", (
            f"the selected models read the wall field(s) {', '.join(sorted(lacking))}, "
            "which have no 3-D form: use stationaryGhosts"))
    if wanted & set(GEOMETRY_FIELDS):
        for name, w in walls:
            if not isinstance(w, (BoxWalls, BlockWalls)):
                what = "ghost nodes" if wanted & {"ghostX", "ghostY", "ghostZ"} \
                    else "wall normals"
                raise CaseError.single(PD, f"walls.{name}.type", (
                    f"{getattr(boundary, 'name', 'the boundary')} reads {what}, which "
                    f"the 3-D set-up writes for box and block walls only (plane faces on "
                    f"the lattice), not for a {w.type}: use stationaryGhosts or adami"))


def _behind(w, p: np.ndarray) -> np.ndarray:
    """Whether the points lie behind (in) the wall entry ``w``: beyond the plane of one of a
    tank's closed sides (its walls continued past its open sides, as a periodic or open
    channel continues them), inside a solid."""
    if isinstance(w, BoxWalls):
        lo, hi = np.asarray(w.min, float), np.asarray(w.max, float)
        out = np.zeros(len(p), bool)
        for face, (axis, side) in FACE_AXES.items():
            if face not in w.open:
                out |= p[:, axis] > hi[axis] if side else p[:, axis] < lo[axis]
        return out
    return signed_distance(w, p) < 0.0


def _covered_faces(walls, k: int, dx: float) -> np.ndarray:
    """Block ``k``'s faces (side below/above, axis) that lie on another wall (a block
    standing on the tank's floor): no face, the fluid cannot reach them. (2, 3): the faces
    at ``min`` and at ``max`` along each axis."""
    w = walls[k]
    lo, hi = np.asarray(w.min, float), np.asarray(w.max, float)
    covered = np.zeros((2, 3), bool)
    for side, edge in ((0, lo), (1, hi)):
        for axis in range(3):
            c = 0.5 * (lo + hi)
            c[axis] = edge[axis] + (0.5 * dx if side else -0.5 * dx)
            covered[side, axis] = any(_behind(o, c[None, :])[0]
                                      for j, o in enumerate(walls) if j != k)
    return covered


def _out_of_blocks(walls, i: int, q: np.ndarray, dx: float) -> np.ndarray:
    """From the points ``q`` of tank ``i``'s inside (the nearest to its wall particles), the
    step out of any block standing on them to the nearest of the block's faces that the
    fluid reaches: the floor's rows under a block lie behind the edge its face makes with
    the floor (the fluid's concave edge), not under the floor's water."""
    step = np.zeros_like(q)
    tol = 1e-6 * dx
    for k, w in enumerate(walls):
        if k == i or not isinstance(w, BlockWalls):
            continue
        lo, hi = np.asarray(w.min, float), np.asarray(w.max, float)
        on = np.all((q > lo - tol) & (q < hi + tol), axis=1)
        if not on.any():
            continue
        depth = np.stack([q[on] - lo, hi - q[on]])                   # (2, n, 3)
        depth = np.where(_covered_faces(walls, k, dx)[:, None, :], np.inf, depth)
        # to the nearest face, and to every face as near within dx/4 (behind the block's
        # vertical edge at the floor: across the edge, as for the block's own rows)
        least = depth.min(axis=(0, 2))
        out = (depth <= least[None, :, None] + 0.25 * dx) & np.isfinite(depth) \
            & (least[None, :, None] > tol)
        step[on] += np.where(out[1], depth[1], 0.0) - np.where(out[0], depth[0], 0.0)
    return step


def wall_geometry(walls, pw: np.ndarray, patch: np.ndarray, dx: float,
                  support_radius: float | None = None) -> dict[str, np.ndarray]:
    """Per wall particle of box tanks and block solids (axis-aligned plane faces): per axis,
    the sign of the normal (into the fluid) of each face the particle belongs to (nx, ny, nz:
    one nonzero on a face, two on an edge, three at a vertex; sphfoam.models.boundaries) and
    ``corner``, the faces it belongs to less one. A block's particle belongs to its nearest
    faces and to every face whose first layer (less than dx behind it) it is in. A block's face that lies on another wall (a
    block standing on the tank's floor) is not a face. With ``support_radius``, ``nFull``:
    the lattice sites inside the support that are behind no wall, the pairs the particle
    forms fully submerged (T §3.9). ``ghostX``, ``ghostY``, ``ghostZ``: the vector to the
    particle's mirror image across the wall surface (twice the vector to the nearest point of
    the tank's inside or of the block's nearest faces; mDBC's ghost node)."""
    n = np.zeros((len(pw), 3))
    corner = np.zeros(len(pw))
    ghost = np.zeros((len(pw), 3))
    for i, w in enumerate(walls):
        sel = np.flatnonzero(patch == i)
        if not sel.size:
            continue
        p = pw[sel]
        lo, hi = np.asarray(w.min, float), np.asarray(w.max, float)
        if isinstance(w, BoxWalls):
            into = np.clip(lo - p, 0.0, None) - np.clip(p - hi, 0.0, None)   # into the tank
            into += _out_of_blocks(walls, i, p + into, dx)
            near = np.abs(into) > 0.25 * dx
            out = np.sign(into)
            ghost[sel] = 2.0 * into      # to the nearest point of the tank, and as far again
        else:
            depth = np.stack([p - lo, hi - p])                 # (2, n, 3): below, above
            depth = np.where(_covered_faces(walls, i, dx)[:, None, :], np.inf, depth)
            d = depth.min(axis=0)
            out = np.where(depth[1] < depth[0], 1.0, -1.0)
            # its nearest faces, and every face whose first layer it is in: a block's faces
            # need not lie on the lattice, so an edge's column can be 0.5 dx behind one face
            # and 0.9 dx behind the other
            nearest = d <= d.min(axis=1)[:, None] + 0.25 * dx
            near = nearest | (d < dx)
            # the ghost node: mirrored across the nearest face (across the edge or vertex
            # where two or three are equally near)
            ghost[sel] = np.where(nearest & np.isfinite(d), 2.0 * d * out, 0.0)
        n[sel] = np.where(near, out, 0.0)
        corner[sel] = np.maximum(near.sum(axis=1) - 1, 0)
    geo = {"nx": n[:, 0], "ny": n[:, 1], "nz": n[:, 2], "corner": corner,
           "ghostX": ghost[:, 0], "ghostY": ghost[:, 1], "ghostZ": ghost[:, 2]}
    if support_radius is not None:
        off = lattice_offsets(support_radius / dx, 3) * dx
        full = np.zeros(len(pw))
        for start in range(0, len(pw), 4096):
            q = (pw[start:start + 4096, None, :] + off[None, :, :]).reshape(-1, 3)
            wet = np.ones(len(q), bool)
            for w in walls:
                wet &= ~_behind(w, q)
            full[start:start + 4096] = wet.reshape(-1, len(off)).sum(axis=1)
        geo["nFull"] = full
    return geo


def generate3d(pd: ParticleDict, ctx, eos, boundary=None, moving: bool = False, waves=(),
               fields=(), support_radius: float | None = None) -> ParticleState:
    """Particles of a 3-D case at rest in hydrostatic equilibrium (see the module)."""
    _refuse(boundary, fields, list(pd.walls.items()))
    dx = pd.dx
    tol = 1 - LATTICE_TOLERANCE
    anchor = case_anchor(pd)
    gmag = float(np.linalg.norm(ctx.g))
    pieces, spacing, wave_box, volume = [], [], [], []
    for name, r in pd.fluid.items():
        if waves and isinstance(r, BoxRegion):
            (x0, y0, z0), (x1, y1, z1) = r.min, r.max
            section = BoxRegion.model_construct(type="box", min=(x0, z0), max=(x1, z1),
                                                grid=None, clipToWalls=False)
            xs, zs, dz = wave_columns(section, dx, waves, gmag)
            ys, sy = fitted_sites(y0, y1, dx)      # across: filled to the faces
            p = np.column_stack([np.tile(xs, ys.size), np.repeat(ys, xs.size),
                                 np.tile(zs, ys.size)])
            pieces.append(p)
            spacing.append(np.tile(dz, ys.size))
            wave_box.append(r)
            volume.append(None if sy == dx else dx * sy * np.tile(dz, ys.size))
        else:
            p, vol, least = fluid_points(r, dx, anchor, volumes=True)
            pieces.append(p)
            # a fitted box's least spacing (it keeps half of it from solids' surfaces)
            spacing.append(np.full(len(p), least))
            wave_box.append(None)
            volume.append(vol)
    pf = np.concatenate(pieces)
    dzf = np.concatenate(spacing)
    # each particle's volume where it is not dx dx dz (NaN: dx dx dz, the mass as before)
    volf = np.concatenate([np.full(len(q), np.nan) if v is None else v
                           for q, v in zip(pieces, volume)])
    regf = np.concatenate([np.full(len(q), i) for i, q in enumerate(pieces)])
    ok = seam_keep(pf, regf, pd.minSpacing * dx)
    pf, dzf, regf, volf = pf[ok], dzf[ok], regf[ok], volf[ok]
    walls = list(pd.walls.values())
    layers = getattr(boundary, "wall_layers", None)
    if walls and getattr(boundary, "wall_placement", "rows") != "none":
        made = [wall_points(w if layers is None else w.model_copy(update={"layers": layers}),
                            dx, anchor, volumes=True) for w in walls]
        pw = np.concatenate([m[0] for m in made])
        dw = np.concatenate([m[1] for m in made])
        volw = np.concatenate([np.full(len(m[0]), np.nan) if m[2] is None else m[2]
                               for m in made])
        patch = np.concatenate([np.full(len(m[0]), i) for i, m in enumerate(made)])
        keep = _first_of_duplicates(pw, 0.5 * dx)
        pw, dw, patch, volw = pw[keep], dw[keep], patch[keep], volw[keep]
        vel = np.zeros((len(walls), 3))
        for i, w in enumerate(walls):          # a tank's constant velocity; solids are still
            v = tuple(getattr(w, "velocity", ()))
            vel[i, :len(v)] = v
        vel = vel[patch]
    else:
        pw, dw, vel, volw = np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3)), np.zeros(0)
        patch = np.zeros(0, dtype=np.int64)
    if len(pw) and len(pf):      # fluid never overlaps walls: dx/2 from every wall particle
        # only whether a wall particle is nearer than dx/2: a bounded search (inf beyond)
        d, _ = cKDTree(pw).query(pf, distance_upper_bound=0.5 * dx, workers=-1)
        ok = d >= 0.5 * dx * tol
        pf, dzf, regf, volf = pf[ok], dzf[ok], regf[ok], volf[ok]
    for w in walls:              # ... and from every solid's surface
        if not isinstance(w, BoxWalls) and len(pf):
            ok = signed_distance(w, pf) >= 0.5 * np.minimum(dx, dzf) * tol
            pf, dzf, regf, volf = pf[ok], dzf[ok], regf[ok], volf[ok]
    if len(pf) == 0:
        raise ValueError(f"{PD}: fluid regions produce no particles at this dx")
    gdown = max(-float(ctx.g[2]), 0.0)      # hydrostatic along -z (z is up in 3-D)
    eta_f = local_surface(pf, dx)
    uf = np.zeros((len(pf), 3))
    p_f = ctx.rho0 * gdown * np.maximum(eta_f - pf[:, 2], 0.0)
    for i, r in enumerate(wave_box):
        if r is None:
            continue
        sel = regf == i
        bed, top = r.min[2], r.max[2]
        x, z = pf[sel, 0], pf[sel, 2]
        uf[sel, 0], uf[sel, 2], p_f[sel] = wave_fields(x, z, bed, top - bed, waves, gmag,
                                                       ctx.rho0)
        eta_f[sel] = top + wave_surface(x, top - bed, waves, gmag)
    if len(pw):
        _, nearest = cKDTree(pf).query(pw, workers=-1)
        p_w = wall_pressure(p_f, pf[:, 2], pw[:, 2], nearest, ctx.rho0 * gdown)
    else:
        p_w = np.zeros(0)
    pos = np.concatenate([pf, pw])
    vel_all = np.concatenate([uf, vel])
    p = np.concatenate([p_f, p_w])
    rho = eos.density(p, ctx)
    kind = np.concatenate([np.full(len(pf), FLUID), np.full(len(pw), WALL)])
    dz = np.concatenate([dzf, np.full(len(pw), dx)])
    extra = {"wallDist": np.concatenate([np.zeros(len(pf)), dw])} if len(pw) else {}
    wanted = (set(getattr(boundary, "wall_fields", ())) | set(fields)) & set(GEOMETRY_FIELDS)
    if wanted and len(pw):
        geo = wall_geometry(walls, pw, patch, dx,
                            support_radius if "nFull" in wanted else None)
        for k in wanted:
            extra[k] = np.concatenate([np.zeros(len(pf)), geo[k]])
    if moving:          # the wall entry of each wall particle and where prescribed motion
        extra["patch"] = np.concatenate([np.full(len(pf), -1.0),  # displaces it from
                                         patch.astype(float) if len(pw) else np.zeros(0)])
        for k, c in zip(("x0", "y0", "z0"), pos.T):
            extra[k] = c.copy()
    mass = rho * dx * dx * dz
    vol = np.concatenate([volf, volw])
    fit = ~np.isnan(vol)
    mass[fit] = rho[fit] * vol[fit]       # fitted boxes and tanks: rho times the cell's volume
    return ParticleState(pos[:, 0], pos[:, 1], vel_all[:, 0], vel_all[:, 1], rho,
                         mass, kind, extra=extra, z=pos[:, 2], w=vel_all[:, 2])
