"""The law of the wall and the hydrostatic pressure on mirror ghosts
(``boundary { type mirrorGhosts; wallLaw ...; pressure hydrostatic; }``).

A free-slip mirror wall exerts no tangential force; ``wallLaw`` adds the wall shear stress
tau_w = rho u*^2 of T(3.84)-(3.85) (or a prescribed U+) as a boundary integral over the wall
line, dv_a/dt = -2 Phi(d_a) u*_a^2 t_a (sphfoam.models.mirror.wall_shear). Shown here:

* Phi, the kernel integrated along a line, against a direct 2-D quadrature, and its
  normalisation (half the kernel on one side of the wall);
* a plane wall under a lattice of fluid exerts tau_w per unit length at any resolution
  (uniform flow with U+; a log-law profile with the smooth and rough laws), along the wall
  for a sloping wall too, against the flow, and nothing when the fluid moves with the wall;
* in a simulation the stress is added to the rates, costs nothing when not selected, and
  bad input is refused;
* the ghosts' hydrostatic pressure p_G = p_a + rho_a g.(x_G - x_a) (the wall's Neumann
  condition), and the tank at rest it holds against T(3.80)'s p_G = p_a.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError
from scipy.integrate import dblquad

from sphfoam import registry
from sphfoam.engine.build import build_pipeline
from sphfoam.engine.plan import Selection
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import FLUID, ParticleState
from sphfoam.models import mirror as gh
from sphfoam.models import walllaw as wl
from sphfoam.models.base import CaseContext

RHO0 = 1000.0
NU = 1e-6


def smooth_profile(us):
    """u(y) of the smooth law T(3.84) with friction velocity us."""
    return lambda y: us * (np.log(y * us / NU) / wl.KAPPA + wl.B_SMOOTH)


def rough_profile(us, ks):
    return lambda y: us * (np.log(y / ks) / wl.KAPPA + wl.B_ROUGH)


@pytest.fixture(scope="module")
def quartic():
    return registry.build("kernel", {"type": "quartic", "hdx": 1.3})


def test_line_kernel_is_the_kernel_integrated_along_the_line(quartic):
    h = 0.013
    reach = quartic.support_radius(h)
    phi = gh.line_kernel(quartic.W, h, reach)
    d = np.linspace(0.0, reach, phi.size)
    # the half-plane y > 0 holds half of the kernel: int_0^R Phi = 1/2 before any scaling
    # (the scaling is a correction of the trapezoid's error only)
    area = float(np.trapezoid(phi, d))
    assert area == pytest.approx(0.5, rel=1e-12)
    # Phi at d against a 2-D quadrature of W over the strip d - e < y < d + e, / 2e
    for di in (0.1 * h, 0.7 * h, 1.5 * h):
        e = 1e-4 * h
        strip = dblquad(lambda s, t: 2 * float(quartic.W(math.hypot(t, s), h)), di - e, di + e,
                        0.0, lambda t: math.sqrt(max(reach ** 2 - t ** 2, 0.0)))[0]
        assert np.interp(di, d, phi) == pytest.approx(strip / (2 * e), rel=2e-3)
    assert phi[-1] == 0.0 and np.all(np.diff(phi) <= 1e-12)


def lattice(dx, rows, length, angle=0.0, profile=lambda y: np.ones_like(y), wall_u=0.0):
    """Fluid on a lattice over a wall line through the origin at ``angle``, rows at
    y' = (k + 1/2) dx above it, x' in [0, length); velocity profile(y') along the wall plus
    the wall's own ``wall_u``. Returns positions, velocities, masses and the (1, 9) segment
    array (the wall extended by 1 m on both sides, so that every particle projects on it)."""
    xs = (np.arange(int(round(length / dx))) + 0.5) * dx
    ys = (np.arange(rows) + 0.5) * dx
    X, Y = (a.ravel() for a in np.meshgrid(xs, ys))
    c, s = math.cos(angle), math.sin(angle)
    x, y = c * X - s * Y, s * X + c * Y
    ut = profile(Y) + wall_u
    u, v = c * ut, s * ut
    seg = np.array([[-c, -s, c, s, -s, c, length + 2.0, wall_u * c, wall_u * s]])
    return x, y, u, v, np.full(x.size, RHO0 * dx * dx), seg


def wall_force(x, y, u, v, m, seg, reach, phi, law, coef):
    ax = np.zeros_like(x)
    ay = np.zeros_like(x)
    n = gh.wall_shear(x, y, u, v, np.zeros(x.size, dtype=np.int64), seg, reach, phi,
                      gh.WALL_SHEAR_LAWS[law], coef, ax, ay)
    return np.sum(m * ax), np.sum(m * ay), n


LAWS = {
    # law, coefficient, profile, u*
    "prescribedUPlus": (1.5, lambda y: np.full_like(y, 0.3), 0.2),
    "smooth": (NU, smooth_profile(0.05), 0.05),
    "rough": (1e-4, rough_profile(0.04, 1e-4), 0.04),
}


@pytest.mark.parametrize("law", list(LAWS))
@pytest.mark.parametrize("dx", [0.05, 0.02, 0.01])
def test_a_plane_wall_exerts_tau_w_at_any_resolution(quartic, law, dx):
    """Sum over the lattice of m_a dv_a/dt = -rho u*^2 per unit length, along the wall: the
    lattice's sum of Phi against its integral (measured 0.008 % low at every dx, asserted
    0.1 %); the profile follows the law, so every particle finds the same u*."""
    coef, profile, us = LAWS[law]
    h = 1.3 * dx
    reach = quartic.support_radius(h)
    phi = gh.line_kernel(quartic.W, h, reach)
    length = 1.0
    fx, fy, n = wall_force(*lattice(dx, 8, length, profile=profile), reach, phi, law, coef)
    assert fx == pytest.approx(-RHO0 * us * us * length, rel=1e-3)
    assert abs(fy) < 1e-12 * RHO0 * us * us
    assert n == int(round(length / dx)) * math.ceil(reach / dx - 0.5)


def test_a_sloping_moving_wall_drags_along_itself_against_the_relative_flow(quartic):
    """A 5 degree wall moving at 0.1 m/s under fluid at 0.1 + 0.3 m/s along it: the force is
    -rho (0.3/U+)^2 along the wall (no normal part); fluid moving with the wall feels none."""
    dx, h = 0.02, 0.026
    reach = quartic.support_radius(h)
    phi = gh.line_kernel(quartic.W, h, reach)
    ang = math.radians(5.0)
    fx, fy, _ = wall_force(*lattice(dx, 6, 1.0, ang, lambda y: np.full_like(y, 0.3), 0.1),
                           reach, phi, "prescribedUPlus", 1.5)
    f = RHO0 * 0.2 ** 2
    assert fx == pytest.approx(-f * math.cos(ang), rel=0.01)
    assert fy == pytest.approx(-f * math.sin(ang), rel=0.01)
    assert abs(-fx * math.sin(ang) + fy * math.cos(ang)) < 1e-9 * f      # normal part
    fx0, fy0, _ = wall_force(*lattice(dx, 6, 1.0, ang, lambda y: np.zeros_like(y), 0.1),
                             reach, phi, "prescribedUPlus", 1.5)
    assert fx0 == 0.0 and fy0 == 0.0


def test_rough_law_below_the_roughness_takes_its_value_at_ks(quartic):
    """A particle closer to the wall than ks gets u* = u_t/8.5 (T(3.85) at y = ks)."""
    h = 0.013
    reach = quartic.support_radius(h)
    phi = gh.line_kernel(quartic.W, h, reach)
    d, ut, ks = 0.002, 0.5, 0.004
    x, y = np.array([0.3]), np.array([d])
    ax, ay = np.zeros(1), np.zeros(1)
    seg = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]])
    gh.wall_shear(x, y, np.array([ut]), np.zeros(1), np.zeros(1, dtype=np.int64), seg, reach,
                  phi, gh.WALL_SHEAR_LAWS["rough"], ks, ax, ay)
    w = np.interp(d, np.linspace(0.0, reach, phi.size), phi)
    assert ax[0] == pytest.approx(-2.0 * w * (ut / wl.B_ROUGH) ** 2, rel=1e-3)
    assert ay[0] == 0.0


# --- in a simulation ------------------------------------------------------------------------
DX, H = 0.01, 0.013


def _pipe(boundary, g=0.0):
    specs = dict(kernel={"type": "quartic", "hdx": 1.3},
                 equationOfState={"type": "tait", "speedOfSound": 20.0},
                 continuity={"type": "differenceForm"}, momentum={"type": "symmetric"},
                 viscosity={"type": "none"}, boundary=boundary)
    sel = Selection(*(registry.build(f, s) for f, s in specs.items()))
    ctx = CaseContext(dx=DX, h=H, rho0=RHO0, nu=NU, g=(0.0, -g), fluid_height=0.1, c0=20.0)
    return build_pipeline(sel, ctx)


def _box_sim(pipe, x, y, u, rho):
    """Fluid particles at (x, y) moving at (u, 0) in a 0.4 m box open at the top, on mirror
    ghosts (no gravity unless the pipeline has it); neighbours, equation of state and rates
    evaluated once."""
    from sphfoam.case.schemas import ParticleDict
    from sphfoam.case.geometry import segments_of

    pd = ParticleDict.model_validate(
        {"dx": DX, "walls": {"tank": {"type": "box", "min": (0, 0), "max": (0.4, 0.2),
                                      "open": "top"}},
         "fluid": {"w": {"type": "box", "min": (0, 0), "max": (0.4, 0.06)}}})
    n = len(x)
    st = ParticleState(np.asarray(x, float), np.asarray(y, float), np.full(n, u),
                       np.zeros(n), np.full(n, rho), np.full(n, RHO0 * DX * DX),
                       np.full(n, FLUID))
    integ = registry.build("integrator", {"type": "monaghan2007"})
    sim = Simulation(st, pipe, integ, h=H, support=pipe.selection.kernel.support,
                     domain_lo=(-0.1, -0.1), domain_hi=(0.5, 0.4), beta=0.2,
                     force_condition=True, adjust_time_step=True, delta_t=1e-4,
                     segments=segments_of(pd))
    sim.neighbour_update()
    sim.eos()
    sim.rates()
    return sim


def _film_sim(pipe, u0):
    """A film of fluid 6 dx deep on the bed of the box, moving at u0."""
    X, Y = (a.ravel() for a in np.meshgrid((np.arange(40) + 0.5) * DX,
                                           (np.arange(6) + 0.5) * DX))
    return _box_sim(pipe, X, Y, u0, RHO0)


def test_the_simulation_adds_the_wall_stress_to_the_rates():
    """The same film with and without ``wallLaw prescribedUPlus``: the accelerations differ
    by exactly what wall_shear adds, and the bed's total is -rho (u0/U+)^2 per unit length
    (the side walls see no tangential flow: the film moves along x)."""
    u0, uplus = 0.3, 1.5
    free = _film_sim(_pipe({"type": "mirrorGhosts"}), u0)
    law = _film_sim(_pipe({"type": "mirrorGhosts", "wallLaw": "prescribedUPlus",
                           "UPlus": uplus}), u0)
    assert not free.pipeline.selection.boundary.implements("after_rates")
    assert law.pipeline.selection.boundary.implements("after_rates")
    fl = law.state.kind == FLUID
    ff = free.state.kind == FLUID
    np.testing.assert_array_equal(law.state.x[fl], free.state.x[ff])
    dfx = np.sum(law.state.m[fl] * (law.state.ax[fl] - free.state.ax[ff]))
    dfy = np.sum(law.state.m[fl] * (law.state.ay[fl] - free.state.ay[ff]))
    # every column of the film projects onto the bed (measured 0.008 % low, the lattice's
    # sum of Phi); the side walls exert nothing (no velocity along them)
    assert dfx == pytest.approx(-RHO0 * (u0 / uplus) ** 2 * 0.4, rel=1e-3)
    assert abs(dfy) < 1e-9 * abs(dfx)


@pytest.mark.parametrize("spec, words", [
    ({"wallLaw": "rough"}, "needs ks"),
    ({"wallLaw": "prescribedUPlus"}, "needs UPlus"),
    ({"wallLaw": "smooth", "UPlus": 1.5}, "UPlus is used only with wallLaw prescribedUPlus"),
    ({"wallLaw": "smooth", "noSlip": True}, "set noSlip no"),
    ({"wallLaw": "slippery"}, "smooth"),
])
def test_bad_wall_law_input_is_refused(spec, words):
    with pytest.raises(ValidationError, match=words):
        registry.build("boundary", {"type": "mirrorGhosts", **spec})


# --- the ghosts' hydrostatic pressure (``pressure hydrostatic``) ------------------------------
def test_hydrostatic_ghost_pressure_is_the_neumann_condition():
    """A particle 0.3 dx above the bed and 0.2 dx from the left wall: each ghost's pressure
    (the equation of state of the density the refresh gives it) is p_a + rho_a g.(x_G - x_a),
    to round-off: 2 rho g d below the bed, p_a across the vertical wall, and the corner
    ghost the bed's; with ``pressure mirror`` every ghost has p_a (T(3.80))."""
    from sphfoam.engine.state import GHOST

    g = 9.81
    rho_a = RHO0 * 1.003
    for pressure in ("hydrostatic", "mirror"):
        pipe = _pipe({"type": "mirrorGhosts", "pressure": pressure}, g)
        st = _box_sim(pipe, [0.2 * DX], [0.3 * DX], 0.0, rho_a)
        eos = pipe.selection.equationOfState
        ctx = CaseContext(dx=DX, h=H, rho0=RHO0, nu=NU, g=(0.0, -g), fluid_height=0.1, c0=20.0)
        ghosts = st.state.kind == GHOST
        pa = eos.pressure(rho_a, ctx)
        pg = eos.pressure(st.state.rho[ghosts], ctx)
        depth = st.state.y[ghosts] - 0.3 * DX                  # y_G - y_a
        expect = pa - rho_a * g * depth if pressure == "hydrostatic" else np.full(3, pa)
        assert ghosts.sum() == 3
        np.testing.assert_allclose(pg, expect, rtol=1e-9, atol=1e-9 * pa)


def test_hydrostatic_ghosts_hold_the_tank_at_rest(tutorial):
    """The hydrostaticTank tutorial on mirror ghosts at dx = 0.02 m for 1 s: with the ghosts'
    hydrostatic pressure the pressure of the fluid (below 0.3 m) is rho g (H - y) within
    0.8 % rms of rho g H (measured 0.57 % at 1 s) and the bottom row stays at dx/2 with
    its pressure within 1.5 % (measured +0.9 %); with T(3.80)'s p_G = p_a the bottom row's
    pressure is 5.7 % above hydrostatic and the rms error 3.0 % (measured)."""
    from sphfoam.case.case import Case
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import read_state
    from sphfoam.setup import setup_case
    from sphfoam.timeloop import run_case

    err = {}
    for pressure in ("hydrostatic", "mirror"):
        case = tutorial("hydrostaticTank", {
            "constant/sphProperties:boundary": {"type": "mirrorGhosts", "pressure": pressure},
            "system/particleDict:dx": 0.02, "system/controlDict:endTime": 1.0,
            "system/controlDict:writeInterval": 1.0})
        setup_case(Case(case), log=lambda m: None)
        run_case(case, progress=False, echo=None)
        s = read_state(list_times(case)[-1][1])
        f = s["type"] == FLUID
        y = s["positions"][f][:, 1]
        p = s["p"][f]
        ref = RHO0 * 9.81 * (0.4 - y)
        deep = y < 0.3
        bottom = y < 0.015
        err[pressure] = (np.sqrt(np.mean(((p - ref)[deep] / (RHO0 * 9.81 * 0.4)) ** 2)),
                         np.mean(p[bottom] / ref[bottom]) - 1.0, y[bottom].mean() / 0.02)
    rms, bottom, row = err["hydrostatic"]
    assert rms < 0.008 and abs(bottom) < 0.015 and row == pytest.approx(0.5, abs=0.01)
    assert err["mirror"][0] > 3 * rms and err["mirror"][1] > 0.03
