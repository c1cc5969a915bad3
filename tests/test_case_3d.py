"""Three-dimensional cases end to end (``dimension 3;`` in system/particleDict): the set-up,
a run through the time loop, time directories, and what a 3-D case refuses by name. The 2-D
engine's own 3-D checks are in tests/test_three_d_engine.py."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import sphfoam
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.io.fields import read_state

TANK3D = Path(__file__).resolve().parent.parent / "tutorials" / "hydrostaticTank3D"


def _edit(path: Path, pattern: str, repl: str) -> None:
    s = path.read_text()
    s2 = re.sub(pattern, repl, s, flags=re.S)
    assert s2 != s, pattern
    path.write_text(s2)


def _copy(tmp_path, name="case") -> Path:
    case = tmp_path / name
    outputs = shutil.ignore_patterns("VTK", "postProcessing", "*.foam", "polyMesh", "log.*")

    def ignore(folder, names):      # the tutorial's own outputs, if it was run in place
        return set(outputs(folder, names)) | {
            n for n in names if re.fullmatch(r"[0-9.e+-]+", n) and folder == str(TANK3D)}

    shutil.copytree(TANK3D, case, ignore=ignore)
    return case


def _particle_dict(case: Path, body: str) -> None:
    pd = case / "system" / "particleDict"
    head = pd.read_text().split("// * * * *")[0]
    pd.write_text(head + "// * * * * //\n" + body)


def test_the_3d_tutorial_case_validates_and_sets_up_in_three_dimensions(tmp_path):
    case = _copy(tmp_path)
    c = Case(case)
    c.validate()
    assert c.dimension == 3 and c.context.dim == 3 and c.gravity == (0.0, 0.0, -9.81)
    assert c.context.fluid_height == pytest.approx(0.4)
    from sphfoam.setup.initial import generate_case

    st = generate_case(c)
    assert st.dim == 3
    fluid = st.kind == 0
    assert fluid.sum() == 20 ** 3                      # volume / dx^3
    walls = ~fluid                                      # 3 layers outside 5 closed sides
    assert walls.sum() == 26 * 26 * 33 - 20 * 20 * 30
    # hydrostatic: p = rho0 g (H - z) from rho through Tait's inverse
    p = c.models.sph["equationOfState"].pressure(st.rho, c.context)
    z = st.z[fluid]
    assert np.allclose(p[fluid], 1000 * 9.81 * (0.4 - z), atol=1e-6)
    assert np.allclose(st.m[fluid], st.rho[fluid] * 0.02 ** 3)


@pytest.mark.parametrize("boundary", ["stationaryGhosts", "adami",
                                      "mirrorGhosts; pressure hydrostatic"])
def test_a_3d_tank_run_stays_hydrostatic_and_writes_3d_time_directories(tmp_path, boundary):
    """hydrostaticTank3D at H/dx = 10 for 0.05 s through sphfoam.run, with DualSPHysics'
    stationary ghosts, with Adami's generalised wall (no slip, AHA12 eqs. (22), (27) over
    the 3-D neighbours) and with mirrored ghosts across the tank's faces (edge and vertex
    ghosts, hydrostatic ghost pressure): the bed pressure (the line through the column's
    pressure, as bedPressure.py) within 2 % of rho g H, the water at rest, the time
    directories 3-D vectors read back bit for bit; Adami's wall particles keep their
    prescribed (zero) velocity in the written fields."""
    case = _copy(tmp_path)
    if boundary != "stationaryGhosts":
        _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
              f"type {boundary};")
    _edit(case / "system" / "particleDict", r"dx\s+0.02;", "dx 0.04;")
    _edit(case / "system" / "controlDict", r"endTime\s+1;", "endTime 0.05;")
    _edit(case / "system" / "controlDict", r"writeInterval\s+0.25;", "writeInterval 0.05;")
    sphfoam.run(case, progress=False)
    f = read_state(case / "0.05", dim=3)
    assert f["positions"].shape[1] == 3 and f["U"].shape[1] == 3
    fluid = f["type"] == 0
    x, y, z = f["positions"][fluid].T
    p = f["p"][fluid]
    mid = (np.abs(x - 0.2) < 0.1) & (np.abs(y - 0.2) < 0.1) & (z > 0.052) & (z < 0.2)
    _, bed = np.polyfit(z[mid], p[mid], 1)
    assert bed == pytest.approx(1000 * 9.81 * 0.4, rel=0.02)
    assert np.abs(f["U"][fluid]).max() < 0.01 * np.sqrt(9.81 * 0.4)
    assert np.all(f["U"][~fluid] == 0.0)
    st = sphfoam.Case(case)
    assert st.dimension == 3


def test_3d_particles_leaving_through_an_open_side_are_removed_and_logged_in_3d(tmp_path):
    """hydrostaticTank3D with its x = 0.4 m side open: the water spills over the edge of
    the floor and falls out of the domain box, the run goes on to its end, and the log
    says where the particles left as (x, y, z), the last time directory holding the
    others."""
    case = _copy(tmp_path)
    _edit(case / "system" / "particleDict", r"dx\s+0.02;", "dx 0.04;")
    _edit(case / "system" / "particleDict", r"open\s+top;", "open (top right);")
    _edit(case / "system" / "controlDict", r"endTime\s+1;", "endTime 0.6;")
    _edit(case / "system" / "controlDict", r"writeInterval\s+0.25;", "writeInterval 0.6;")
    rep = sphfoam.run(case, progress=False)
    assert rep.end_time == pytest.approx(0.6) and rep.removed > 0
    lines = [ln for ln in (case / "log.sphfoam").read_text().splitlines()
             if "left the domain" in ln]
    assert sum(int(ln.split("removed ")[1].split()[0]) for ln in lines) == rep.removed
    near = [float(v) for v in lines[0].split("near (")[1].split(")")[0].split(",")]
    assert len(near) == 3 and near[0] > 0.4 and 0.0 < near[1] < 0.4 and near[2] < 0.0
    f = read_state(case / "0.6", dim=3)
    assert f["positions"].shape[0] == rep.particles


def test_a_3d_case_refuses_what_has_no_3d_form_by_name(tmp_path):
    case = _copy(tmp_path)
    sph = case / "constant" / "sphProperties"
    sph.write_text(sph.read_text() + "\nturbulence { type mixingLength; }\n")
    with pytest.raises(CaseError, match=r"turbulence.type: turbulence "
                                        r"'mixingLength' has no 3-D form"):
        Case(case).validate()
    case = _copy(tmp_path, "b")
    _edit(case / "constant" / "g", r"\(0 0 -9.81\)", "(0 -9.81)")
    with pytest.raises(CaseError, match=r"constant/g: value.*expected a vector \(x y z\)"):
        Case(case).validate()
    case = _copy(tmp_path, "c")
    _particle_dict(case, "dimension 3; dx 0.02;\n"
                   "fluid { w { type polygon; points ((0 0) (1 0) (0 1)); } }\n")
    with pytest.raises(CaseError, match=r"fluid.w.*a polygon is two-dimensional: a 3-D case "
                                        r"uses box, cylinder, extrude or mesh"):
        Case(case).validate()
    case = _copy(tmp_path, "d")               # mirrored ghosts: no wall law in 3-D
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
          "type mirrorGhosts; wallLaw smooth;")
    with pytest.raises(CaseError, match=r"boundary.type: boundary 'mirrorGhosts': wallLaw "
                                        r"smooth has no 3-D form"):
        Case(case).validate()
    case = _copy(tmp_path, "d2")              # ... and box tanks' faces only
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
          "type mirrorGhosts;")
    _particle_dict(case, "dimension 3; dx 0.05;\n"
                   "fluid { w { type box; min (0 0 0); max (0.4 0.4 0.2); } }\n"
                   "walls { tank { type box; min (0 0 0); max (0.4 0.4 0.4); }\n"
                   "        post { type cylinder; point1 (0.2 0.2 0); point2 (0.2 0.2 0.3); "
                   "radius 0.05; } }\n")
    with pytest.raises(CaseError, match=r"walls.post.type: mirrorGhosts in 3-D mirrors across "
                                        r"the plane faces of box tanks only, not a cylinder"):
        sphfoam.setup_case(case)
    case = _copy(tmp_path, "f")       # repulsive walls: normals of box and block walls only
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
          "type repulsiveMonaghanKos;")
    _particle_dict(case, "dimension 3; dx 0.05;\n"
                   "fluid { w { type box; min (0 0 0); max (0.4 0.4 0.2); } }\n"
                   "walls { tank { type box; min (0 0 0); max (0.4 0.4 0.4); open top; }\n"
                   "        pile { type cylinder; point1 (0.2 0.2 0); point2 (0.2 0.2 0.4);"
                   " radius 0.05; } }\n")
    from sphfoam.setup.initial import generate_case

    with pytest.raises(CaseError, match=r"walls.pile.type: repulsiveMonaghanKos reads wall "
                                        r"normals, which the 3-D set-up writes for box and "
                                        r"block walls only"):
        generate_case(Case(case))


def test_3d_mirror_ghosts_of_a_particle_by_a_vertex_of_the_tank():
    """A particle near the floor, the left and the front face of a box tank gets seven
    ghosts (three faces, three edges, the vertex) at the reflected positions, T(3.77) once,
    twice and three times; free slip reverses the normal components only, no slip every
    component about the faces' mean velocity (zero here); the hydrostatic ghost pressure
    p_G = p_a + rho_a g.(x_G - x_a). A particle near the floor only gets one; one above the
    tank's open top, none."""
    from sphfoam.case.geometry import Plane
    from sphfoam.models import mirror3d as m3

    faces = [Plane(2, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0),   # floor z = 0
             Plane(0, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0),   # left x = 0
             Plane(1, 0.0, 1.0, (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 0.0), 0)]   # front y = 0
    pl = m3.plane_array(faces)
    x, y, z = (np.array(v) for v in ([0.03, 0.5, 0.03], [0.02, 0.5, 0.5], [0.01, 0.04, 1.2]))
    kind = np.zeros(3, dtype=np.int64)
    count = np.zeros(3, dtype=np.int64)
    m3.count_ghosts(x, y, z, kind, pl, 0.1, count)
    assert count.tolist() == [7, 1, 0]
    offset = np.array([0, 7, 8])
    src, f1, f2, f3 = (np.full(8, -9, dtype=np.int64) for _ in range(4))
    m3.fill_ghosts(x, y, z, kind, pl, 0.1, offset, src, f1, f2, f3)
    assert src.tolist() == [0] * 7 + [1]
    sets = {tuple(sorted(f for f in (a, b, c) if f >= 0)) for a, b, c in zip(f1, f2, f3)}
    assert sets == {(0,), (1,), (2,), (0, 1), (0, 2), (1, 2), (0, 1, 2)}
    u, v, w = np.array([1.0, 0, 0]), np.array([2.0, 0, 0]), np.array([3.0, 0, 0])
    rho0, B, gamma = 1000.0, 1e5, 7.0
    for j in range(7):
        on = [f for f in (f1[j], f2[j], f3[j]) if f >= 0]
        axes = {int(pl[f, 0]) for f in on}
        want = [(-c if k in axes else c) for k, c in enumerate((0.03, 0.02, 0.01))]
        for no_slip in (False, True):
            gx_, gy_, gz_, gu, gv, gw, grho = m3.ghost_state(
                0.03, 0.02, 0.01, 1.0, 2.0, 3.0, 1001.0, pl, f1[j], f2[j], f3[j], no_slip,
                True, 0.0, 0.0, -9.81, rho0, B, gamma, np.empty(3), np.empty(3), np.empty(3))
            assert np.allclose((gx_, gy_, gz_), want, rtol=0, atol=1e-15)
            vel = [(-c if (no_slip or k in axes) else c) for k, c in enumerate((1, 2, 3))]
            assert (gu, gv, gw) == tuple(float(c) for c in vel)
            pa = B * ((1001.0 / rho0) ** gamma - 1.0)
            pg = pa + 1001.0 * -9.81 * (gz_ - 0.01)
            assert B * ((grho / rho0) ** gamma - 1.0) == pytest.approx(pg, rel=1e-12)


def test_2d_cases_refuse_3d_shapes_and_keep_two_components(tmp_path):
    case = _copy(tmp_path)
    _particle_dict(case, "dx 0.02;\n"
                   "fluid { w { type cylinder; point1 (0 0 0); point2 (0 0 1); radius 1; } }\n")
    _edit(case / "constant" / "g", r"\(0 0 -9.81\)", "(0 -9.81 0)")
    with pytest.raises(CaseError, match=r"point2.*a 2-D case's vectors are \(x y\), z = 0: a "
                                        r"3-D case sets `dimension 3;`"):
        Case(case).validate()
    _particle_dict(case, "dx 0.02;\n"
                   "fluid { w { type cylinder; point1 (0 0); point2 (0 1); radius 1; } }\n")
    with pytest.raises(CaseError, match=r"a cylinder is a 3-D shape: set `dimension 3;`"):
        Case(case).validate()


def test_solid_shapes_take_their_layers_and_push_the_fluid_out(tmp_path):
    """A block, a cylinder and an extruded wedge in a box of water: each gets wall
    particles within `layers` dx inside its surface and no fluid particle within dx/2 of
    it."""
    from sphfoam.case.solids import signed_distance
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    _particle_dict(case, """dimension 3; dx 0.02;
fluid { water { type box; min (0 0 0); max (0.8 0.4 0.3); } }
walls
{
    tank  { type box; min (0 0 0); max (0.8 0.4 0.5); layers 3; open top; }
    block { type block; min (0.1 0.1 0); max (0.2 0.2 0.2); layers 2; }
    pile  { type cylinder; point1 (0.4 0.2 0); point2 (0.4 0.2 0.4); radius 0.05; }
    wedge { type extrude; points ((0.55 0) (0.75 0) (0.75 0.15)); span (0 0.4); }
}
""")
    c = Case(case)
    st = generate_case(c)
    pts = np.column_stack(st.positions)
    fluid = st.kind == 0
    for name, w in list(c.particles.walls.items())[1:]:
        d = signed_distance(w, pts)
        own = (d < 0) & ~fluid
        assert own.sum() > 0, name
        assert -d[own].max() <= w.layers * 0.02 * (1 + 1e-6), name
        assert d[fluid].min() >= 0.01 * (1 - 1e-3), name
    assert fluid.sum() < 40 * 20 * 15


@pytest.mark.parametrize("boundary", ["stationaryGhosts", "repulsiveMonaghanKos", "hybrid",
                                      "mirrorGhosts"])
def test_an_extruded_dam_break_periodic_across_stays_uniform_and_matches_2d(tmp_path,
                                                                           boundary):
    """A 2-D dam break and the same case extruded 12 dx across (three cells), periodic in y: after 0.1 s
    the 3-D run has no motion across (|v| at round-off) and every column of particles
    across y moves alike; its front is within a particle spacing of the 2-D run's (the
    kernels differ: 2-D and 3-D SPH agree to a discretisation error, not to round-off).
    With DualSPHysics' stationary ghosts, the repulsive wall of Monaghan & Kos and T's
    hybrid wall (the 3-D forms of the last two: their faces' lattices, sphfoam.models.
    boundaries), and mirrored ghosts (across the tank's faces, with edge ghosts:
    sphfoam.models.mirror3d)."""
    dx = 0.02
    runs = {}
    for dim in (2, 3):
        case = _copy(tmp_path, f"d{dim}")
        if boundary != "stationaryGhosts":
            _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
                  f"type {boundary};")
        _edit(case / "system" / "controlDict", r"endTime\s+1;", "endTime 0.1;")
        _edit(case / "system" / "controlDict", r"writeInterval\s+0.25;", "writeInterval 0.1;")
        if dim == 2:
            _edit(case / "constant" / "g", r"\(0 0 -9.81\)", "(0 -9.81)")
            _particle_dict(case, f"""dx {dx};
fluid {{ water {{ type box; min (0 0); max (0.2 0.2); }} }}
walls {{ tank {{ type box; min (0 0); max (0.6 0.4); layers 3; open top; }} }}
""")
        else:
            _particle_dict(case, f"""dimension 3; dx {dx};
fluid {{ water {{ type box; min (0 0 0); max (0.2 0.24 0.2); }} }}
walls {{ tank {{ type box; min (0 0 0); max (0.6 0.24 0.4); layers 3; open (top front back); }} }}
domain {{ min (-0.2 0 -0.2); max (0.8 0.24 0.8); periodic y; }}
""")
        sphfoam.run(case, progress=False)
        runs[dim] = read_state(case / "0.1", dim=dim)
    f3, f2 = runs[3], runs[2]
    fl3 = f3["type"] == 0
    pos, vel, ids = f3["positions"][fl3], f3["U"][fl3], f3["origId"][fl3]
    assert np.abs(vel[:, 1]).max() < 1e-9
    nj, nk = 12, 10                         # ids: ((i nj) + j) nk + k, the set-up's lattice
    i, j, k = ids // (nj * nk), (ids // nk) % nj, ids % nk
    col = i * nk + k
    for c_ in (0, 2):
        spread = np.zeros(col.max() + 1)
        lo = np.full(col.max() + 1, np.inf)
        np.minimum.at(lo, col, pos[:, c_])
        np.maximum.at(spread, col, pos[:, c_] - lo[col])
        assert spread.max() < 1e-9 * dx
    assert (j >= 0).all() and np.unique(j).size == nj
    fl2 = f2["type"] == 0
    front2 = f2["positions"][fl2, 0].max()
    front3 = pos[:, 0].max()
    assert front3 > 0.2 + dx and front2 > 0.2 + dx     # both fronts have moved
    assert abs(front3 - front2) < dx


def test_adami_free_slip_in_3d_mirrors_each_faces_normal_component(tmp_path):
    """Adami's free slip on the 3-D tank's box walls, water moving at (U, V, W): a floor
    particle takes (U, V, -W), one of the y = 0 side (U, -V, W), one on the edge of the two
    (U, -V, -W) and one at the vertex with x = 0 (-U, -V, -W): the fluid's velocity, each
    face's normal component mirrored about the still wall's (2 U_w - u~_f); put back to zero
    after the rates. On a cylinder (no plane faces) it is refused by name."""
    from sphfoam.assemble import build_simulation
    from sphfoam.engine.state import FLUID, WALL
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
          "type adami; noSlip no;")
    _edit(case / "system" / "particleDict", r"dx\s+0.02;", "dx 0.04;")
    c = Case(case)
    st = generate_case(c)
    U, V, W = 0.3, -0.2, 0.1
    fluid = st.kind == FLUID
    st.u[fluid], st.v[fluid], st.w[fluid] = U, V, W
    sim = build_simulation(c, st)
    sim.neighbour_update()
    sim.eos()
    sim.rates()
    st = sim.state
    wall = st.kind == WALL
    assert not st.u[wall].any() and not st.v[wall].any() and not st.w[wall].any()
    sim._prepass(sim._grid_args())                      # what the pair terms see
    mid = lambda q: (q > 0.1) & (q < 0.3)               # noqa: E731
    for where, want in (((mid(st.x) & mid(st.y) & (st.z < 0)), (U, V, -W)),
                        ((mid(st.x) & (st.y < 0) & mid(st.z)), (U, -V, W)),
                        ((mid(st.x) & (st.y < 0) & (st.z < 0)), (U, -V, -W)),
                        (((st.x < 0) & (st.y < 0) & (st.z < 0)), (-U, -V, -W))):
        sel = wall & where & (np.abs(st.p) > 0)         # wall particles with fluid in reach
        assert sel.sum() >= 3
        for comp, val in zip((st.u, st.v, st.w), want):
            assert comp[sel] == pytest.approx(val, rel=1e-9)
    _particle_dict(case, "dimension 3; dx 0.05;\n"
                   "fluid { w { type box; min (0 0 0); max (0.4 0.4 0.2); } }\n"
                   "walls { tank { type box; min (0 0 0); max (0.4 0.4 0.4); }\n"
                   "        post { type cylinder; point1 (0.2 0.2 0); point2 (0.2 0.2 0.3); "
                   "radius 0.05; } }\n")
    with pytest.raises(CaseError, match=r"walls.post.type: adami reads wall normals, which "
                                        r"the 3-D set-up writes for box and block walls only"):
        sphfoam.setup_case(case)


def test_a_3d_piston_paddle_moves_its_block_by_the_wave_makers_stroke(tmp_path):
    """A block wall with a piston paddle's motion in 3-D: after a few steps its particles
    sit at their set-up position plus X(t) along the direction and move at X'(t); the other
    walls have not moved."""
    from sphfoam.assemble import build_simulation
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    _particle_dict(case, """dimension 3; dx 0.05;
fluid { water { type box; min (0 0 0); max (1 0.3 0.3); } }
walls
{
    tank   { type box; min (-0.5 0 0); max (1 0.3 0.6); layers 3; open (top left); }
    paddle
    {
        type block; min (-0.15 0 0); max (0 0.3 0.6); layers 3;
        motion { type pistonPaddle; direction (1 0 0);
                 waveMaker { type goring; height 0.03; depth 0.3; } }
    }
}
""")
    c = Case(case)
    st = generate_case(c)
    assert {"patch", "x0", "y0", "z0"} <= set(st.extra)
    sim = build_simulation(c, st)
    for _ in range(10):
        sim.step()
    st = sim.state
    mot = c.models.motions[1]
    paddle = st.extra["patch"] == 1
    tank = st.extra["patch"] == 0
    X = mot.displacement(sim.time)[0]
    assert X > 0
    assert np.allclose(st.x[paddle], st.extra["x0"][paddle] + X, rtol=0, atol=1e-12)
    assert np.array_equal(st.y[paddle], st.extra["y0"][paddle])
    assert np.array_equal(st.z[paddle], st.extra["z0"][paddle])
    assert np.allclose(st.u[paddle], mot.velocity(sim.time)[0], rtol=0, atol=1e-12)
    assert np.array_equal(st.x[tank], st.extra["x0"][tank])
    assert not sim.pipeline.selection.still_walls


def test_a_3d_displacement_table_moves_its_block_and_a_2d_table_is_refused(tmp_path):
    """A block wall moved by a displacement table of (t (dx dy dz)) rows in 3-D: after a
    few steps its particles sit at their set-up position plus the table's displacement,
    interpolated linearly, on all three axes, and move at its slope; a table of (dx dy)
    rows, or a paddle's (x y) direction, in a 3-D case is refused naming the entry."""
    from sphfoam.assemble import build_simulation
    from sphfoam.setup.initial import generate_case

    walls = """dimension 3; dx 0.05;
fluid { water { type box; min (0 0 0); max (1 0.3 0.3); } }
walls
{
    tank   { type box; min (-0.5 0 0); max (1 0.3 0.6); layers 3; open (top left); }
    paddle
    {
        type block; min (-0.15 0.05 0); max (0 0.25 0.6); layers 3;
        motion { type displacementTable; table ((0 (0 0 0)) (1 (0.2 -0.1 0.05))); }
    }
}
"""
    case = _copy(tmp_path)
    _particle_dict(case, walls)
    c = Case(case)
    st = generate_case(c)
    sim = build_simulation(c, st)
    for _ in range(10):
        sim.step()
    st = sim.state
    t = sim.time
    paddle = st.extra["patch"] == 1
    assert t > 0
    for k, (pos, vel, d) in enumerate(zip(st.positions, st.velocities, (0.2, -0.1, 0.05))):
        x0 = st.extra["xyz"[k] + "0"][paddle]
        assert np.allclose(pos[paddle], x0 + d * t, rtol=0, atol=1e-12), k
        assert np.allclose(vel[paddle], d, rtol=0, atol=1e-12), k
    tank = st.extra["patch"] == 0
    assert np.array_equal(st.z[tank], st.extra["z0"][tank])
    for motion, key in (("{ type displacementTable; table ((0 (0 0)) (1 (0.2 0))); }",
                         "table"),
                        ("{ type pistonPaddle; direction (1 0); "
                         "waveMaker { type goring; height 0.03; depth 0.3; } }", "direction")):
        bad = _copy(tmp_path / key)
        _particle_dict(bad, walls.replace(
            "motion { type displacementTable; table ((0 (0 0 0)) (1 (0.2 -0.1 0.05))); }",
            f"motion {motion}"))
        with pytest.raises(CaseError, match=rf"walls.paddle.motion.{key}: motion '\w+' "
                                            r"gives 2 components; a 3-D case needs \(x y z\)"):
            Case(bad).validate()


def test_a_2d_block_wall_gets_its_rows_inside_and_the_fluid_outside(tmp_path):
    """``type block`` works in 2-D as in 3-D: rows of wall particles inside its edges, the
    fluid outside, half a spacing off."""
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    _edit(case / "constant" / "g", r"\(0 0 -9.81\)", "(0 -9.81)")
    _particle_dict(case, """dx 0.02;
fluid { water { type box; min (0 0); max (1 0.4); } }
walls
{
    tank  { type box; min (0 0); max (1 0.6); layers 3; open top; }
    block { type block; min (0.4 0); max (0.6 0.2); layers 2; }
}
""")
    st = generate_case(Case(case))
    inside = (st.x > 0.4) & (st.x < 0.6) & (st.y > 0) & (st.y < 0.2)
    assert not (inside & (st.kind == 0)).any()
    ring = inside & (np.minimum.reduce([st.x - 0.4, 0.6 - st.x, 0.2 - st.y, st.y]) < 0.04)
    assert (st.kind[ring] == 1).all() and ring.sum() == 2 * (10 + 10 + 6 + 6)
    assert not (inside & ~ring).any()                  # two rows, nothing further in


# --- repulsive and hybrid walls in 3-D ----------------------------------------------------
_TANK_1ROW = """dimension 3; dx {dx};
fluid {{ water {{ type box; min (0 0 0); max (0.2 0.2 0.2); }} }}
walls {{ tank {{ type box; min (0 0 0); max (0.4 0.4 0.4); layers 3; open top; }} }}
"""


def _wall_force(case: Path, points) -> np.ndarray:
    """The acceleration less gravity of a lone fluid particle at each of ``points`` beside
    the case's wall particles (as set up): the walls' force per unit mass on it."""
    from sphfoam.assemble import build_simulation
    from sphfoam.engine.state import ParticleState
    from sphfoam.setup.initial import generate_case

    c = Case(case)
    st = generate_case(c)
    wall = st.kind != 0
    out = []
    for pt in points:
        def both(a, v):
            return np.concatenate([[v], a[wall]])
        one = ParticleState(both(st.x, pt[0]), both(st.y, pt[1]), both(st.u, 0.0),
                            both(st.v, 0.0), both(st.rho, 1000.0), np.full(1 + wall.sum(), st.m[0]),
                            both(st.kind, 0), extra={k: both(a, 0.0)
                                                     for k, a in st.extra.items()},
                            z=both(st.z, pt[2]), w=both(st.w, 0.0))
        sim = build_simulation(c, one)
        sim.neighbour_update()
        sim.eos()
        sim.rates()
        i = np.flatnonzero((sim.state.id == 0) & (sim.state.kind == 0))[0]
        out.append([sim.state.ax[i], sim.state.ay[i], sim.state.az[i] + 9.81])
    return np.array(out)


@pytest.mark.parametrize("boundary", ["repulsiveMonaghanKos", "repulsiveMonaghan2003"])
def test_3d_repulsive_walls_push_along_each_face_normal_with_weights_summing_to_one(
        tmp_path, boundary):
    """A lone fluid particle at height y above the floor of a one-row tank feels T(3.71)'s
    (or T(3.75)'s) Gamma(y) along the floor's normal wherever it stands on the floor's lattice
    (the hat weights of the face's two axes sum to one), and beside the edge of the floor and
    a side wall the sum of the two faces' forces, each along its own normal: the force of
    the 2-D wall, exact to round-off. (All particles of one mass: m_b / (m_a + m_b) = 1/2.)"""
    dx = 0.02
    case = _copy(tmp_path)
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;",
          f"type {boundary};")
    _particle_dict(case, _TANK_1ROW.format(dx=dx))
    c = Case(case)
    ctx = c.context
    zb = -dx / 2                               # the floor's row of wall particles

    def gamma(y):
        if boundary == "repulsiveMonaghanKos":
            q = y / (2 * dx)
            return 0.01 * ctx.c0 ** 2 / ctx.h * (1 - q) / np.sqrt(q) if q < 1 else 0.0
        q, beta = y / ctx.h, 0.02 * ctx.c0 ** 2 / y
        f = 2 / 3 if q < 2 / 3 else (2 * q - 1.5 * q * q if q < 1 else 0.5 * (2 - q) ** 2)
        return 0.5 * beta * f if q < 2 else 0.0          # m_b / (m_a + m_b) = 1/2

    y = 0.8 * dx
    mid = [(0.2 + s * dx, 0.2 + t * dx, zb + y) for s, t in
           ((0, 0), (0.5, 0), (0.3, 0.7), (-0.45, 0.2))]
    a = _wall_force(case, mid)
    assert np.allclose(a[:, 2], gamma(y), rtol=1e-12)
    assert np.abs(a[:, :2]).max() < 1e-9 * gamma(y)
    xs, ys = 0.7 * dx, 1.1 * dx               # beside the side wall x = 0 and the floor
    a = _wall_force(case, [(-dx / 2 + xs, 0.2 + 0.3 * dx, zb + ys)])[0]
    assert a[0] == pytest.approx(gamma(xs), rel=1e-12)
    assert a[2] == pytest.approx(gamma(ys), rel=1e-12)
    assert abs(a[1]) < 1e-9 * gamma(xs)


def _hybrid_walls(tmp_path, dx: float, fluid: str, block: str):
    """A 3-D case with hybrid walls (the set-up writes every wall field) of a tank 0.6 x 0.6
    x 0.4 m, one layer, open on top, the water box ``fluid`` and the ``block`` entry; set up:
    (case, state, wall mask, wall positions, wall normals nx, ny, nz)."""
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;", "type hybrid;")
    _particle_dict(case, f"""dimension 3; dx {dx};
fluid {{ water {{ type box; {fluid} }} }}
walls
{{
    tank  {{ type box; min (0 0 0); max (0.6 0.6 0.4); layers 1; open top; }}
    block {{ type block; {block} }}
}}
""")
    c = Case(case)
    st = generate_case(c)
    w = st.kind != 0
    pos = np.column_stack(st.positions)[w]
    n = np.column_stack([st.extra[k][w] for k in ("nx", "ny", "nz")])
    return c, st, w, pos, n


def test_3d_block_faces_off_the_lattice_keep_their_first_layer(tmp_path):
    """A block whose sides are not whole numbers of dx (SPHERIC Test 2's container model,
    0.161 m = 4.39 dx at H/dx = 15: on a lattice anchored at its corner its outer rows lay
    0.9 dx behind the front face) is filled to its faces: round(L/dx) sites spaced L/n
    along each side, the first layer half a spacing behind every face, the particles'
    volumes m/rho adding up to the block's. Every particle of a face's first layer takes
    that face's normal, so the front-side edges are edges (two normals), not side faces
    only (free-slip Adami walls mirror the normal components; with the front's missing
    there, the water's approach was not mirrored)."""
    from sphfoam.case.geometry import fitted_boxes

    dx = 0.05
    c, st, w, pos, n = _hybrid_walls(tmp_path, dx, "min (0.4 0 0); max (0.6 0.6 0.2);",
                                     "min (0.1 0.2 0); max (0.27 0.4 0.15); layers 3;")
    block = (pos[:, 0] > 0.1) & (pos[:, 0] < 0.27) & (pos[:, 1] > 0.2) & (pos[:, 1] < 0.4) \
        & (pos[:, 2] > 0)
    front = block & np.isclose(pos[:, 0], pos[block, 0].max())
    sx = 0.17 / 3                                    # 3.4 dx: 3 sites
    assert 0.27 - pos[front, 0].max() == pytest.approx(sx / 2)
    assert pos[block, 0].min() - 0.1 == pytest.approx(sx / 2)
    assert block.sum() == 3 * 4 * 3
    assert (st.m[w][block] / st.rho[w][block]).sum() == pytest.approx(0.17 * 0.2 * 0.15)
    assert any(note.startswith("walls.block ") and "3 x 4 x 3 sites" in note
               for note in fitted_boxes(c.particles))
    assert front.sum() == 12 and (n[front][:, 0] == 1).all()
    edge = front & ((pos[:, 1] == pos[block, 1].min()) | (pos[:, 1] == pos[block, 1].max()))
    assert edge.sum() == 6 and (np.abs(n[edge][:, 1]) == 1).all()
    assert np.array_equal(st.extra["corner"][w], np.abs(n).sum(axis=1) - 1)


def test_3d_wall_geometry_of_a_tank_and_a_block_on_its_floor(tmp_path):
    """The set-up's 3-D wall normals for one row: a tank's faces, edges and vertices belong
    to one, two and three faces (the signs of their normals into the water); a block on the
    floor has no bottom face (it stands on the tank), and the floor's rows under it lie
    behind its feet (edges and corners of the water); the hybrid wall's nFull counts the
    lattice sites in the support in front of the faces (a quarter space on an edge)."""
    dx = 0.05
    c, st, w, pos, n = _hybrid_walls(tmp_path, dx, "min (0 0 0); max (0.6 0.6 0.2);",
                                     "min (0.1 0.1 0); max (0.2 0.2 0.1); layers 1;")
    corner = st.extra["corner"][w]
    assert set(np.unique(n)) <= {-1.0, 0.0, 1.0}
    assert np.array_equal(corner, np.abs(n).sum(axis=1) - 1)
    h = dx / 2
    floor = np.isclose(pos[:, 2], -h) & (np.abs(pos[:, :2] - 0.425) < 0.03).all(axis=1)
    assert floor.any() and (n[floor] == [0, 0, 1]).all()
    edge = np.isclose(pos[:, 2], -h) & np.isclose(pos[:, 0], -h) & \
        (np.abs(pos[:, 1] - 0.4) < 0.08)
    assert edge.any() and (n[edge] == [1, 0, 1]).all()
    vertex = np.isclose(pos, [0.6 + h, -h, -h]).all(axis=1)
    assert (n[vertex] == [-1, 1, 1]).all()
    block = (pos[:, :2] > 0.1).all(axis=1) & (pos[:, :2] < 0.2).all(axis=1)
    top = block & np.isclose(pos[:, 2], 0.1 - h)
    assert top.any() and (n[top][:, 2] == 1).all()
    low = block & np.isclose(pos[:, 2], h) & (np.abs(pos[:, 0] - 0.15) < 0.03) & \
        (np.abs(pos[:, 1] - 0.15) < 0.03)
    assert not (n[low][:, 2] < 0).any()                  # no face on the tank's floor
    side = block & np.isclose(pos[:, 0], 0.1 + h) & np.isclose(pos[:, 2], h)
    assert side.any() and (n[side][:, 0] == -1).all() and (n[side][:, 2] == 0).all()
    # the floor's row under the block lies behind the block's feet, the water's concave
    # edges and corners (here dx/2 from two of its faces: behind the vertical edge's foot)
    under = (pos[:, :2] > 0.1).all(axis=1) & (pos[:, :2] < 0.2).all(axis=1) & \
        np.isclose(pos[:, 2], -h)
    assert under.sum() == 4
    assert np.array_equal(n[under][:, :2], np.where(pos[under, :2] < 0.15, -1.0, 1.0))
    assert (n[under][:, 2] == 1).all() and (corner[under] == 2).all()
    r = c.context.support / dx
    k = np.arange(-4, 5)
    off = np.stack(np.meshgrid(k, k, k, indexing="ij"), -1).reshape(-1, 3)
    inside = (off ** 2).sum(1) < r * r - 1e-9
    nfull = st.extra["nFull"][w]
    assert (nfull[floor] == np.sum(inside & (off[:, 2] >= 1))).all()
    assert (nfull[edge] == np.sum(inside & (off[:, 2] >= 1) & (off[:, 0] >= 1))).all()


@pytest.mark.parametrize("dim", [2, 3])
def test_a_tank_and_a_box_off_the_lattice_are_filled_to_their_faces(tmp_path, dim):
    """A tank and a box of water whose sides are not whole numbers of dx (SPHERIC's MARIN
    reservoir, 1.228 m at dx = 0.55/30, is 66.98 spacings): the water holds the box's volume
    (sum of m/rho) and reaches each face within half its spacing, and every closed side of
    the tank has its `layers` layers dx/2, 3dx/2, ... behind it (the lattice anchored at the
    corner put the far sides' first layer 0.84 dx behind and dropped the third)."""
    from sphfoam.setup.initial import generate_case

    case = _copy(tmp_path)
    dx, lo, hi, tank = 0.02, (0.0, 0.0, 0.0), (0.331, 0.209, 0.157), (0.431, 0.209, 0.4)
    if dim == 2:
        _edit(case / "constant" / "g", r"\(0 0 -9.81\)", "(0 -9.81)")
        v = lambda p: "(%g %g)" % (p[0], p[2])          # noqa: E731 (x, z) in 2-D
        body = f"dx {dx};\n"
    else:
        v = lambda p: "(%g %g %g)" % p                  # noqa: E731
        body = f"dimension 3; dx {dx};\n"
    _particle_dict(case, body + f"""
fluid {{ water {{ type box; min {v(lo)}; max {v(hi)}; }} }}
walls {{ tank {{ type box; min {v(lo)}; max {v(tank)}; layers 3; open top; }} }}
""")
    c = Case(case)
    st = generate_case(c)
    from sphfoam.case.geometry import fitted_boxes
    notes = fitted_boxes(c.particles)          # what `sphfoam setup` says it fitted
    assert [n.split(" ")[0] for n in notes] == ["fluid.water", "walls.tank"]
    assert ("17 x 10 x 8 particles" if dim == 3 else "17 x 8 particles") in notes[0]
    axes = [0, 2] if dim == 2 else [0, 1, 2]
    pos = np.column_stack(st.positions)
    fluid = st.kind == 0
    volume = np.prod([hi[a] - lo[a] for a in axes])
    assert (st.m[fluid] / st.rho[fluid]).sum() == pytest.approx(volume, rel=1e-12)
    for k, a in enumerate(axes):
        f = pos[fluid, k]
        n = round((hi[a] - lo[a]) / dx)
        s = (hi[a] - lo[a]) / n
        assert abs(s - dx) <= dx / (2 * n)
        assert f.min() == pytest.approx(lo[a] + s / 2) and f.max() == pytest.approx(hi[a] - s / 2)
        # the tank's layers behind its closed faces, along this axis, away from the edges
        mid = np.ones(len(pos), bool)
        for kk, aa in enumerate(axes):
            if aa != a:
                mid &= (pos[:, kk] > lo[aa] + 0.05) & (pos[:, kk] < 0.15)
        walls = pos[mid & ~fluid, k]
        ends = [lo[a]] if a == 2 else [lo[a], tank[a]]   # the top is open
        for end in ends:
            depth = np.sort(np.abs(walls[np.abs(walls - end) < 4 * dx] - end))
            assert np.unique(np.round(depth / dx, 9)).tolist() == [0.5, 1.5, 2.5], (a, end)
