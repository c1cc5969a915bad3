"""Walls from mesh files (particleDict `type mesh`, read with meshio): the segments against the
known geometry, the same particles as the equivalent polyline wall, and clear errors."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.case.geometry import segments_of
from sphfoam.case.meshwalls import MeshWallError, read_mesh_walls


def box_mesh(x0, x1, y0, y1, z0, z1):
    """The six faces of a box as quads, vertices counter-clockwise seen from outside."""
    V = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], float)

    def i(a, b, c):
        return 4 * a + 2 * b + c

    Q = np.array([[i(0, 0, 0), i(0, 0, 1), i(0, 1, 1), i(0, 1, 0)],
                  [i(1, 0, 0), i(1, 1, 0), i(1, 1, 1), i(1, 0, 1)],
                  [i(0, 0, 0), i(1, 0, 0), i(1, 0, 1), i(0, 0, 1)],
                  [i(0, 1, 0), i(0, 1, 1), i(1, 1, 1), i(1, 1, 0)],
                  [i(0, 0, 0), i(0, 1, 0), i(1, 1, 0), i(1, 0, 0)],
                  [i(0, 0, 1), i(1, 0, 1), i(1, 1, 1), i(0, 1, 1)]])
    return V, Q


def signed_area(loop):
    p = np.asarray(loop)
    return 0.5 * np.sum(p[:-1, 0] * p[1:, 1] - p[1:, 0] * p[:-1, 1])


def test_stl_box_section_is_the_rectangle_clockwise(tmp_path):
    """A closed box (STL triangles, outward normals) cut at z = 0: one closed loop, the four
    corners, traversed clockwise so the solid (inside) lies on its right."""
    V, Q = box_mesh(1.0, 2.0, 0.2, 0.5, -1.0, 1.0)
    tris = np.concatenate([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])
    f = tmp_path / "box.stl"
    meshio.write(f, meshio.Mesh(V, [("triangle", tris)]))
    (loop,) = read_mesh_walls(f)
    assert len(loop) == 5 and np.allclose(loop[0], loop[-1])
    assert {tuple(np.round(p, 12)) for p in loop} == {(1, .2), (1, .5), (2, .5), (2, .2)}
    assert signed_area(loop) == pytest.approx(-0.3, rel=1e-12)      # clockwise, area 0.3


def test_faceted_cylinder_gives_one_closed_loop_on_the_circle(tmp_path):
    """A cylinder of 64 facets, radius 0.3 about (1, 0.5), in a binary STL (triangles only,
    caps as fans): one loop through the 64 vertices, all on the circle, clockwise, enclosing
    the polygon's area."""
    n, r = 64, 0.3
    ang = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([1 + r * np.cos(ang), 0.5 + r * np.sin(ang)])
    V = np.vstack([np.column_stack([ring, np.full(n, z)]) for z in (-0.5, 0.5)]
                  + [[[1, 0.5, -0.5], [1, 0.5, 0.5]]])
    k = np.arange(n)
    k1 = (k + 1) % n
    tris = np.concatenate([np.column_stack([k, k1, n + k1]), np.column_stack([k, n + k1, n + k]),
                           np.column_stack([np.full(n, 2 * n), k1, k]),
                           np.column_stack([np.full(n, 2 * n + 1), n + k, n + k1])])
    f = tmp_path / "cylinder.stl"
    meshio.write(f, meshio.Mesh(V, [("triangle", tris)]), binary=True)
    (loop,) = read_mesh_walls(f)
    p = np.asarray(loop)
    assert len(loop) == n + 1 and np.allclose(p[0], p[-1])
    assert np.allclose(np.hypot(p[:, 0] - 1, p[:, 1] - 0.5), r, atol=1e-6)  # float32 STL
    assert signed_area(loop) == pytest.approx(-0.5 * n * r * r * np.sin(2 * np.pi / n),
                                              rel=1e-5)


def test_obj_quads_tilted_plane_scale_and_translate(tmp_path):
    """The box tilted about the y axis and cut at z = 0.25 (file units): the section of the
    faces x = x0 + z tan(a); then scale 0.001 (a file in mm) and a shift."""
    V, Q = box_mesh(1000.0, 2000.0, 0.0, 500.0, -1000.0, 1000.0)
    a = 0.3
    V = V.copy()
    V[:, 0] += V[:, 2] * np.tan(a)
    f = tmp_path / "box.obj"
    meshio.write(f, meshio.Mesh(V, [("quad", Q)]))
    (loop,) = read_mesh_walls(f, z=250.0, scale=1e-3, translate=(0.5, -0.1))
    xs = 1e-3 * (np.array([1000.0, 2000.0]) + 250.0 * np.tan(a)) + 0.5
    want = {(round(x, 9), round(y, 9)) for x in xs for y in (-0.1, 0.4)}
    assert {(round(p[0], 9), round(p[1], 9)) for p in loop} == want
    assert signed_area(loop) < 0


def _outward(V, faces):
    """Each face's vertex order reversed where its normal points towards the origin."""
    out = []
    for f in faces:
        P = V[list(f)]
        n = np.cross(P[1] - P[0], P[2] - P[0])
        out.append(list(f) if n @ P.mean(axis=0) > 0 else list(f)[::-1])
    return np.array(out)


def test_obj_polygon_faces(tmp_path):
    """A hexagonal prism along y (OBJ: hexagon caps at y = -1, 1 as `polygon` cells, quad
    sides, outward normals) cut by z = 0 through two of its vertices: the rectangle
    |x| <= 1, |y| <= 1, its short sides from the caps, clockwise."""
    ang = np.radians(60.0 * np.arange(6))
    V = np.vstack([np.column_stack([np.cos(ang), np.full(6, y), np.sin(ang)])
                   for y in (-1.0, 1.0)])
    sides = _outward(V, [[k, (k + 1) % 6, 6 + (k + 1) % 6, 6 + k] for k in range(6)])
    caps = _outward(V, [list(range(6)), list(range(6, 12))])
    f = tmp_path / "hex.obj"
    meshio.write(f, meshio.Mesh(V, [("quad", sides), ("polygon", caps)]))
    assert [c.type for c in meshio.read(f).cells] == ["quad", "polygon"]
    (loop,) = read_mesh_walls(f)
    assert len(loop) == 5
    assert {tuple(np.round(p, 9)) for p in loop} == {(-1, -1), (-1, 1), (1, 1), (1, -1)}
    assert signed_area(loop) == pytest.approx(-4.0)


def test_line_cells_chain_merge_and_orientation(tmp_path):
    """Line cells (VTK): one reversed cell is joined into the chain, which runs the way most
    cells do; collinear cells merge into one segment."""
    P = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 1, 0], [5, 1, 0]], float)
    cells = np.array([[0, 1], [2, 1], [2, 3], [3, 4]])       # the second cell is reversed
    f = tmp_path / "bed.vtk"
    meshio.write(f, meshio.Mesh(P, [("line", cells)]))
    (line,) = read_mesh_walls(f)
    assert np.allclose(line, [(0, 0), (2, 0), (3, 1), (5, 1)])


def test_flat_gmsh_mesh_gives_its_boundary(tmp_path):
    """A 2-D Gmsh mesh of the solid (four triangles of a unit square, mixed orientation):
    its boundary, clockwise (the meshed region on the right)."""
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    T = np.array([[0, 1, 4], [1, 2, 4], [3, 2, 4], [3, 4, 0]])   # two of them clockwise
    f = tmp_path / "solid.msh"
    meshio.write(f, meshio.Mesh(P, [("triangle", T)]), file_format="gmsh22")
    (loop,) = read_mesh_walls(f)
    assert len(loop) == 5
    assert {tuple(p) for p in loop} == {(0, 0), (1, 0), (1, 1), (0, 1)}
    assert signed_area(loop) == pytest.approx(-1.0)


def test_mesh_wall_gives_the_particles_of_the_same_polyline(tutorial):
    """tutorials/damBreakObstacle's block from its OBJ file: the segments and the set-up
    particles (every boundary model places and labels wall particles from the segments) are
    those of the equivalent `polyline` wall."""
    from sphfoam.setup import setup_case

    edits = {"system/particleDict:dx": 0.02}
    mesh_case = tutorial("damBreakObstacle", edits)
    poly = tutorial("damBreak", {**edits, "system/particleDict:walls.obstacle": {
        "type": "polyline", "points": [[0.6, 0.0], [0.6, 0.06], [0.7, 0.06], [0.7, 0.0]],
        "side": "right", "layers": 3}})
    cm, cp = Case(mesh_case), Case(poly)
    sm, sp = segments_of(cm.particles), segments_of(cp.particles)
    assert np.allclose([(*s.p0, *s.p1, *s.normal) for s in sm],
                       [(*s.p0, *s.p1, *s.normal) for s in sp], atol=1e-12, rtol=0)
    assert sm[-3].normal == pytest.approx((-1.0, 0.0))           # upstream face: into the water
    a, b = setup_case(cm, log=lambda m: None), setup_case(cp, log=lambda m: None)
    assert a.n == b.n and a.n_fluid == b.n_fluid
    for k in ("x", "y", "rho"):
        assert np.allclose(getattr(a, k), getattr(b, k), atol=1e-12)
    for k in b.extra:
        assert np.allclose(a.extra[k], b.extra[k], atol=1e-12), k
    # no fluid particle inside the block
    f = a.kind == 0
    assert not np.any((a.x[f] > 0.6) & (a.x[f] < 0.7) & (a.y[f] < 0.06))


def _mesh_case(tutorial, **entry):
    return tutorial("damBreakObstacle", {f"system/particleDict:walls.obstacle.{k}": v
                                         for k, v in entry.items()})


def _problem(case) -> str:
    with pytest.raises(CaseError) as e:
        Case(case).validate()
    return str(e.value)


def test_missing_unreadable_empty_and_uncut_meshes_are_clear_errors(tutorial, tmp_path):
    with pytest.raises(MeshWallError, match="file not found"):
        read_mesh_walls(tmp_path / "none.stl")
    key = "system/particleDict: walls.obstacle.file"
    msg = _problem(_mesh_case(tutorial, file="constant/geometry/nothere.stl"))
    assert key in msg and "nothere.stl: file not found" in msg

    case = _mesh_case(tutorial, file="constant/geometry/broken.stl")
    (case / "constant/geometry/broken.stl").write_text("solid x\n  facet normal what\n")
    msg = _problem(case)
    assert key in msg and "meshio cannot read it" in msg

    case = _mesh_case(tutorial, file="constant/geometry/points.vtk")
    meshio.write(case / "constant/geometry/points.vtk",
                 meshio.Mesh(np.zeros((3, 3)), [("vertex", np.array([[0], [1], [2]]))]))
    msg = _problem(case)
    assert key in msg and "no line cells and no triangles or quads" in msg

    case = _mesh_case(tutorial, z=1.0)
    msg = _problem(case)
    assert key in msg and "does not cross the plane z = 1" in msg and "-0.05 .. 0.05" in msg

    case = _mesh_case(tutorial, type="mesh", side="up")
    assert "walls.obstacle" in _problem(case)


def test_cli_check_reports_a_missing_mesh_on_one_screen(tutorial):
    from typer.testing import CliRunner

    from sphfoam.cli import app

    case = _mesh_case(tutorial, file="constant/geometry/nothere.stl")
    r = CliRunner().invoke(app, ["check", str(case)])
    assert r.exit_code != 0 and "Traceback" not in r.output
    assert "walls.obstacle.file" in r.output
