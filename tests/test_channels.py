"""Channel flows of T §3.4.1: the start-up series T(3.42) and T(3.46), the velocityProfile
function object, coarse Poiseuille and Couette runs against theory, and the convergence of the
steady Poiseuille u_max with the particle spacing (T Tables 3.1-3.2).

The runs use the tutorials' dictionaries (tutorials/poiseuille, tutorials/couette) at coarse
resolutions through tutorials/poiseuille/convergence.py, on one numba thread (faster than two
for a few hundred particles on a shared machine). Physical parameters are the thesis' (F, nu,
l, u0): the number of steps to a steady state does not depend on them anyway, since the
viscous limit dt <= 0.125 h^2/nu binds and the spin-up time scales as l^2/nu.
"""

from __future__ import annotations

import importlib.util
import math
from types import SimpleNamespace

import numpy as np
import pytest

from sphfoam.engine.state import FLUID
from sphfoam.reference import channel_theory as ct
from sphfoam.sampling.profiles import VelocityProfile

from conftest import TUTORIALS, set_entry

F, NU, L, U0 = 8e-6, 1e-6, 0.01, 1e-4
UMAX = F * L * L / (8 * NU)                   # 1e-4 m/s, T(3.41)


def _load_convergence():
    spec = importlib.util.spec_from_file_location(
        "poiseuille_convergence", TUTORIALS / "poiseuille" / "convergence.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


cv = _load_convergence()


# --- the series ---------------------------------------------------------------------------------
def test_poiseuille_series_tends_to_the_parabola():
    y = np.linspace(0.0, L, 41)
    steady = F / (2 * NU) * y * (L - y)                      # T(3.40)
    assert ct.poiseuille_umax(F, NU, L) == pytest.approx(1e-4, rel=1e-12)
    np.testing.assert_allclose(ct.poiseuille(y, 1e4, F, NU, L), steady, rtol=0, atol=1e-12 * UMAX)
    np.testing.assert_allclose(ct.poiseuille_series(y, 1e4, F, NU, L, 3), steady, rtol=0,
                               atol=1e-12 * UMAX)
    # the slowest mode decays as exp(-pi^2 nu t / l^2): at t = 120 s u_max is 7.4e-6 short
    assert ct.poiseuille([L / 2], 120.0, F, NU, L)[0] == pytest.approx(
        UMAX * (1 - 32 / math.pi ** 3 * math.exp(-math.pi ** 2 * NU * 120 / L ** 2)), rel=1e-9)


def test_poiseuille_series_starts_from_rest():
    y = np.linspace(0.0, L, 41)
    # the plain partial sum: the tail after n terms is below 0.26 u_max / (2n)^2
    assert np.abs(ct.poiseuille_series(y, 0.0, F, NU, L, 2000)).max() < 1e-6 * UMAX
    assert np.abs(ct.poiseuille(y, 0.0, F, NU, L)).max() < 1e-12 * UMAX
    # away from the walls the fluid first accelerates freely: u = F t
    mid = np.array([0.3 * L, 0.5 * L])
    np.testing.assert_allclose(ct.poiseuille(mid, 0.05, F, NU, L), F * 0.05, rtol=1e-9)


def test_couette_series_limits():
    y = np.linspace(0.0, L, 41)
    np.testing.assert_allclose(ct.couette(y, 1e4, U0, NU, L), U0 * y / L, rtol=0,
                               atol=1e-12 * U0)                                      # T(3.45)
    inner = np.linspace(0.25 * L, 0.75 * L, 11)
    # the plain partial sum converges like 1/n at t = 0
    assert np.abs(ct.couette_series(inner, 0.0, U0, NU, L, 1_000_000)).max() < 1e-6 * U0
    u0 = ct.couette(y, 0.0, U0, NU, L)
    assert np.abs(u0[:-1]).max() < 1e-12 * U0 and u0[-1] == U0
    # both walls hold their velocity at every time
    for t in (0.1, 2.0, 20.0):
        u = ct.couette(np.array([0.0, L]), t, U0, NU, L)
        assert abs(u[0]) < 1e-12 * U0 and u[1] == pytest.approx(U0, rel=1e-12)


@pytest.mark.parametrize("t", [1e-4, 0.01, 0.5, 2.0, 5.0, 20.0])
def test_converged_solutions_match_the_long_series(t):
    """poiseuille()/couette() (few terms, or images at small t) against partial sums with
    many more terms: equal to 1e-12 of the velocity scale where the long sum has converged."""
    y = np.linspace(0.0, L, 81)
    long_p = ct.poiseuille_series(y, t, F, NU, L, 100_000)
    np.testing.assert_allclose(ct.poiseuille(y, t, F, NU, L), long_p, rtol=0, atol=1e-12 * UMAX)
    if t >= 0.01:   # below that 1e6 Couette terms are not enough: the images are the reference
        long_c = ct.couette_series(y, t, U0, NU, L, 100_000)
        np.testing.assert_allclose(ct.couette(y, t, U0, NU, L), long_c, rtol=0,
                                   atol=1e-12 * U0)


def test_velocity_deficit_law():
    y = np.linspace(0.01, 0.99, 50)
    us = ct.friction_velocity(0.002, 1.0)
    assert us == pytest.approx(math.sqrt(0.002 * 0.5))
    u = ct.velocity_deficit(y, 0.5, us, 1.0)
    assert ct.velocity_deficit([0.5], 0.5, us, 1.0)[0] == 0.5
    eta = np.minimum(y, 1 - y)
    np.testing.assert_allclose((u - 0.5) / us, np.log(eta / 0.5) / ct.KAPPA, rtol=1e-12)


def test_richardson_reproduces_thesis_table_3_2():
    """T Table 3.2 from the u_max of T Table 3.1."""
    r = cv.richardson(1.0168e-4, 1.0216e-4, 1.0314e-4)            # 80, 40, 20
    assert r["p"] == pytest.approx(1.0, abs=0.05)
    assert r["phi0"] == pytest.approx(1.012e-4, rel=2e-4)
    assert 100 * r["psci_fine"] == pytest.approx(0.59, abs=0.03)
    assert 100 * r["psci_coarse"] == pytest.approx(1.18, abs=0.04)
    assert r["asymptotic"] == pytest.approx(0.995, abs=0.002)
    r = cv.richardson(1.0144e-4, 1.0168e-4, 1.0216e-4)            # 160, 80, 40
    assert r["p"] == pytest.approx(1.02, abs=0.03)
    assert r["phi0"] == pytest.approx(1.012e-4, rel=2e-4)
    assert cv.triples([10, 20, 40, 80]) == [(10, 20, 40), (20, 40, 80)]


# --- the function object on a synthetic state -------------------------------------------------------
def _fake_run(tmp_path, coeffs: dict, y, u, dx, g=(0.0, 0.0), nu=1e-6):
    fo = VelocityProfile(VelocityProfile.Coeffs(**coeffs))
    fo.object_name = "profile"
    ctx = SimpleNamespace(dx=dx, g=g, nu=nu)
    fo.start(SimpleNamespace(path=tmp_path), ctx, "0")
    n = len(y)
    state = SimpleNamespace(y=np.asarray(y, float), u=np.asarray(u, float),
                            kind=np.full(n, FLUID))
    sim = SimpleNamespace(time=0.0, state=state)
    fo.execute(sim)
    sim.time = 7.0
    fo.end()
    return fo


def test_profile_bins_follow_the_particle_rows(tmp_path):
    """Rows at k dx (wall rows on the wall lines) or at (k + 1/2) dx (cell centres): one bin
    per row either way, and the centreline value is exact for a parabola."""
    dx = L / 40
    for offset, rows in ((0.0, 39), (0.5, 40)):
        yr = (np.arange(41) + offset) * dx
        yr = yr[(yr > 0.1 * dx) & (yr < L - 0.1 * dx)]
        y = np.repeat(yr, 3) + np.tile([-0.1, 0.0, 0.1], yr.size) * dx
        u = ct.poiseuille_steady(y, F, NU, L)
        fo = _fake_run(tmp_path / str(offset), {"l": L, "theory": "poiseuille", "plot": False},
                       y, u, dx, g=(F, 0.0))
        assert fo.yc.size == rows
        np.testing.assert_allclose(fo.yc, yr, atol=1e-12)
        r = fo.samples[-1]
        assert r["uCentre"] == pytest.approx(UMAX, rel=2e-3)        # the rows' mean
        summary = np.loadtxt(fo.folder / "uMax.dat")
        assert summary.shape == (8,) and summary[0] == 7.0
        table = np.loadtxt(fo.folder / "profile.dat")
        assert table.shape == (rows, 3)                             # y, u(7), theory(7)


def test_log_law_fit_recovers_the_friction_velocity(tmp_path):
    dx, l, Fx = 0.025, 1.0, 0.002
    yr = np.arange(1, 40) * dx
    us = ct.friction_velocity(Fx, l)
    u = ct.velocity_deficit(yr, 0.6, us, l)
    fo = _fake_run(tmp_path, {"l": l, "theory": "logLaw", "times": [0.0]}, yr, u, dx,
                   g=(Fx, 0.0))
    r = fo.samples[-1]
    assert r["uStarFit"] == pytest.approx(us, rel=1e-6)
    assert (fo.folder / "profile.png").is_file()
    assert "u* fitted" in (fo.folder / "profile.dat").read_text()


def test_log_law_force_balance_counts_the_fluid(tmp_path):
    """A channel periodic over 0.3 m with 39 rows of 12 particles of mass rho0 dx^2 (the
    tutorial's): the fluid fills 39 dx = 0.975 m of the l = 1 m between the wall rows, so
    each wall carries F rho0 0.975/2 and u* = sqrt(0.002 * 0.4875) = 0.0312250 m/s, not
    sqrt(F l/2) = 0.0316228."""
    dx, l, Fx, rho0 = 0.025, 1.0, 0.002, 1000.0
    yr = np.repeat(np.arange(1, 40) * dx, 12)
    fo = VelocityProfile(VelocityProfile.Coeffs(l=l, theory="logLaw", times=[0.0], plot=False))
    fo.object_name = "profile"
    dom = SimpleNamespace(periodic=["x"], min=(0.0, -0.1), max=(0.3, 1.1))
    fo.start(SimpleNamespace(path=tmp_path, particles=SimpleNamespace(domain=dom)),
             SimpleNamespace(dx=dx, g=(Fx, 0.0), nu=1e-6, rho0=rho0), "0")
    state = SimpleNamespace(y=yr, u=ct.velocity_deficit(yr, 0.9, 0.03, l),
                            kind=np.full(yr.size, FLUID), m=np.full(yr.size, rho0 * dx * dx))
    fo.execute(SimpleNamespace(time=0.0, state=state))
    assert fo.samples[-1]["uStarTheory"] == pytest.approx(0.0312250, rel=1e-6)
    assert fo.samples[-1]["uStarFit"] == pytest.approx(0.03, rel=1e-6)


def test_profile_window_average(tmp_path):
    """With ``window`` the sampled profile is the mean over the steps of the window."""
    dx = L / 10
    yr = np.arange(1, 10) * dx
    fo = VelocityProfile(VelocityProfile.Coeffs(l=L, times=[1.0], window=0.5, plot=False))
    fo.object_name = "profile"
    fo.start(SimpleNamespace(path=tmp_path), SimpleNamespace(dx=dx, g=(0.0, 0.0), nu=1e-6),
             "0")
    state = SimpleNamespace(y=yr, u=np.zeros(yr.size), kind=np.full(yr.size, FLUID))
    sim = SimpleNamespace(time=0.0, state=state)
    seen = []
    for k, t in enumerate([0.0, 0.4, 0.6, 0.8, 1.0, 1.2]):
        sim.time = t
        state.u = np.full(yr.size, float(k))
        if k == 0 or fo.due(sim, False):
            fo.execute(sim)
            seen.append(t)
    assert seen == [0.0, 0.6, 0.8, 1.0]                  # due from 1.0 - 0.5 on, then never
    assert len(fo.samples) == 1 and fo.samples[0]["steps"] == 3
    np.testing.assert_allclose(fo.samples[0]["u"], (2 + 3 + 4) / 3)


# --- runs ---------------------------------------------------------------------------------------------
def _case(tmp_path, name, n, end_time, times=(), plot=False, edits=None):
    case = cv.prepare(tmp_path / f"{name}{n}", n, end_time, times, template=TUTORIALS / name,
                      plot=plot)
    for where, value in (edits or {}).items():
        rel, key = where.split(":")
        set_entry(case, rel, key, value)
    return case


def test_poiseuille_start_up_follows_the_series(tmp_path):
    """20 particles across (19 fluid rows), from rest: profiles at 2 s and 5 s within 5 % of
    T(3.42) (measured: max |u - T(3.42)| = 3.4 % and 2.6 % of the profile's maximum, next to
    the walls; centreline -0.10 % and +0.23 %)."""
    case = _case(tmp_path, "poiseuille", 20, 5.0, times=(2.0, 5.0), plot=True)
    r = cv.run_resolution(case, "rest")
    rows = r["rows"]
    assert rows.shape == (2, 8)
    for t, uc, uct, err, *_ in rows:
        assert abs(err) < 5.0, f"u_centre {err:+.2f} % off T(3.42) at t = {t:g}"
    # at 2 s the centre still accelerates freely, u = F t: a check of the integrator
    assert rows[0][1] == pytest.approx(F * rows[0][0], rel=0.01)
    table = np.loadtxt(case / "postProcessing" / "profile" / "0" / "profile.dat")
    for k in (1, 3):                                   # columns u(t), theory(t)
        u, th = table[:, k], table[:, k + 1]
        assert np.abs(u - th).max() < 0.05 * th.max()
    assert (case / "postProcessing" / "profile" / "0" / "profile.png").is_file()


def test_couette_follows_the_series(tmp_path):
    """The thesis' 40 across, top wall at u0 from t = 0: every row within 2 % of u0 of T(3.46)
    at 2, 5, 10, 20 s and at the (steady) end, 60 s (measured: 1.1, 0.8, 0.6, 0.4, 0.3 %; at
    20 across the 2 s profile is 2.3 % off next to the moving wall, where the layer is only
    sqrt(nu t) = 3 dx thick)."""
    case = _case(tmp_path, "couette", 40, 60.0, times=(2.0, 5.0, 10.0, 20.0))
    r = cv.run_resolution(case, "rest")
    rows = r["rows"]
    assert rows.shape[0] == 5
    for t, *_, prof in rows:
        assert prof < 2.0, f"Couette profile {prof:.2f} % of u0 off T(3.46) at t = {t:g}"
    assert rows[-1][1] == pytest.approx(0.5 * U0, rel=0.01)      # steady u(l/2) = u0/2


@pytest.fixture(scope="module")
def steady(tmp_path_factory):
    """Steady Poiseuille flow at N = 15, 30, 60 across (about a minute on one busy core: the
    60 run is ~10 000 steps of 780 particles). Started from the steady parabola T(3.40), which
    settles to the SPH steady state in ~6 l^2/(pi^2 nu) = 60 s (from rest it takes 120 s)."""
    base = tmp_path_factory.mktemp("steady")
    out = {}
    for n in (15, 30, 60):
        case = _case(base, "poiseuille", n, 60.0)
        out[n] = cv.run_resolution(case, "theory")
    return out


def test_poiseuille_steady_umax(steady):
    """Steady u_max within 2 % of F l^2/(8 nu) at 60 across (measured +1.85 %; the thesis'
    T Table 3.1: 1.84 %). The error is first order in dx and above 2 % below ~55 across: the
    thesis has 3.14 % at 20 and 2.16 % at 40, sphfoam +3.2 % and +2.2 %."""
    errors = [steady[n]["error"] for n in (15, 30, 60)]
    assert 0.0 < errors[2] < 2.0, errors
    assert errors[0] > errors[1] > errors[2], errors


def test_convergence_order(steady):
    """Observed order of T(3.49) on 15, 30, 60 across between 0.8 and 2.5 (thesis: 1.0), and the
    continuum u_max of T(3.51) within 2 % of theory (thesis: +1.2 %)."""
    r = cv.richardson(steady[60]["u_max"], steady[30]["u_max"], steady[15]["u_max"])
    assert 0.8 < r["p"] < 2.5, r
    assert abs(r["phi0"] / UMAX - 1) < 0.02, r
    assert r["asymptotic"] == pytest.approx(1.0, abs=0.05), r
