"""One simulation: particle state + compiled pipeline + neighbour grid + integrator.

Python here runs once per stage of a step; every per-particle or per-pair loop is in numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

from sphfoam.engine.context import RunContext
from sphfoam.engine.neighbours import REDUCTION_CHUNKS, CellList, displacement_check, permute
from sphfoam.engine.plan import missing_dimension
from sphfoam.engine.state import FLUID, ParticleState
from sphfoam.engine.stepping import StepContext, advance
from sphfoam.engine.timestep import stable_time_step_into


@njit(parallel=True, cache=True)
def prescribe_patch(x, y, u, v, patch, x0, y0, which, ox, oy, uu, vv):
    """Particles of wall entry ``which``: r = r0 + d(t), v = d'(t)."""
    for a in prange(x.shape[0]):
        if patch[a] == which:
            x[a] = x0[a] + ox
            y[a] = y0[a] + oy
            u[a] = uu
            v[a] = vv


@njit(parallel=True, cache=True)
def prescribe_patch_3d(x, y, z, u, v, w, patch, x0, y0, z0, which, ox, oy, oz, uu, vv, ww):
    """Particles of wall entry ``which`` in 3-D: r = r0 + d(t), v = d'(t)."""
    for a in prange(x.shape[0]):
        if patch[a] == which:
            x[a] = x0[a] + ox
            y[a] = y0[a] + oy
            z[a] = z0[a] + oz
            u[a] = uu
            v[a] = vv
            w[a] = ww


def _refuse_two_dimensional_hooks(sel, motions) -> None:
    """In three dimensions: refuse, by name, a selected model whose run-time hooks are
    written for two (mirror ghosts, Adami's wall velocity, the wall law; a model's
    ``hook_dims`` say which it has) and a motion with no 3-D form."""
    for m in sel.models():
        why = missing_dimension(m, 3)
        if why is not None:
            raise ValueError(why)
    for m in (motions or {}).values():
        if 3 not in getattr(m, "dims", (2,)):
            raise ValueError(f"motion {m.name!r} has no 3-D form")


@dataclass
class Removal:
    """Particles that left the domain box during a step."""

    time: float
    count: int
    ids: np.ndarray
    where: np.ndarray  # (count, 2) last positions


class Simulation:
    """The particle state stepped by the compiled pipeline of a selection.

    Everything model-specific reaches the simulation through the selected models' run-time
    hooks (``sphfoam.models.base``): the simulation itself names no model.
    """

    def __init__(self, state: ParticleState, pipeline, integrator, *, domain_lo, domain_hi,
                 beta: float, force_condition: bool, adjust_time_step: bool, delta_t: float,
                 max_delta_t: float = math.inf, cell_size_factor: float = 1.05,
                 dt_limit: float = math.inf, segments=(), planes=(), motions=None,
                 h: float | None = None, support: float | None = None,
                 filter_every: int | None = None):
        self.state = state
        self.pipeline = pipeline
        self.prm = pipeline.prm
        #: the working precision of the pipeline (``sphSchemes`` ``precision``)
        self.dtype = pipeline.prm.dtype
        if state.dtype != self.dtype:
            state.set_precision(self.dtype)
        self.integrator = integrator
        #: the integrator's particle updates, compiled (None until its first step)
        self.updates = None
        #: the velocity positions move with, as the integrator's last ``advect`` made it
        self._pU = None
        #: the smoothing length and support radius are the pipeline's (one source of truth);
        #: ``h`` and ``support`` (in units of h), when given, must agree with them
        self.h = pipeline.h
        reach = pipeline.support_radius
        if h is not None and abs(h - self.h) > 1e-12 * self.h:
            raise ValueError("h does not match the pipeline's")
        if support is not None and abs(support * self.h - reach) > 1e-9 * reach:
            raise ValueError("kernel support does not match the pipeline's")
        self.beta = float(beta)
        self.force_condition = bool(force_condition)
        self.adjust_time_step = bool(adjust_time_step)
        self.delta_t = float(delta_t)
        self.max_delta_t = float(max_delta_t)
        sel = pipeline.selection
        if cell_size_factor < 1.0:
            raise ValueError("cellSizeFactor must be >= 1 (cells smaller than the support miss "
                             "neighbours)")
        if state.dim != sel.dim:
            raise ValueError(f"a {state.dim}-D state and a {sel.dim}-D pipeline")
        self.dim = sel.dim
        if self.dim == 3:
            _refuse_two_dimensional_hooks(sel, motions)
        self.cells = CellList(domain_lo, domain_hi, reach * cell_size_factor,
                              sel.periodic_x, sel.periodic_y, sel.periodic_z)
        #: when the density filter's pass runs (the filter model's schedule), None: never
        schedules = [m.schedule() for m in sel.models() if m.schedule() is not None]
        self.filter_schedule = schedules[0] if pipeline.density_filter is not None and \
            schedules else None
        if filter_every is not None and filter_every != self.filter_every:
            raise ValueError(f"filter_every {filter_every} differs from the filter's schedule "
                             f"({self.filter_every})")
        #: whether the density filter ran before the step in progress (integrators read it)
        self.filtered = False
        self.model_dt_limit = float(dt_limit)
        self.time = 0.0
        self.step_index = 0
        self.last_dt = float(delta_t)
        self.removals: list[Removal] = []
        self.aux = np.zeros((pipeline.n_aux, state.n), dtype=self.dtype)
        self.on_removal = None
        self._fld = None
        self._pc = None
        #: (nb_start, nb_idx) of the current step (sphfoam.engine.pipeline.Pipeline)
        self._nb = (None, None)
        #: evaluate the rates and density passes over half lists (each pair once, for both
        #: particles) where the selection and the list allow it (``Pipeline.half_lists``);
        #: False: always the gather over full lists (the same sums in another order)
        self.half_lists = True
        #: the current list's array for the half-list loops (``Pipeline.half_lists``), or None
        self._half = None
        #: the thread count the bands of ``_half`` are dealt to
        self._half_threads = 0
        #: the per-particle sums of the half-list prepass (``Pipeline.prepass_half``)
        self._sums = None
        #: in a step: whether its prepass ran (``Pipeline.prepass_once``); None outside a step
        self._prepassed = None
        #: rates evaluations so far in the step being taken (None outside a step)
        self._evaluations = None
        #: per-range partial results of the whole-state reductions (no allocation per step)
        self._reduce = np.empty((3, REDUCTION_CHUNKS))
        #: positions at the last build of the list (None: rebuild at the next step)
        self._ref = None
        self.list_built = 0
        self.list_reused = 0
        #: prescribed motions by wall-entry index (sphfoam.models.motion)
        self.motions = dict(motions or {})
        self.segments = list(segments)
        #: the plane faces of a 3-D case's box tanks (sphfoam.case.geometry.Plane)
        self.planes = list(planes)
        self._hooks = {name: sel.hooks(name) for name in
                       ("before_neighbours", "add_particles", "after_sort",
                        "before_evaluation", "before_passes", "after_rates",
                        "after_density_rate", "walls_moved", "after_step", "keeps_neighbours")}
        #: the models that make the advection velocity, applied in selection order, each to
        #: the previous one's result (XSPH, then a particle shifting)
        self._advection = sel.hooks("advection_velocity")
        self._summaries = sel.hooks("summary")
        #: list radius (the cell side) minus the support: how far pairs may close in
        self.skin = self.cells.cell_size - reach
        #: a model that adds or removes particles at the neighbour update needs a new list
        #: every step, unless it says (``keeps_neighbours``) when the particles it added
        #: still serve
        changers = [m for m in sel.models() if m.implements("add_particles") or
                    m.implements("before_neighbours")]
        self.reuse_neighbours = all(m.implements("keeps_neighbours") for m in changers)
        #: what the models' hooks see of this simulation (never the simulation itself)
        self.context = RunContext(self)
        #: what the integrator's step sees of it
        self._stepping = StepContext(self)
        for attach in sel.hooks("attach"):
            attach(self.context)

    @property
    def filter_every(self) -> int:
        """Steps between density-filter passes (0: none)."""
        return int(self.filter_schedule.interval) if self.filter_schedule else 0

    def _run_hooks(self, name, *args):
        for hook in self._hooks[name]:
            hook(self.context, *args)

    def summary(self) -> str:
        """What the selected models report at the end of a run ("" for nothing)."""
        return "; ".join(x for x in (f() for f in self._summaries) if x)

    def model_hook(self, model, name: str) -> None:
        """The run-time hook ``name`` of the selected ``model`` alone, now: for a function
        object that reads the state as the pair passes see it (``forces`` over walls whose
        velocity the passes see differently: ``before_passes``, then ``after_rates``)."""
        getattr(model, name)(self.context)

    # --- walls ---------------------------------------------------------------------------
    def move_walls(self, t: float):
        """Put every wall with a prescribed motion where it is at time ``t`` (particles and
        the models that follow walls). The integrators call this at each stage time."""
        if not self.motions:
            return
        st = self.state
        offs, vels = {}, {}
        for which, mot in self.motions.items():
            off, vel = mot.displacement(t), mot.velocity(t)
            if self.dim == 3:
                off, vel = (tuple(off) + (0.0,))[:3], (tuple(vel) + (0.0,))[:3]
                if "patch" in st.extra:
                    ex = st.extra
                    prescribe_patch_3d(st.x, st.y, st.z, st.u, st.v, st.w, ex["patch"],
                                       ex["x0"], ex["y0"], ex["z0"], float(which), *off, *vel)
            elif "patch" in st.extra:
                prescribe_patch(st.x, st.y, st.u, st.v, st.extra["patch"], st.extra["x0"],
                                st.extra["y0"], float(which), *off[:2], *vel[:2])
            offs[which], vels[which] = off, vel
        self._run_hooks("walls_moved", offs, vels)
        self._run_hooks("before_evaluation")

    # --- stages --------------------------------------------------------------------------
    def invalidate_neighbours(self):
        """Rebuild the neighbour list at the next step (after a write, so that a run restarted
        from the written time does exactly what an uninterrupted one does)."""
        self._ref = None

    def _list_still_valid(self) -> bool:
        """Whether the neighbour list of an earlier step serves this one: none left the
        domain, every pair now within the support is listed even after this step's motion
        (largest displacement since the build plus 1.5 v_max dt < skin / 2), and every model
        that adds particles says they still serve (``keeps_neighbours``)."""
        st = self.state
        ref = self._ref
        if ref is None or not self.reuse_neighbours or ref[0].shape[0] != st.n:
            return False
        cl = self.cells
        x1 = cl.x0 + cl.ncx * cl.cell_size
        y1 = cl.y0 + cl.ncy * cl.cell_size
        z1 = cl.z0 + cl.ncz * cl.cell_size
        z, zr, w = (st.z, ref[2], st.w) if self.dim == 3 else (st.x[:0], st.x[:0], st.u[:0])
        d2, v2, out = displacement_check(st.x, st.y, ref[0], ref[1], st.u, st.v, cl.x0, cl.y0,
                                         x1, y1, cl.lx, cl.ly, self._reduce, z, zr, w, cl.z0,
                                         z1, cl.lz)
        if out:
            return False
        reach = math.sqrt(d2) + 1.5 * math.sqrt(v2) * self.last_dt
        if not reach < 0.5 * self.skin:
            return False
        return all(keeps(self.context) for keeps in self._hooks["keeps_neighbours"])

    def neighbour_update(self):
        """The neighbour list of this step: the previous one while it is valid; otherwise bin
        into cells, drop particles that left the domain, let models add particles (e.g.
        mirror ghosts), sort by cell and list the neighbours."""
        st = self.state
        if self._list_still_valid():
            self.list_reused += 1
            return
        self._fld = None
        self._run_hooks("before_neighbours")
        cell, outside = self.cells.bin(*st.positions)
        if outside:
            gone = cell < 0
            rem = Removal(self.time, int(gone.sum()), st.id[gone].copy(),
                          np.column_stack([a[gone] for a in st.positions]))
            self.removals.append(rem)
            if self.on_removal:
                self.on_removal(rem)
            st.keep(~gone)
            cell = cell[~gone]
        for add in self._hooks["add_particles"]:
            cell = np.concatenate([cell, add(self.context, cell)])
        order = self.cells.sort(cell)
        st.apply(order, permute)
        self._run_hooks("after_sort", order)
        # one neighbour list for every loop of the step: within the cell side, so a pair that
        # comes within the support during the step is in it (the margin cellSizeFactor - 1)
        self._nb = self.pipeline.neighbour_list(st.x, st.y, st.kind, self.cells,
                                                self.cells.cell_size, *self._nb,
                                                z=st.z if self.dim == 3 else None)
        self._ref = tuple(a.copy() for a in st.positions)
        self.list_built += 1
        self._half = (self.pipeline.half_lists(*self._nb, self.cells, self._half)
                      if self.half_lists else None)
        self._half_threads = numba.get_num_threads()       # as half_lists dealt the bands

    def _dealt_half(self):
        """The half lists, their bands dealt to the threads numba runs now
        (``neighbours.deal_bands``: dealt again when the thread count changed)."""
        threads = numba.get_num_threads()
        if threads != self._half_threads:
            self.pipeline.deal_bands(self._half, threads, self._nb[0])
            self._half_threads = threads
        return self._half

    def _grid_args(self):
        st = self.state
        if self.aux.shape[1] != st.n:
            self.aux = np.zeros((self.pipeline.n_aux, st.n), dtype=self.dtype)
        if self._fld is None or self._fld.shape[1] != st.n:
            names = self.pipeline.fields
            self._fld = (np.stack([st.extra[k] for k in names]) if names
                         else np.zeros((0, st.n)))
        nb_start, nb_idx = self._nb
        if nb_start is None or nb_start.shape[0] != st.n + 1:
            raise RuntimeError("the neighbour list is stale: call neighbour_update first")
        args = (*st.positions, *st.velocities, st.rho, st.p, st.c, st.m, st.kind, nb_start, nb_idx,
                self.prm, self.aux, self._fld)
        if self.pipeline.pair_cache:
            # per listed pair: what the prepass stores for the later loops (kernel values)
            if self._pc is None or self._pc.shape[1] != nb_idx.shape[0]:
                self._pc = np.zeros((len(self.pipeline.pair_cache), nb_idx.shape[0]),
                                    dtype=self.dtype)
            args += (self._pc,)
        return args

    def _prepass(self, args, stage: str = "rates"):
        pipe = self.pipeline
        if not pipe.prepass_before(stage):
            return
        if pipe.prepass_once:
            # once per step: before the step's first evaluation (outside a step: always)
            if self._prepassed:
                return
            if self._prepassed is not None:
                self._prepassed = True
        if self.half_lists and self._half is not None and pipe.prepass_half is not None:
            # over half lists: then the loops after it are half-list loops too
            # (Plan.prepass_half_terms), which read the pair cache where it stored it
            if self._sums is None or self._sums.shape[1] != self.state.n:
                self._sums = np.empty((pipe.prepass_sums, self.state.n), dtype=self.dtype)
            pipe.prepass_half(*args, self._dealt_half(), self._sums)
        else:
            pipe.prepass(*args)

    def position_velocity(self, *U):
        """The velocity positions are advanced with: ``U`` ((u, v), or (u, v, w) in 3-D)
        itself, or what the selected models that set the advection velocity make of it (e.g.
        XSPH, T(3.62)), each applied to the previous one's result."""
        for advection in self._advection:
            U = tuple(advection(self.context, *U))
        return U

    def advect(self):
        """The velocity positions move with from the velocity now (``pU@`` of the
        integrators' updates)."""
        self._pU = self.position_velocity(*self.state.velocities)

    def run_update(self, name: str, scalars: dict):
        """The integrator's particle update ``name`` (``sphfoam.engine.stepping``)."""
        if self.updates is None or self.updates.integrator is not self.integrator:
            from sphfoam.engine.updates import ParticleUpdates

            self.updates = ParticleUpdates(self.integrator, self.dim)
        self.updates.run(name, self.state, self._pU, scalars)

    def filter_density(self):
        """Run the density filter's pass (T(3.64)-(3.69)); the caller decides when."""
        st = self.state
        self.eos()
        args = self._grid_args()
        self._prepass(args, "filter")
        out = np.empty_like(st.rho)
        self.pipeline.density_filter(*args, out)
        st.rho = out

    def eos(self):
        st = self.state
        self._run_hooks("before_evaluation")
        self.pipeline.equation_of_state(st.rho, st.p, st.c, self.prm)

    def step_pass(self):
        """The once-per-step pass of the selected models (a per-step wall state), if any."""
        if self.pipeline.step_pass is not None:
            self.pipeline.step_pass(*self._grid_args())

    def rates(self):
        """dv/dt and drho/dt of every particle, and sigma of T(3.89) where a time step may be
        taken from it: not in the later evaluations of a step of an integrator that says
        ``time_step_from_first_evaluation`` (``state.sigma`` keeps the first's)."""
        st = self.state
        self._run_hooks("before_evaluation")
        self._run_hooks("before_passes")
        args = self._grid_args()
        self._prepass(args)
        sigma = True
        if self._evaluations is not None:
            sigma = self._evaluations == 0 or not getattr(
                self.integrator, "time_step_from_first_evaluation", False)
            self._evaluations += 1
        out_sigma = st.sigma if sigma else st.sigma[:0]
        if self.half_lists and self._half is not None and self.pipeline.rates_half is not None:
            self.pipeline.rates_half(*args, self._dealt_half(), *st.accelerations, st.drho,
                                     out_sigma)
        else:
            self.pipeline.rates(*args, *st.accelerations, st.drho, out_sigma)
        self._run_hooks("after_rates")

    def density_rate(self):
        self._run_hooks("before_evaluation")
        self._run_hooks("before_passes")
        args = self._grid_args()
        self._prepass(args, "density")
        if self.half_lists and self._half is not None and \
                self.pipeline.density_half is not None:
            self.pipeline.density_half(*args, self._dealt_half(), self.state.drho)
        else:
            self.pipeline.density_rate(*args, self.state.drho)
        self._run_hooks("after_density_rate")

    def time_step(self) -> float:
        if not self.adjust_time_step:
            return self.delta_t
        st = self.state
        dt = stable_time_step_into(self.h, st.c, st.sigma, st.ax, st.ay, st.kind, self.beta,
                                   self.force_condition, self._reduce[:2],
                                   st.az if self.dim == 3 else st.ax[:0])
        return min(dt, self.max_delta_t, self.model_dt_limit)

    # --- stepping ------------------------------------------------------------------------
    def step(self, dt_remaining: float = math.inf) -> float:
        """Re-sort, filter the density when due, then one step of the integrator
        (:func:`sphfoam.engine.stepping.advance`)."""
        dt = advance(self, dt_remaining)
        self._run_hooks("after_step")
        return dt

    def pressure(self) -> np.ndarray:
        """Pressure from the current density (for output)."""
        self.eos()
        return self.state.p.copy()

    @property
    def energy_unit(self) -> str:
        """J per metre of span in 2-D, J in 3-D (the mass is per unit span in 2-D)."""
        return "J/m" if self.state.dim == 2 else "J"

    def kinetic_energy(self) -> float:
        st = self.state
        f = st.kind == FLUID
        return float(0.5 * np.sum(st.m[f] * sum(c[f] ** 2 for c in st.velocities)))
