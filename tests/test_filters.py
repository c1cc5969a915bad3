"""Density filters (sphfoam/models/filters.py): Shepard T(3.69), MLS T(3.64)-(3.68), delta-SPH.

* the MLS re-initialisation reproduces a linear density field exactly, at the lattice's edges
  too, while the Shepard filter does not (so the check can fail);
* both keep a uniform field uniform; Shepard smooths noise;
* delta-SPH diffuses a density bump (the peak loses density) conservatively
  (sum_a V_a drho_a = 0), matches a numpy evaluation, and leaves no code when not selected;
* the hydrostatic tank runs stably with each filter.

The selections use the hydrostaticTank tutorial's models, so the tank runs below reuse the
pipelines these tests compile (numba's disk cache makes reruns cheap).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from sphfoam import registry
from sphfoam.case import foamdict
from sphfoam.case.schemas import SPH_FAMILIES
from sphfoam.case.times import list_times
from sphfoam.engine.build import build_pipeline
from sphfoam.engine.emit_cpu import generate_source
from sphfoam.engine.pipeline import CORE_PARAMS
from sphfoam.engine.plan import Selection
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import read_state
from sphfoam.models.base import CaseContext
from sphfoam.timeloop import run_case

RHO0 = 1000.0
C0 = 20.0
DX = 1.0           # lattice units: rho = rho0 (1 + 0.01 x) changes by 1 % per spacing
HDX = 1.3
N = 16             # N x N lattice

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"


def tutorial_specs() -> dict:
    """The hydrostaticTank tutorial's models (c0 given directly: values do not change the
    generated source), so the tank runs below reuse the pipelines the lattice tests compile."""
    d = foamdict.read(TUTORIALS / "hydrostaticTank" / "constant" / "sphProperties")
    specs = {f: dict(d[f]) for f in SPH_FAMILIES if f in d}
    specs["equationOfState"] = {"type": "tait", "speedOfSound": C0}
    specs["kernel"]["hdx"] = HDX
    specs.pop("densityFilter", None)
    return specs


SPECS = tutorial_specs()


class Setup:
    def __init__(self, filt: dict):
        specs = {f: SPECS.get(f, {"type": d}) for f, d in SPH_FAMILIES.items()}
        specs["densityFilter"] = filt
        models = {f: registry.build(f, s) for f, s in specs.items()}
        self.sel = Selection(**models)
        self.kernel = models["kernel"]
        self.filt = models["densityFilter"]
        self.h = HDX * DX
        self.ctx = CaseContext(dx=DX, h=self.h, rho0=RHO0, nu=1e-6, g=(0.0, 0.0),
                               fluid_height=0.0, c0=C0)
        self.pipe = build_pipeline(self.sel, self.ctx)

    def simulation(self, rho, m=None, u=None) -> Simulation:
        x, y = lattice()
        n = x.size
        m = np.full(n, RHO0 * DX * DX) if m is None else m
        u = np.zeros(n) if u is None else u
        st = ParticleState(x, y, u, np.zeros(n), rho, m, np.zeros(n, dtype=np.int64))
        integ = registry.build("integrator", {"type": "monaghan2007"})
        sim = Simulation(st, self.pipe, integ, h=self.h, support=self.kernel.support,
                         domain_lo=(-2 * DX, -2 * DX), domain_hi=((N + 2) * DX, (N + 2) * DX),
                         beta=0.2, force_condition=True, adjust_time_step=True, delta_t=1e-4,
                         filter_every=getattr(self.filt.coeffs, "every", 0))
        sim.neighbour_update()          # sorts the state by cell: read x, y, rho from sim.state
        return sim


def lattice():
    xs = (np.arange(N) + 0.5) * DX
    X, Y = np.meshgrid(xs, xs)
    return X.ravel(), Y.ravel()


def interior(st, setup):
    """Particles whose kernel support lies wholly inside the lattice."""
    r = setup.kernel.support * setup.h
    return (st.x > r) & (st.x < N * DX - r) & (st.y > r) & (st.y < N * DX - r)


def filtered(setup, rho_of_xy, m=None):
    """Filter once a density field given as a function of position; return (state, before)."""
    x, y = lattice()
    sim = setup.simulation(rho_of_xy(x, y), m=m)
    before = sim.state.rho.copy()
    sim.filter_density()
    return sim.state, before


@pytest.fixture(scope="module")
def shepard():
    return Setup({"type": "shepard"})


@pytest.fixture(scope="module")
def mls():
    return Setup({"type": "mlsReinitialisation"})


@pytest.fixture(scope="module")
def delta():
    return Setup({"type": "deltaSPH", "delta": 0.1})


def linear(x, y):
    return RHO0 * (1.0 + 0.01 * x)


# --- periodic filters ---------------------------------------------------------------------
def test_mls_reproduces_a_linear_field_and_shepard_does_not(shepard, mls):
    st, _ = filtered(mls, linear)
    exact = linear(st.x, st.y)
    # first-order consistency: exact wherever the moment matrix is invertible, edges and
    # corners included (no particle of a full lattice falls back to Shepard)
    assert np.max(np.abs(st.rho / exact - 1.0)) < 1e-10
    st, _ = filtered(shepard, linear)
    exact = linear(st.x, st.y)
    err = np.abs(st.rho / exact - 1.0)
    inner = interior(st, shepard)
    # with equal masses the volumes m/rho vary: the interior average is biased (harmonic)
    assert err[inner].max() > 1e-6
    # at the edges the one-sided support biases it by a good part of a spacing's change
    assert err[~inner].max() > 1e-3


def test_mls_exact_for_unequal_masses(mls):
    rng = np.random.default_rng(3)
    m = RHO0 * DX * DX * (1.0 + rng.uniform(-0.2, 0.2, N * N))
    st, _ = filtered(mls, lambda x, y: RHO0 * (1.0 + 0.01 * x - 0.02 * y + 0.005), m=m)
    exact = RHO0 * (1.0 + 0.01 * st.x - 0.02 * st.y + 0.005)
    assert np.max(np.abs(st.rho / exact - 1.0)) < 1e-10


@pytest.mark.parametrize("which", ["shepard", "mls"])
def test_uniform_field_stays_uniform(which, shepard, mls):
    setup = {"shepard": shepard, "mls": mls}[which]
    st, _ = filtered(setup, lambda x, y: np.full(x.size, 1.003 * RHO0))
    inner = interior(st, setup)
    assert np.max(np.abs(st.rho[inner] / (1.003 * RHO0) - 1.0)) < 1e-12
    # zeroth-order consistency: everywhere, not only in the interior
    assert np.max(np.abs(st.rho / (1.003 * RHO0) - 1.0)) < 1e-12


def test_shepard_smooths_noise(shepard):
    rng = np.random.default_rng(7)
    noise = rng.normal(0.0, 0.005, N * N)
    st, before = filtered(shepard, lambda x, y: RHO0 * (1.0 + noise))
    inner = interior(st, shepard)
    assert np.var(st.rho[inner]) < 0.25 * np.var(before[inner])
    # the mean is kept (to the noise's own size)
    assert abs(st.rho[inner].mean() - before[inner].mean()) < 0.1 * before[inner].std()


def test_only_fluid_density_changes_and_walls_are_kept(shepard):
    x, y = lattice()
    sim = shepard.simulation(linear(x, y))
    wall = sim.state.x < 2 * DX
    sim.state.kind[wall] = 1
    before = sim.state.rho.copy()
    sim.filter_density()
    assert np.array_equal(sim.state.rho[wall], before[wall])
    assert not np.array_equal(sim.state.rho[~wall], before[~wall])


def test_filter_pass_runs_every_n_steps(shepard, mls, delta):
    assert shepard.pipe.density_filter is not None and mls.pipe.density_filter is not None
    assert shepard.filt.coeffs.every == 40 and mls.filt.coeffs.every == 30
    x, y = lattice()
    sim = shepard.simulation(linear(x, y))
    assert sim.filter_every == 40
    # delta-SPH acts in the rates: no pass is generated and none is scheduled
    assert delta.pipe.density_filter is None
    assert delta.simulation(linear(x, y)).filter_every == 0


def test_filter_pass_runs_before_the_steps_its_schedule_names():
    """Stepping a simulation: the Shepard pass (every 3 steps) runs before steps 3, 6, 9 (by
    the run's step index, as after a restart), and only then; Verlet takes an Euler step
    after each pass (``sim.filtered``)."""
    setup = Setup({"type": "shepard", "every": 3})
    x, y = lattice()
    sim = setup.simulation(RHO0 * (1.0 + 0.001 * np.sin(x / DX)))
    sim.integrator = registry.build("integrator", {"type": "verlet", "everyN": 1000})
    ran, flagged = [], []
    original = sim.filter_density

    def recording():
        ran.append(sim.step_index)
        original()

    sim.filter_density = recording
    for _ in range(10):
        sim.step()
        flagged.append(sim.filtered)
    assert ran == [3, 6, 9]
    assert flagged == [i in (3, 6, 9) for i in range(10)]
    sim.step_index = 14                     # a run restarted at step 14: next pass at 15
    ran.clear()
    sim.step()
    sim.step()
    assert ran == [15]


def test_mls_falls_back_to_shepard_for_an_isolated_pair(mls, shepard):
    """Two particles (collinear neighbourhood): A is singular, the guard gives Shepard."""
    x = np.array([5.0, 5.0 + DX, 12.0])
    y = np.array([5.0, 5.0, 12.0])
    rho = np.array([1000.0, 1010.0, 990.0])
    m = np.full(3, RHO0)
    out = []
    for setup in (mls, shepard):
        st = ParticleState(x, y, np.zeros(3), np.zeros(3), rho, m, np.zeros(3, dtype=np.int64))
        integ = registry.build("integrator", {"type": "monaghan2007"})
        sim = Simulation(st, setup.pipe, integ, h=setup.h, support=setup.kernel.support,
                         domain_lo=(0, 0), domain_hi=(20, 20), beta=0.2, force_condition=True,
                         adjust_time_step=True, delta_t=1e-4)
        sim.neighbour_update()
        sim.filter_density()
        out.append(sim.state.rho[np.argsort(sim.state.id)])
    assert np.all(np.isfinite(out[0]))
    assert np.allclose(out[0], out[1], rtol=1e-12)
    assert out[0][2] == pytest.approx(990.0, rel=1e-12)   # alone: keeps its density


# --- delta-SPH ------------------------------------------------------------------------------
def bump(x, y):
    c = 0.5 * N * DX
    return RHO0 * (1.0 + 0.01 * np.exp(-((x - c) ** 2 + (y - c) ** 2) / (2.0 * (1.5 * DX) ** 2)))


def test_delta_sph_diffuses_a_bump_conservatively(delta, shepard):
    x, y = lattice()
    sim = delta.simulation(bump(x, y))
    sim.eos()
    sim.rates()
    st = sim.state
    peak = np.argmax(st.rho)
    assert st.drho[peak] < 0.0
    # the lowest ring around the bump gains
    assert st.drho.max() > 0.0
    V = st.m / st.rho
    assert abs(np.sum(V * st.drho)) < 1e-12 * np.sum(np.abs(V * st.drho))
    # numpy reference of the same sum
    h = delta.h
    pts = np.column_stack([st.x, st.y])
    ij = cKDTree(pts).query_pairs(delta.kernel.support * h * (1 - 1e-12), output_type="ndarray")
    a, b = np.r_[ij[:, 0], ij[:, 1]], np.r_[ij[:, 1], ij[:, 0]]
    dxx, dyy = st.x[a] - st.x[b], st.y[a] - st.y[b]
    r2 = dxx ** 2 + dyy ** 2
    q = np.sqrt(r2) / h
    F = delta.kernel.alpha_2d / h ** 4 * np.array([delta.kernel.dfdq_q(float(v)) for v in q])
    psi_dot_grad = 2.0 * (st.rho[a] - st.rho[b]) * F * r2 / (r2 + 0.01 * h * h)
    ref = np.zeros(st.n)
    np.add.at(ref, a, 0.1 * h * C0 * psi_dot_grad * st.m[b] / st.rho[b])
    assert np.allclose(st.drho, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    # without delta-SPH the same state at rest has no density rate at all
    sim0 = shepard.simulation(bump(x, y))
    sim0.eos()
    sim0.rates()
    assert np.all(sim0.state.drho == 0.0)


def _source(filt: dict) -> str:
    specs = {f: SPECS.get(f, {"type": d}) for f, d in SPH_FAMILIES.items()}
    specs["densityFilter"] = filt
    sel = Selection(**{f: registry.build(f, s) for f, s in specs.items()})
    ctx = CaseContext(dx=0.01, h=0.013, rho0=RHO0, nu=1e-6, g=(0.0, -9.81), fluid_height=0.3,
                      c0=C0)
    names = list(CORE_PARAMS)
    for mdl in sel.models():
        names += list(mdl.params(ctx))
    return generate_source(sel, names)


def test_unselected_filters_leave_no_code():
    none = _source({"type": "none"})
    assert "filt_" not in none and "density_filter" not in none
    d = _source({"type": "deltaSPH"})
    assert "filt_dc0" in d and "def density_filter" not in d
    for name in ("shepard", "mlsReinitialisation"):
        src = _source({"type": name})
        assert "def density_filter" in src and "filt_psi" not in src
    compile(none, "<none>", "exec")


def test_delta_sph_needs_c0():
    model = registry.build("densityFilter", {"type": "deltaSPH"})
    with pytest.raises(ValueError, match="c0"):
        model.params(CaseContext(dx=0.01, h=0.013, rho0=RHO0, nu=1e-6, g=(0.0, -9.81),
                                 fluid_height=0.3))


# --- the hydrostatic tank ---------------------------------------------------------------------
@pytest.mark.parametrize("filt", ["shepard", "mlsReinitialisation", "deltaSPH"])
def test_hydrostatic_tank_is_stable_with_filter(tutorial, filt):
    """0.3 s of the tank at H/dx = 20 (about 1600 steps: 41 Shepard passes, 54 MLS ones)."""
    dx = 0.02
    case = tutorial("hydrostaticTank", {"constant/sphProperties:densityFilter": {"type": filt},
                                        "system/particleDict:dx": dx,
                                        "system/controlDict:endTime": 0.3,
                                        "system/controlDict:writeInterval": 0.3})
    rep = run_case(case, progress=False, echo=None)
    assert rep.removed == 0
    assert f"densityFilter={filt}" in (case / "log.sphfoam").read_text()
    H, W, G = 0.4, 0.5, 9.81
    s = read_state(list_times(case)[-1][1])
    f = s["type"] == 0
    x, y = s["positions"][f].T
    assert np.all(np.isfinite(s["positions"])) and np.all(np.isfinite(s["p"]))
    assert x.min() > 0 and x.max() < W and y.min() > 0
    speed = np.sqrt((s["U"][f] ** 2).sum(axis=1))
    assert speed.max() < 0.1 * math.sqrt(G * H)
    # the bottom fluid row against rho g (H - dx/2) (+3 % at 0.3 s, with or without a filter)
    bottom = f & (s["positions"][:, 1] < dx)
    assert s["p"][bottom].mean() == pytest.approx(RHO0 * G * (H - 0.5 * dx), rel=0.05)
