"""Solitary-wave theories (waveTheory family) and Goring's paddle (waveMaker goring).

T(4.x) = thesis chapter 4, P(n) = corrected-SPH paper section 2.  z is measured up from the bed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

import sphfoam.models.goring  # noqa: F401  (registers before sphfoam.models imports it)
import sphfoam.models.wavetheory as wt
from sphfoam.reference import solitary
from sphfoam import registry

THEORIES = ["boussinesq", "mcCowan", "laitone", "kdv1", "kdv2"]
G = 9.81


def wave(name, A, d=1.0, **coeffs):
    return registry.build("waveTheory", {"type": name, **coeffs}).solitary(A, d, g=G)


def field_points(w, n=41):
    """A grid over the fluid under the wave, within +-6 half-widths of the crest."""
    L = 12.0 / w.decay
    x = np.linspace(-L, L, n)[:, None]
    frac = np.linspace(0.02, 0.98, 15)[None, :]
    return x + 0 * frac, frac * (w.d + w.eta(x))


# --- registry ---------------------------------------------------------------------------------
def test_all_theories_are_registered_with_docs():
    for name in THEORIES:
        cls = registry.get("waveTheory", name)
        assert cls.family == "waveTheory" and cls.doc and cls.__dict__.get("__doc__")
        assert isinstance(registry.build("waveTheory", {"type": name}), wt.WaveTheory)


@pytest.mark.parametrize("spec", [{"type": "kdv1", "height": 1.0}, {"type": "mcCowan", "rho": -1},
                                  {"type": "laitone", "rho": "water"}])
def test_bad_theory_coefficients_raise(spec):
    with pytest.raises(ValidationError):
        registry.build("waveTheory", spec)


def test_rho_coefficient_and_bad_wave_arguments():
    w = wave("kdv2", 0.1, rho=1025.0)
    assert w.rho == 1025.0
    assert w.p(0.0, 0.0) == pytest.approx(1025.0 / 1000.0 * wave("kdv2", 0.1).p(0.0, 0.0))
    for name in THEORIES:
        with pytest.raises(ValueError):
            wave(name, -0.1)
        with pytest.raises(ValueError):
            wave(name, 0.1, d=0.0)


# --- profiles and celerities -----------------------------------------------------------------
@pytest.mark.parametrize("name", THEORIES)
@pytest.mark.parametrize("eps", [0.01, 0.1, 0.4])
def test_crest_height_symmetry_and_decay(name, eps):
    d = 2.0
    w = wave(name, eps * d, d)
    assert w.eta(0.0) == pytest.approx(eps * d, rel=1e-12)                  # eta(crest) = A
    x = np.linspace(0.1, 8.0, 50) / w.decay
    assert np.allclose(w.eta(x), w.eta(-x), rtol=1e-12, atol=0)              # symmetric
    assert np.all(np.diff(w.eta(x)) < 0) and np.all(w.eta(x) > 0)            # one hump
    assert w.eta(60.0 / w.decay) < 1e-20 * d                                 # no far-field level
    # crest at x0 + c t, shape of permanent form
    assert np.allclose(w.eta(x, t=3.0, x0=1.5), w.eta(x - 1.5 - 3.0 * w.c), rtol=1e-12, atol=0)


@pytest.mark.parametrize("eps", [0.01, 0.02, 0.05])
def test_theories_agree_for_small_waves(eps):
    """All five profiles are the same to O(A/d) relative: spread <= 0.3 (A/d) A (measured:
    0.23 (A/d) A, from the (1 - 5/8 A/d) width of the second-order and McCowan waves)."""
    A = eps
    ws = [wave(n, A) for n in THEORIES]
    x = np.linspace(-15.0, 15.0, 1201) / ws[0].kappa
    etas = np.array([w.eta(x) for w in ws])
    assert np.ptp(etas, axis=0).max() <= 0.3 * eps * A
    assert np.ptp(etas, axis=0).max() <= 0.02 * A
    cs = np.array([w.c for w in ws])
    assert np.ptp(cs) <= 0.5 * eps**2 * math.sqrt(G)                        # c agree to O(eps^2)


@pytest.mark.parametrize("eps", [0.01, 0.1, 0.3, 0.6])
def test_celerities_are_the_published_formulas(eps):
    d = 1.5
    A, c0 = eps * d, math.sqrt(G * d)
    assert wave("boussinesq", A, d).c == pytest.approx(math.sqrt(G * (d + A)), rel=1e-14)   # T(4.4)
    assert wave("kdv1", A, d).c == pytest.approx(c0 * (1 + eps / 2), rel=1e-14)           # P(11)
    second = c0 * (1 + eps / 2 - 3 / 20 * eps**2)                                        # T(4.14)
    assert wave("laitone", A, d).c == pytest.approx(second, rel=1e-14)
    assert wave("kdv2", A, d).c == pytest.approx(second, rel=1e-14)                       # P(17)
    mc = wave("mcCowan", A, d)
    assert mc.c == pytest.approx(math.sqrt(G * d * math.tan(mc.M) / mc.M), rel=1e-14)    # T(4.7)


@pytest.mark.parametrize("name", THEORIES)
def test_celerity_increases_with_height(name):
    cs = [wave(name, A).c for A in np.linspace(0.01, 0.5, 12)]
    assert np.all(np.diff(cs) > 0) and cs[0] > math.sqrt(G)


# --- McCowan's M and N -------------------------------------------------------------------------
@pytest.mark.parametrize("eps", [0.001, 0.01, 0.05, 0.1, 0.3, 0.5, 0.7])
def test_mccowan_M_N_solve_the_two_equations(eps):
    w = wave("mcCowan", eps * 3.0, 3.0)
    r10, r11 = solitary.mccowan_residuals(w.M, w.N, eps)                     # T(4.10), T(4.11)
    assert abs(r10) < 1e-10 and abs(r11) < 1e-10
    assert 0 < w.M < math.pi / (1 + eps) and 0 < w.N < 2 / 3
    if eps <= 0.01:                                                          # M ~ sqrt(3 A/d)
        assert w.M == pytest.approx(math.sqrt(3 * eps), rel=2 * eps)


def test_mccowan_surface_solves_implicit_equation():
    w = wave("mcCowan", 0.3)
    x = np.linspace(-20, 20, 201)
    Y = 1 + w.eta(x) / w.d
    C = np.cosh(w.M * x / w.d)
    rhs = w.N / w.M * np.sin(w.M * Y) / (np.cos(w.M * Y) + C)                # T(4.6)
    assert np.max(np.abs(Y - 1 - rhs)) < 1e-14


# --- velocity fields -------------------------------------------------------------------------
def divergence(w, x, z, h):
    dudx = (w.u(x + h, z) - w.u(x - h, z)) / (2 * h)
    dwdz = (w.w(x, z + h) - w.w(x, z - h)) / (2 * h)
    return dudx + dwdz


def kinematic_residual(w, x, h):
    """(u - c) d(eta)/dx - w at the surface: zero for a steady wave (eta_t = -c eta_x)."""
    zs = w.d + w.eta(x)
    deta = (w.eta(x + h) - w.eta(x - h)) / (2 * h)
    return (w.u(x, zs) - w.c) * deta - w.w(x, zs)


@pytest.mark.parametrize("name", ["boussinesq", "kdv1", "mcCowan"])
@pytest.mark.parametrize("eps", [0.05, 0.3])
def test_continuity_is_exact(name, eps):
    """du/dx + dw/dz = 0 to finite-difference error: < 1e-6 of the scale sqrt(g d) eps^1.5/d."""
    w = wave(name, eps)
    x, z = field_points(w)
    scale = math.sqrt(G * w.d) * eps**1.5 / w.d
    assert np.max(np.abs(divergence(w, x, z, 1e-4))) < 1e-6 * scale
    assert np.max(np.abs(w.w(x[:, 0], 0.0))) == 0.0                          # impermeable bed


@pytest.mark.parametrize("name,order", [("laitone", 2.5), ("kdv2", 3.5)])
def test_continuity_of_second_order_theories(name, order):
    """Truncated theories: the residual is O(eps^order) (Laitone's T(4.16) w is truncated at
    O(eps^2.5), P(13)-(14) are consistent to O(eps^3.5)): < 2 sqrt(g d) eps^order / d and the
    observed order from eps = 0.1 -> 0.05 is within 0.3 of the theory's."""
    r = {}
    for eps in (0.1, 0.05):
        w = wave(name, eps)
        x, z = field_points(w)
        r[eps] = np.max(np.abs(divergence(w, x, z, 1e-4)))
        assert r[eps] < 2.0 * math.sqrt(G) * eps**order
    assert abs(math.log2(r[0.1] / r[0.05]) - order) < 0.3


@pytest.mark.parametrize("name", ["boussinesq", "mcCowan"])
@pytest.mark.parametrize("eps", [0.05, 0.3, 0.6])
def test_kinematic_surface_condition_is_exact(name, eps):
    w = wave(name, eps)
    x = np.linspace(-12, 12, 241) / w.decay
    assert np.max(np.abs(kinematic_residual(w, x, 1e-5))) < 1e-7 * math.sqrt(G) * eps**1.5


@pytest.mark.parametrize("name,order", [("kdv1", 2.5), ("laitone", 2.5), ("kdv2", 3.5)])
def test_kinematic_surface_condition_to_order(name, order):
    """The residual, scaled by sqrt(g d) eps^order, stays bounded (< 2) and the observed order
    from eps = 0.04 -> 0.02 is within 0.3 of the theory's."""
    r = {}
    for eps in (0.04, 0.02):
        w = wave(name, eps)
        x = np.linspace(-12, 12, 241) / w.decay
        r[eps] = np.max(np.abs(kinematic_residual(w, x, 1e-5)))
        assert r[eps] < 2.0 * math.sqrt(G) * eps**order
    assert abs(math.log2(r[0.04] / r[0.02]) - order) < 0.3


@pytest.mark.parametrize("name", THEORIES)
def test_mass_flux_equals_c_eta(name):
    """Steady wave: the depth-integrated flux q = int_0^{d+eta} u dz equals c eta.  Exact for
    Boussinesq and McCowan (1e-9), O(eps) relative for kdv1, O(eps^2) for the second-order ones."""
    eps = 0.1
    w = wave(name, eps)
    x = np.linspace(-8, 8, 81) / w.decay
    zs = w.d + w.eta(x)
    s, wts = np.polynomial.legendre.leggauss(24)
    z = 0.5 * zs[:, None] * (s[None, :] + 1)
    q = 0.5 * zs * np.sum(wts[None, :] * w.u(x[:, None], z), axis=1)
    err = np.max(np.abs(q - w.c * w.eta(x))) / (w.c * w.A)
    tol = {"boussinesq": 1e-9, "mcCowan": 1e-9, "kdv1": eps, "laitone": eps**2, "kdv2": eps**2}
    assert err < tol[name]


def test_velocity_signs_and_crest_values():
    for name in THEORIES:
        w = wave(name, 0.2)
        L = 3.0 / w.decay
        assert w.w(L, 0.5) > 0 > w.w(-L, 0.5)                                # rising ahead of crest
        assert w.w(0.0, 0.7) == pytest.approx(0.0, abs=1e-15)
        assert 0 < w.u(0.0, 1.2) < w.c                                       # no breaking
    b = wave("boussinesq", 0.2)
    assert b.u(0.0, 0.3) == pytest.approx(b.c * 0.2 / 1.2, rel=1e-14)         # T(4.5)
    k = wave("kdv1", 0.2)
    assert k.u(0.0, 0.3) == pytest.approx(math.sqrt(G) * 0.2, rel=1e-14)      # P(7)


# --- volume and pressure ---------------------------------------------------------------------
def test_volumes():
    d, eps = 2.0, 0.05
    exact = 4 * d * d * math.sqrt(eps / 3)                       # int A sech^2 = 2A/kappa
    assert wave("boussinesq", eps * d, d).volume() == pytest.approx(exact, rel=1e-9)
    assert wave("kdv1", eps * d, d).volume() == pytest.approx(exact, rel=1e-9)
    lai = wave("laitone", eps * d, d)
    assert lai.volume() == pytest.approx(d * d / lai.alpha * (2 * eps - eps**2 / 2), rel=1e-9)
    assert wave("mcCowan", eps * d, d).volume() == pytest.approx(exact, rel=0.03)


@pytest.mark.parametrize("name", THEORIES)
def test_pressure_hydrostatic_far_field_and_zero_at_surface(name):
    w = wave(name, 0.2, d=1.5)
    z = np.linspace(0, 1.5, 7)
    assert np.allclose(w.p(1e3, z), 1000.0 * G * (1.5 - z), rtol=1e-12, atol=1e-9)
    x = np.linspace(-5, 5, 41)
    ps = w.p(x, 1.5 + w.eta(x))
    assert np.max(np.abs(ps)) < (1000.0 * G * 1.5 * 0.2**3 if name == "kdv2" else 1e-9)
    if name != "kdv2":                                                       # hydrostatic below eta
        xx, zz = field_points(w)
        assert np.allclose(w.p(xx, zz), 1000.0 * G * (1.5 + w.eta(xx) - zz), rtol=1e-14)


def test_kdv2_pressure_is_bernoulli_to_second_order():
    """P(15) equals steady Bernoulli in the wave frame, p = rho (g (d - z) + c u - (u^2 + w^2)/2),
    to O(eps^3): the difference over rho g d is < 3 eps^3 and shrinks ~8x when eps halves."""
    r = []
    for eps in (0.1, 0.05):
        w = wave("kdv2", eps)
        x, z = field_points(w)
        u, v = w.u(x, z), w.w(x, z)
        bern = 1000.0 * (G * (w.d - z) + w.c * u - 0.5 * (u * u + v * v))
        r.append(np.max(np.abs(w.p(x, z) - bern)) / (1000.0 * G * w.d))
        assert r[-1] < 3 * eps**3
    assert r[0] / r[1] > 6.0


# --- Goring's paddle -------------------------------------------------------------------------
def goring(**c):
    return registry.build("waveMaker", {"type": "goring", **c})


def test_goring_stroke_duration_and_registry():
    H, d = 0.1, 0.5
    m = goring(height=H, depth=d)
    assert m.stroke == pytest.approx(math.sqrt(16 * H * d / 3), rel=1e-12, abs=0)   # T(4.23)
    kappa, c = math.sqrt(3 * H / (4 * d**3)), math.sqrt(G * (d + H))
    tau = 2 / (kappa * c) * (math.atanh(0.999) + H / d)                               # T(4.24)
    assert m.duration == pytest.approx(tau, rel=1e-14)
    assert m.duration == pytest.approx(2 * 3.80 / (kappa * c) + m.stroke / c, rel=1e-4)
    ext = goring(height=H, depth=d, extended=True)
    assert ext.duration == pytest.approx(1.1 * m.duration, rel=1e-14)
    # the paddle displaces the volume of the Boussinesq wave: d S = 2 H/kappa
    assert d * m.stroke == pytest.approx(wave("boussinesq", H, d).volume(), rel=1e-9)
    assert "goring" in registry.names("waveMaker")


@pytest.mark.parametrize("extended", [False, True])
@pytest.mark.parametrize("H,d,delay", [(0.05, 1.0, 0.0), (0.3, 0.4, 1.25)])
def test_goring_trajectory(H, d, delay, extended):
    m = goring(height=H, depth=d, delay=delay, extended=extended)
    t = delay + np.linspace(0.0, m.duration, 401)[1:-1]
    X = m.position(t)
    assert np.max(np.abs(m.residual(t, X))) < 1e-10                         # T(4.20)
    assert np.all(np.diff(X) > 0)                                            # monotone
    # before, at the ends of and after the motion
    assert m.position(delay) == 0.0 and m.velocity(delay - 1.0) == 0.0
    assert m.position(delay - 0.5) == 0.0
    assert m.position(delay + 2 * m.duration) == m.travel
    assert m.velocity(delay + 2 * m.duration) == 0.0
    assert m.position(delay + 1e-9) == pytest.approx(0.0, abs=1e-8)          # continuous start
    assert m.position(delay + m.duration - 1e-9) == pytest.approx(m.travel, abs=1e-8)
    assert m.stroke * 0.998 < m.travel < m.stroke                            # tanh(3.8) = 0.999
    # velocity = central difference of position
    h = 1e-5 * m.duration
    fd = (m.position(t + h) - m.position(t - h)) / (2 * h)
    assert np.allclose(m.velocity(t), fd, rtol=1e-6, atol=1e-9 * m.stroke / m.duration)
    # Goring's condition at the midpoint (crest): dX/dt = c H/(d + H)
    mid = delay + 0.5 * m.duration
    assert m.velocity(mid) == pytest.approx(m.celerity * H / (d + H), rel=1e-8)
    assert m.position(mid) == pytest.approx(0.5 * m.travel, rel=1e-12)


def test_goring_velocity_is_boussinesq_u_at_the_paddle():
    """dX/dt = u(xi, t) of T(4.5) for the wave whose crest passes xi = 0 at t' = 0, T(4.17)."""
    H, d = 0.2, 1.0
    m = goring(height=H, depth=d)
    b = wave("boussinesq", H, d)
    t = np.linspace(0.05, 0.95, 37) * m.duration
    xi = m.position(t) + m.xi0
    assert np.allclose(m.velocity(t), b.u(xi, 0.5 * d, t=t - 0.5 * m.duration), rtol=1e-10)


def test_goring_is_independent_of_call_order():
    """The warm-started Newton gives the same answer for any order of scalar calls."""
    m, fresh = goring(height=0.2, depth=0.6), goring(height=0.2, depth=0.6)
    rng = np.random.default_rng(1)
    for t in rng.uniform(-1.0, 1.2 * m.duration, 200):
        assert m.position(t) == pytest.approx(fresh.position(t), rel=1e-12, abs=1e-14)
        assert isinstance(m.position(t), float) and isinstance(m.velocity(t), float)


def test_goring_drives_a_piston_paddle():
    mo = registry.build("motion", {"type": "pistonPaddle",
                                   "waveMaker": {"type": "goring", "height": 0.1, "depth": 0.5}})
    T = mo.maker.duration
    assert mo.displacement(0.0) == (0.0, 0.0)
    assert mo.displacement(2 * T)[0] == pytest.approx(mo.maker.travel)
    assert mo.velocity(0.5 * T)[0] > 0


@pytest.mark.parametrize("bad", [{"height": -0.1, "depth": 1.0}, {"height": 0.1, "depth": 0.0},
                                 {"height": 0.1}, {"height": 0.1, "depth": 1.0, "delay": -1.0},
                                 {"height": 0.1, "depth": 1.0, "g": 0.0},
                                 {"height": 0.1, "depth": 1.0, "stroke": 0.2}])
def test_goring_bad_coefficients_raise(bad):
    with pytest.raises(ValidationError):
        goring(**bad)
