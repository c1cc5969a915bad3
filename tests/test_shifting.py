"""Particle shifting (sphfoam/models/shifting.py), issue 13: Lind et al. (2012) and the
delta+-SPH form of Sun et al. (2017), with Marrone et al. (2010)'s free-surface detection.

* a uniform lattice in a periodic box is not shifted;
* a perturbed lattice becomes more uniform (the spread of nearest-neighbour distances shrinks);
* at a flat free surface the shift has no normal component (and has one without the surface
  rule, so the check can fail);
* the shift moves positions only: the velocities are untouched and momentum is conserved over
  steps; beside XSPH the advection velocity is v + dv_XSPH + delta_u.

Two pipelines are compiled: deltaPlusShifting alone, and XSPH with lindShifting, both in a
periodic box (a slab with empty space above and below gives two flat free surfaces).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from sphfoam import registry
from sphfoam.engine.build import build_pipeline
from sphfoam.engine.plan import Selection
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import ParticleState
from sphfoam.models.base import CaseContext

DX, HDX, NX = 0.01, 1.3, 16
H = HDX * DX
L = NX * DX                    # periodic box L x 2L
C0 = 10.0
SPECS = dict(kernel={"type": "quartic"}, equationOfState={"type": "tait", "speedOfSound": C0},
             continuity={"type": "differenceForm"}, momentum={"type": "symmetric"},
             viscosity={"type": "artificial", "alpha": 0.1},
             boundary={"type": "stationaryGhosts"})
CTX = CaseContext(dx=DX, h=H, rho0=1000.0, nu=1e-6, g=(0.0, 0.0), fluid_height=L, c0=C0)


class Box:
    def __init__(self, shifting: dict, vc: str = "none"):
        models = {f: registry.build(f, s) for f, s in SPECS.items()}
        self.sel = Selection(**models,
                             velocityCorrection=registry.build("velocityCorrection",
                                                               {"type": vc}),
                             particleShifting=registry.build("particleShifting", shifting),
                             periodic_x=True, periodic_y=True)
        self.kappa = models["kernel"].support
        self.pipe = build_pipeline(self.sel, CTX, domain_hi=(L, 2 * L))

    def sim(self, x, y, u=None, v=None):
        n = x.size
        u = np.zeros(n) if u is None else u
        v = np.zeros(n) if v is None else v
        st = ParticleState(x, y, u, v, np.full(n, 1000.0), np.full(n, 1000.0 * DX * DX),
                           np.zeros(n, dtype=np.int64))
        sim = Simulation(st, self.pipe, registry.build("integrator", {"type": "monaghan2007"}),
                         h=H, support=self.kappa, domain_lo=(0, 0), domain_hi=(L, 2 * L),
                         beta=0.2, force_condition=True, adjust_time_step=True, delta_t=1e-4)
        self.evaluate(sim)
        return sim

    @staticmethod
    def evaluate(sim):
        sim.neighbour_update()
        sim.step_pass()
        sim.eos()
        sim.rates()

    def shift(self, sim):
        a = sim.aux
        return a[self.pipe.aux_index("shift_du")], a[self.pipe.aux_index("shift_dv")]


@pytest.fixture(scope="module")
def dplus():
    return Box({"type": "deltaPlusShifting"})


@pytest.fixture(scope="module")
def lind():
    return Box({"type": "lindShifting"}, vc="xsph")


def lattice(rows=2 * NX, y0=0.0):
    xs = (np.arange(NX) + 0.5) * DX
    ys = y0 + (np.arange(rows) + 0.5) * DX
    X, Y = np.meshgrid(xs, ys)
    return X.ravel(), Y.ravel()


def perturbed(seed=0, amp=0.2):
    x, y = lattice()
    rng = np.random.default_rng(seed)
    return (x + rng.uniform(-amp, amp, x.size) * DX, y + rng.uniform(-amp, amp, x.size) * DX)


def nn_spread(st):
    d, _ = cKDTree(np.column_stack([st.x, st.y]), boxsize=(L, 2 * L)).query(
        np.column_stack([st.x, st.y]), k=2)
    return np.std(d[:, 1]) / DX


def test_uniform_lattice_is_not_shifted(dplus, lind):
    x, y = lattice()
    sim = dplus.sim(x, y)
    du, dv = dplus.shift(sim)
    assert np.abs(du).max() < 1e-10 * C0 and np.abs(dv).max() < 1e-10 * C0
    # interior everywhere: lambda = 1 to the kernel's discrete normalisation
    lam = sim.aux[dplus.pipe.aux_index("shift_lambda")]
    assert np.allclose(lam, lam[0]) and abs(lam[0] - 1.0) < 0.02
    # Lind's shift with XSPH in a uniform stream: the advection velocity is the stream's
    u0 = np.full(x.size, 0.7)
    sim = lind.sim(x, y, u=u0)
    pu, pv = sim.position_velocity(sim.state.u, sim.state.v)
    assert np.allclose(pu, 0.7, rtol=0, atol=1e-12) and np.abs(pv).max() < 1e-12


def _relax(box, sim, dt, steps):
    for _ in range(steps):
        st = sim.state
        pu, pv = sim.position_velocity(st.u, st.v)
        st.x += dt * (pu - st.u)           # the shift alone (the stream carries all alike)
        st.y += dt * (pv - st.v)
        box.evaluate(sim)


def test_delta_plus_makes_a_perturbed_lattice_more_uniform(dplus):
    sim = dplus.sim(*perturbed(1))
    s0 = nn_spread(sim.state)
    du, dv = dplus.shift(sim)
    assert np.hypot(du, dv).max() > 0.0
    _relax(dplus, sim, 0.2 * H / C0, 40)    # CFL 0.2 steps
    assert nn_spread(sim.state) < 0.6 * s0, (s0, nn_spread(sim.state))


def test_lind_makes_a_perturbed_lattice_more_uniform(lind):
    x, y = perturbed(2)
    u0 = np.full(x.size, 1.0)
    sim = lind.sim(x, y, u=u0)
    s0 = nn_spread(sim.state)
    _relax(lind, sim, 0.1 * H / 1.0, 40)
    assert nn_spread(sim.state) < 0.6 * s0, (s0, nn_spread(sim.state))
    # a particle at rest is not shifted by Lind's D = A h |v| dt (XSPH of a fluid at rest: 0)
    sim0 = lind.sim(x, y)
    pu, pv = sim0.position_velocity(sim0.state.u, sim0.state.v)
    assert np.all(pu == 0.0) and np.all(pv == 0.0)


def test_flat_free_surface_is_shifted_only_tangentially(dplus):
    """A slab of 10 rows in the middle of the 2L-tall box: two flat free surfaces, perturbed
    in x only, so the shift has a tangential part everywhere and a normal one at the surfaces
    (without the surface rule)."""
    x, y = lattice(rows=10, y0=0.5 * L)
    rng = np.random.default_rng(4)
    x = x + rng.uniform(-0.15, 0.15, x.size) * DX
    sim = dplus.sim(x, y)
    st = sim.state
    lam = sim.aux[dplus.pipe.aux_index("shift_lambda")]
    ny = sim.aux[dplus.pipe.aux_index("shift_ny")]
    top = st.y > y.max() - 0.5 * DX
    bottom = st.y < y.min() + 0.5 * DX
    mid = np.abs(st.y - 0.5 * (y.min() + y.max())) < 1.1 * DX
    # Marrone et al.'s detection: the surface rows are below the interior bound, the middle
    # of the slab is not; the normals point out of the fluid
    assert lam[top].max() < 0.75 and lam[bottom].max() < 0.75 and lam[mid].min() > 0.75
    assert np.all(ny[top] > 0.9) and np.all(ny[bottom] < -0.9)
    du, dv = dplus.shift(sim)
    near = np.abs(st.y - 0.5 * (y.min() + y.max())) > 2.1 * DX   # rows 0-2 from a surface
    assert np.abs(du[near]).max() > 0.0
    # only tangential near the surface; the normal direction per particle is its own n
    nx = sim.aux[dplus.pipe.aux_index("shift_nx")]
    assert np.abs(du * nx + dv * ny)[near].max() < 1e-12 * np.abs(du).max()
    # without the surface rule the surface rows are pushed outwards: the check can fail
    free = Box({"type": "deltaPlusShifting", "surfaceLambda": 0.0})
    sim_f = free.sim(x, y)
    dvf = free.shift(sim_f)[1]
    tf = sim_f.state.y > y.max() - 0.5 * DX
    assert dvf[tf].min() > 0.1 * np.abs(du).max()


def test_free_surface_rows_below_free_surface_lambda_are_not_shifted(dplus):
    """freeSurfaceLambda: a particle whose own lambda is below it (a flat surface's first
    row, lambda about 0.5) keeps its place; every other particle gets the shift it gets
    without the option (tangential near the surface, full inside)."""
    x, y = lattice(rows=10, y0=0.5 * L)
    rng = np.random.default_rng(4)
    x = x + rng.uniform(-0.15, 0.15, x.size) * DX
    y = y + rng.uniform(-0.05, 0.05, x.size) * DX
    frozen = Box({"type": "deltaPlusShifting", "freeSurfaceLambda": 0.55})
    sim_d, sim_f = dplus.sim(x, y), frozen.sim(x, y)
    assert np.array_equal(sim_d.state.x, sim_f.state.x)          # the same order
    lam = sim_f.aux[frozen.pipe.aux_index("shift_lambda")]
    du_d, dv_d = dplus.shift(sim_d)
    du_f, dv_f = frozen.shift(sim_f)
    surface = lam < 0.55
    top = sim_f.state.y > y.max() - 0.5 * DX
    assert np.all(surface[top]) and surface.sum() < 0.4 * x.size
    assert np.all(du_f[surface] == 0.0) and np.all(dv_f[surface] == 0.0)
    assert np.abs(du_d[surface]).max() > 0.0                          # what it undoes
    assert np.array_equal(du_f[~surface], du_d[~surface])
    assert np.array_equal(dv_f[~surface], dv_d[~surface])


def test_shifting_moves_positions_only_and_conserves_momentum(lind):
    x, y = perturbed(3)
    rng = np.random.default_rng(3)
    u, v = rng.normal(0, 0.3, x.size), rng.normal(0, 0.3, x.size)
    sim = lind.sim(x, y, u.copy(), v.copy())
    st = sim.state
    u_before, v_before = st.u.copy(), st.v.copy()
    pu, pv = sim.position_velocity(st.u, st.v)
    assert np.array_equal(st.u, u_before) and np.array_equal(st.v, v_before)
    # beside XSPH: v + dv_XSPH + delta_u, in selection order
    a = sim.aux
    idx = lind.pipe.aux_index
    assert np.allclose(pu, st.u + a[idx("xsph_du")] + a[idx("shift_du")], rtol=0, atol=1e-14)
    assert np.allclose(pv, st.v + a[idx("xsph_dv")] + a[idx("shift_dv")], rtol=0, atol=1e-14)
    assert np.abs(a[idx("shift_du")]).max() > 1e-3 * np.abs(st.u).max()
    mom = lambda s: np.array([np.sum(s.m * s.u), np.sum(s.m * s.v)])  # noqa: E731
    p0 = mom(st)
    scale = np.sum(st.m * np.hypot(st.u, st.v))
    for _ in range(20):
        sim.step()
    assert np.abs(mom(sim.state) - p0).max() < 1e-12 * scale


def test_tank_runs_with_shifting_beside_xsph_and_renormalised_diffusion(tutorial):
    """The hydrostaticTank case selecting the new words in constant/sphProperties (the case
    layer, the runner and the log): 0.1 s at H/dx = 8 stays at rest and in the tank."""
    import math

    from sphfoam.case.times import list_times
    from sphfoam.io.fields import read_state
    from sphfoam.timeloop import run_case

    case = tutorial("hydrostaticTank", {
        "constant/sphProperties:densityFilter": {"type": "antuonoDeltaSPH"},
        "constant/sphProperties:velocityCorrection": {"type": "xsph"},
        "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting"},
        "system/particleDict:dx": 0.05, "system/controlDict:endTime": 0.1,
        "system/controlDict:writeInterval": 0.1})
    rep = run_case(case, progress=False, echo=None)
    assert rep.removed == 0
    log = (case / "log.sphfoam").read_text()
    assert "particleShifting=deltaPlusShifting" in log and "velocityCorrection=xsph" in log
    s = read_state(list_times(case)[-1][1])
    f = s["type"] == 0
    assert np.all(np.isfinite(s["positions"]))
    x, y = s["positions"][f].T
    assert x.min() > 0 and x.max() < 0.5 and y.min() > 0
    assert np.sqrt((s["U"][f] ** 2).sum(axis=1)).max() < 0.05 * math.sqrt(9.81 * 0.4)


def test_contract_extensions_step_terms_for_fluid_and_composed_advection(dplus, lind):
    """The two generic extensions the shifting needs: a ``step`` term applying to ``fluid``
    runs for fluid particles (before, the step pass ran for walls only and such a term was
    silently dropped); several ``advection_velocity`` hooks compose in selection order."""
    src = lind.pipe.source_path.read_text()
    step = src[src.index("def step_pass"):]
    assert "if kind[a] == FLUID:" in step.split("\ndef ")[0] and "shift_mxx" in step
    # without a fluid step term the step pass keeps its wall-only form (hybrid's)
    models = {f: registry.build(f, s) for f, s in SPECS.items()}
    models["boundary"] = registry.build("boundary", {"type": "hybrid"})
    names = ["h", "inv_h", "support2", "eta2", "gx", "gy"]
    for mdl in Selection(**models).models():
        names += list(mdl.params(CTX))
    from sphfoam.engine.emit_cpu import generate_source
    hyb = generate_source(Selection(**models), names)
    hstep = hyb[hyb.index("def step_pass"):].split("\ndef ")[0]
    assert "if kind[a] != FLUID:" in hstep and "kind[a] == FLUID" not in hstep
    # composition: XSPH's hook first, then the shifting's
    hooks = lind.sel.hooks("advection_velocity")
    assert [h.__self__.family for h in hooks] == ["velocityCorrection", "particleShifting"]


def test_velocity_correction_adds_the_shift_along_the_velocity_gradient(dplus):
    """correctVelocity: du_a/dt += (delta_u_a . grad) u_a (Lind et al. 2012's Taylor correction
    as an ALE term); grad u from the fluid neighbours, right for a smooth field to within the
    lattice's quadrature (8 % here: a lattice perturbed by 0.05 dx and the quartic kernel's
    discrete normalisation; a wrong sign or a missing component is 50-200 % off), and nothing
    else in the rates changes."""
    corr = Box({"type": "deltaPlusShifting", "correctVelocity": True})
    x, y = perturbed(5, amp=0.05)
    k1, k2 = 2 * np.pi / (2 * L), 2 * np.pi / L        # periodic in the box L x 2L
    u = 0.3 * np.sin(k1 * y) + 0.1 * np.cos(k2 * x)
    v = 0.2 * np.sin(k2 * x) - 0.1 * np.cos(k1 * y)
    plain = dplus.sim(x, y, u.copy(), v.copy())
    sim = corr.sim(x, y, u.copy(), v.copy())
    idx = corr.pipe.aux_index
    du, dv = corr.shift(sim)
    assert np.array_equal(du, dplus.shift(plain)[0]) and np.abs(du).max() > 0.0
    st = sim.state
    # exact (delta_u . grad) u at the particles' (sorted) positions
    ux = -0.1 * k2 * np.sin(k2 * st.x)
    uy = 0.3 * k1 * np.cos(k1 * st.y)
    vx = 0.2 * k2 * np.cos(k2 * st.x)
    vy = 0.1 * k1 * np.sin(k1 * st.y)
    ax_exact = du * ux + dv * uy
    ay_exact = du * vx + dv * vy
    ax, ay = sim.aux[idx("shift_ax")], sim.aux[idx("shift_ay")]
    for got, want in ((ax, ax_exact), (ay, ay_exact)):
        assert np.linalg.norm(got - want) < 0.08 * np.linalg.norm(want), \
            np.linalg.norm(got - want) / np.linalg.norm(want)
    # the rates are the plain ones plus the correction (the two sorted alike: same positions)
    assert np.array_equal(st.x, plain.state.x)
    assert np.allclose(st.ax - plain.state.ax, ax, rtol=0, atol=1e-12 * np.abs(ax).max())
    assert np.allclose(st.ay - plain.state.ay, ay, rtol=0, atol=1e-12 * np.abs(ay).max())
    assert np.array_equal(st.drho, plain.state.drho)


def test_density_correction_adds_the_shift_along_the_density_gradient(dplus):
    """correctDensity: drho_a/dt += delta_u_a . grad rho_a (the Taylor correction of the
    density; a particle shifted down a hydrostatic column must get the density of its new
    depth), in the rates and in the density-only pass; nothing else changes."""
    corr = Box({"type": "deltaPlusShifting", "correctDensity": True})
    x, y = perturbed(6, amp=0.05)
    k1, k2 = 2 * np.pi / (2 * L), 2 * np.pi / L
    plain = dplus.sim(x, y)
    sim = corr.sim(x, y)
    for s in (plain, sim):                      # a smooth density field, the same for both
        st = s.state
        st.rho[:] = 1000.0 * (1.0 + 0.01 * np.sin(k1 * st.y) + 0.005 * np.cos(k2 * st.x))
        Box.evaluate(s)
    st = sim.state
    du, dv = corr.shift(sim)
    assert np.abs(du).max() > 0.0
    want = du * (-5.0 * k2 * np.sin(k2 * st.x)) + dv * (10.0 * k1 * np.cos(k1 * st.y))
    got = sim.aux[corr.pipe.aux_index("shift_drho")]
    assert np.linalg.norm(got - want) < 0.08 * np.linalg.norm(want), \
        np.linalg.norm(got - want) / np.linalg.norm(want)
    assert np.array_equal(st.x, plain.state.x)
    tol = 1e-12 * np.abs(got).max()
    assert np.allclose(st.drho - plain.state.drho, got, rtol=0, atol=tol)
    assert np.array_equal(st.ax, plain.state.ax) and np.array_equal(st.ay, plain.state.ay)
    # the density-only pass: the same addition (from the last pre-pass)
    sim.density_rate()
    plain.density_rate()
    assert np.allclose(st.drho - plain.state.drho, got, rtol=0, atol=tol)


def test_surface_r_weighs_the_anti_clumping_term_only_near_the_surface(dplus):
    """surfaceR: a particle near the free surface (the surface rule's set) gets the shift of
    R = surfaceR, every other one that of R. With R 0, surfaceR 0.2 on a perturbed slab the
    surface rows' shifts are the paper's (dplus, R 0.2) and the middle rows' those of R 0;
    the two differ there, so the check can fail."""
    x, y = lattice(rows=10, y0=0.5 * L)
    rng = np.random.default_rng(7)
    x = x + rng.uniform(-0.15, 0.15, x.size) * DX
    y = y + rng.uniform(-0.1, 0.1, x.size) * DX
    split = Box({"type": "deltaPlusShifting", "R": 0.0, "surfaceR": 0.2})
    bulk = Box({"type": "deltaPlusShifting", "R": 0.0})
    assert split.sel.particleShifting._split and not bulk.sel.particleShifting._split
    sims = [b.sim(x, y) for b in (split, dplus, bulk)]
    assert all(np.array_equal(s.state.x, sims[0].state.x) for s in sims)
    (du_s, dv_s), (du_p, dv_p), (du_0, dv_0) = (b.shift(s) for b, s in
                                                zip((split, dplus, bulk), sims))
    scale = np.abs(np.concatenate([du_p, dv_p])).max()
    as_paper = (np.abs(du_s - du_p) < 1e-9 * scale) & (np.abs(dv_s - dv_p) < 1e-9 * scale)
    as_bulk = (np.abs(du_s - du_0) < 1e-9 * scale) & (np.abs(dv_s - dv_0) < 1e-9 * scale)
    st = sims[0].state
    mid = np.abs(st.y - (0.5 * L + 5 * DX)) < 1.2 * DX
    rim = np.abs(st.y - (0.5 * L + 5 * DX)) > 3.4 * DX             # the two outer rows
    assert np.all(as_paper | as_bulk)
    assert np.all(as_paper[rim]) and np.all(as_bulk[mid])
    assert not np.any(as_paper[mid] & as_bulk[mid])                # R matters there
    assert not np.any(as_paper[rim] & as_bulk[rim])


MASS = {"type": "deltaPlusShifting", "correctDensity": True, "correctMass": True}


@pytest.fixture(scope="module")
def carried():
    return Box(MASS)


def _prescribed_shift(box):
    """A lattice with a smooth density and a prescribed smooth delta_u (periodic in the box),
    the rates pass run on it alone (sim.rates would make its own delta_u first): (sim, du,
    dv, div), div the exact div(rho delta_u)."""
    x, y = lattice()
    sim = box.sim(x, y)
    st = sim.state
    k1, k2 = 2 * np.pi / (2 * L), 2 * np.pi / L
    st.rho[:] = 1000.0 * (1.0 + 0.01 * np.sin(k1 * st.y))
    Box.evaluate(sim)
    idx = box.pipe.aux_index
    amp = 0.01
    du = amp * np.sin(k2 * st.x) * np.cos(k1 * st.y)
    dv = amp * np.cos(k2 * st.x) * np.sin(k1 * st.y)
    sim.aux[idx("shift_du")] = du
    sim.aux[idx("shift_dv")] = dv
    st.drho[:] = 0.0
    sim.pipeline.rates(*sim._grid_args(), *st.accelerations, st.drho, st.sigma)
    rho_y = 10.0 * k1 * np.cos(k1 * st.y)
    div = st.rho * amp * (k2 + k1) * np.cos(k2 * st.x) * np.cos(k1 * st.y) + dv * rho_y
    return sim, du, dv, div


def test_mass_flux_is_the_divergence_of_rho_delta_u(carried):
    """correctMass: dm_a/dt = V_a sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a W_ab
    is V_a div(rho delta_u)_a, the ALE mass flux. On a lattice with a smooth density and a
    prescribed smooth delta_u (periodic in the box) it matches the exact divergence to within
    the kernel's smoothing of the wave (7 % here; a wrong sign, factor or component is
    50-200 % off), and sums to zero to round-off: the fluid's mass is conserved."""
    sim, du, dv, div = _prescribed_shift(carried)
    st = sim.state
    mdot = sim.aux[carried.pipe.aux_index("shift_mdot")]
    got = mdot / (st.m / st.rho)
    assert np.linalg.norm(got - div) < 0.08 * np.linalg.norm(div), \
        np.linalg.norm(got - div) / np.linalg.norm(div)
    assert abs(mdot.sum()) < 1e-13 * np.abs(mdot).sum()


def test_mass_flux_takes_no_mass_from_a_particle_at_its_floor(carried):
    """correctMass's floor (massFloor 0.5 by default): with the prescribed delta_u of the
    test above and every fifth particle holding 0.5 rho0 dx^2, those particles give no mass
    (their dm/dt >= 0 to round-off, where without the floor some gave), and the flux still
    sums to zero to round-off; at 0.55 rho0 dx^2 (halfway up the ramp) they give less than
    without the floor but still give."""
    x, y = lattice()
    sim = carried.sim(x, y)
    st = sim.state
    Box.evaluate(sim)
    idx = carried.pipe.aux_index
    k1, k2 = 2 * np.pi / (2 * L), 2 * np.pi / L
    sim.aux[idx("shift_du")] = 0.01 * np.sin(k2 * st.x) * np.cos(k1 * st.y)
    sim.aux[idx("shift_dv")] = 0.01 * np.cos(k2 * st.x) * np.sin(k1 * st.y)
    m0 = 1000.0 * DX * DX
    light = np.arange(st.n) % 5 == 0
    names = list(sim.pipeline.module.PARAMS)
    prm = sim.prm

    def mdot(floor):
        prm[names.index("shift_mfl")], prm[names.index("shift_mrp")] = floor, 1 / (0.2 * floor)
        sim.pipeline.rates(*sim._grid_args(), *st.accelerations, st.drho, st.sigma)
        return sim.aux[idx("shift_mdot")].copy()

    for m_light in (0.5, 0.55):
        st.m[light] = m_light * m0
        free = mdot(1e-3)                               # no particle near this floor
        held = mdot(0.5)
        scale = np.abs(free).max()
        gives = light & (free < -1e-3 * scale)
        assert gives.sum() > 10
        assert abs(held.sum()) < 1e-13 * np.abs(held).sum()
        if m_light == 0.5:
            assert held[light].min() > -1e-12 * scale
        else:
            assert np.all(held[gives] > free[gives]) and held[gives].min() < 0.0
    prm[names.index("shift_mfl")], prm[names.index("shift_mrp")] = 0.5, 10.0


def _shift_only(box, sim, dt, steps, carry):
    """Move the particles by the shift alone (as ``_relax``), with the mass the shift carries
    added after each move as the time loop's ``after_step`` does."""
    for _ in range(steps):
        st = sim.state
        pu, pv = sim.position_velocity(st.u, st.v)
        st.x += dt * (pu - st.u)
        st.y += dt * (pv - st.v)
        if carry:
            sim.last_dt = dt
            box.sel.particleShifting.after_step(sim.context)
        box.evaluate(sim)


def _number_volumes(x, y):
    """1 / sum_b W_ab with the quartic kernel in the periodic box: the room each particle's
    position gives it, whatever its mass."""
    from sphfoam.models.kernels import Quartic, quartic_f

    pts = np.column_stack([x % L, y % (2 * L)])
    pairs = cKDTree(pts, boxsize=(L, 2 * L)).query_pairs(Quartic.support * H,
                                                          output_type="ndarray")
    d = pts[pairs[:, 0]] - pts[pairs[:, 1]]
    d[:, 0] -= L * np.round(d[:, 0] / L)
    d[:, 1] -= 2 * L * np.round(d[:, 1] / (2 * L))
    norm = Quartic.alpha_2d / H ** 2
    w = norm * np.array([quartic_f(q) for q in np.hypot(d[:, 0], d[:, 1]) / H])
    s = np.full(x.size, norm * quartic_f(0.0))
    np.add.at(s, pairs[:, 0], w)
    np.add.at(s, pairs[:, 1], w)
    return 1.0 / s


def test_shift_carries_each_particles_volume_with_its_spacing(carried):
    """With correctMass the volume m/rho of every particle changes as the room its position
    gives it (1 / sum_b W_ab) does while the shift rearranges a perturbed lattice: the two
    changes correlate to 0.99 and differ by 14 % of their size (the SPH divergence against the
    change of a kernel sum); the total mass is kept to round-off. Without it the volumes stay
    where they were (the shift's masses are the set-up's), so the check can fail."""
    plain = Box({"type": "deltaPlusShifting", "correctDensity": True})
    dt = 0.2 * H / C0
    for box, carry in ((carried, True), (plain, False)):
        sim = box.sim(*perturbed(1))

        def volumes(s=sim.state):
            o = np.argsort(s.id)
            return (s.m / s.rho)[o], _number_volumes(s.x[o], s.y[o])

        m0 = sim.state.m.sum()
        v0, n0 = volumes()
        _shift_only(box, sim, dt, 40, carry)
        v1, n1 = volumes(sim.state)
        dv, dn = v1 - v0, n1 - n0
        assert np.std(dn) > 0.03 * DX * DX                  # the lattice was rearranged
        if carry:
            assert np.corrcoef(dv, dn)[0, 1] > 0.98
            assert np.linalg.norm(dv - dn) < 0.2 * np.linalg.norm(dn)
            assert abs(sim.state.m.sum() - m0) < 1e-13 * m0
            assert np.std(sim.state.m) > 0.03 * sim.state.m.mean()
        else:
            assert np.array_equal(dv, np.zeros_like(dv))


def test_mass_carried_over_steps_conserves_mass(carried):
    """The simulation's steps with correctMass (the mass added after each step): the
    particles' masses change, their sum stays to round-off; correctMass without the
    density's ALE term, and massFloor without correctMass, are refused by name."""
    x, y = perturbed(2)
    sim = carried.sim(x, y)
    st = sim.state
    m0 = np.empty(st.n)
    m0[st.id] = st.m
    total = m0.sum()
    for _ in range(10):
        sim.step()
    st = sim.state
    assert np.abs(st.m - m0[st.id]).max() > 1e-4 * m0.mean()
    assert abs(st.m.sum() - total) < 1e-13 * total
    with pytest.raises(ValueError, match="correctMass needs correctDensity"):
        registry.build("particleShifting", {"type": "deltaPlusShifting", "correctMass": True})
    with pytest.raises(ValueError, match="massFloor bounds the mass that correctMass carries"):
        registry.build("particleShifting", {"type": "deltaPlusShifting", "massFloor": 0.4})


def test_a_full_support_has_no_surface_normal(dplus):
    """A still slab of 14 rows (a perfect lattice): the rows more than a support from both
    free surfaces have nu_a of round-off, whose direction is anyone's; they get no normal
    (n = 0), so the surface rule leaves their (round-off) shift alone and the CPU and the
    device, whose round-off differs, agree. The surface rows keep their outward normals."""
    x, y = lattice(rows=14, y0=0.5 * L)
    sim = dplus.sim(x, y)
    st = sim.state
    idx = dplus.pipe.aux_index
    n = np.hypot(sim.aux[idx("shift_nx")], sim.aux[idx("shift_ny")])
    depth = np.minimum(st.y - y.min(), y.max() - st.y)
    inner = depth > dplus.kappa * H + 0.1 * DX
    assert inner.sum() >= 2 * NX
    assert np.all(n[inner] == 0.0), n[inner].max()
    top = st.y > y.max() - 0.5 * DX
    assert np.all(sim.aux[idx("shift_ny")][top] > 0.99)


def _kernel_sums(x, y):
    """sum_b m_b W_ab (self included) with the quartic kernel in the periodic box."""
    return 1000.0 * DX * DX / _number_volumes(x, y)


def test_consistent_continuity_is_the_kernel_sums_rate_plus_the_shifts_mass_flux():
    """consistentContinuity (Sun et al. 2019): drho_a/dt gains the continuity's pair term
    with the shift's velocity, sum_b m_b (delta_u_a - delta_u_b) . grad_a W_ab, which is the
    rate of the kernel sum sum_b m_b W_ab when the particles move by delta_u, and the shift's
    mass flux div(rho delta_u)_a. On a lattice with a smooth density and a prescribed smooth
    delta_u (periodic in the box) the term less the kernel sums' change over a small move by
    delta_u matches the exact div(rho delta_u) to within the kernel's smoothing of the wave
    (7 % here; without the first part, or with a wrong sign, it is 100-200 % off); the
    rates and the density-only pass add it to drho; beside correctDensity it is refused by
    name."""
    box = Box({"type": "deltaPlusShifting", "consistentContinuity": True})
    sim, du, dv, div = _prescribed_shift(box)
    st = sim.state
    idx = box.pipe.aux_index
    got = sim.aux[idx("shift_drho_cont")]
    amp = 0.01
    eps = 1e-6 * DX / amp
    m = st.m[0]
    sums = (_kernel_sums(st.x + eps * du, st.y + eps * dv) - _kernel_sums(st.x, st.y)) / eps
    sums *= m / (1000.0 * DX * DX)
    assert np.linalg.norm(got - sums - div) < 0.08 * np.linalg.norm(div), \
        np.linalg.norm(got - sums - div) / np.linalg.norm(div)
    assert np.linalg.norm(sums) > 0.5 * np.linalg.norm(div)    # the first part matters
    # the rates and the density-only pass add it (the continuity's own term is zero at rest)
    Box.evaluate(sim)
    got = sim.aux[idx("shift_drho_cont")]
    tol = 1e-12 * np.abs(got).max()
    assert np.abs(got).max() > 0.0
    assert np.allclose(st.drho, got, rtol=0, atol=tol)
    st.drho[:] = 0.0
    sim.density_rate()
    assert np.allclose(st.drho, got, rtol=0, atol=tol)
    with pytest.raises(ValueError, match="consistentContinuity .* not combined with"):
        registry.build("particleShifting", {"type": "deltaPlusShifting",
                                            "consistentContinuity": True,
                                            "correctDensity": True})
