"""Time-marching schemes (T §3.11). Each integrator orchestrates one step in Python and does
every per-particle update in numba."""

from __future__ import annotations

from numba import njit, prange

from sphfoam.registry import Model, register

_JIT = dict(cache=True, fastmath=True, parallel=True)


@njit(**_JIT)
def _monaghan_half(x, y, u, v, pu, pv, rho, ax, ay, drho, kind, dt0, u_half, v_half):
    """T(3.91)-(3.93): r, v, rho to mid-step (walls keep their velocity and move with it).
    ``pu, pv`` is the velocity positions move with (u, v, or XSPH-corrected)."""
    hdt = 0.5 * dt0
    for a in prange(x.shape[0]):
        rho[a] += hdt * drho[a]
        x[a] += hdt * pu[a]         # wall particles move with their prescribed velocity
        y[a] += hdt * pv[a]
        if kind[a] == 0:
            u[a] += hdt * ax[a]
            v[a] += hdt * ay[a]
        u_half[a] = u[a]
        v_half[a] = v[a]


@njit(**_JIT)
def _monaghan_full(x, y, u, v, ax, ay, kind, dt0, dt1, pu_half, pv_half):
    """T(3.94)-(3.95): v^1 = v^1/2 + (dt0 + dt1)/2 F^1/2;  r^1 = r^1/2 + dt1/2 v^1/2."""
    for a in prange(x.shape[0]):
        x[a] += 0.5 * dt1 * pu_half[a]
        y[a] += 0.5 * dt1 * pv_half[a]
        if kind[a] == 0:
            u[a] += 0.5 * (dt0 + dt1) * ax[a]
            v[a] += 0.5 * (dt0 + dt1) * ay[a]


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
        sim.eos()
        sim.rates()                               # F^1/2
        dth = sim.time_step()
        if sim.adjust_time_step:
            dt1 = max(2.0 * dth - dt0, 0.5 * dth)
        else:
            dt1 = dt0
        dt1 = min(dt1, 2.0 * dt_remaining - dt0)   # land exactly on the next write time
        pu, pv = sim.position_velocity(st.u_half, st.v_half)
        _monaghan_full(st.x, st.y, st.u, st.v, st.ax, st.ay, st.kind, dt0, dt1, pu, pv)
        # rho^1/2 + dt1/2 D^1 with D^1 from r^1, v^1 (T(3.96))
        sim.density_rate()
        _density_update(st.rho, st.drho, 0.5 * dt1)
        sim.last_dt = 0.5 * (dt0 + dt1)
        return sim.last_dt
