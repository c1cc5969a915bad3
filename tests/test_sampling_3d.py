"""Sampling in 2-D and 3-D: wave gauges at (x y) points and lines of gauges, 3-D probes,
pressure sensors, forces on named walls and slices, against hydrostatics (rho g depth,
the weight of the water, rho g H^2 / 2 on a wall) on the set-up's state and through a run,
``sphfoam sample`` and ``sphfoam plot``."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import sphfoam
from sphfoam import registry
from sphfoam.case.edit import set_entry
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.engine.state import FLUID
from sphfoam.sampling.waves import surface_elevation, surface_elevation_3d

TUTORIALS = Path(__file__).resolve().parent.parent / "tutorials"
RHO, G = 1000.0, 9.81


def _case(tmp_path, tutorial, name, particles: str, functions: str = "") -> Path:
    case = tmp_path / name
    shutil.copytree(TUTORIALS / tutorial, case, ignore=shutil.ignore_patterns(
        "VTK", "postProcessing", "*.foam", "polyMesh", "log.*", "[0-9]*"))
    pd = case / "system" / "particleDict"
    head = pd.read_text().split("// * * * *")[0]
    pd.write_text(head + "// * * * * //\n" + particles)
    cd = case / "system" / "controlDict"
    s = re.sub(r"functions\s*\{\s*\}", "functions\n{\n" + functions + "\n}", cd.read_text())
    s = re.sub(r"endTime\s+[0-9.e-]+;", "endTime 0.02;", s)
    s = re.sub(r"writeInterval\s+[0-9.e-]+;", "writeInterval 0.01;", s)
    cd.write_text(s)
    return case


TANK2D = """dx 0.02;
fluid { water { type box; min (0 0); max (0.5 0.4); } }
walls {
  tank { type box; min (0 0); max (0.5 0.6); layers 3; open (top left); }
  left { type polyline; points ((0 0.6) (0 -0.06)); side right; layers 3; }
  block { type polyline; points ((0.2 0) (0.2 0.1) (0.3 0.1) (0.3 0)); layers 3; }
}
"""
TANK3D = """dimension 3;
dx 0.04;
fluid { water { type box; min (0 0 0); max (0.4 0.4 0.4); } }
walls {
  tank { type box; min (0 0 0); max (0.4 0.4 0.6); layers 3; open top; }
  block { type block; min (0.12 0.12 0); max (0.28 0.28 0.12); layers 3; }
}
"""


class _Saved:
    def __init__(self, state):
        self.state, self.time = state, 0.0


def _setup(case):
    from sphfoam.setup.initial import generate_case

    c = Case(case)
    c.validate()
    st = generate_case(c)
    st.p = c.models.sph["equationOfState"].pressure(st.rho, c.context)
    return c, st


def _fo(c, spec, name="fo"):
    fo = registry.build("functionObject", spec, {"dim": c.dimension})
    fo.object_name = name
    fo.start(c, c.context, "0")
    return fo


# --- wave gauges -------------------------------------------------------------------------------
def test_3d_gauge_reads_an_extruded_2d_surface_as_the_2d_gauge():
    """A sloping, wavy lattice surface uniform across y: the 3-D gauge at (x, y) equals the
    2-D gauge at x to 1e-12 m, wherever y is."""
    dx = 0.01
    xs = dx * (np.arange(200) + 0.5)
    top = 0.3 + 0.05 * np.sin(xs / 0.3)
    x2, y2 = [], []
    for x, t in zip(xs, top):
        n = int(t / dx)
        x2 += [x] * n
        y2 += list(dx * (np.arange(n) + 0.5))
    x2, y2 = np.array(x2), np.array(y2)
    ys = dx * (np.arange(12) + 0.5)
    X = np.tile(x2, ys.size)
    Y = np.repeat(ys, x2.size)
    Z = np.tile(y2, ys.size)
    gx = np.array([0.3, 0.555, 1.0, 1.51])
    ref = surface_elevation(x2, y2, gx, dx)
    for yg in (0.05, 0.061, 0.0):
        got = surface_elevation_3d(X, Y, Z, np.column_stack([gx, np.full(gx.size, yg)]), dx)
        assert np.allclose(got, ref, rtol=0, atol=1e-12)


def test_3d_gauge_recovers_a_plane_surface_sloping_in_x_and_y():
    """Tops on a tilted plane z = 0.3 + 0.1 x + 0.05 y (one particle column per cell): the
    gauge reads the plane + dx/2 at the gauge to 1e-12 m (the least-squares plane is exact)."""
    dx = 0.01
    c = dx * (np.arange(40) + 0.5)
    X, Y = np.meshgrid(c, c)
    Z = 0.3 + 0.1 * X + 0.05 * Y
    g = np.array([[0.2, 0.2], [0.103, 0.251]])
    got = surface_elevation_3d(X.ravel(), Y.ravel(), Z.ravel(), g, dx)
    want = 0.3 + 0.1 * g[:, 0] + 0.05 * g[:, 1] + 0.5 * dx
    assert np.allclose(got, want, rtol=0, atol=1e-12)


def test_3d_wire_gauge_ignores_a_splash_above_the_water():
    """A 3-D lattice of water 0.2 m deep with a sheet three rows thick 0.2 m above it over
    part of the gauges: the fraction gauge reads the sheet's top, the wire gauge the water's
    surface plus the sheet's thickness (3 dx, to 0.1 dx); where no sheet passes they read
    the same to 1e-9 m."""
    from sphfoam.models.kernels import WendlandC2
    from sphfoam.sampling.waves import fraction_surface_3d, wire_surface_3d

    dx, k = 0.02, WendlandC2()
    h = 1.3 * dx
    c = dx * (np.arange(20) + 0.5)
    X, Y, Z = (a.ravel() for a in np.meshgrid(c, c, dx * (np.arange(10) + 0.5)))
    sX, sY, sZ = (a.ravel() for a in np.meshgrid(c[:10], c, 0.4 + dx * (np.arange(3) + 0.5)))
    x, y, z = np.concatenate([X, sX]), np.concatenate([Y, sY]), np.concatenate([Z, sZ])
    v = np.full(x.size, dx**3)
    g = np.array([[0.1, 0.2], [0.3, 0.2]])           # under the sheet, clear of it
    frac = fraction_surface_3d(x, y, z, v, g, k, h, dx)
    wire = wire_surface_3d(x, y, z, v, g, k, h, dx)
    water = fraction_surface_3d(X, Y, Z, v[:X.size], g, k, h, dx)
    assert abs(water[0] - 0.2) <= 0.05 * dx and abs(frac[0] - 0.4 - 3 * dx) <= 0.1 * dx
    assert abs(wire[0] - water[0] - 3 * dx) <= 0.1 * dx
    assert abs(wire[1] - frac[1]) <= 1e-9


def test_3d_gauges_and_probes_at_rest(tmp_path):
    """The 3-D tank at rest: particle gauges read H = 0.4 m exactly (lattice tops + dx/2),
    fraction gauges away from the walls within 0.01 dx; a line of gauges adds its points;
    a probe at mid-depth reads rho g H/2 within 1 %."""
    c, st = _setup(_case(tmp_path, "hydrostaticTank3D", "a", TANK3D))
    fo = _fo(c, {"type": "waveGauges", "points": [[0.2, 0.2], [0.1, 0.3]],
                 "line": {"start": [0.05, 0.2], "end": [0.35, 0.2], "nPoints": 4}})
    assert fo.columns == ("time", "eta(0.2,0.2)", "eta(0.1,0.3)", "eta(0.05,0.2)",
                          "eta(0.15,0.2)", "eta(0.25,0.2)", "eta(0.35,0.2)")
    f = st.kind == 0
    assert np.allclose(fo.measure_3d(st, f), 0.4, rtol=0, atol=1e-12)
    fr = _fo(c, {"type": "waveGauges", "points": [[0.2, 0.2], [0.14, 0.26]],
                 "surface": "fraction"})
    assert np.allclose(fr.measure_3d(st, f), 0.4, rtol=0, atol=0.01 * 0.04)
    wi = _fo(c, {"type": "waveGauges", "points": [[0.2, 0.2], [0.14, 0.26]],
                 "surface": "wire"})
    assert np.allclose(wi.measure_3d(st, f), fr.measure_3d(st, f), rtol=0, atol=1e-9)
    pr = _fo(c, {"type": "probes", "points": [[0.2, 0.2, 0.2]]})
    assert pr.columns == ("time", "p(0.2,0.2,0.2)", "Ux(0.2,0.2,0.2)", "Uy(0.2,0.2,0.2)",
                          "Uz(0.2,0.2,0.2)")
    pr.execute(_Saved(st))
    pr.end()
    row = np.loadtxt(pr.file, ndmin=2)[0]
    assert row[1] == pytest.approx(RHO * G * 0.2, rel=0.01)
    assert np.all(row[2:] == 0.0)


def test_3d_wall_run_up_reads_an_extruded_2d_wall_as_the_2d_run_up(tmp_path):
    """runUp mode wall in 3-D: water against the wall x = 0.4 of the 3-D tank, lifted on a
    ramp uniform across y (a lattice column per (x, y), tops rising towards the wall), reads
    what the 2-D runUp reads on one of its slices: the particle run-up exactly, the fraction
    run-up (the fluid mirrored across the wall, the crossing on the wall's vertical at y)
    within 0.02 dx of the 2-D one; particle mode without y reads the whole wall; a beach,
    or a fraction without y, is refused in 3-D."""
    from sphfoam.sampling.waves import fraction_wall_run_up

    c, _ = _setup(_case(tmp_path, "hydrostaticTank3D", "r", TANK3D))
    dx = 0.04
    xs = dx * (np.arange(10) + 0.5)
    ys = dx * (np.arange(10) + 0.5)
    top = 0.2 + 0.25 * xs                          # the water rises towards x = 0.4
    x2 = np.concatenate([[x] * int(t / dx) for x, t in zip(xs, top)])
    z2 = np.concatenate([dx * (np.arange(int(t / dx)) + 0.5) for t in top])
    X, Y, Z = np.tile(x2, ys.size), np.repeat(ys, x2.size), np.tile(z2, ys.size)
    st = type("S", (), {})()
    st.x, st.y, st.z = X, Y, Z
    st.rho, st.m = np.full(X.size, RHO), np.full(X.size, RHO * dx ** 3)
    f = np.ones(X.size, dtype=bool)
    kernel, h = c.models.sph["kernel"], c.context.h
    want = z2[x2 > 0.36].max() + 0.5 * dx
    part = _fo(c, {"type": "runUp", "mode": "wall", "x": 0.4, "y": 0.2})
    assert part.measure_3d(st, f) == pytest.approx(want, abs=1e-12)
    whole = _fo(c, {"type": "runUp", "mode": "wall", "x": 0.4}, "w")
    assert whole.measure_3d(st, f) == pytest.approx(want, abs=1e-12)
    frac = _fo(c, {"type": "runUp", "mode": "wall", "x": 0.4, "y": 0.2, "surface": "fraction"},
               "f")
    r2 = fraction_wall_run_up(x2, z2, np.full(x2.size, dx * dx), 0.4, kernel, h, dx)
    assert np.isfinite(r2) and frac.measure_3d(st, f) == pytest.approx(r2, abs=0.02 * dx)
    for spec, msg in (({"mode": "beach", "start": [0, 0], "angle": 5}, "mode beach has no 3-D"),
                      ({"mode": "wall", "x": 0.4, "surface": "fraction"}, "give its y")):
        with pytest.raises(Exception, match=msg):
            registry.build("functionObject", {"type": "runUp", **spec}, {"dim": 3})


def test_3d_crest_tracker_reads_an_extruded_crest_as_the_2d_tracker(tmp_path):
    """crestTracker in 3-D: a solitary-like hump in columns, uniform across y; the tracker's
    gauges along x on the line y read the crest (x_c, eta_c) of the 2-D tracker on the 2-D
    slice, by the particle gauges to 1e-12 m and the fraction gauges to 0.02 dx; without y,
    or with surface volume, it is refused in 3-D."""
    c, _ = _setup(_case(tmp_path, "hydrostaticTank3D", "c", TANK3D))
    dx = 0.04
    xs = dx * (np.arange(10) + 0.5)
    top = 0.2 + 0.08 / np.cosh((xs - 0.23) / 0.08) ** 2
    n = np.rint(top / dx).astype(int)              # columns as the set-up fills them:
    x2 = np.repeat(xs, n)                          # n particles spaced top/n, so the tops
    z2 = np.concatenate([(np.arange(k) + 0.5) * t / k for k, t in zip(n, top)])   # vary
    ys = dx * (np.arange(10) + 0.5)
    st = type("S", (), {})()
    st.x, st.y, st.z = np.tile(x2, ys.size), np.repeat(ys, x2.size), np.tile(z2, ys.size)
    st.rho, st.m = np.full(st.x.size, RHO), np.full(st.x.size, RHO * dx ** 3)
    f = np.ones(st.x.size, dtype=bool)
    ctx2 = type("C", (), {"dx": dx, "h": c.context.h, "dim": 2})()
    for surface, tol in (("particle", 1e-12), ("fraction", 0.02 * dx)):
        spec = {"type": "crestTracker", "y": 0.2, "xMin": 0.02, "xMax": 0.38,
                "surface": surface}
        three = _fo(c, spec, f"c{surface}")
        two = registry.build("functionObject", {k: v for k, v in spec.items() if k != "y"},
                             {"dim": 2})
        two.case, two.ctx = c, ctx2
        xc3, ec3 = three.measure_3d(st, f)
        xc2, ec2 = two.measure(x2, z2, np.full(x2.size, dx * dx))
        assert np.isfinite(xc3) and ec3 > 0.2
        assert xc3 == pytest.approx(xc2, abs=tol) and ec3 == pytest.approx(ec2, abs=tol)
    for spec, msg in (({}, "give its y"), ({"y": 0.2, "surface": "volume"},
                                           "surface volume has no 3-D form")):
        with pytest.raises(Exception, match=msg):
            registry.build("functionObject", {"type": "crestTracker", **spec}, {"dim": 3})
    for spec, dim, msg in (({"x": [0.1]}, 3, r"lines stand at points \(\(x y\) ...\), not x"),
                           ({"points": [[0.1, 0.2]]}, 2, "a 2-D case gives x"),
                           ({}, 3, "give the line positions points, or follow crest")):
        with pytest.raises(Exception, match=msg):
            registry.build("functionObject", {"type": "lines", **spec}, {"dim": dim})


def test_gauges_refuse_the_wrong_dimensions_positions(tmp_path):
    case = _case(tmp_path, "hydrostaticTank3D", "a", TANK3D,
                 "g { type waveGauges; x (0.2); }")
    with pytest.raises(CaseError, match=r"functions.g.*not x"):
        Case(case).validate()
    case = _case(tmp_path, "hydrostaticTank3D", "b", TANK3D,
                 "g { type waveGauges; points ((0.2 0.2)); surface volume; }")
    with pytest.raises(CaseError, match=r"surface volume has no 3-D form"):
        Case(case).validate()
    case = _case(tmp_path, "hydrostaticTank", "c", TANK2D,
                 "s { type slices; point (0.2 0.2); normal (0 1); size (0.4 0.4); }")
    with pytest.raises(CaseError, match=r"functionObject 'slices' has no 2-D form"):
        Case(case).validate()


# --- pressure sensors --------------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_pressure_sensors_read_hydrostatic_pressure(tmp_path, dim):
    """Sensors on the bed, a side wall and the block's top, each read 1.5 dx into the
    water: rho g (H - z) at the moved point within 1 % (measured: 0.3 % in 2-D at H/dx 20,
    0.8 % in 3-D at H/dx 10); a sensor above the water reads NaN (kernel sum < 0.5)."""
    if dim == 2:
        c, st = _setup(_case(tmp_path, "hydrostaticTank", "a", TANK2D))
        pts = [[0.1, 0.0], [0.06, 0.2], [0.25, 0.1], [0.1, 0.55]]
        nrm = [[0, 1], [1, 0], [0, 1], [0, 1]]
    else:
        c, st = _setup(_case(tmp_path, "hydrostaticTank3D", "a", TANK3D))
        pts = [[0.06, 0.2, 0.0], [0.0, 0.2, 0.2], [0.2, 0.2, 0.12], [0.2, 0.2, 0.55]]
        nrm = [[0, 0, 1], [1, 0, 0], [0, 0, 1], [0, 0, 1]]
    fo = _fo(c, {"type": "pressureSensors", "points": pts, "normals": nrm})
    moved = fo.sensor_points(c.context.dx)
    assert np.allclose(moved - np.asarray(pts), 1.5 * c.context.dx * np.asarray(nrm))
    p, ksum = fo.measure(st)
    want = RHO * G * (0.4 - moved[:3, -1])
    assert np.allclose(p[:3], want, rtol=0.01)
    assert np.all(ksum[:3] > 0.9) and np.isnan(p[3])


def test_pressure_sensors_need_one_normal_per_sensor(tmp_path):
    case = _case(tmp_path, "hydrostaticTank", "a", TANK2D,
                 "s { type pressureSensors; points ((0.1 0) (0.2 0)); normals ((0 1)); }")
    with pytest.raises(CaseError, match="1 normals for 2 points"):
        Case(case).validate()


# --- forces ------------------------------------------------------------------------------------
def test_forces_2d_on_a_wall_a_block_and_the_tank(tmp_path):
    """2-D, per metre: the left wall carries -rho g H^2/2 in x, the submerged block
    (0.1 x 0.1 m on the bed) -rho g (H - 0.1) 0.1 in y with its moment about the origin
    x_c F_y, and the three walls together the water's weight, all within 1 % (measured:
    0.28 %, 0.33 %, 0.38 %); horizontal forces of the tank and the left wall cancel."""
    c, st = _setup(_case(tmp_path, "hydrostaticTank", "a", TANK2D))
    r = {b: _fo(c, {"type": "forces", "patches": [b]}).measure(st)
         for b in ("left", "block", "tank")}
    H = 0.4
    assert r["left"][0, 0] == pytest.approx(-RHO * G * H**2 / 2, rel=0.01)
    assert r["block"][0, 1] == pytest.approx(-RHO * G * (H - 0.1) * 0.1, rel=0.01)
    assert abs(r["block"][0, 0]) < 1e-9
    assert r["block"][2, 2] == pytest.approx(0.25 * r["block"][0, 1], rel=1e-9)
    water = H * 0.5 - 0.01
    total = sum(v[0, 1] for v in r.values())
    assert total == pytest.approx(-RHO * G * water, rel=0.01)
    assert r["left"][0, 0] + r["tank"][0, 0] == pytest.approx(0.0, abs=1e-9)
    assert np.all(r["left"][:, 2][:2] == 0.0)    # 2-D: no z force
    both = _fo(c, {"type": "forces", "patches": ["left", "block"]}).measure(st)
    assert np.allclose(both, r["left"] + r["block"], rtol=1e-12, atol=1e-9)


def test_forces_viscous_part_is_zero_on_free_slip_stationary_ghosts(tmp_path):
    """The water moving along the bed at 0.3 m/s: stationary ghosts rub (a viscous force
    along the motion on the tank); with ``noSlip no`` they do not, and ``forces`` writes a
    viscous force of exactly 0 while the pressure force is the same."""
    c, st = _setup(_case(tmp_path, "hydrostaticTank", "a", TANK2D))
    st.u[st.kind == FLUID] = 0.3
    rub = _fo(c, {"type": "forces", "patches": ["tank"]}).measure(st)
    set_entry(c.path, "constant/sphProperties", "boundary.noSlip", False)
    c2 = Case(c.path)
    c2.validate()
    slip = _fo(c2, {"type": "forces", "patches": ["tank"]}).measure(st)
    assert rub[1, 0] > 1.0                                # N/m along the motion
    assert np.all(slip[1] == 0.0) and np.all(slip[3] == 0.0)
    assert np.array_equal(slip[0], rub[0])


BED2D = """dx 0.02;
fluid { water { type box; min (0 0); max (0.5 0.2); } }
walls {
  bed { type polyline; points ((-0.06 0) (0.56 0)); side right; layers 3; }
  sides { type box; min (0 -0.06); max (0.5 0.6); layers 3; open (top bottom); }
}
"""


def test_forces_on_free_slip_mdbc_walls_read_the_velocities_the_passes_see(tmp_path):
    """The water moving along the bed at 0.3 m/s over mDBC walls, ``forces`` on the bed
    through a simulation (``execute``, after a step): no slip the wall particles' velocity
    is zero and the bed rubs (a viscous force along the motion); free slip the passes give them the
    water's tangential velocity at their nodes, and ``forces`` sees the same: the bed's
    viscous force is gone but for the two corner columns, where a node across the corner
    takes the side wall's normal velocity (under a tenth of the no-slip force)."""
    from sphfoam.assemble import build_simulation

    out = {}
    for slip in (False, True):
        case = _case(tmp_path, "hydrostaticTank", f"s{int(slip)}", BED2D)
        set_entry(case, "constant/sphProperties", "boundary.type", "mDBC")
        if slip:
            set_entry(case, "constant/sphProperties", "boundary.noSlip", False)
        c, st = _setup(case)
        st.u[st.kind == FLUID] = 0.3
        sim = build_simulation(c, st)
        sim.step()                          # the neighbour list, and the nodes' lists
        fo = _fo(c, {"type": "forces", "patches": ["bed"]}, name=f"bed{int(slip)}")
        fo.execute(sim)
        fo.end()
        rows = np.loadtxt(fo.file)
        out[slip] = rows
        walls = sim.state.kind != FLUID
        assert np.all(sim.state.u[walls] == 0.0)            # put back after the measurement
    rub, free = out[False], out[True]
    assert rub[7] > 1.0                                      # viscous_x, N/m along the motion
    assert abs(free[7]) < 0.1 * rub[7]


def test_forces_3d_block_and_tank_and_the_output_through_a_run(tmp_path):
    """3-D at H/dx 10: the block (0.16 x 0.16 x 0.12 m on the bed) carries
    -rho g (H - 0.12) A_top in z within 1 % (measured 0.05 %), the tank and the block the
    water's weight within 1 % (measured 0.3 %); then a run writes force.dat and
    moment.dat in OpenFOAM's layout, every function object samples, ``sphfoam sample``
    gives the run's rows again and ``sphfoam plot`` draws each."""
    fns = """
    gauges { type waveGauges; points ((0.2 0.2)); writeControl writeTime; }
    probes { type probes; points ((0.2 0.2 0.2)); writeControl writeTime; }
    sensors { type pressureSensors; points ((0.06 0.2 0)); normal (0 0 1);
              writeControl writeTime; }
    blockForce { type forces; patches (block); CofR (0.2 0.2 0); writeControl writeTime; }
    slice { type slices; point (0.2 0.2 0.3); normal (0 1 0); size (0.4 0.6);
            writeControl writeTime; }
    profile { type lines; points ((0.06 0.06)); nPoints 6; writeControl writeTime; }
    wallRunUp { type runUp; mode wall; x 0.4; y 0.2; writeControl writeTime; }
    crest { type crestTracker; y 0.2; xMin 0.02; xMax 0.38; writeControl writeTime; }
"""
    case = _case(tmp_path, "hydrostaticTank3D", "a", TANK3D, fns)
    c, st = _setup(case)
    blk = _fo(c, {"type": "forces", "patches": ["block"]}).measure(st)
    tank = _fo(c, {"type": "forces", "patches": ["tank"]}).measure(st)
    A = 0.16 * 0.16
    assert blk[0, 2] == pytest.approx(-RHO * G * (0.4 - 0.12) * A, rel=0.01)
    assert np.abs(blk[0, :2]).max() < 1e-9
    weight = RHO * G * (0.4**3 - A * 0.12)
    assert blk[0, 2] + tank[0, 2] == pytest.approx(-weight, rel=0.01)

    sphfoam.run(case, progress=False)
    out = case / "postProcessing"
    lines = (out / "blockForce/0/force.dat").read_text().splitlines()
    assert lines[1].split() == ["#", "Time", "total_x", "total_y", "total_z", "pressure_x",
                                "pressure_y", "pressure_z", "viscous_x", "viscous_y",
                                "viscous_z"]
    force = np.loadtxt(out / "blockForce/0/force.dat", ndmin=2)
    moment = np.loadtxt(out / "blockForce/0/moment.dat", ndmin=2)
    assert force.shape == (3, 10) and moment.shape == (3, 10)
    assert np.allclose(force[:, 1:4], force[:, 4:7] + force[:, 7:10])
    assert np.allclose(force[:, 3], -RHO * G * (0.4 - 0.12) * A, rtol=0.02)
    assert np.abs(moment[:, 1:]).max() < 1e-9 * RHO     # about the block's axis
    vts = out / "slice/0/0.01/slice.vts"
    assert vts.is_file() and (out / "slice/0/slice.pvd").is_file()
    from sphfoam.postprocess import plot_case, read_vts, sample

    pts, (n1, n2), fields = read_vts(vts)
    assert (n1, n2) == (11, 16) and fields["U"].shape == (n1 * n2, 3)
    wet = np.isfinite(fields["p"])
    assert wet.any() and (~wet).any()
    assert not wet[pts[:, 2] > 0.45].any()                            # dry above the water
    deep = wet & (pts[:, 2] > 0.15) & (pts[:, 2] < 0.3)
    assert np.allclose(fields["p"][deep], RHO * G * (0.4 - pts[deep, 2]), rtol=0.03)
    before = {n: (out / n / "0" / f).read_text() for n, f in
              (("blockForce", "force.dat"), ("probes", "probes.dat"))}
    sample(case, log=lambda *a: None)
    for (n, f), text in zip((("blockForce", "force.dat"), ("probes", "probes.dat")),
                            before.values()):
        run_rows = np.loadtxt(text.splitlines(), ndmin=2)
        sampled = np.loadtxt(out / n / "0" / f, ndmin=2)
        assert np.allclose(sampled, run_rows, rtol=1e-6, atol=1e-9), n
    with (out / "profile/0/0.01/line.dat").open() as fh:
        head = [next(fh) for _ in range(2)]
    top = re.search(r"\(x y\) = \(0.06 0.06\), surface z = ([0-9.]+)", head[0])
    assert top and float(top.group(1)) == pytest.approx(0.4, abs=0.01 * 0.04), head[0]
    assert head[1].split() == ["#", "z", "Ux", "Uy", "Uz", "p"]
    prof = np.loadtxt(out / "profile/0/0.01/line.dat", ndmin=2)
    assert prof.shape == (6, 5) and prof[0, 0] == 0.0
    assert prof[-1, 0] == pytest.approx(float(top.group(1)))
    mid = (prof[:, 0] > 0.1) & (prof[:, 0] < 0.3)
    assert np.allclose(prof[mid, 4], RHO * G * (0.4 - prof[mid, 0]), rtol=0.03)
    run_up = np.loadtxt(out / "wallRunUp/0/wallRunUp.dat", ndmin=2)
    assert np.allclose(run_up[:, 1], 0.4, atol=0.01 * 0.04)      # still water at the wall
    said = []
    pngs = plot_case(case, log=said.append)
    names = {p.name for p in pngs}
    assert {"probes.png", "sensors.png", "blockForce.png", "slice.png", "profile.png",
            "wallRunUp.png"} <= names, said
