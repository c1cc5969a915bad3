"""Time-marching schemes (T §3.11). Each integrator orchestrates one step in Python and does
every per-particle update in numba."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from pydantic import Field

from sphfoam.engine.fastmath import FASTMATH
from sphfoam.engine.state import kept_arrays
from sphfoam.registry import Coeffs, Model, register

#: fast math without reassociation: the cached code computes what freshly compiled code does
#: (sphfoam.engine.fastmath)
_JIT = dict(cache=True, fastmath=set(FASTMATH), parallel=True)


@njit(**_JIT)
def _monaghan_half(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt0, u0, v0):
    """T(3.91)-(3.93): r, v, rho to mid-step; v^0 is kept in ``u0, v0`` for the kick.
    ``pu, pv`` is the velocity positions move with (u, v, or XSPH-corrected); wall particles
    keep their velocity and move with it."""
    hdt = 0.5 * dt0
    for a in prange(x.shape[0]):
        rho[a] += hdt * drho[a]
        x[a] += hdt * pu[a]
        y[a] += hdt * pv[a]
        u0[a] = u[a]
        v0[a] = v[a]
        if kind[a] == 0:
            u[a] += hdt * ax[a]
            v[a] += hdt * ay[a]


@njit(**_JIT)
def _monaghan_kick(u, v, u0, v0, ax, ay, kind, dt0, dt1):
    """T(3.94) in its reversible form: v^1 = v^0 + (dt0 + dt1)/2 F^1/2."""
    for a in prange(u.shape[0]):
        if kind[a] == 0:
            u[a] = u0[a] + 0.5 * (dt0 + dt1) * ax[a]
            v[a] = v0[a] + 0.5 * (dt0 + dt1) * ay[a]


@njit(**_JIT)
def _drift(x, y, pu, pv, dt):
    """r += dt v (every particle: walls move with their prescribed velocity)."""
    for a in prange(x.shape[0]):
        x[a] += dt * pu[a]
        y[a] += dt * pv[a]


@njit(**_JIT)
def _density_update(rho, drho, dt):
    for a in prange(rho.shape[0]):
        rho[a] += dt * drho[a]


@register
class Monaghan2007(Model):
    """Monaghan's (2007) variable-step scheme, T(3.91)-(3.96).

    Per step: F^0, D^0 at the start; dt0 from T(3.88)-(3.90); mid-step r, v, rho; F^1/2;
    dt1 = 2 dt^1/2 - dt0 (kept >= dt^1/2 / 2 so that a sudden drop of the stable step cannot
    make dt1 vanish or turn negative); v^1, r^1; D^1; rho^1. The step advances time by
    (dt0 + dt1) / 2. Everything a step needs is recomputed from (r, v, rho), so a restart
    from a written time reproduces an uninterrupted run bit for bit.

    T(3.94)-(3.95) as printed (v^1 = v^1/2 + ..., r^1 = r^1/2 + dt1/2 v^1/2) would give a
    free particle 1.5 g and is not reversible; we use the drift-kick-drift form the text
    describes (reversible without viscosity, exact in free fall):
    v^1 = v^0 + (dt0 + dt1)/2 F^1/2 and r^1 = r^1/2 + dt1/2 v^1. v^1/2 serves only to
    evaluate the velocity-dependent forces at mid-step.
    """

    family = "integrator"
    name = "monaghan2007"
    doc = "Monaghan (2007) two-stage variable-step scheme, T(3.91)-(3.96)"
    force_evaluations_per_step = 2

    def step(self, sim, dt_remaining: float) -> float:
        """Advance ``sim`` by one step of at most ``dt_remaining``; return the time advanced."""
        st = sim.state
        sim.eos()
        sim.rates()                               # F^0, D^0
        dt0 = min(sim.time_step(), dt_remaining)
        pu, pv = sim.position_velocity(st.u, st.v)
        _monaghan_half(st.x, st.y, st.u, st.v, pu, pv, st.rho, st.ax, st.ay, st.drho, st.kind,
                       dt0, st.u_half, st.v_half)
        sim.move_walls(sim.time + 0.5 * dt0)
        sim.eos()
        sim.rates()                               # F^1/2
        dth = sim.time_step()
        if sim.adjust_time_step:
            dt1 = max(2.0 * dth - dt0, 0.5 * dth)
        else:
            dt1 = dt0
        dt1 = min(dt1, 2.0 * dt_remaining - dt0)   # land exactly on the next write time
        _monaghan_kick(st.u, st.v, st.u_half, st.v_half, st.ax, st.ay, st.kind, dt0, dt1)
        pu, pv = sim.position_velocity(st.u, st.v)
        _drift(st.x, st.y, pu, pv, 0.5 * dt1)
        sim.move_walls(sim.time + 0.5 * (dt0 + dt1))
        # rho^1/2 + dt1/2 D^1 with D^1 from r^1, v^1 (T(3.96))
        sim.density_rate()
        _density_update(st.rho, st.drho, 0.5 * dt1)
        sim.last_dt = 0.5 * (dt0 + dt1)
        return sim.last_dt


# --- predictor-corrector, P(37)-(38) -------------------------------------------------------
@njit(**_JIT)
def _pc_predict(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt, x0, y0, u0, v0, rho0):
    """P(37): rho, v, r to t^k + dt/2 with M^k, F^k, U^k; the state at t^k into x0 ... rho0."""
    n = x.shape[0]
    hdt = 0.5 * dt
    for a in prange(n):
        x0[a] = x[a]
        y0[a] = y[a]
        u0[a] = u[a]
        v0[a] = v[a]
        rho0[a] = rho[a]
        rho[a] += hdt * drho[a]
        x[a] += hdt * pu[a]         # walls move with their prescribed velocity
        y[a] += hdt * pv[a]
        if kind[a] == 0:
            u[a] += hdt * ax[a]
            v[a] += hdt * ay[a]


@njit(**_JIT)
def _pc_correct(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt, x0, y0, u0, v0, rho0):
    """P(38): rho^k+1 = rho^k + dt M^k+1/2, v^k+1 = v^k + dt F^k+1/2, r^k+1 = r^k + dt U^k+1/2."""
    for a in prange(x.shape[0]):
        rho[a] = rho0[a] + dt * drho[a]
        x[a] = x0[a] + dt * pu[a]
        y[a] = y0[a] + dt * pv[a]
        if kind[a] == 0:
            u[a] = u0[a] + dt * ax[a]
            v[a] = v0[a] + dt * ay[a]
        else:
            u[a] = u0[a]
            v[a] = v0[a]


@register
class PredictorCorrector(Model):
    """Predictor-corrector (explicit midpoint) scheme of the paper, P(37)-(38).

    Per step: M^k, F^k, U^k at the start; dt from P(39) / T(3.88)-(3.90) (``sim.time_step``);
    predictor P(37) to t^k + dt/2; M, F, U at the mid-step; corrector P(38) from the state at
    t^k with the mid-step rates. The paper's corrector is the whole-step update from t^k (the
    DualSPHysics form, a half step from the mid-step followed by phi^k+1 = 2 phi^k+1/2 - phi^k,
    is algebraically the same). Nothing carries over between steps, so a restart is exact.
    """

    family = "integrator"
    name = "predictorCorrector"
    doc = "predictor-corrector (midpoint) scheme, P(37)-(38), step from P(39) / T(3.88)-(3.90)"
    force_evaluations_per_step = 2
    #: dt comes from the step's first evaluation: the mid-step one skips sigma, T(3.89)
    time_step_from_first_evaluation = True

    def step(self, sim, dt_remaining: float) -> float:
        """Advance ``sim`` by one step of at most ``dt_remaining``; return the time advanced."""
        st = sim.state
        sim.eos()
        sim.rates()                               # M^k, F^k
        dt = min(sim.time_step(), dt_remaining)
        pu, pv = sim.position_velocity(st.u, st.v)   # U^k
        saved = kept_arrays(self, "_saved", 5, st.n)   # the state at the step's start
        _pc_predict(st.x, st.y, st.u, st.v, pu, pv, st.rho, st.ax, st.ay, st.drho, st.kind,
                    dt, *saved)
        sim.move_walls(sim.time + 0.5 * dt)
        sim.eos()
        sim.rates()                               # M^k+1/2, F^k+1/2
        pu, pv = sim.position_velocity(st.u, st.v)   # U^k+1/2
        _pc_correct(st.x, st.y, st.u, st.v, pu, pv, st.rho, st.ax, st.ay, st.drho, st.kind,
                    dt, *saved)
        sim.move_walls(sim.time + dt)
        sim.last_dt = dt
        return dt


# --- Verlet (DualSPHysics) -----------------------------------------------------------------
@njit(**_JIT)
def _verlet_step(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt, dtv, euler,
                 u_old, v_old, rho_old, dt_old, t_hist, t_new):
    """One Verlet (``euler`` False) or Euler step; (u_old, v_old, rho_old) hold the state one
    step back on entry and the state at t^n on exit. ``dtv`` = dt^n-1 + dt^n (= 2 dt for a
    fixed step) spans the leapfrog branch from t^n-1 to t^n+1."""
    hdt2 = 0.5 * dt * dt
    for a in prange(x.shape[0]):
        un = u[a]
        vn = v[a]
        rn = rho[a]
        if kind[a] == 0:
            x[a] += dt * pu[a] + hdt2 * ax[a]
            y[a] += dt * pv[a] + hdt2 * ay[a]
            if euler:
                u[a] = un + dt * ax[a]
                v[a] = vn + dt * ay[a]
            else:
                u[a] = u_old[a] + dtv * ax[a]
                v[a] = v_old[a] + dtv * ay[a]
        else:
            x[a] += dt * pu[a]      # walls keep their velocity and move with it
            y[a] += dt * pv[a]
        if euler:
            rho[a] = rn + dt * drho[a]
        else:
            rho[a] = rho_old[a] + dtv * drho[a]
        u_old[a] = un
        v_old[a] = vn
        rho_old[a] = rn
        dt_old[a] = dt
        t_hist[a] = t_new


@register
class Verlet(Model):
    """Verlet scheme of DualSPHysics (Monaghan 1989): v^n+1 = v^n-1 + 2 dt F^n,
    r^n+1 = r^n + dt v^n + dt^2/2 F^n, rho^n+1 = rho^n-1 + 2 dt D^n.

    Limitation (measured): the leapfrog branch v^{n+1} = v^{n-1} + 2 dt F^n is unconditionally
    unstable on a diffusion term, so a viscosity-dominated flow (the laminar Poiseuille case at
    Re = 1) blows up after some 30-40 s even with an Euler step every 40; use another integrator
    there, or a small ``everyN``.

    One force evaluation per step; dt from T(3.88)-(3.90). Every ``everyN`` steps (by the run's
    step index), on the first step, after a density-filter pass, and whenever the stored
    history does not belong to the step just before (e.g. after a restart from a time written
    by another integrator) an Euler step v^n+1 = v^n + dt F^n, rho^n+1 = rho^n + dt D^n is
    taken instead, which couples the two leapfrog branches. With a variable step the branch
    spans dt^n-1 + dt^n, which is 2 dt for a fixed step. The history (v^n-1, rho^n-1, dt^n-1 and
    the time of the state it precedes) is kept in the persistent particle fields ``Ux_0``,
    ``Uy_0``, ``rho_0``, ``deltaT_0``, ``historyTime``, so a restart reproduces an
    uninterrupted run bit for bit. Positions move with ``sim.position_velocity`` at t^n.
    """

    family = "integrator"
    name = "verlet"
    doc = ("Verlet scheme of DualSPHysics (Monaghan 1989), v^n+1 = v^n-1 + 2 dt F^n, with an "
           "Euler step every everyN steps")
    force_evaluations_per_step = 1

    class Coeffs(Coeffs):
        everyN: int = Field(40, ge=1, description="an Euler step every everyN steps couples "
                            "the two leapfrog branches (DualSPHysics' VerletSteps)")

    #: v^n-1, rho^n-1, dt^n-1 and the time of the state they precede
    HISTORY = ("Ux_0", "Uy_0", "rho_0", "deltaT_0", "historyTime")

    def _history_valid(self, sim) -> bool:
        """Whether ``state.extra`` holds history for the current state (else: Euler step);
        (re)creates the arrays when they are missing."""
        st = sim.state
        ex = st.extra
        if st.n == 0 or not all(k in ex and ex[k].shape == (st.n,) for k in self.HISTORY):
            for k in self.HISTORY:
                ex[k] = np.zeros(st.n)
            return False
        dt_old = float(ex["deltaT_0"][0])
        t_hist = float(ex["historyTime"][0])
        return dt_old > 0.0 and abs(t_hist - sim.time) <= 1e-9 * max(dt_old, abs(t_hist))

    def step(self, sim, dt_remaining: float) -> float:
        """Advance ``sim`` by one step of at most ``dt_remaining``; return the time advanced."""
        st = sim.state
        valid = self._history_valid(sim)
        sim.eos()
        sim.rates()                               # F^n, D^n
        dt = min(sim.time_step(), dt_remaining)
        euler = (not valid) or sim.filtered or sim.step_index % self.coeffs.everyN == 0
        ex = st.extra
        dtv = float(ex["deltaT_0"][0]) + dt if valid else 2.0 * dt
        pu, pv = sim.position_velocity(st.u, st.v)
        _verlet_step(st.x, st.y, st.u, st.v, pu, pv, st.rho, st.ax, st.ay, st.drho, st.kind,
                     dt, dtv, bool(euler), ex["Ux_0"], ex["Uy_0"], ex["rho_0"], ex["deltaT_0"],
                     ex["historyTime"], sim.time + dt)
        sim.move_walls(sim.time + dt)
        sim.last_dt = dt
        return dt


# --- symplectic position Verlet (DualSPHysics) ---------------------------------------------
@njit(**_JIT)
def _symplectic_half(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt, u0, v0, rho0, du0, dv0):
    """r, rho, v to t^n + dt/2 with U^n, D^n, F^n; (u^n, v^n, rho^n) and the velocity
    correction U^n - v^n (zero without XSPH) into u0 ... dv0."""
    n = x.shape[0]
    hdt = 0.5 * dt
    for a in prange(n):
        u0[a] = u[a]
        v0[a] = v[a]
        rho0[a] = rho[a]
        du0[a] = pu[a] - u[a]
        dv0[a] = pv[a] - v[a]
        x[a] += hdt * pu[a]
        y[a] += hdt * pv[a]
        rho[a] += hdt * drho[a]
        if kind[a] == 0:
            u[a] += hdt * ax[a]
            v[a] += hdt * ay[a]


@njit(**_JIT)
def _symplectic_velocity_density(u, v, rho, ax, ay, drho, kind, dt, u0, v0, rho0):
    """v^n+1 = v^n + dt F^n+1/2; rho^n+1 = rho^n (2 - eps)/(2 + eps) with
    eps = -(D^n+1/2 / rho^n+1/2) dt (walls keep their velocity; their density evolves)."""
    for a in prange(u.shape[0]):
        eps = -drho[a] / rho[a] * dt
        rho[a] = rho0[a] * (2.0 - eps) / (2.0 + eps)
        if kind[a] == 0:
            u[a] = u0[a] + dt * ax[a]
            v[a] = v0[a] + dt * ay[a]
        else:
            u[a] = u0[a]
            v[a] = v0[a]


@njit(**_JIT)
def _symplectic_drift(x, y, u, v, pu, pv, du0, dv0, dt):
    """r^n+1 = r^n+1/2 + dt/2 (v^n+1 + 2 dU^n+1/2 - dU^n): with a velocity correction
    dU = U - v (XSPH) the correction enters at the mid-step over the whole step (second
    order); without one this is r^n+1/2 + dt/2 v^n+1 exactly (2 U - v - 0 = v in floating
    point when U is v)."""
    hdt = 0.5 * dt
    for a in prange(x.shape[0]):
        x[a] += hdt * (2.0 * pu[a] - u[a] - du0[a])
        y[a] += hdt * (2.0 * pv[a] - v[a] - dv0[a])


@register
class Symplectic(Model):
    """Symplectic position Verlet of DualSPHysics (Leimkuhler et al. 1996).

    Per step: F^n, D^n and dt (T(3.88)-(3.90)); half step r^n+1/2 = r^n + dt/2 v^n,
    rho^n+1/2 = rho^n + dt/2 D^n, v^n+1/2 = v^n + dt/2 F^n; F^n+1/2, D^n+1/2; then
    v^n+1 = v^n + dt F^n+1/2, r^n+1 = r^n+1/2 + dt/2 v^n+1 and
    rho^n+1 = rho^n (2 - eps)/(2 + eps) with eps = -(D^n+1/2 / rho^n+1/2) dt. Positions move
    with ``sim.position_velocity``; a velocity correction (XSPH) dU is applied at the mid-step,
    r^n+1 = r^n+1/2 + dt/2 (v^n+1 + 2 dU^n+1/2 - dU^n), which keeps the scheme second order
    (with no correction this is the formula above exactly). Nothing carries over between
    steps, so a restart is exact.
    """

    family = "integrator"
    name = "symplectic"
    doc = ("symplectic position Verlet of DualSPHysics (Leimkuhler), half step, F^n+1/2, "
           "rho^n+1 = rho^n (2 - eps)/(2 + eps)")
    force_evaluations_per_step = 2
    #: dt comes from the step's first evaluation: the mid-step one skips sigma, T(3.89)
    time_step_from_first_evaluation = True

    def step(self, sim, dt_remaining: float) -> float:
        """Advance ``sim`` by one step of at most ``dt_remaining``; return the time advanced."""
        st = sim.state
        sim.eos()
        sim.rates()                               # F^n, D^n
        dt = min(sim.time_step(), dt_remaining)
        pu, pv = sim.position_velocity(st.u, st.v)
        saved = kept_arrays(self, "_saved", 5, st.n)   # the state at the step's start
        _symplectic_half(st.x, st.y, st.u, st.v, pu, pv, st.rho, st.ax, st.ay, st.drho,
                         st.kind, dt, *saved)
        sim.move_walls(sim.time + 0.5 * dt)
        sim.eos()
        sim.rates()                               # F^n+1/2, D^n+1/2
        u0, v0, rho0, du0, dv0 = saved
        _symplectic_velocity_density(st.u, st.v, st.rho, st.ax, st.ay, st.drho, st.kind, dt,
                                     u0, v0, rho0)
        pu, pv = sim.position_velocity(st.u, st.v)   # v^n+1 + XSPH correction at n+1/2
        _symplectic_drift(st.x, st.y, st.u, st.v, pu, pv, du0, dv0, dt)
        sim.move_walls(sim.time + dt)
        sim.last_dt = dt
        return dt
