"""The mixing-length eddy viscosity ``turbulence { type mixingLength; }``
(sphfoam.models.turbulence.MixingLength): nu_t = l_m^2 |S|, l_m = kappa eta sqrt(1 - eta/H).

* the stress on a prescribed linear shear against l_m^2 gamma^2, by hand and on every particle
  (the corrected gradient is exact for a linear field, also at the edge of the fluid);
* the log law is its equilibrium: in a two-wall channel moving with the smooth log law, the
  stress is u*^2 (1 - eta/H) and its divergence the body force u*^2/H away from the walls;
* the pair forces conserve momentum;
* the signed distance to the wall lines by hand, and as the set-up writes it;
* nothing in the pipeline when not selected; bad input gives clear errors.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from sphfoam import registry
from sphfoam.case.errors import CaseError
from sphfoam.engine.build import build_pipeline
from sphfoam.engine.plan import Selection
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import FLUID, WALL, ParticleState
from sphfoam.models.mirror import line_distance, segment_array
from sphfoam.case.geometry import Segment
from test_walllaw import BASE, CTX, DELTA, DX, H, NCOL, NU, RHO0, source  # tests/ on sys.path

KAPPA = 0.41
L = NCOL * DX


def selection(turbulence: dict) -> Selection:
    specs = {**BASE, "turbulence": {"type": "mixingLength", **turbulence}}
    return Selection(**{f: registry.build(f, s) for f, s in specs.items()}, periodic_x=True)


def lattice(nrow: int, top_wall: bool):
    """Fluid rows y = dx .. (nrow - 1) dx (.. nrow dx without a top wall) over 3 wall rows
    y = 0, -dx, -2dx (wall line y = dx/2) and, with ``top_wall``, 3 rows from y = nrow dx
    (wall line (nrow - 1/2) dx), periodic over NCOL dx in x; and the wall segments."""
    xs = (np.arange(NCOL) + 0.5) * DX
    yf = np.arange(1, nrow if top_wall else nrow + 1) * DX
    yw = -np.arange(3) * DX
    segs = [Segment((0.0, 0.5 * DX), (L, 0.5 * DX), (0.0, 1.0), 0)]
    if top_wall:
        yw = np.r_[yw, nrow * DX + np.arange(3) * DX]
        segs.append(Segment((L, (nrow - 0.5) * DX), (0.0, (nrow - 0.5) * DX), (0.0, -1.0), 1))
    Xf, Yf = (a.ravel() for a in np.meshgrid(xs, yf))
    Xw, Yw = (a.ravel() for a in np.meshgrid(xs, yw))
    top = Yw > 0.5 * nrow * DX
    extra = {"nx": np.zeros(Xf.size + Xw.size),
             "ny": np.r_[np.zeros(Xf.size), np.where(top, -1.0, 1.0)],
             "wallDist": np.r_[np.zeros(Xf.size),
                               np.where(top, Yw - (nrow - 0.5) * DX, 0.5 * DX - Yw)],
             "lineDist": np.zeros(Xf.size + Xw.size)}        # the hook fills it in
    return Xf, Yf, Xw, Yw, extra, segs


def evaluate(sel, state, segs, lo, hi):
    pipe = build_pipeline(sel, CTX, domain_lo=lo, domain_hi=hi)
    sim = Simulation(state, pipe, registry.build("integrator", {"type": "monaghan2007"}),
                     h=H, support=sel.kernel.support, domain_lo=lo, domain_hi=hi, beta=0.2,
                     force_condition=True, adjust_time_step=True, delta_t=1e-4, segments=segs)
    sim.neighbour_update()
    sim.eos()
    sim.rates()
    return sim


def aux(sim, name):
    return sim.aux[sim.pipeline.module.AUX.index(name)]


def state_of(Xf, Yf, Xw, Yw, extra, u_fluid):
    x, y = np.r_[Xf, Xw], np.r_[Yf, Yw]
    kind = np.r_[np.full(Xf.size, FLUID), np.full(Xw.size, WALL)]
    u = np.r_[u_fluid, np.zeros(Xw.size)]
    return ParticleState(x, y, u, np.zeros(x.size), np.full(x.size, RHO0),
                         np.full(x.size, RHO0 * DX * DX), kind, extra=extra)


# --- the stress on a prescribed shear -------------------------------------------------------
def test_stress_of_a_linear_shear_is_l_m_squared_gamma_squared():
    """u = gamma (y + delta) over one wall (physical wall at y = -delta), H = 0.2 m, gamma =
    2/s: simple shear, |S| = gamma, tau_xy/rho = 2 nu_t S_xy = l_m^2 gamma^2 on every fluid
    particle (the first and the last rows too: the gradient over the fluid neighbours,
    corrected to first order, is exact for a linear field), tau_xx = tau_yy = 0. By hand,
    the row y = 3 dx = 0.03 m: eta = 0.031, 1 - 0.031/0.2 = 0.845, sqrt = 0.919239, l_m =
    0.41 * 0.031 * 0.919239 = 0.0116835, l_m^2 gamma^2 = 1.365047e-4 * 4 = 5.46019e-4."""
    gamma, Hout = 2.0, 0.2
    Xf, Yf, Xw, Yw, extra, segs = lattice(10, top_wall=False)
    sim = evaluate(selection({"outerLength": Hout}),
                   state_of(Xf, Yf, Xw, Yw, extra, gamma * (Yf + DELTA)), segs,
                   (0.0, -0.1), (L, 0.2))
    st = sim.state
    fluid = st.kind == FLUID
    eta = st.y + DELTA
    lm = KAPPA * eta * np.sqrt(np.clip(1.0 - eta / Hout, 0.0, None))
    np.testing.assert_allclose(st.extra["lineDist"], st.y - 0.5 * DX, atol=1e-15)
    txy = aux(sim, "turb_txy")
    np.testing.assert_allclose(txy[fluid], (lm * gamma)[fluid] ** 2, rtol=1e-9)
    row3 = fluid & (np.abs(st.y - 0.03) < 1e-9)
    np.testing.assert_allclose(txy[row3], 5.46019e-4, rtol=1e-5)
    scale = np.max(txy[fluid])
    assert np.max(np.abs(aux(sim, "turb_txx")[fluid])) < 1e-9 * scale
    assert np.max(np.abs(aux(sim, "turb_tyy")[fluid])) < 1e-9 * scale
    # wall particles: the rows behind the physical wall have l_m = 0; the first row (eta =
    # delta, l_m = kappa delta sqrt(1 - delta/H)) the gradient of its fluid neighbours
    # relative to its own zero velocity (the wall law, where selected, replaces it)
    first = (st.kind == WALL) & (np.abs(st.y) < 1e-9)
    deeper = (st.kind == WALL) & (st.y < -0.5 * DX)
    assert np.all(txy[deeper] == 0.0)
    assert np.all(txy[first] > 0.0) and np.all(txy[first] < txy[fluid].min())


def test_without_outer_length_the_mixing_length_is_kappa_eta():
    gamma = 2.0
    Xf, Yf, Xw, Yw, extra, segs = lattice(10, top_wall=False)
    sim = evaluate(selection({}), state_of(Xf, Yf, Xw, Yw, extra, gamma * (Yf + DELTA)),
                   segs, (0.0, -0.1), (L, 0.2))
    fluid = sim.state.kind == FLUID
    eta = sim.state.y[fluid] + DELTA
    np.testing.assert_allclose(aux(sim, "turb_txy")[fluid], (KAPPA * eta * gamma) ** 2,
                               rtol=1e-9)


# --- the log law is the equilibrium ----------------------------------------------------------
NROW = 40                                       # 39 fluid rows, as the tutorial
US = 0.05
HALF = 0.5 * (NROW * DX + 2 * DELTA)            # physical walls at -delta, NROW dx + delta


@pytest.fixture(scope="module")
def log_channel():
    Xf, Yf, Xw, Yw, extra, segs = lattice(NROW, top_wall=True)
    eta = np.minimum(Yf + DELTA, NROW * DX + DELTA - Yf)
    u = US * (np.log(eta * US / NU) / KAPPA + 5.2)
    sel = selection({"outerLength": HALF, "wallLaw": "smooth"})
    return evaluate(sel, state_of(Xf, Yf, Xw, Yw, extra, u), segs, (0.0, -0.1),
                    (L, NROW * DX + 0.1))


def test_log_law_profile_carries_the_linear_stress(log_channel):
    """The smooth log law u = u* (ln(eta u*/nu)/kappa + 5.2) between two walls: the mixing
    length's stress is the channel's u*^2 (1 - eta/H) away from the walls and the centre
    (7 dx <= eta <= H - 2 dx: measured within 1.9 %; 3 %), its divergence the body force
    u*^2/H of the steady state there (8 dx <= eta <= H - 2 dx: within 3.6 %; 5 %). Nearer
    the wall the gradient sees the log's curvature across the kernel (the first row's
    stress is 0.45 of the law's); the walls' total force is the wall law's, 2 rho u*^2 per
    unit length within the lattice's sum of grad W over the half-lattices (2.7 %; 4 %)."""
    sim = log_channel
    st = sim.state
    fluid = st.kind == FLUID
    eta = np.minimum(st.y + DELTA, NROW * DX + DELTA - st.y)
    sign = np.where(st.y < 0.5 * NROW * DX, 1.0, -1.0)
    txy = aux(sim, "turb_txy")
    band = fluid & (eta >= 7 * DX) & (eta <= HALF - 2 * DX)
    np.testing.assert_allclose(txy[band], (sign * US ** 2 * (1.0 - eta / HALF))[band],
                               rtol=0.03)
    F = US ** 2 / HALF
    inner = fluid & (eta >= 8 * DX) & (eta <= HALF - 2 * DX)
    for y in np.unique(np.round(st.y[inner], 9)):
        row = inner & (np.abs(st.y - y) < 1e-9)
        assert st.ax[row].mean() == pytest.approx(-F, rel=0.05), y
    fx = np.sum(st.m[fluid] * st.ax[fluid]) / L
    assert fx == pytest.approx(-2.0 * RHO0 * US ** 2, rel=0.04)
    ustar = aux(sim, "turb_ustar")
    first = (st.kind == WALL) & ((np.abs(st.y) < 1e-9) | (np.abs(st.y - NROW * DX) < 1e-9))
    np.testing.assert_allclose(ustar[first], US, rtol=0.005)


def test_pair_forces_conserve_momentum():
    """A block of fluid, periodic in x, with random velocities (a wall line below it sets
    eta): the stress forces are pairwise opposite, so their sum vanishes to rounding."""
    rng = np.random.default_rng(3)
    n = 12
    xs = (np.arange(n) + 0.5) * DX
    X, Y = (a.ravel() for a in np.meshgrid(xs, xs))
    X = X + rng.uniform(-0.1, 0.1, X.size) * DX
    Y = Y + rng.uniform(-0.1, 0.1, Y.size) * DX
    u, v = rng.normal(0.0, 0.1, X.size), rng.normal(0.0, 0.1, X.size)
    st = ParticleState(X, Y, u, v, np.full(X.size, RHO0), np.full(X.size, RHO0 * DX * DX),
                       np.full(X.size, FLUID), extra={"lineDist": np.zeros(X.size)})
    segs = [Segment((0.0, -0.05), (n * DX, -0.05), (0.0, 1.0), 0)]
    sim = evaluate(selection({"outerLength": 0.5}), st, segs, (0.0, -0.1), (n * DX, 0.3))
    s = sim.state
    assert np.all(s.extra["lineDist"] > 0.0)
    assert np.max(np.abs(aux(sim, "turb_txy"))) > 0.0
    scale = np.sum(s.m * np.hypot(s.ax, s.ay))
    assert abs(np.sum(s.m * s.ax)) < 1e-12 * scale
    assert abs(np.sum(s.m * s.ay)) < 1e-12 * scale


# --- the wall distance ------------------------------------------------------------------------
def test_line_distance_by_hand():
    """An L of wall lines: the bed y = 0 (normal +y) from x = 0 to 1 and a wall x = 1 (normal
    -x) from y = 0 to 1; signed distances to the nearest, negative behind it."""
    segs = [Segment((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), 0),
            Segment((1.0, 0.0), (1.0, 1.0), (-1.0, 0.0), 1)]
    x = np.array([0.5, 0.9, 0.5, 2.0, 0.2])
    y = np.array([0.2, 0.5, -0.3, 0.5, 0.05])
    out = np.zeros(x.size)
    line_distance(x, y, segment_array(segs), out)
    np.testing.assert_allclose(out, [0.2, 0.1, -0.3, -1.0, 0.05], atol=1e-15)
    # moved by a prescribed motion of the second wall (patch 1) by -0.3 in x
    line_distance(x, y, segment_array(segs, {1: (-0.3, 0.0)}), out)
    np.testing.assert_allclose(out[:2], [0.2, -0.2], atol=1e-15)
    line_distance(x, y, np.zeros((0, 9)), out)
    assert np.all(np.isinf(out))


def test_setup_writes_the_wall_distance(tutorial):
    """The tutorial's particles carry lineDist: fluid min(y - dx/2, l - dx/2 - y), the first
    wall rows -dx/2 (behind the wall lines y = dx/2 and l - dx/2)."""
    from sphfoam.case.case import Case
    from sphfoam.io.fields import read_state
    from sphfoam.setup.initial import setup_case

    case = tutorial("turbulentChannel")
    setup_case(Case(case), log=lambda *a: None)
    s = read_state(case / "0")
    y, dx = s["positions"][:, 1], 0.025
    fluid = s["type"] == FLUID
    np.testing.assert_allclose(s["lineDist"][fluid],
                               np.minimum(y - 0.5 * dx, 1.0 - 0.5 * dx - y)[fluid], atol=1e-12)
    first = (s["type"] == WALL) & ((np.abs(y) < 1e-9) | (np.abs(y - 1.0) < 1e-9))
    np.testing.assert_allclose(s["lineDist"][first], -0.5 * dx, atol=1e-12)


# --- costs nothing when not selected; bad input ----------------------------------------------
def test_nothing_of_it_in_other_closures():
    sps = Selection(**{f: registry.build(f, s) for f, s in
                       {**BASE, "turbulence": {"type": "smagorinskySPS"}}.items()},
                    periodic_x=True)
    src = source(sps)
    for word in ("ml_", "lineDist", "turb_kappa"):
        assert word not in src, word
    ml = selection({"outerLength": 0.5})
    assert ml.field_names() == ["lineDist"]
    assert "ml_det" in source(ml)
    assert ml.turbulence.params(CTX).keys() == {"turb_kappa", "turb_mlinvh", "turb_mloff"}


@pytest.mark.parametrize("spec", [{}, {"outerLength": 0.5, "wallLaw": "smooth"},
                                  {"wallLaw": "rough", "ks": 1e-4},
                                  {"wallLaw": "prescribedUPlus", "UPlus": 1.5}])
def test_declared_reads_and_writes_match_the_code(spec):
    from test_contract import assert_declarations_match

    assert_declarations_match(registry.build("turbulence", {"type": "mixingLength", **spec}))


@pytest.mark.parametrize("spec, words", [
    ({"outerLength": -0.5}, "greater than 0"),
    ({"kappa": 0.0}, "greater than 0"),
    ({"Cs": 0.12}, "Extra inputs are not permitted"),
    ({"wallLaw": "rough"}, "wallLaw rough needs ks"),
])
def test_bad_coefficients(spec, words):
    with pytest.raises(ValidationError) as e:
        registry.build("turbulence", {"type": "mixingLength", **spec})
    assert words in str(e.value)


def test_wall_delta_sets_eta_without_a_wall_law():
    mdl = registry.build("turbulence", {"type": "mixingLength", "wallDelta": 0.2})
    assert mdl.params(CTX)["turb_mloff"] == pytest.approx(0.5 * DX + 0.2 * DX, rel=1e-15)


def test_a_case_without_walls_is_refused():
    Xf, Yf, Xw, Yw, extra, segs = lattice(10, top_wall=False)
    with pytest.raises(CaseError) as e:
        evaluate(selection({}), state_of(Xf, Yf, Xw, Yw, extra, 0.0 * Yf), [],
                 (0.0, -0.1), (L, 0.2))
    assert "system/particleDict" in str(e.value) and "mixingLength" in str(e.value)
