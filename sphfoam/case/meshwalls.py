"""Walls from mesh files (``particleDict`` wall entries of ``type mesh``), read with meshio.

A mesh gives the 2-D wall lines in one of three ways, turned into polylines whose solid lies
on their *right* (``side right``, as for a ``polyline`` wall):

* **line cells** (``line``, and the end nodes of ``line3``), e.g. a ``.vtk`` or Gmsh ``.msh``
  of line segments, projected on the (x, y) plane; the solid lies on the right of the cells'
  direction (each connected chain takes the direction most of its cells have);
* **a surface** (``triangle``, ``quad`` cells, the corner nodes of their higher-order forms,
  and convex ``polygon`` cells, split into fans of triangles),
  e.g. an STL, OBJ, VTK or Gmsh surface of a 3-D body: its section by the plane z = ``z``.
  Each face crossing the plane contributes the segment between the two points where its
  edges cut the plane, oriented so that the face's normal (right-hand rule on its vertex
  order: the outward normal of a closed STL/OBJ body) points to the segment's left, into the
  fluid; the solid lies behind the faces, on the right;
* **a flat surface** (every vertex at the same z), e.g. a 2-D Gmsh mesh of the solid's cross
  section: its boundary edges, the solid being the meshed region.

Consecutive collinear segments are merged, so a prism cut by the plane gives its few straight
sides, not one segment per facet.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

_LINE_CELLS = {"line": 2, "line3": 2}
_SURFACE_CELLS = {"triangle": 3, "triangle6": 3, "triangle7": 3,
                  "quad": 4, "quad8": 4, "quad9": 4}


class MeshWallError(ValueError):
    """A mesh file that cannot give wall segments; the message says why."""


def read_mesh_walls(path, z: float = 0.0, scale: float = 1.0,
                    translate=(0.0, 0.0)) -> list[list[tuple[float, float]]]:
    """Polylines (vertex lists, solid on the right) of the mesh file ``path``: its line
    cells, the section of its surface by the plane z = ``z`` (in file units), or the boundary
    of a flat surface; then scaled by ``scale`` and shifted by ``translate``."""
    mesh, pts, lines, faces = read_cells(path)
    extent = float(np.ptp(pts, axis=0).max()) or 1.0
    tol = 1e-9 * extent
    tris = _triangles(faces)
    if tris.size:
        zs = pts[np.unique(tris), 2]
        if np.ptp(zs) <= tol:
            segs = _boundary_edges(pts, tris)
        else:
            segs = _section(pts, tris, z)
            if not segs.size:
                raise MeshWallError(f"{path}: the surface does not cross the plane z = {z:g} "
                                    f"(its z range is {zs.min():g} .. {zs.max():g})")
        chains = _chain_directed(segs, tol)
    elif lines:
        e = np.concatenate(lines)
        segs = np.stack([pts[e[:, 0], :2], pts[e[:, 1], :2]], axis=1)
        chains = _chain_undirected(segs, tol)
    else:
        kinds = ", ".join(sorted({b.type for b in mesh.cells})) or "none"
        raise MeshWallError(f"{path}: no line cells and no triangles or quads (cells: {kinds})")
    out = []
    tx, ty = float(translate[0]), float(translate[1])
    for c in chains:
        c = _merge_collinear(c, tol)
        if len(c) >= 2:
            out.append([(float(scale * x + tx), float(scale * y + ty)) for x, y in c])
    if not out:
        raise MeshWallError(f"{path}: every wall segment has zero length")
    return out


def read_cells(path):
    """Read the mesh file ``path`` with meshio: (the meshio mesh, its points (n, 3), its line
    cells' end nodes [(m, 2)], its surface cells' corner nodes [(m, 3 or 4)], convex
    ``polygon`` cells split into fans of triangles). Raises MeshWallError with the reason."""
    import meshio

    path = Path(path)
    if not path.is_file():
        raise MeshWallError(f"{path}: file not found")
    try:
        with warnings.catch_warnings():         # meshio's STL format sniffing overflows
            warnings.simplefilter("ignore", RuntimeWarning)
            mesh = meshio.read(path)
    except Exception as e:          # meshio raises ReadError, KeyError, ValueError, ...
        msg = str(e).strip() or type(e).__name__
        raise MeshWallError(f"{path}: meshio cannot read it ({msg})") from None
    pts = np.asarray(mesh.points, dtype=float)
    if pts.ndim != 2 or pts.shape[0] == 0:
        raise MeshWallError(f"{path}: the mesh has no points")
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    lines, faces = [], []
    for block in mesh.cells:
        if block.type == "polygon":              # n-gons (OBJ, VTK): fans of triangles
            for f in (block.data if isinstance(block.data, list) else list(block.data)):
                f = np.asarray(f, dtype=np.int64)
                if f.size >= 3:
                    faces.append(np.column_stack([np.full(f.size - 2, f[0]), f[1:-1], f[2:]]))
            continue
        data = np.asarray(block.data, dtype=np.int64)
        if block.type in _LINE_CELLS and data.size:
            lines.append(data[:, :_LINE_CELLS[block.type]])
        elif block.type in _SURFACE_CELLS and data.size:
            faces.append(data[:, :_SURFACE_CELLS[block.type]])
    return mesh, pts, lines, faces


def _triangles(faces: list[np.ndarray]) -> np.ndarray:
    """Triangles of the surface cells, quads split along their 0-2 diagonal."""
    tris = []
    for f in faces:
        if f.shape[1] == 3:
            tris.append(f)
        else:
            tris += [f[:, [0, 1, 2]], f[:, [0, 2, 3]]]
    return np.concatenate(tris) if tris else np.zeros((0, 3), np.int64)


def _section(pts: np.ndarray, tris: np.ndarray, z0: float) -> np.ndarray:
    """Segments (n, 2, 2) where the triangles cross z = z0, the face normal on their left.

    A vertex on the plane counts as above it, so an edge lying in the plane comes from the
    one face below it and a face touching the plane at a vertex gives nothing."""
    P = pts[tris]                                    # (n, 3 vertices, xyz)
    above = P[:, :, 2] >= z0
    n_above = above.sum(axis=1)
    cut = (n_above == 1) | (n_above == 2)
    P, above, tris = P[cut], above[cut], tris[cut]
    if not len(P):
        return np.zeros((0, 2, 2))
    ends = []
    for a, b in ((0, 1), (1, 2), (2, 0)):           # the two edges whose ends differ
        # from the end with the lower vertex number, so that the two faces sharing an edge
        # compute the very same point, and exactly a vertex lying on the plane
        swap = (tris[:, a] > tris[:, b])[:, None]
        o = np.where(swap, P[:, b], P[:, a])
        e = np.where(swap, P[:, a], P[:, b])
        crosses = above[:, a] != above[:, b]
        t = np.where(crosses, (z0 - o[:, 2]) / np.where(crosses, e[:, 2] - o[:, 2], 1.0), 0.0)
        q = o[:, :2] + t[:, None] * (e[:, :2] - o[:, :2])
        q = np.where((t >= 1.0)[:, None], e[:, :2], np.where((t <= 0.0)[:, None], o[:, :2], q))
        ends.append((crosses, q))
    first = np.where(ends[0][0][:, None], ends[0][1], ends[1][1])
    second = np.where(ends[2][0][:, None], ends[2][1], ends[1][1])
    normal = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])[:, :2]
    d = second - first
    flip = (-d[:, 1] * normal[:, 0] + d[:, 0] * normal[:, 1]) < 0   # left normal . n < 0
    p0 = np.where(flip[:, None], second, first)
    p1 = np.where(flip[:, None], first, second)
    return np.stack([p0, p1], axis=1)


def _boundary_edges(pts: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Edges of a flat triangulation used by one triangle only, traversed clockwise around
    the meshed region (which therefore lies on their right)."""
    P = pts[tris][:, :, :2]
    u, v = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    t = np.where((area < 0)[:, None], tris[:, [0, 2, 1]], tris)      # all counter-clockwise
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    border = edges[count[inv.ravel()] == 1][:, ::-1]                  # reversed: clockwise
    return np.stack([pts[border[:, 0], :2], pts[border[:, 1], :2]], axis=1)


def _keys(segs: np.ndarray, tol: float) -> np.ndarray:
    return np.round(segs / tol).astype(np.int64)


def _chain_directed(segs: np.ndarray, tol: float) -> list[list[tuple[float, float]]]:
    """Join oriented segments end to start into polylines (closed loops repeat their start)."""
    k = _keys(segs, tol)
    keep = np.any(k[:, 0] != k[:, 1], axis=1)
    segs, k = segs[keep], k[keep]
    starts: dict[tuple, list[int]] = {}
    ends: set[tuple] = set()
    for i, (a, b) in enumerate(k):
        starts.setdefault(tuple(a), []).append(i)
        ends.add(tuple(b))
    used = np.zeros(len(segs), bool)
    order = sorted(range(len(segs)), key=lambda i: tuple(k[i, 0]) in ends)  # chain heads first
    chains = []
    for i0 in order:
        if used[i0]:
            continue
        used[i0] = True
        chain = [tuple(segs[i0, 0]), tuple(segs[i0, 1])]
        cur = tuple(k[i0, 1])
        while True:
            nxt = next((j for j in starts.get(cur, ()) if not used[j]), None)
            if nxt is None:
                break
            used[nxt] = True
            chain.append(tuple(segs[nxt, 1]))
            cur = tuple(k[nxt, 1])
        chains.append(chain)
    return chains


def _chain_undirected(segs: np.ndarray, tol: float) -> list[list[tuple[float, float]]]:
    """Join line cells sharing an end into polylines, whatever each cell's direction; a
    chain runs the way most of its cells do."""
    k = _keys(segs, tol)
    keep = np.any(k[:, 0] != k[:, 1], axis=1)
    segs, k = segs[keep], k[keep]
    at: dict[tuple, list[int]] = {}
    for i, (a, b) in enumerate(k):
        at.setdefault(tuple(a), []).append(i)
        at.setdefault(tuple(b), []).append(i)
    used = np.zeros(len(segs), bool)
    # open chains start at a vertex with one cell; what is left are loops
    heads = [i for i in range(len(segs))
             if len(at[tuple(k[i, 0])]) == 1 or len(at[tuple(k[i, 1])]) == 1] + \
        list(range(len(segs)))
    chains = []
    for i0 in heads:
        if used[i0]:
            continue
        used[i0] = True
        fwd = not (len(at[tuple(k[i0, 1])]) == 1 and len(at[tuple(k[i0, 0])]) != 1)
        a, b = (0, 1) if fwd else (1, 0)
        chain = [tuple(segs[i0, a]), tuple(segs[i0, b])]
        with_dir = int(fwd)
        cur = tuple(k[i0, b])
        while True:
            nxt = next((j for j in at.get(cur, ()) if not used[j]), None)
            if nxt is None:
                break
            used[nxt] = True
            forward = tuple(k[nxt, 0]) == cur
            chain.append(tuple(segs[nxt, 1 if forward else 0]))
            with_dir += int(forward)
            cur = tuple(k[nxt, 1 if forward else 0])
        if 2 * with_dir < len(chain) - 1:
            chain.reverse()
        chains.append(chain)
    return chains


def _merge_collinear(chain, tol: float):
    """Drop the vertices where a polyline goes straight on."""
    out = [chain[0]]
    for j in range(1, len(chain) - 1):
        a, b, c = np.asarray(out[-1]), np.asarray(chain[j]), np.asarray(chain[j + 1])
        u, v = b - a, c - b
        if np.hypot(*u) <= tol:
            continue
        cross = u[0] * v[1] - u[1] * v[0]
        if abs(cross) <= 1e-9 * np.hypot(*u) * np.hypot(*v) and u @ v > 0:
            continue
        out.append(chain[j])
    if np.hypot(*(np.asarray(chain[-1]) - np.asarray(out[-1]))) > tol or len(out) == 1:
        out.append(chain[-1])
    closed = len(out) > 3 and np.allclose(out[0], out[-1], atol=tol, rtol=0)
    if closed:                          # the start of a loop may be a straight-through vertex
        a, b, c = np.asarray(out[-2]), np.asarray(out[0]), np.asarray(out[1])
        u, v = b - a, c - b
        if abs(u[0] * v[1] - u[1] * v[0]) <= 1e-9 * np.hypot(*u) * np.hypot(*v) and u @ v > 0:
            out = out[1:-1] + [out[1]]
    return out
