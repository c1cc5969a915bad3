"""One simulation: particle state + compiled pipeline + neighbour grid + integrator.

Python here runs once per stage of a step; every per-particle or per-pair loop is in numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from sphfoam.engine.neighbours import CellList, permute
from sphfoam.engine.state import FLUID, ParticleState
from sphfoam.engine.timestep import stable_time_step


@njit(parallel=True, cache=True, fastmath=True)
def add_correction(u, du, kind):
    """u + du for fluid particles (walls keep their prescribed velocity)."""
    out = np.empty_like(u)
    for a in prange(u.shape[0]):
        out[a] = u[a] + du[a] if kind[a] == 0 else u[a]
    return out


@dataclass
class Removal:
    """Particles that left the domain box during a step."""

    time: float
    count: int
    ids: np.ndarray
    where: np.ndarray  # (count, 2) last positions


class Simulation:
    def __init__(self, state: ParticleState, pipeline, integrator, *, h: float, support: float,
                 domain_lo, domain_hi, beta: float, force_condition: bool,
                 adjust_time_step: bool, delta_t: float, max_delta_t: float = math.inf,
                 cell_size_factor: float = 1.05, filter_every: int = 0,
                 dt_limit: float = math.inf):
        self.state = state
        self.pipeline = pipeline
        self.prm = pipeline.prm
        self.integrator = integrator
        self.h = float(h)
        self.beta = float(beta)
        self.force_condition = bool(force_condition)
        self.adjust_time_step = bool(adjust_time_step)
        self.delta_t = float(delta_t)
        self.max_delta_t = float(max_delta_t)
        sel = pipeline.selection
        if cell_size_factor < 1.0:
            raise ValueError("cellSizeFactor must be >= 1 (cells smaller than the support miss "
                             "neighbours)")
        if abs(support ** 2 * h ** 2 - self.prm[2]) > 1e-9 * self.prm[2]:
            raise ValueError("kernel support does not match the pipeline's")
        self.cells = CellList(domain_lo, domain_hi, support * h * cell_size_factor,
                              sel.periodic_x, sel.periodic_y)
        self.filter_every = int(filter_every) if pipeline.density_filter is not None else 0
        self.model_dt_limit = float(dt_limit)
        self.time = 0.0
        self.step_index = 0
        self.last_dt = float(delta_t)
        self.removals: list[Removal] = []
        self.aux = np.zeros((pipeline.n_aux, state.n))
        self.on_removal = None

    # --- stages --------------------------------------------------------------------------
    def neighbour_update(self):
        """Bin into cells, drop particles that left the domain, sort by cell."""
        st = self.state
        cell, outside = self.cells.bin(st.x, st.y)
        if outside:
            gone = cell < 0
            rem = Removal(self.time, int(gone.sum()), st.id[gone].copy(),
                          np.column_stack([st.x[gone], st.y[gone]]))
            self.removals.append(rem)
            if self.on_removal:
                self.on_removal(rem)
            st.keep(~gone)
            cell = cell[~gone]
        order = self.cells.sort(cell)
        st.apply(order, permute)

    def _grid_args(self):
        st, cl = self.state, self.cells
        if self.aux.shape[1] != st.n:
            self.aux = np.zeros((self.pipeline.n_aux, st.n))
        return (st.x, st.y, st.u, st.v, st.rho, st.p, st.c, st.m, st.kind, cl.cell_start,
                cl.x0, cl.y0, 1.0 / cl.cell_size, cl.ncx, cl.ncy, self.prm, self.aux)

    def _prepass(self, args):
        if self.pipeline.prepass is not None:
            self.pipeline.prepass(*args)

    def position_velocity(self, u, v):
        """The velocity positions are advanced with: (u, v) itself, or with a velocity
        correction selected (XSPH, T(3.62)), u + du and v + dv from the last pre-pass."""
        vc = self.pipeline.selection.velocityCorrection
        if vc is None or not getattr(vc, "advects_positions", False):
            return u, v
        aux_names = self.pipeline.module.AUX
        du = self.aux[aux_names.index(vc.aux[0])]
        dv = self.aux[aux_names.index(vc.aux[1])]
        return add_correction(u, du, self.state.kind), add_correction(v, dv, self.state.kind)

    def filter_density(self):
        """Run the density filter's pass (T(3.64)-(3.69)); the caller decides when."""
        st = self.state
        self.eos()
        args = self._grid_args()
        self._prepass(args)
        out = np.empty_like(st.rho)
        self.pipeline.density_filter(*args, out)
        st.rho = out

    def eos(self):
        st = self.state
        self.pipeline.equation_of_state(st.rho, st.p, st.c, self.prm)

    def rates(self):
        st = self.state
        args = self._grid_args()
        self._prepass(args)
        self.pipeline.rates(*args, st.ax, st.ay, st.drho, st.sigma)

    def density_rate(self):
        args = self._grid_args()
        self._prepass(args)
        self.pipeline.density_rate(*args, self.state.drho)

    def time_step(self) -> float:
        if not self.adjust_time_step:
            return self.delta_t
        st = self.state
        dt = stable_time_step(self.h, st.c, st.sigma, st.ax, st.ay, st.kind, self.beta,
                              self.force_condition)
        return min(dt, self.max_delta_t, self.model_dt_limit)

    # --- stepping ------------------------------------------------------------------------
    def step(self, dt_remaining: float = math.inf) -> float:
        """Re-sort, filter the density when due, then one step of the integrator."""
        self.neighbour_update()
        if self.filter_every and self.step_index > 0 and self.step_index % self.filter_every == 0:
            self.filter_density()
        dt = self.integrator.step(self, dt_remaining)
        self.time += dt
        self.step_index += 1
        return dt

    def pressure(self) -> np.ndarray:
        """Pressure from the current density (for output)."""
        self.eos()
        return self.state.p.copy()

    def kinetic_energy(self) -> float:
        st = self.state
        f = st.kind == FLUID
        return float(0.5 * np.sum(st.m[f] * (st.u[f] ** 2 + st.v[f] ** 2)))
