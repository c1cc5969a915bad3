"""Surface meshes in three dimensions (``system/particleDict`` ``dimension 3``): a ``mesh``
fluid region (the lattice sites inside a closed surface) and ``mesh`` walls (a closed
surface: a solid with ``layers`` of wall particles inside it; an open surface, such as a
terrain or a sheet of sea wall: layers behind its faces, on the side opposite their
normals). The file is read with meshio (STL, OBJ, VTK, Gmsh, ... : triangles, quads and
convex polygons, sphfoam.case.meshwalls.read_cells), scaled by ``scale`` and shifted by
``translate``; the set-up then uses it as any other shape of sphfoam.case.solids, through
its signed distance (negative inside the solid) and its bounding box.

Which library: **VTK** (a dependency already, for the VTK export), not one written here and
not trimesh (which would be a new dependency for what VTK does in C++ over whole arrays):

* the distance to the surface is ``vtkImplicitPolyDataDistance`` (a cell locator and the
  exact point-to-triangle distance), evaluated for all points in one call of its
  ``FunctionValue(array, array)``;
* inside a *closed* surface is ``vtkSelectEnclosedPoints`` (ray casting with parity, voted
  over several rays), run as a filter on all points at once; it needs no orientation of the
  faces, so an STL whose normals point inwards still gives the solid it encloses;
* behind an *open* surface is the sign of ``vtkImplicitPolyDataDistance``: negative on the
  side opposite the faces' normals (right-hand rule on each face's vertex order). The faces
  must therefore be consistently oriented, which is checked. The solid of an open sheet is
  its shadow: the points behind it whose nearest point of the surface is not on its rim
  (the distance to the rim edges is numpy's, over whole arrays); a point nearest the rim
  lies beside the sheet, not behind it, so a sheet should reach to the tank's walls or
  past the fluid (a terrain under the whole basin) to keep water from behind it.

Checks, each a MeshWallError naming the file (the case reports it under the entry's
``file`` key): the file exists and meshio reads it, it has triangles (or quads or
polygons) of non-zero area, a surface that must be closed (a fluid region) is closed, an
edge is shared by at most two faces, and an open surface is consistently oriented.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sphfoam.case.meshwalls import MeshWallError, _triangles, read_cells

__all__ = ["Surface", "read_surface"]


class Surface:
    """A triangulated surface in case coordinates (m), with the VTK objects that measure
    the distance to it and find the points it encloses."""

    def __init__(self, path: Path, points: np.ndarray, tris: np.ndarray):
        self.path = path
        self.points = points
        self.tris = tris
        edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]),
                        axis=1)
        edges, count = np.unique(edges, axis=0, return_counts=True)
        #: the rim (edges of one face only) as segments (m, 2, 3)
        self.rim = points[edges[count == 1]]
        #: edges of one face only (an open surface's rim), and of more than two faces
        self.open_edges = int((count == 1).sum())
        self.nonmanifold_edges = int((count > 2).sum())
        self.closed = self.open_edges == 0 and self.nonmanifold_edges == 0
        directed = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
        #: every edge of two faces runs one way in one and the other way in the other
        self.oriented = len(np.unique(directed, axis=0)) == len(directed)
        self.lo = points[np.unique(tris)].min(axis=0)
        self.hi = points[np.unique(tris)].max(axis=0)
        self._poly = _polydata(points, tris)
        self._distance = None

    def __repr__(self) -> str:
        return (f"Surface({self.path.name}: {len(self.tris)} triangles, "
                f"{'closed' if self.closed else 'open'})")

    @property
    def volume(self) -> float:
        """The enclosed volume (m^3, closed surfaces; its magnitude whatever the faces'
        orientation)."""
        P = self.points[self.tris]
        return abs(float(np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum())) / 6

    def distance(self, p: np.ndarray) -> np.ndarray:
        """vtkImplicitPolyDataDistance at the points ``p`` (n, 3): the distance to the
        surface, negative behind the faces (opposite their normals)."""
        from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
        from vtkmodules.vtkCommonCore import vtkDoubleArray
        from vtkmodules.vtkFiltersCore import vtkImplicitPolyDataDistance

        p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 3)
        if len(p) == 0:
            return np.zeros(0)
        if self._distance is None:
            self._distance = vtkImplicitPolyDataDistance()
            self._distance.SetInput(self._poly)
        out = vtkDoubleArray()
        self._distance.FunctionValue(numpy_to_vtk(p, deep=True), out)
        return vtk_to_numpy(out).astype(np.float64).copy()

    def inside(self, p: np.ndarray) -> np.ndarray:
        """Whether each point ``p`` (n, 3) lies inside the closed surface
        (vtkSelectEnclosedPoints: ray parity, independent of the faces' orientation)."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkCommonDataModel import vtkPolyData
        from vtkmodules.vtkFiltersModeling import vtkSelectEnclosedPoints

        if not self.closed:
            raise ValueError(f"{self.path}: inside of an open surface")
        p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 3)
        if len(p) == 0:
            return np.zeros(0, bool)
        cloud = vtkPolyData()
        cloud.SetPoints(_vtk_points(p))
        sel = vtkSelectEnclosedPoints()
        sel.SetInputData(cloud)
        sel.SetSurfaceData(self._poly)
        sel.CheckSurfaceOff()              # checked here already (closed, manifold)
        sel.SetTolerance(1e-9)             # of the surface's bounding box diagonal
        sel.Update()
        return vtk_to_numpy(sel.GetOutput().GetPointData().GetArray("SelectedPoints")) != 0

    def signed_distance(self, p: np.ndarray) -> np.ndarray:
        """Distance of the points ``p`` (n, 3) to the surface, negative in the solid: inside a
        closed surface, behind the faces of an open one."""
        d = self.distance(p)
        if self.closed:
            return np.where(self.inside(p), -np.abs(d), np.abs(d))
        # behind an open sheet: its shadow, the points whose nearest point of the surface is
        # inside it, not on its rim (a point nearest the rim is beside the sheet)
        behind = d < 0
        if behind.any() and len(self.rim):
            q = np.asarray(p, float).reshape(-1, 3)[behind]
            extent = float(np.linalg.norm(self.hi - self.lo)) or 1.0
            beside = self.rim_distance(q) <= np.abs(d[behind]) * (1 + 1e-9) + 1e-12 * extent
            behind[np.flatnonzero(behind)[beside]] = False
        return np.where(behind, d, np.abs(d))

    def rim_distance(self, p: np.ndarray) -> np.ndarray:
        """Distance of the points ``p`` (n, 3) to the rim of an open surface (numpy, whole
        arrays: a block of rim edges against all points at a time)."""
        best = np.full(len(p), np.inf)
        a, b = self.rim[:, 0], self.rim[:, 1]
        ab = b - a
        L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
        step = max(1, int(4e6 // max(len(p), 1)))
        for k in range(0, len(a), step):
            rel = p[:, None, :] - a[None, k:k + step]                       # (n, m, 3)
            t = np.clip(np.einsum("nmj,mj->nm", rel, ab[k:k + step]) / L2[k:k + step], 0, 1)
            gap = rel - t[:, :, None] * ab[None, k:k + step]
            best = np.minimum(best, np.sqrt(np.einsum("nmj,nmj->nm", gap, gap)).min(axis=1))
        return best


def _vtk_points(p: np.ndarray):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints

    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(p, dtype=np.float64), deep=True))
    return pts


def _polydata(points: np.ndarray, tris: np.ndarray):
    from vtkmodules.util.numpy_support import numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    poly = vtkPolyData()
    poly.SetPoints(_vtk_points(points))
    cells = vtkCellArray()
    offsets = np.arange(0, 3 * len(tris) + 1, 3, dtype=np.int64)
    cells.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True),
                  numpy_to_vtkIdTypeArray(tris.astype(np.int64).ravel(), deep=True))
    poly.SetPolys(cells)
    return poly


def read_surface(path, scale: float = 1.0, translate=(0.0, 0.0, 0.0),
                 closed: bool = False) -> Surface:
    """The triangulated surface of the mesh file ``path`` (its triangles, quads split along
    a diagonal, polygons as fans), its points scaled by ``scale`` and shifted by
    ``translate``; coincident points (an STL's repeated corners) are merged. ``closed``:
    the surface must be closed (a fluid region). Raises MeshWallError with the reason."""
    path = Path(path)
    mesh, pts, _, faces = read_cells(path)
    tris = _triangles(faces)
    if not tris.size:
        kinds = ", ".join(sorted({b.type for b in mesh.cells})) or "none"
        raise MeshWallError(f"{path}: no triangles, quads or polygons: a 3-D mesh shape is "
                            f"a surface (cells: {kinds})")
    if tris.max() >= len(pts) or tris.min() < 0:
        raise MeshWallError(f"{path}: faces refer to points the file does not have")
    pts = scale * pts + np.asarray(translate, float).reshape(1, 3)
    extent = float(np.ptp(pts[np.unique(tris)], axis=0).max())
    tol = 1e-9 * (extent or 1.0)
    key = np.round(pts / tol).astype(np.int64)          # merge coincident points
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    pts, tris = pts[first], inverse.ravel()[tris]
    distinct = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & \
        (tris[:, 2] != tris[:, 0])
    tris = tris[distinct]
    P = pts[tris]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    if not len(tris) or area.sum() <= tol * tol:
        raise MeshWallError(f"{path}: every face has zero area")
    s = Surface(path, pts, tris)
    if s.nonmanifold_edges:
        raise MeshWallError(f"{path}: {s.nonmanifold_edges} edge(s) belong to more than two "
                            "faces (a non-manifold surface has no inside and no behind)")
    if closed and not s.closed:
        raise MeshWallError(f"{path}: the surface is not closed ({s.open_edges} edge(s) "
                            "belong to one face only): a mesh fluid region is the inside of "
                            "a closed surface")
    if not s.closed and not s.oriented:
        raise MeshWallError(f"{path}: an open surface whose faces are not consistently "
                            "oriented: the solid lies behind its faces (opposite their "
                            "normals), so every face must wind the same way")
    if s.closed and s.volume <= tol ** 3:
        raise MeshWallError(f"{path}: the closed surface encloses no volume")
    return s
