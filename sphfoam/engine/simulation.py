"""One simulation: particle state + compiled pipeline + neighbour grid + integrator.

Python here runs once per stage of a step; every per-particle or per-pair loop is in numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from sphfoam.engine import ghosts as gh
from sphfoam.engine.neighbours import CellList, permute
from sphfoam.engine.state import FLUID, GHOST, ParticleState
from sphfoam.engine.timestep import stable_time_step


@njit(parallel=True, cache=True, fastmath=True)
def add_correction(u, du, kind):
    """u + du for fluid particles (walls keep their prescribed velocity)."""
    out = np.empty_like(u)
    for a in prange(u.shape[0]):
        out[a] = u[a] + du[a] if kind[a] == 0 else u[a]
    return out


@njit(parallel=True, cache=True)
def prescribe_patch(x, y, u, v, patch, x0, y0, which, ox, oy, uu, vv):
    """Particles of wall entry ``which``: r = r0 + d(t), v = d'(t)."""
    for a in prange(x.shape[0]):
        if patch[a] == which:
            x[a] = x0[a] + ox
            y[a] = y0[a] + oy
            u[a] = uu
            v[a] = vv


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
                 dt_limit: float = math.inf, segments=(), motions=None):
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
        self._fld = None
        #: fluid particles put back across a mirror wall they had crossed (see ghosts.push_back)
        self.pushed_back = 0
        #: prescribed motions by wall-entry index (sphfoam.models.motion)
        self.motions = dict(motions or {})
        self.segments = list(segments)
        bnd = sel.boundary
        self.mirror = bool(getattr(bnd, "ghosts", False))
        if self.mirror:
            if not self.segments:
                raise ValueError("mirrorGhosts needs walls in system/particleDict")
            self.no_slip = bool(bnd.coeffs.noSlip)
            self.reach = support * h
            self.seg = gh.segment_array(self.segments)
            self.corners = gh.corner_pairs(self.segments, 1e-9 * max(1.0, self.reach))
            self._ghost = None

    # --- walls ---------------------------------------------------------------------------
    def move_walls(self, t: float):
        """Put every wall with a prescribed motion where it is at time ``t`` (particles and,
        for mirrored ghosts, segments). The integrators call this at each stage time."""
        if not self.motions:
            return
        st = self.state
        offs, vels = {}, {}
        for which, mot in self.motions.items():
            (ox, oy), (uu, vv) = mot.displacement(t), mot.velocity(t)
            offs[which], vels[which] = (ox, oy), (uu, vv)
            if "patch" in st.extra:
                prescribe_patch(st.x, st.y, st.u, st.v, st.extra["patch"], st.extra["x0"],
                                st.extra["y0"], float(which), ox, oy, uu, vv)
        if self.mirror:
            self.seg = gh.segment_array(self.segments, offs, vels)
        self._sync_ghosts()

    def _make_ghosts(self):
        """Mirror every fluid particle near a wall across it (T(3.77)); returns the cells of
        the new ghosts (those outside the cell grid are dropped)."""
        st = self.state
        count = np.zeros(st.n, dtype=np.int64)
        gh.count_ghosts(st.x, st.y, st.kind, self.seg, self.corners, self.reach, count)
        offset = np.zeros(st.n, dtype=np.int64)
        np.cumsum(count[:-1], out=offset[1:])
        ng = int(count.sum())
        src = np.empty(ng, dtype=np.int64)
        s1 = np.empty(ng, dtype=np.int64)
        s2 = np.empty(ng, dtype=np.int64)
        gh.fill_ghosts(st.x, st.y, st.kind, self.seg, self.corners, self.reach, offset, src,
                       s1, s2)
        n0 = st.n
        st.append(np.zeros(ng), np.zeros(ng), np.zeros(ng), np.zeros(ng), np.zeros(ng),
                  np.zeros(ng), np.full(ng, GHOST), -1 - st.id[src])
        gidx = np.arange(n0, n0 + ng)
        gh.refresh_ghosts(st.x, st.y, st.u, st.v, st.rho, st.m, gidx, src, s1, s2, self.seg,
                          self.no_slip)
        self._ghost = (gidx, src, s1, s2)

    def _sync_ghosts(self):
        if self.mirror and self._ghost is not None:
            st = self.state
            gidx, src, s1, s2 = self._ghost
            gh.refresh_ghosts(st.x, st.y, st.u, st.v, st.rho, st.m, gidx, src, s1, s2,
                              self.seg, self.no_slip)

    # --- stages --------------------------------------------------------------------------
    def neighbour_update(self):
        """Bin into cells, drop particles that left the domain, (re)make mirrored ghosts,
        sort by cell."""
        st = self.state
        self._fld = None
        if self.mirror and (st.kind == GHOST).any():
            st.keep(st.kind != GHOST)
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
        if self.mirror:
            n0 = st.n
            self._make_ghosts()
            gcell, gout = self.cells.bin(st.x[n0:], st.y[n0:])
            cell = np.concatenate([cell, gcell])
            if gout:      # a ghost beyond the grid: drop it (its particle is at the edge)
                keep = cell >= 0
                st.keep(keep)
                cell = cell[keep]
                gidx, src, s1, s2 = self._ghost
                kg = keep[n0:]
                self._ghost = (np.arange(n0, n0 + int(kg.sum())), src[kg], s1[kg], s2[kg])
        order = self.cells.sort(cell)
        st.apply(order, permute)
        if self.mirror:
            inv = np.empty_like(order)
            inv[order] = np.arange(order.size)
            gidx, src, s1, s2 = self._ghost
            self._ghost = (inv[gidx], inv[src], s1, s2)

    def _grid_args(self):
        st, cl = self.state, self.cells
        if self.aux.shape[1] != st.n:
            self.aux = np.zeros((self.pipeline.n_aux, st.n))
        if self._fld is None or self._fld.shape[1] != st.n:
            names = self.pipeline.fields
            self._fld = (np.stack([st.extra[k] for k in names]) if names
                         else np.zeros((0, st.n)))
        return (st.x, st.y, st.u, st.v, st.rho, st.p, st.c, st.m, st.kind, cl.cell_start,
                cl.x0, cl.y0, 1.0 / cl.cell_size, cl.ncx, cl.ncy, self.prm, self.aux, self._fld)

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
        self._sync_ghosts()
        self.pipeline.equation_of_state(st.rho, st.p, st.c, self.prm)

    def boundary_step(self):
        """The boundary's once-per-step wall update (e.g. hybrid wet/dry), if it has one."""
        if self.pipeline.boundary_step is not None:
            self.pipeline.boundary_step(*self._grid_args())

    def rates(self):
        st = self.state
        self._sync_ghosts()
        args = self._grid_args()
        self._prepass(args)
        self.pipeline.rates(*args, st.ax, st.ay, st.drho, st.sigma)

    def density_rate(self):
        self._sync_ghosts()
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
        self.move_walls(self.time)
        self.neighbour_update()
        self.boundary_step()
        if self.filter_every and self.step_index > 0 and self.step_index % self.filter_every == 0:
            self.filter_density()
        dt = self.integrator.step(self, dt_remaining)
        self.time += dt
        self.step_index += 1
        if self.mirror:
            # a particle that crossed a mirror wall during the step goes back before anything
            # (a write, a function object, the next step) sees it
            st = self.state
            self.pushed_back += gh.push_back(st.x, st.y, st.u, st.v, st.kind, self.seg,
                                             self.reach)
        return dt

    def pressure(self) -> np.ndarray:
        """Pressure from the current density (for output)."""
        self.eos()
        return self.state.p.copy()

    def kinetic_energy(self) -> float:
        st = self.state
        f = st.kind == FLUID
        return float(0.5 * np.sum(st.m[f] * (st.u[f] ** 2 + st.v[f] ** 2)))
