"""The modified dynamic boundary (mDBC, English et al. 2022): the ghost nodes the set-up
writes, the first-order fit at the node and its fall-back, the tank at rest, the refusals."""

from __future__ import annotations

import re

import numpy as np
import pytest

from conftest import sliding_layer

from sphfoam.case.case import Case
from sphfoam.case.times import list_times
from sphfoam.engine.state import FLUID, WALL
from sphfoam.io.fields import read_state
from sphfoam.models import mdbc
from sphfoam.models.kernels import WendlandC2
from sphfoam.setup import setup_case
from sphfoam.timeloop import run_case

RHO0, G = 1000.0, 9.81


def _fit(fluid, rho, wall, offset, dx, hdx=1.3, g=(0.0, 0.0, 0.0), vel=None, U0=None,
         corner=0.0):
    """mdbc.wall_density for one wall particle at ``wall`` with its ghost node at
    ``wall + offset``, over the fluid particles ``fluid`` (n, dim) of density ``rho`` and
    volume dx^dim (Wendland C2, Tait with gamma 7, B = 1e5, c0 = 10). With ``vel`` (dim, n),
    the fluid's velocities, the free-slip form: also the wall particle's velocity about the
    prescribed ``U0`` (zero by default)."""
    dim = fluid.shape[1]
    pos = np.vstack([fluid, wall[None, :]])
    n = len(pos)
    x, y = pos[:, 0].copy(), pos[:, 1].copy()
    z = pos[:, 2].copy() if dim == 3 else x[:0]
    m = np.append(rho * dx ** dim, 0.0)
    r = np.append(rho, RHO0)
    p, c = np.zeros(n), np.zeros(n)
    off = [np.array([v]) for v in offset] + ([] if dim == 3 else [x[:0]])
    kernel = WendlandC2()
    det_min = mdbc.MIN_DETERMINANT * mdbc.full_support_determinant(kernel, hdx, dim)
    slip = vel is not None
    if slip:
        uvw = [np.append(v, 0.0) for v in vel] + ([] if dim == 3 else [x[:0]])
        U = np.zeros((3, 1))
        U[:dim, 0] = U0 if U0 is not None else 0.0
        out = np.zeros((3, 1))
        extra = (True, *uvw, np.array([corner]), U, out)
    else:
        out = None
        extra = (False, x[:0], x[:0], x[:0], x[:0], np.zeros((3, 0)), np.zeros((3, 0)))
    mdbc.wall_density(np.array([n - 1]), *off, np.array([0, n - 1]), np.arange(n - 1), x, y,
                      z, m, r, p, c, 0.0, 0.0, 0.0, hdx * dx, kernel.support, kernel.f_jit,
                      det_min, RHO0, 1e5, 7.0, 10.0, *g, np.zeros((1, 4, 8)), *extra,
                      np.array([0, 1]))
    if slip:
        return r[-1], p[-1], c[-1], out[:dim, 0]
    return r[-1], p[-1], c[-1]


@pytest.mark.parametrize("dim", [2, 3])
def test_the_fit_at_the_ghost_node_extrapolates_a_linear_density_exactly(dim):
    """English et al. (2022) eq. (10): a density linear in space, sampled by the fluid
    above a wall (half the node's support empty), is extrapolated to the wall particle
    dx/2 behind the wall exactly (to round-off), as a hydrostatic column's is; p and c
    follow from Tait's equation; an extrapolated density below rho0 is held at rho0."""
    dx = 0.1
    k = np.arange(-6, 7) * dx
    up = (np.arange(6) + 0.5) * dx
    grids = np.meshgrid(*([k] * (dim - 1) + [up]), indexing="ij")
    fluid = np.column_stack([g.ravel() for g in grids])
    grad = np.array([3.0, 5.0, -7.0][:dim] if dim == 3 else [3.0, -5.0])
    rho = RHO0 + fluid @ grad
    wall = np.zeros(dim)
    wall[-1] = -0.5 * dx
    offset = np.zeros(dim)
    offset[-1] = dx
    r, p, c = _fit(fluid, rho, wall, offset, dx)
    assert RHO0 + wall @ grad > RHO0
    assert r == pytest.approx(RHO0 + wall @ grad, abs=1e-9)
    assert p == pytest.approx(1e5 * ((r / RHO0) ** 7 - 1.0), rel=1e-12)
    assert c == pytest.approx(10.0 * (r / RHO0) ** 3, rel=1e-12)
    # the density falling towards the wall below rho0: the wall is held at rho0 (no pull)
    r, p, _ = _fit(fluid, RHO0 + 0.1 - fluid @ grad, wall, offset, dx)
    assert r == RHO0 and p == 0.0


def test_a_node_at_the_edge_of_the_water_takes_the_hydrostatic_zeroth_order():
    """Two fluid particles in the node's support cannot carry a linear fit in 2-D (the
    moment matrix is singular): the particle takes the node's zeroth order of the pressure
    continued hydrostatically to it (AHA12 eq. (27) weighted at the node): the mean of the
    two (equally weighted) p_f + rho_f g (y_f - y_w); with no fluid in its support it is
    left at rho0."""
    dx = 0.1
    fluid = np.array([[0.0, 0.05], [0.1, 0.05]])
    rho = np.array([1001.0, 1003.0])
    r, p, _ = _fit(fluid, rho, np.array([0.05, -0.05]), (0.0, 0.1), dx, g=(0.0, -9.81, 0.0))
    pf = 1e5 * ((rho / RHO0) ** 7 - 1.0)
    assert p == pytest.approx(np.mean(pf + rho * 9.81 * 0.1), rel=1e-12)
    assert r == pytest.approx(RHO0 * (1.0 + p / 1e5) ** (1.0 / 7.0), rel=1e-14)
    r, _, _ = _fit(fluid, rho, np.array([5.0, -0.05]), (0.0, 0.1), dx)
    assert r == RHO0


def _free_slip(ug, U, n):
    """The free-slip wall velocity: the node's tangential part; its normal part mirrored
    about the wall's where the water approaches (dn < 0), the wall's where it leaves."""
    dn = (ug - U) @ n
    return ug - (2.0 if dn < 0.0 else 1.0) * dn * n


@pytest.mark.parametrize("dim", [2, 3])
def test_free_slip_gives_the_wall_the_nodes_tangential_velocity(dim):
    """``noSlip no``: the fluid's velocity, linear in space, is fitted at the ghost node
    exactly (to round-off); the wall particle takes its tangential part, and its normal
    part mirrored about the wall's prescribed velocity U where the water approaches the
    wall (2-D here) and U's own where it leaves (3-D here); across a tilted wall (2-D) the
    same along its normal; behind an edge or corner (``corner`` 1) each component along
    the node's offset likewise."""
    dx = 0.1
    k = np.arange(-6, 7) * dx
    up = (np.arange(6) + 0.5) * dx
    grids = np.meshgrid(*([k] * (dim - 1) + [up]), indexing="ij")
    fluid = np.column_stack([g.ravel() for g in grids])
    rho = np.full(len(fluid), RHO0)
    base = np.array([0.3, -0.2, 0.4][:dim])
    grad = np.array([[0.5, -1.0, 2.0], [1.5, 0.25, -0.5], [-2.0, 1.0, 0.75]])[:dim, :dim]
    vel = (base[:, None] + grad @ fluid.T)
    wall = np.zeros(dim)
    wall[-1] = -0.5 * dx
    offset = np.zeros(dim)
    offset[-1] = dx
    n = offset / dx
    ug = base + grad @ (wall + offset)
    assert (ug[-1] < 0.0) == (dim == 2)          # 2-D: towards the wall; 3-D: away from it
    _, _, _, uw = _fit(fluid, rho, wall, offset, dx, vel=vel)
    np.testing.assert_allclose(uw, _free_slip(ug, 0.0 * ug, n), atol=1e-12)
    assert uw[-1] == pytest.approx(-ug[-1] if dim == 2 else 0.0, abs=1e-12)
    # a wall moving with U: about U's normal component
    U = np.array([0.1, 0.2, -0.05][:dim])
    _, _, _, uw = _fit(fluid, rho, wall, offset, dx, vel=vel, U0=U)
    np.testing.assert_allclose(uw, _free_slip(ug, U, n), atol=1e-12)
    # the no-slip form leaves the density's fit as it was
    r0 = _fit(fluid, rho + fluid @ np.ones(dim), wall, offset, dx)[0]
    r1 = _fit(fluid, rho + fluid @ np.ones(dim), wall, offset, dx, vel=vel)[0]
    assert r0 == r1
    if dim == 2:
        # a wall tilted by 30 degrees, both ways: the node along its unit normal n
        for sign in (1.0, -1.0):
            n = np.array([-sign * np.sin(np.pi / 6), np.cos(np.pi / 6)])
            off = 0.5 * dx * n
            w0 = -0.5 * off
            _, _, _, uw = _fit(fluid, rho, w0, off, dx, vel=vel)
            np.testing.assert_allclose(uw, _free_slip(base + grad @ (w0 + off), 0 * n, n),
                                       atol=1e-12)
    # behind an edge (a corner in 2-D): the node across both planes, each component
    offset = np.zeros(dim)
    offset[-1] = dx
    offset[0] = dx
    wall = np.zeros(dim)
    wall[-1] = -0.5 * dx
    wall[0] = -6.0 * dx - 0.5 * dx
    _, _, _, uw = _fit(fluid, rho, wall, offset, dx, vel=vel, corner=1.0)
    ug = base + grad @ (wall + offset)
    expect = ug.copy()
    for c in (0, dim - 1):
        expect[c] = -ug[c] if ug[c] < 0.0 else 0.0
    np.testing.assert_allclose(uw, expect, atol=1e-12)


def _edit(path, pattern, repl):
    text = path.read_text()
    new, n = re.subn(pattern, repl, text, count=1)
    assert n == 1, pattern
    path.write_text(new)


def _mdbc_3d(tutorial, regions: str):
    """hydrostaticTank3D with mDBC walls and the particleDict (dx = 0.05 m) holding
    ``regions`` (its fluid and walls entries)."""
    case = tutorial("hydrostaticTank3D")
    _edit(case / "constant" / "sphProperties", r"type\s+stationaryGhosts;", "type mDBC;")
    (case / "system" / "particleDict").write_text(
        "FoamFile { version 2.0; format ascii; class dictionary; object particleDict; }\n"
        "dimension 3; dx 0.05;\n" + regions)
    return case


def test_3d_ghost_nodes_mirror_each_wall_particle_across_the_wall(tutorial):
    """The set-up's ghost nodes in 3-D: a tank's face particle is mirrored across its face
    (the node as far in front as the particle is behind), an edge or vertex particle across
    the edge or vertex (diagonally); a block on the floor mirrors across its own nearest
    face, never its bottom (which stands on the floor)."""
    from sphfoam.setup.initial import generate_case

    case = _mdbc_3d(tutorial,
                    "fluid { water { type box; min (0.35 0 0); max (0.6 0.6 0.2); } }\n"
                    "walls {\n"
                    "    tank  { type box; min (0 0 0); max (0.6 0.6 0.4); layers 3; open top; }\n"
                    "    block { type block; min (0.1 0.1 0); max (0.3 0.3 0.15); layers 3; }\n"
                    "}\n")
    st = generate_case(Case(case))
    w = st.kind == WALL
    pos = np.column_stack(st.positions)[w]
    g = np.column_stack([st.extra[k][w] for k in ("ghostX", "ghostY", "ghostZ")])
    h = 0.025
    floor = np.isclose(pos[:, 2], -5 * h) & (np.abs(pos[:, :2] - 0.425) < 0.03).all(axis=1)
    assert floor.any() and np.allclose(g[floor], [0, 0, 10 * h])
    edge = np.isclose(pos[:, 2], -h) & np.isclose(pos[:, 0], -3 * h) & \
        (np.abs(pos[:, 1] - 0.4) < 0.08)
    assert edge.any() and np.allclose(g[edge], [6 * h, 0, 2 * h])
    vertex = np.isclose(pos, [0.6 + h, -h, -h]).all(axis=1)
    assert np.allclose(g[vertex], [-2 * h, 2 * h, 2 * h])
    block = (pos[:, :2] > 0.1).all(axis=1) & (pos[:, :2] < 0.3).all(axis=1) & \
        (pos[:, 2] > 0)
    assert block.any() and not (g[block][:, 2] < 0).any()          # never into the floor
    top = block & np.isclose(pos[:, 2], 0.15 - h) & \
        (np.abs(pos[:, :2] - 0.2) < 0.03).all(axis=1)
    assert top.sum() == 4 and np.allclose(g[top], [0, 0, 2 * h])
    side = block & np.isclose(pos[:, 0], 0.3 - h) & np.isclose(pos[:, 2], 3 * h) & \
        (np.abs(pos[:, 1] - 0.2) < 0.03)
    assert side.sum() == 2 and np.allclose(g[side], [2 * h, 0, 0])
    # every first-layer particle's node lies in front of the wall: outside the tank's walls
    # and the block, except the floor's under the block (a deeper layer's node may lie in
    # another wall: it sees no water)
    node = pos + g
    faced = np.linalg.norm(g, axis=1) < 1.01 * np.sqrt(3.0) * 0.05
    inside = (node[faced] > 0).all(axis=1) & (node[faced, :2] < 0.6).all(axis=1)
    in_block = (node[faced] > [0.1, 0.1, -1]).all(axis=1) & \
        (node[faced] < [0.3, 0.3, 0.15]).all(axis=1)
    under_block = (pos[faced, :2] > 0.1).all(axis=1) & (pos[faced, :2] < 0.3).all(axis=1) \
        & (pos[faced, 2] < 0)                   # the floor under the block: no water there
    assert (inside & ~in_block | under_block).all()


def test_mdbc_refuses_3d_walls_without_ghost_nodes_by_name(tutorial):
    """The 3-D set-up writes ghost nodes for box tanks and blocks (plane faces): a cylinder
    wall with mDBC is refused, naming the file, the wall and the model."""
    from sphfoam.case.errors import CaseError

    case = _mdbc_3d(tutorial,
                    "fluid { w { type box; min (0 0 0); max (0.4 0.4 0.2); } }\n"
                    "walls { tank { type box; min (0 0 0); max (0.4 0.4 0.4); }\n"
                    "        post { type cylinder; point1 (0.2 0.2 0); point2 (0.2 0.2 0.3); "
                    "radius 0.05; } }\n")
    with pytest.raises(CaseError, match=r"system/particleDict.*walls.post.type: mDBC reads "
                                        r"ghost nodes, which the 3-D set-up writes for box "
                                        r"and block walls only"):
        setup_case(Case(case), log=lambda m: None)


def test_a_2d_tank_rests_on_mdbc_walls_without_the_dynamic_boundarys_gap(tutorial):
    """The hydrostatic tank (H/dx = 20, 0.5 s) on mDBC walls: nobody in a wall; the water
    rests against the bed (its lowest row within 0.7 dx of the bed, the first wall row
    dx/2 behind it: the wall's pressure is the water's continued through it); the bed
    pressure within 2 % of rho g H; the first wall row's pressure the column's continued
    to it, rho g (H + dx/2), within 3 %; the wall velocity zero."""
    from sphfoam.sampling.hydrostatic import bed_pressure

    dx, Hw, W = 0.02, 0.4, 0.5
    case = tutorial("hydrostaticTank", {"constant/sphProperties:boundary.type": "mDBC",
                                        "system/particleDict:dx": dx,
                                        "system/controlDict:endTime": 0.5,
                                        "system/controlDict:writeInterval": 0.25})
    setup_case(Case(case), log=lambda m: None)
    rep = run_case(case, progress=False, echo=None)
    assert rep.removed == 0
    for t, folder in list_times(case)[1:]:
        s = read_state(folder)
        f = s["type"] == FLUID
        x, y = s["positions"][f].T
        assert x.min() > 0 and x.max() < W and y.min() > 0, f"a particle in a wall at t={t}"
    mid = np.abs(x - 0.25) < 0.15
    assert y[mid].min() < 0.7 * dx
    bed = bed_pressure(x, y, s["p"][f], x0=0.0, width=W, depth=Hw, reach=2.6 * dx, dx=dx)[0]
    assert bed == pytest.approx(RHO0 * G * Hw, rel=0.02)
    w = s["type"] == WALL
    xw, yw = s["positions"][w].T
    first = np.isclose(yw, -0.5 * dx) & (np.abs(xw - 0.25) < 0.15)
    assert s["p"][w][first].mean() == pytest.approx(RHO0 * G * (Hw + 0.5 * dx), rel=0.03)
    assert (s["U"][w] == 0.0).all()


def test_a_3d_tank_on_mdbc_walls_holds_the_column(tutorial):
    """hydrostaticTank3D at H/dx = 10 on mDBC walls (ghost nodes across faces, edges and
    vertices) to 0.3 s, written every 0.025 s: the bed pressure (the line through the
    column's pressure, as bedPressure.py) averages within 1.5 % of rho g H (+0.9 % measured)
    and stays within 3 % at every written time (an acoustic oscillation of about 2 %,
    against 0.5 % on the stationary ghosts and 0.9 % on Adami's walls); the water stays
    at rest against the bed (its lowest particle within 0.55 dx of it; the fastest, at the
    surface's corners, below 3 % of sqrt(g H): 0.040 m/s measured)."""
    dx, Hw = 0.04, 0.4
    case = tutorial("hydrostaticTank3D", {"constant/sphProperties:boundary.type": "mDBC",
                                          "system/particleDict:dx": dx,
                                          "system/controlDict:endTime": 0.3,
                                          "system/controlDict:writeInterval": 0.025})
    setup_case(Case(case), log=lambda m: None)
    rep = run_case(case, progress=False, echo=None)
    assert rep.removed == 0
    beds = []
    for _, folder in list_times(case)[1:]:
        f = read_state(folder, dim=3)
        fluid = f["type"] == FLUID
        x, y, z = f["positions"][fluid].T
        mid = (np.abs(x - 0.2) < 0.1) & (np.abs(y - 0.2) < 0.1) & (z > 0.052) & (z < 0.2)
        beds.append(np.polyfit(z[mid], f["p"][fluid][mid], 1)[1] / (RHO0 * G * Hw))
        assert z.min() > 0.45 * dx
        assert np.abs(f["U"][fluid]).max() < 0.03 * np.sqrt(G * Hw)
    assert len(beds) == 12
    assert np.mean(beds) == pytest.approx(1.0, abs=0.015)
    assert np.all(np.abs(np.array(beds) - 1.0) < 0.03)


@pytest.mark.parametrize("no_slip", [True, False], ids=["noSlip", "freeSlip"])
@pytest.mark.parametrize("integrator", ["monaghan2007", "predictorCorrector", "verlet",
                                        "symplectic"])
def test_mdbc_walls_hold_the_dam_break_under_each_integrator(tutorial, integrator, no_slip):
    """The dam break at H0/dx = 10 to 0.15 s on mDBC walls, no-slip and free slip, under
    each integrator (the hooks run before every equation of state, rates and density pass;
    free slip sets the wall velocities for the pair passes and puts them back after): no
    water leaves, nobody crosses the bed or the end walls, and the wall particles stay where
    they were set up with their velocity zero (as written), bit for bit."""
    case = tutorial("damBreak", {
        "constant/sphProperties:boundary": {"type": "mDBC", "noSlip": no_slip},
        "system/sphSchemes:integrator": {"type": integrator},
        "system/particleDict:dx": 0.025,
        "system/controlDict:endTime": 0.15,
        "system/controlDict:writeInterval": 0.15})
    setup_case(Case(case), log=lambda m: None)
    rep = run_case(case, progress=False, echo=None)
    assert rep.removed == 0
    times = list_times(case)
    s0, s1 = read_state(times[0][1]), read_state(times[-1][1])
    assert times[-1][0] == pytest.approx(0.15)
    w0, w1 = s0["type"] == WALL, s1["type"] == WALL
    x0 = s0["positions"][w0][np.argsort(s0["origId"][w0])]
    x1 = s1["positions"][w1][np.argsort(s1["origId"][w1])]
    assert np.array_equal(x0, x1) and (s1["U"][w1] == 0.0).all()
    f = s1["type"] == FLUID
    x, y = s1["positions"][f].T
    assert y.min() > 0.0 and x.min() > 0.0


def test_balanced_chunks_split_the_walls_into_runs_of_equal_work():
    """The fit's and the lists' parallel loops take contiguous runs of wall particles with
    about equal work: every wall particle once, in order, whatever the lists hold."""
    rng = np.random.default_rng(3)
    counts = np.where(rng.uniform(size=1000) < 0.4, rng.integers(20, 80, 1000), 0)
    counts[:500] = 0                                       # a dry half, as in a tank
    starts = np.concatenate([[0], np.cumsum(counts)])
    for parts in (1, 2, 64, 5000):
        b = mdbc.balanced_chunks(starts, parts)
        assert b[0] == 0 and b[-1] == 1000 and np.all(np.diff(b) >= 0) and len(b) == parts + 1
    b = mdbc.balanced_chunks(starts, 2)
    work = starts + 8 * np.arange(1001)
    assert abs(work[b[1]] - work[-1] / 2) <= 80 + 8        # within one wall of the half
    assert b[1] > 600                                      # not the plain split at 500
    assert np.array_equal(mdbc.balanced_chunks(np.zeros(1, dtype=np.int64), 4), [0] * 5)


@pytest.mark.parametrize("no_slip", ["yes", "no"])
def test_backend_cuda_serves_mdbc_in_both_dimensions(tutorial, no_slip):
    """mDBC's device form (sphfoam.models.mdbc_cuda) stands for every hook the model
    implements, with and without slip, in 2-D and 3-D: backend cuda refuses nothing (the
    fields against the CPU: tests/test_cuda_backend.py)."""
    from sphfoam.assemble import selection
    from sphfoam.engine.cuda.build import refusals
    from sphfoam.engine.cuda.forms import covered_hooks

    for name in ("damBreak", "damBreak3D"):
        sel = selection(Case(tutorial(name, {
            "constant/sphProperties:boundary": {"type": "mDBC", "noSlip": no_slip}})))
        assert refusals(sel) == []
        bnd = sel.boundary
        hooks = {h for h in covered_hooks(bnd) if bnd.implements(h)}
        slip = {"before_passes", "after_rates", "after_density_rate"}
        assert hooks == {"attach", "after_sort", "before_evaluation"} | (
            slip if no_slip == "no" else set())


@pytest.mark.parametrize("no_slip", [True, False], ids=["noSlip", "freeSlip"])
def test_free_slip_mdbc_keeps_a_sliding_layers_momentum(no_slip):
    """A layer 10 dx deep sliding at 0.5 m/s over three rows of mDBC wall particles,
    periodic along the bed, no gravity, artificial viscosity 0.1, 300 steps (as the
    stationary ghosts' test in test_boundaries.py). No slip (the walls' velocity zero in
    the viscous term) the wall rubs: the layer loses 3-7 % of its momentum (4 %). Free slip
    the wall particles take the fluid's tangential velocity at their nodes: the tangential
    difference is gone from every pair and the momentum is kept to 1e-5; the walls stay put
    (the integrator moves them with the prescribed velocity, zero)."""
    def ghosts(x, y, wall):                 # the floor y = 0: the node at -y across it
        return {"ghostX": np.zeros(x.size), "ghostY": np.where(wall, -2.0 * y, 0.0),
                "corner": np.zeros(x.size)}

    kept, s, x, y = sliding_layer({"type": "mDBC", "noSlip": no_slip}, ghosts)
    if no_slip:
        assert 0.93 < kept < 0.98
    else:
        assert abs(kept - 1.0) < 1e-5
    walls = s.kind == WALL
    assert np.all(s.x[walls] == x[s.id[walls]]) and np.all(s.y[walls] == y[s.id[walls]])
    assert np.all(s.u[walls] == 0.0) and np.all(s.v[walls] == 0.0)
