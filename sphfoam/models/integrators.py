"""Time-marching schemes (T §3.11). Each integrator declares its per-particle updates
(:class:`~sphfoam.engine.stepping.ParticleUpdate`, written once with ``@`` for the
components) and orders the stages of a step in Python, once per step; the backend compiles
and runs the updates (see :mod:`sphfoam.engine.stepping`)."""

from __future__ import annotations

import numpy as np
from pydantic import Field

from sphfoam.engine.stepping import ParticleUpdate, field_components
from sphfoam.registry import Coeffs, Model, register

#: r += dt U (every particle: walls move with their prescribed velocity)
DRIFT = ParticleUpdate("drift", "X@[a] += dt * pU@[a]")
#: rho += dt drho/dt
DENSITY = ParticleUpdate("density", "rho[a] += dt * drho[a]")

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
    updates = (
        # T(3.91)-(3.93): r, v, rho to mid-step; v^0 kept in U@0 for the kick; walls keep
        # their velocity and move with it
        ParticleUpdate("half", scalars=("dt0",), setup="hdt = 0.5 * dt0", code="""
rho[a] += hdt * drho[a]
X@[a] += hdt * pU@[a]
U@0[a] = U@[a]
if kind[a] == FLUID:
    U@[a] += hdt * a@[a]"""),
        # T(3.94) in its reversible form: v^1 = v^0 + (dt0 + dt1)/2 F^1/2
        ParticleUpdate("kick", scalars=("dt0", "dt1"), code="""
if kind[a] == FLUID:
    U@[a] = U@0[a] + 0.5 * (dt0 + dt1) * a@[a]"""),
        DRIFT, DENSITY)
    kept = {"U@0": "working"}

    def step(self, run, dt_remaining: float) -> float:
        """Advance ``run`` by one step of at most ``dt_remaining``; return the time advanced."""
        run.evaluate()                            # F^0, D^0
        dt0 = min(run.time_step(), dt_remaining)
        run.advect()
        run.update("half", dt0=dt0)
        run.move_walls(run.time + 0.5 * dt0)
        run.evaluate()                            # F^1/2
        dth = run.time_step()
        if run.adjust_time_step:
            dt1 = max(2.0 * dth - dt0, 0.5 * dth)
        else:
            dt1 = dt0
        dt1 = min(dt1, 2.0 * dt_remaining - dt0)   # land exactly on the next write time
        run.update("kick", dt0=dt0, dt1=dt1)
        run.advect()
        run.update("drift", dt=0.5 * dt1)
        run.move_walls(run.time + 0.5 * (dt0 + dt1))
        run.evaluate_density()
        run.update("density", dt=0.5 * dt1)
        return 0.5 * (dt0 + dt1)


@register
class PredictorCorrector(Model):
    """Predictor-corrector (explicit midpoint) scheme of the paper, P(37)-(38).

    Per step: M^k, F^k, U^k at the start; dt from P(39) / T(3.88)-(3.90) (``run.time_step``);
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
    updates = (
        # P(37): rho, v, r to t^k + dt/2 with M^k, F^k, U^k; the state at t^k kept
        ParticleUpdate("predict", setup="hdt = 0.5 * dt", code="""
X@0[a] = X@[a]
U@0[a] = U@[a]
rho0[a] = rho[a]
rho[a] += hdt * drho[a]
X@[a] += hdt * pU@[a]
if kind[a] == FLUID:
    U@[a] += hdt * a@[a]"""),
        # P(38): rho^k+1 = rho^k + dt M^k+1/2, v^k+1 = v^k + dt F^k+1/2,
        # r^k+1 = r^k + dt U^k+1/2
        ParticleUpdate("correct", code="""
rho[a] = rho0[a] + dt * drho[a]
X@[a] = X@0[a] + dt * pU@[a]
if kind[a] == FLUID:
    U@[a] = U@0[a] + dt * a@[a]
else:
    U@[a] = U@0[a]"""))
    kept = {"X@0": "double", "U@0": "double", "rho0": "double"}


    def step(self, run, dt_remaining: float) -> float:
        """Advance ``run`` by one step of at most ``dt_remaining``; return the time advanced."""
        run.evaluate()                            # M^k, F^k
        dt = min(run.time_step(), dt_remaining)
        run.advect()                              # U^k
        run.update("predict", dt=dt)
        run.move_walls(run.time + 0.5 * dt)
        run.evaluate()                            # M^k+1/2, F^k+1/2
        run.advect()                              # U^k+1/2
        run.update("correct", dt=dt)
        run.move_walls(run.time + dt)
        return dt


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
    uninterrupted run bit for bit. Positions move with ``run.advect()`` at t^n.
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
    #: one Verlet (``euler`` False) or Euler step; the history holds the state one step
    #: back on entry and the state at t^n on exit. ``dtv`` = dt^n-1 + dt^n (= 2 dt for a
    #: fixed step) spans the leapfrog branch from t^n-1 to t^n+1
    updates = (ParticleUpdate("step", scalars=("dt", "dtv", "euler", "t_new"),
                              setup="hdt2 = 0.5 * dt * dt", code="""
U@n = U@[a]
rn = rho[a]
if kind[a] == FLUID:
    X@[a] += dt * pU@[a] + hdt2 * a@[a]
    if euler:
        U@[a] = U@n + dt * a@[a]
    else:
        U@[a] = U@_old[a] + dtv * a@[a]
else:
    X@[a] += dt * pU@[a]
if euler:
    rho[a] = rn + dt * drho[a]
else:
    rho[a] = rho_old[a] + dtv * drho[a]
U@_old[a] = U@n
rho_old[a] = rn
dt_old[a] = dt
t_hist[a] = t_new"""),)
    #: the history, persistent particle fields (written to and read from time directories)
    history = {"U@_old": "U{axis}_0", "rho_old": "rho_0", "dt_old": "deltaT_0",
               "t_hist": "historyTime"}

    def _history_valid(self, run) -> bool:
        """Whether ``state.extra`` holds history for the current state (else: Euler step);
        (re)creates the arrays when they are missing."""
        st = run.state
        ex = st.extra
        names = [c for f in self.history.values() for c in field_components(f, st.dim)]
        if st.n == 0 or not all(k in ex and ex[k].shape == (st.n,) for k in names):
            for k in names:
                ex[k] = np.zeros(st.n)
            return False
        dt_old = float(ex["deltaT_0"][0])
        t_hist = float(ex["historyTime"][0])
        return dt_old > 0.0 and abs(t_hist - run.time) <= 1e-9 * max(dt_old, abs(t_hist))

    def step(self, run, dt_remaining: float) -> float:
        """Advance ``run`` by one step of at most ``dt_remaining``; return the time advanced."""
        valid = self._history_valid(run)
        run.evaluate()                            # F^n, D^n
        dt = min(run.time_step(), dt_remaining)
        euler = (not valid) or run.filtered or run.step_index % self.coeffs.everyN == 0
        dtv = float(run.state.extra["deltaT_0"][0]) + dt if valid else 2.0 * dt
        run.advect()
        run.update("step", dt=dt, dtv=dtv, euler=bool(euler), t_new=run.time + dt)
        run.move_walls(run.time + dt)
        return dt


@register
class Symplectic(Model):
    """Symplectic position Verlet of DualSPHysics (Leimkuhler et al. 1996).

    Per step: F^n, D^n and dt (T(3.88)-(3.90)); half step r^n+1/2 = r^n + dt/2 v^n,
    rho^n+1/2 = rho^n + dt/2 D^n, v^n+1/2 = v^n + dt/2 F^n; F^n+1/2, D^n+1/2; then
    v^n+1 = v^n + dt F^n+1/2, r^n+1 = r^n+1/2 + dt/2 v^n+1 and
    rho^n+1 = rho^n (2 - eps)/(2 + eps) with eps = -(D^n+1/2 / rho^n+1/2) dt. Positions move
    with ``run.advect()``; a velocity correction (XSPH) dU is applied at the mid-step,
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
    updates = (
        # r, rho, v to t^n + dt/2 with U^n, D^n, F^n; (v^n, rho^n) and the velocity
        # correction U^n - v^n (zero without XSPH) kept
        ParticleUpdate("half", setup="hdt = 0.5 * dt", code="""
U@0[a] = U@[a]
rho0[a] = rho[a]
dU@0[a] = pU@[a] - U@[a]
X@[a] += hdt * pU@[a]
rho[a] += hdt * drho[a]
if kind[a] == FLUID:
    U@[a] += hdt * a@[a]"""),
        # v^n+1 = v^n + dt F^n+1/2; rho^n+1 = rho^n (2 - eps)/(2 + eps) with
        # eps = -(D^n+1/2 / rho^n+1/2) dt (walls keep their velocity; their density evolves)
        ParticleUpdate("velocityDensity", code="""
eps = -drho[a] / rho[a] * dt
rho[a] = rho0[a] * (2.0 - eps) / (2.0 + eps)
if kind[a] == FLUID:
    U@[a] = U@0[a] + dt * a@[a]
else:
    U@[a] = U@0[a]"""),
        # r^n+1 = r^n+1/2 + dt/2 (v^n+1 + 2 dU^n+1/2 - dU^n): with a velocity correction
        # dU = U - v (XSPH) the correction enters at the mid-step over the whole step
        # (second order); without one this is r^n+1/2 + dt/2 v^n+1 exactly (2 U - v - 0 = v
        # in floating point when U is v)
        ParticleUpdate("drift", setup="hdt = 0.5 * dt", code="""
X@[a] += hdt * (2.0 * pU@[a] - U@[a] - dU@0[a])"""))
    kept = {"U@0": "double", "rho0": "double", "dU@0": "double"}


    def step(self, run, dt_remaining: float) -> float:
        """Advance ``run`` by one step of at most ``dt_remaining``; return the time advanced."""
        run.evaluate()                            # F^n, D^n
        dt = min(run.time_step(), dt_remaining)
        run.advect()
        run.update("half", dt=dt)
        run.move_walls(run.time + 0.5 * dt)
        run.evaluate()                            # F^n+1/2, D^n+1/2
        run.update("velocityDensity", dt=dt)
        run.advect()                              # v^n+1 + XSPH correction at n+1/2
        run.update("drift", dt=dt)
        run.move_walls(run.time + dt)
        return dt
