"""Three-dimensional geometry of ``system/particleDict``: every 3-D fluid region and wall
entry as a signed distance (negative inside the shape) and a bounding box.

Boxes and cylinders have closed forms; an extruded section is the intersection of its
x-z polygon (distance to its edges, inside by the even-odd rule of matplotlib's Path) with
the slab of its span. A surface mesh (``type mesh``) is measured by VTK
(sphfoam.case.meshsolids): negative inside a closed surface, behind an open one's faces;
``side left`` turns a mesh wall inside out (a container; in front of an open sheet). The set-up (sphfoam.setup.particles3d) fills a fluid region with the
lattice sites inside it and puts a solid wall's layers at the sites within ``layers`` dx
inside its surface; a tank (``box`` walls) is the one shape whose solid lies outside.
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as MplPath

from sphfoam.case.schemas import (BlockWalls, BoxRegion, BoxWalls, CylinderRegion,
                                  CylinderWalls, ExtrudeRegion, ExtrudeWalls, MeshRegion,
                                  MeshWalls)

#: a tank's sides in 3-D (z up): (axis, 0 for the min side, 1 for the max side)
FACE_AXES = {"left": (0, 0), "right": (0, 1), "front": (1, 0), "back": (1, 1),
             "bottom": (2, 0), "top": (2, 1)}


def box_distance(lo, hi, p: np.ndarray) -> np.ndarray:
    """Signed distance of the points ``p`` (n, 3) to the box [lo, hi]: negative inside."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    q = np.abs(p - c) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return outside + inside


def cylinder_distance(p1, p2, radius, p: np.ndarray) -> np.ndarray:
    """Signed distance to the capped cylinder of ``radius`` around ``p1``-``p2``."""
    p1, p2 = np.asarray(p1, float), np.asarray(p2, float)
    axis = p2 - p1
    length = float(np.linalg.norm(axis))
    t = axis / length
    rel = p - p1
    along = rel @ t
    radial = np.linalg.norm(rel - along[:, None] * t, axis=1)
    d = np.column_stack([radial - radius, np.abs(along - 0.5 * length) - 0.5 * length])
    return np.linalg.norm(np.maximum(d, 0.0), axis=1) + np.minimum(d.max(axis=1), 0.0)


def polygon_distance(points, q: np.ndarray) -> np.ndarray:
    """Signed distance of the 2-D points ``q`` (n, 2) to the closed polygon ``points``."""
    pts = np.asarray(points, float)
    loop = np.vstack([pts, pts[:1]])
    d = np.full(len(q), np.inf)
    for a, b in zip(loop[:-1], loop[1:]):
        ab = b - a
        L2 = float(ab @ ab)
        if L2 == 0.0:
            continue
        s = np.clip((q - a) @ ab / L2, 0.0, 1.0)
        d = np.minimum(d, np.linalg.norm(q - (a + s[:, None] * ab), axis=1))
    inside = MplPath(pts).contains_points(q)
    return np.where(inside, -d, d)


def extrude_distance(points, span, p: np.ndarray) -> np.ndarray:
    """Signed distance to the x-z section ``points`` extruded over y in ``span``."""
    d2 = polygon_distance(points, p[:, [0, 2]])
    dy = np.abs(p[:, 1] - 0.5 * (span[0] + span[1])) - 0.5 * (span[1] - span[0])
    d = np.column_stack([d2, dy])
    return np.linalg.norm(np.maximum(d, 0.0), axis=1) + np.minimum(d.max(axis=1), 0.0)


def signed_distance(shape, p: np.ndarray) -> np.ndarray:
    """Signed distance of the points ``p`` (n, 3) to a 3-D region or solid wall entry,
    negative inside it (for a tank, inside its box)."""
    if isinstance(shape, (BoxRegion, BoxWalls, BlockWalls)):
        return box_distance(shape.min, shape.max, p)
    if isinstance(shape, (CylinderRegion, CylinderWalls)):
        return cylinder_distance(shape.point1, shape.point2, shape.radius, p)
    if isinstance(shape, (ExtrudeRegion, ExtrudeWalls)):
        return extrude_distance(shape.points, shape.span, p)
    if isinstance(shape, MeshRegion):
        return shape.surface.signed_distance(p)
    if isinstance(shape, MeshWalls):
        d = shape.surface.signed_distance(p)
        return -d if shape.side == "left" else d
    raise TypeError(f"{type(shape).__name__} is not a 3-D shape")


def bounds(shape) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo, hi) around a 3-D region or wall entry (a tank's or solid's surface)."""
    if isinstance(shape, (BoxRegion, BoxWalls, BlockWalls)):
        return np.asarray(shape.min, float), np.asarray(shape.max, float)
    if isinstance(shape, (CylinderRegion, CylinderWalls)):
        p1, p2 = np.asarray(shape.point1, float), np.asarray(shape.point2, float)
        t = (p2 - p1) / np.linalg.norm(p2 - p1)
        reach = shape.radius * np.sqrt(np.clip(1.0 - t * t, 0.0, 1.0))
        return np.minimum(p1, p2) - reach, np.maximum(p1, p2) + reach
    if isinstance(shape, (ExtrudeRegion, ExtrudeWalls)):
        pts = np.asarray(shape.points, float)
        lo = np.array([pts[:, 0].min(), shape.span[0], pts[:, 1].min()])
        hi = np.array([pts[:, 0].max(), shape.span[1], pts[:, 1].max()])
        return lo, hi
    if isinstance(shape, (MeshRegion, MeshWalls)):
        return shape.surface.lo.copy(), shape.surface.hi.copy()
    raise TypeError(f"{type(shape).__name__} is not a 3-D shape")


def tank_wall_depth(wall: BoxWalls, p: np.ndarray) -> np.ndarray:
    """Distance of the points ``p`` behind a tank's closed sides (0 inside the tank; inf
    beyond an open side, where there is no wall): where its wall layers go."""
    lo, hi = np.asarray(wall.min, float), np.asarray(wall.max, float)
    behind = np.zeros((len(p), 3))
    for axis in range(3):
        below = np.maximum(lo[axis] - p[:, axis], 0.0)
        above = np.maximum(p[:, axis] - hi[axis], 0.0)
        behind[:, axis] = below + above
    d = np.linalg.norm(behind, axis=1)
    for face in wall.open:
        axis, side = FACE_AXES[face]
        beyond = p[:, axis] > hi[axis] if side else p[:, axis] < lo[axis]
        d[beyond] = np.inf
    return d
