"""Surface meshes in 3-D (particleDict `dimension 3;`, `type mesh`; sphfoam.case.meshsolids):
a closed mesh filled with fluid, a closed mesh as a solid (its wall layers inside it, the
fluid outside), an open sheet (layers behind its faces), a closed mesh as a container
(`side left`), scale and translate, the file formats, and clear errors naming file and key.
Meshes are written with meshio into a temporary case."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import meshio
import numpy as np
import pytest

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.case.meshsolids import read_surface
from sphfoam.case.meshwalls import MeshWallError
from sphfoam.case.solids import signed_distance
from sphfoam.setup.initial import generate_case

TANK3D = Path(__file__).resolve().parent.parent / "tutorials" / "hydrostaticTank3D"
DX = 0.02


def box_mesh(lo, hi):
    """The six faces of a box as triangles, wound counter-clockwise seen from outside."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    V = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], float)

    def i(a, b, c):
        return 4 * a + 2 * b + c

    Q = np.array([[i(0, 0, 0), i(0, 0, 1), i(0, 1, 1), i(0, 1, 0)],
                  [i(1, 0, 0), i(1, 1, 0), i(1, 1, 1), i(1, 0, 1)],
                  [i(0, 0, 0), i(1, 0, 0), i(1, 0, 1), i(0, 0, 1)],
                  [i(0, 1, 0), i(0, 1, 1), i(1, 1, 1), i(1, 1, 0)],
                  [i(0, 0, 0), i(0, 1, 0), i(1, 1, 0), i(1, 0, 0)],
                  [i(0, 0, 1), i(1, 0, 1), i(1, 1, 1), i(0, 1, 1)]])
    return V, np.concatenate([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])


def sphere_mesh(centre, radius, n=40):
    """A UV sphere: n rings of 2n segments, triangles wound counter-clockwise seen from
    outside (the outward normal)."""
    th = np.linspace(0, np.pi, n + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.column_stack([np.sin(T).ravel() * np.cos(P).ravel(),
                            np.sin(T).ravel() * np.sin(P).ravel(), np.cos(T).ravel()])
    V = np.vstack([[0, 0, 1], ring, [0, 0, -1]]) * radius + np.asarray(centre, float)
    m = 2 * n
    top, bottom = 0, len(V) - 1

    def r(i, j):
        return 1 + i * m + j % m

    tris = [[top, r(0, j), r(0, j + 1)] for j in range(m)]
    for i in range(n - 2):
        for j in range(m):
            tris += [[r(i, j), r(i + 1, j), r(i + 1, j + 1)],
                     [r(i, j), r(i + 1, j + 1), r(i, j + 1)]]
    tris += [[bottom, r(n - 2, j + 1), r(n - 2, j)] for j in range(m)]
    return V, np.array(tris)


def write(path: Path, V, T, cell="triangle", **kw) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    meshio.write(path, meshio.Mesh(V, [(cell, T)]), **kw)


def case_with(tmp_path, body: str, name="case") -> Path:
    case = tmp_path / name
    shutil.copytree(TANK3D, case, ignore=lambda folder, names: {
        n for n in names if re.fullmatch(r"[0-9.e+-]+", n) or n in (
            "VTK", "postProcessing", "polyMesh") or n.endswith(".foam")})
    pd = case / "system" / "particleDict"
    pd.write_text(pd.read_text().split("// * * * *")[0] + "// * * * * //\n" + body)
    return case


def test_a_closed_surface_is_oriented_closed_and_measured(tmp_path):
    V, T = sphere_mesh((0.4, 0.2, 0.2), 0.1)
    write(tmp_path / "ball.stl", V, T)
    s = read_surface(tmp_path / "ball.stl")
    assert s.closed and s.oriented and s.open_edges == 0
    assert s.volume == pytest.approx(4 / 3 * np.pi * 0.1 ** 3, rel=0.01)
    p = np.array([[0.4, 0.2, 0.2], [0.4, 0.2, 0.35], [0.45, 0.2, 0.2], [0.4, 0.2, 0.301]])
    d = s.signed_distance(p)
    np.testing.assert_allclose(d, [-0.1, 0.05, -0.05, 0.001], atol=2e-3)
    # an STL whose normals point inwards encloses the same solid
    write(tmp_path / "inward.stl", V, T[:, ::-1])
    np.testing.assert_allclose(read_surface(tmp_path / "inward.stl").signed_distance(p), d,
                               atol=1e-12)
    # scale and translate (a file in mm)
    write(tmp_path / "mm.stl", (V - [0.4, 0.2, 0.2]) * 1000, T)
    s2 = read_surface(tmp_path / "mm.stl", scale=0.001, translate=(0.4, 0.2, 0.2))
    np.testing.assert_allclose(s2.signed_distance(p), d, atol=1e-9)
    np.testing.assert_allclose(s2.lo, [0.3, 0.1, 0.1], atol=1e-9)


@pytest.mark.parametrize("shape", ["cube", "sphere"])
def test_a_mesh_fluid_region_holds_its_volume_over_dx_cubed(tmp_path, shape):
    case = case_with(tmp_path, f"""dimension 3; dx {DX};
fluid {{ water {{ type mesh; file "constant/geometry/water.stl"; }} }}
walls {{ tank {{ type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }} }}
""")
    if shape == "cube":      # 12 dx a side, off the lattice's planes: 12 sites a side
        lo = np.array([0.113, 0.051, 0.007])
        hi = lo + 12 * DX
        V, T = box_mesh(lo, hi)
        vol = float(np.prod(hi - lo))
    else:
        V, T = sphere_mesh((0.4, 0.2, 0.2), 0.15)
        vol = 4 / 3 * np.pi * 0.15 ** 3
    write(case / "constant" / "geometry" / "water.stl", V, T)
    c = Case(case)
    st = generate_case(c)
    fluid = st.kind == 0
    assert fluid.sum() == pytest.approx(vol / DX ** 3, rel=0.03)
    pts = np.column_stack(st.positions)[fluid]
    assert (signed_distance(c.particles.fluid["water"], pts) < 0).all()
    # hydrostatic from the top of each column, as any region
    assert st.z[fluid].max() < V[:, 2].max()


def test_a_closed_mesh_solid_takes_its_layers_and_pushes_the_fluid_out(tmp_path):
    case = case_with(tmp_path, f"""dimension 3; dx {DX};
fluid {{ water {{ type box; min (0 0 0); max (0.8 0.4 0.3); }} }}
walls
{{
    tank {{ type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }}
    ball {{ type mesh; file "constant/geometry/ball.obj"; layers 2; }}
    post {{ type mesh; file "constant/geometry/post.stl"; scale 0.001;
            translate (0.6 0.1 0); }}
}}
""")
    V, T = sphere_mesh((0.3, 0.2, 0.2), 0.1)
    write(case / "constant" / "geometry" / "ball.obj", V, T)
    V, T = box_mesh((0, 0, 0), (100, 100, 400))
    write(case / "constant" / "geometry" / "post.stl", V, T, binary=True)
    c = Case(case)
    st = generate_case(c)
    pts = np.column_stack(st.positions)
    fluid = st.kind == 0
    for name, r_in in (("ball", 0.1 - 2 * DX), ("post", None)):
        w = c.particles.walls[name]
        d = signed_distance(w, pts)
        own = (d < 0) & ~fluid
        assert -d[own].min() <= w.layers * DX * (1 + 1e-6), name      # within layers dx
        assert -d[own].max() < 0.5 * DX, name                        # from the surface in
        assert d[fluid].min() >= 0.5 * DX * (1 - 1e-6), name          # fluid dx/2 outside
        if r_in is not None:        # the ball's shell: the lattice sites 0.06 .. 0.1 out
            shell = 4 / 3 * np.pi * (0.1 ** 3 - r_in ** 3) / DX ** 3
            assert own.sum() == pytest.approx(shell, rel=0.05)
    post = signed_distance(c.particles.walls["post"], pts)
    assert ((post < 0) & ~fluid & (pts[:, 0] > 0.6) & (pts[:, 0] < 0.7)).sum() > 0
    assert not ((post < -3 * DX * (1 + 1e-6)) & ~fluid).any()   # hollow: 3 layers only
    # the volumes the solids took out of the box of water, within a layer
    water = 0.8 * 0.4 * 0.3 / DX ** 3
    taken = (4 / 3 * np.pi * 0.1 ** 3 + 0.1 * 0.1 * 0.3) / DX ** 3
    assert water - taken * 1.3 < fluid.sum() < water - taken * 0.9


def test_an_open_sheet_has_its_layers_behind_its_faces(tmp_path):
    """A sloping terrain sheet across the whole tank, normals up: the wall layers below it,
    the fluid above it; `side left` puts them on the other side."""
    x = np.linspace(-0.1, 0.9, 11)
    y = np.linspace(-0.1, 0.5, 7)
    X, Y = np.meshgrid(x, y, indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), 0.05 + 0.1 * X.ravel()])
    k = lambda i, j: i * len(y) + j         # noqa: E731
    T = np.array([t for i in range(len(x) - 1) for j in range(len(y) - 1)
                  for t in ([k(i, j), k(i + 1, j), k(i + 1, j + 1)],
                            [k(i, j), k(i + 1, j + 1), k(i, j + 1)])])
    body = f"""dimension 3; dx {DX};
fluid {{ water {{ type box; min (0 0 0); max (0.8 0.4 0.3); }} }}
walls
{{
    tank {{ type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }}
    bed {{ type mesh; file "constant/geometry/bed.vtk"; layers 3; SIDE }}
}}
"""
    case = case_with(tmp_path, body.replace("SIDE", ""))
    write(case / "constant" / "geometry" / "bed.vtk", V, T)
    c = Case(case)
    bed = c.particles.walls["bed"]
    assert not bed.surface.closed and bed.surface.oriented
    st = generate_case(c)
    pts = np.column_stack(st.positions)
    fluid = st.kind == 0
    height = pts[:, 2] - (0.05 + 0.1 * pts[:, 0])     # above the sheet
    assert (height[fluid] >= 0.5 * DX * np.cos(np.arctan(0.1)) * (1 - 1e-6)).all()
    own = ~fluid & (height < 0) & (pts[:, 2] > 0) & (pts[:, 0] > 0) & (pts[:, 0] < 0.8) \
        & (pts[:, 1] > 0) & (pts[:, 1] < 0.4)
    depth = -height[own] * np.cos(np.arctan(0.1))    # normal distance below the sheet
    assert own.sum() > 0 and depth.max() <= 3 * DX * (1 + 1e-6)
    d = signed_distance(bed, pts[own])
    np.testing.assert_allclose(d, -depth, atol=1e-9)
    # side left: the solid in front of the faces, so no water above the sheet at all
    case2 = case_with(tmp_path, body.replace("SIDE", "side left;"), "left")
    write(case2 / "constant" / "geometry" / "bed.vtk", V, T)
    st2 = generate_case(Case(case2))
    p2 = np.column_stack(st2.positions)
    h2 = p2[:, 2] - (0.05 + 0.1 * p2[:, 0])
    assert (h2[st2.kind == 0] <= -0.5 * DX * np.cos(np.arctan(0.1)) * (1 - 1e-6)).all()
    assert (st2.kind == 0).sum() > 0


def test_an_open_patch_removes_only_its_shadow(tmp_path):
    """A square sheet, normal up, inside the water (a shelf): the fluid goes from the column
    below it (its shadow) and stays beside it, where the nearest point is its rim."""
    V = np.array([[0.3, 0.1, 0.15], [0.5, 0.1, 0.15], [0.5, 0.3, 0.15], [0.3, 0.3, 0.15]])
    T = np.array([[0, 1, 2], [0, 2, 3]])
    case = case_with(tmp_path, f"""dimension 3; dx {DX};
fluid {{ water {{ type box; min (0 0 0); max (0.8 0.4 0.3); }} }}
walls {{ tank {{ type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }}
        shelf {{ type mesh; file "constant/geometry/shelf.ply"; layers 2; }} }}
""")
    write(case / "constant" / "geometry" / "shelf.ply", V, T)
    st = generate_case(Case(case))
    pts = np.column_stack(st.positions)
    fluid = st.kind == 0
    under = (np.abs(pts[:, 0] - 0.4) < 0.1) & (np.abs(pts[:, 1] - 0.2) < 0.1)
    assert not (fluid & under & (pts[:, 2] < 0.15)).any()          # the shadow: no water
    assert (fluid & under & (pts[:, 2] > 0.16)).sum() == 10 * 10 * 7
    shelf = ~fluid & under & (pts[:, 2] < 0.15) & (pts[:, 2] > 0.15 - 2 * DX - 1e-9)
    assert shelf.sum() == 10 * 10 * 2                               # its 2 layers
    # all else stays water: 10 x 10 sites go from 8 rows, the 7 below the sheet and the one
    # on it (closer than dx/2)
    assert fluid.sum() == 40 * 20 * 15 - 10 * 10 * 8


def test_a_closed_mesh_with_side_left_is_a_container(tmp_path):
    case = case_with(tmp_path, f"""dimension 3; dx {DX};
fluid {{ water {{ type box; min (0 0 0); max (0.2 0.2 0.1); }} }}
walls {{ tank {{ type mesh; file "constant/geometry/tank.msh"; side left; layers 2; }} }}
""")
    V, T = box_mesh((0, 0, 0), (0.2, 0.2, 0.3))
    write(case / "constant" / "geometry" / "tank.msh", V, T, file_format="gmsh22")
    st = generate_case(Case(case))
    fluid = st.kind == 0
    assert fluid.sum() == 10 * 10 * 5
    # 2 layers outside all six sides of the closed box: 14 x 14 x 19 - 10 x 10 x 15 sites,
    # less those farther than 2 dx from it: at the 12 edges the site (1.5 1.5) dx out of
    # each 2 x 2 cross-section (4 (10 + 10 + 15)), at the 8 corners 4 of each 2 x 2 x 2
    assert (~fluid).sum() == 14 * 14 * 19 - 10 * 10 * 15 - 4 * (10 + 10 + 15) - 8 * 4
    pts = np.column_stack(st.positions)[~fluid]
    assert (np.abs(pts - [0.1, 0.1, 0.15]) > [0.1, 0.1, 0.15]).any(axis=1).all()


def test_bad_meshes_are_case_errors_naming_file_and_key(tmp_path):
    body = f"""dimension 3; dx {DX};
fluid {{ water {{ type box; min (0 0 0); max (0.4 0.4 0.3); }}
        blob {{ type mesh; file "constant/geometry/FLUID"; }} }}
walls {{ tank {{ type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }}
        rock {{ type mesh; file "constant/geometry/WALL"; EXTRA }} }}
"""

    def errors(fluid, wall, extra=""):
        case = case_with(tmp_path, body.replace("FLUID", fluid).replace("WALL", wall)
                         .replace("EXTRA", extra), name=f"c{len(list(tmp_path.iterdir()))}")
        geo = case / "constant" / "geometry"
        V, T = box_mesh((0.5, 0.1, 0), (0.6, 0.2, 0.1))
        write(geo / "cube.stl", V, T)
        write(geo / "open.stl", V, np.delete(T, [0, 6], axis=0))  # one side missing
        write(geo / "twisted.stl", V[:4], np.array([[0, 1, 2], [1, 2, 3]]))  # mis-wound
        write(geo / "lines.vtk", V, np.array([[0, 1], [1, 3]]), cell="line")
        write(geo / "flat.obj", np.array([[0.5, 0.1, 0], [0.55, 0.1, 0], [0.6, 0.1, 0]]),
              np.array([[0, 1, 2]]))                               # collinear corners
        with pytest.raises(CaseError) as e:
            generate_case(Case(case))
        return str(e.value)

    msg = errors("missing.stl", "missing.obj")
    assert re.search(r"fluid\.blob\.file: .*missing\.stl: file not found", msg)
    assert re.search(r"walls\.rock\.file: .*missing\.obj: file not found", msg)
    msg = errors("open.stl", "open.stl")
    assert re.search(r"fluid\.blob\.file: .*open\.stl: the surface is not closed \(4 edge",
                     msg)
    assert "walls.rock" not in msg                 # an open wall is a sheet: allowed
    msg = errors("lines.vtk", "twisted.stl")
    assert re.search(r"fluid\.blob\.file: .*lines\.vtk: no triangles, quads or polygons",
                     msg)
    assert re.search(r"walls\.rock\.file: .*twisted\.stl: an open surface whose faces are "
                     r"not consistently oriented", msg)
    msg = errors("cube.stl", "flat.obj")
    assert re.search(r"walls\.rock\.file: .*flat\.obj: every face has zero area", msg)
    msg = errors("cube.stl", "cube.stl", "z 0.05;")
    assert re.search(r"walls\.rock.*z \(the cutting plane of a 2-D case's mesh wall\) has no "
                     r"meaning in 3-D", msg)
    msg = errors("cube.stl", "cube.stl", "translate (1 2);")
    assert re.search(r"walls\.rock\..*translate.*expected a vector \(x y z\)", msg)


def test_a_2d_case_refuses_a_mesh_fluid_region_and_keeps_its_mesh_walls(tmp_path):
    with pytest.raises(MeshWallError):      # 2-D mesh walls still read sections only
        from sphfoam.case.meshwalls import read_mesh_walls

        V, T = box_mesh((0, 0, 0), (1, 1, 1))
        write(tmp_path / "b.stl", V, T)
        read_mesh_walls(tmp_path / "b.stl", z=2.0)
    case = case_with(tmp_path, f"""dx {DX};
fluid {{ w {{ type mesh; file "x.stl"; }} }}
""")
    (case / "constant" / "g").write_text((case / "constant" / "g").read_text()
                                         .replace("(0 0 -9.81)", "(0 -9.81)"))
    with pytest.raises(CaseError, match=r"fluid\.w.*a mesh fluid region is a 3-D shape"):
        Case(case).validate()
