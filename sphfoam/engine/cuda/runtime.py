"""The CUDA backend's runtime: :class:`CudaSimulation`, the ``Simulation``'s interface to the
time loop over device arrays.

The state, the integrator's kept arrays and history, the aux fields, the coefficients, the
cell list and the neighbour list live on the device between writes; Python launches the
kernels of a step and reads back scalars only (the time step, the list check, the list's
length, the count of particles that left). ``state`` copies the arrays back on demand
(writes, function objects).
"""

from __future__ import annotations

import math
import time as _time

import numpy as np

from sphfoam.engine.cuda import cuda_module
from sphfoam.engine.bodies import components as components_of
from sphfoam.engine.cuda.context import DeviceContext
from sphfoam.engine.cuda.forms import device_forms
from sphfoam.engine.neighbours import CellList
from sphfoam.engine.state import FLUID, GHOST, ParticleState
from sphfoam.engine.stepping import StepContext, advance, components, field_components

#: the health monitor's last good state is kept on the device every this many passing steps
SNAPSHOT_EVERY = 10

_STATE_I8 = ("kind", "id")


def _state_arrays(dim: int):
    """The device state's arrays in ``dim`` dimensions: (positions, float64), (velocities,
    density, mass: the working precision), (scratch: rewritten each evaluation)."""
    axes = [ax for ax, _ in components_of(dim)]
    return (tuple(axes), (*(vel for _, vel in components_of(dim)), "rho", "m"),
            ("p", "c", *(f"a{ax}" for ax in axes), "drho", "sigma"))


class _DeviceExtra(dict):
    """The persistent extra fields on the device; a host array set is copied there."""

    def __init__(self, cuda):
        super().__init__()
        self._cuda = cuda

    def __setitem__(self, k, v):
        if isinstance(v, np.ndarray):
            v = self._cuda.to_device(np.ascontiguousarray(v, dtype=np.float64))
        super().__setitem__(k, v)


class _DeviceState:
    """What an integrator's ``step`` reads of the state: ``n``, ``dim`` and ``extra``
    (device arrays; one element read is one scalar copied back)."""

    def __init__(self, sim):
        self._sim = sim

    @property
    def dim(self) -> int:
        return self._sim.dim

    @property
    def n(self) -> int:
        return self._sim.n

    @property
    def extra(self):
        return self._sim.d_extra


class _DeviceStepContext(StepContext):
    __slots__ = ()

    @property
    def state(self):
        return self._sim._dstate


class DeviceSnapshot:
    """Device copies of the state's arrays at one step (the health monitor's last good
    state), with that step's time, index and time step; ``host()`` copies them back."""

    def __init__(self):
        self.arrays: dict = {}
        self.fields: tuple = ()
        self.time = math.nan
        self.step = -1
        self.dt = math.nan

    @classmethod
    def of(cls, sim, kept: "DeviceSnapshot | None") -> "DeviceSnapshot":
        snap = kept if kept is not None else cls()
        src = {k: a for k, a in sim.d.items() if k not in sim._scratch}
        src.update({f"extra.{k}": a for k, a in sim.d_extra.items()})
        src["fld"] = sim.d_fld
        for k, a in src.items():
            dst = snap.arrays.get(k)
            if dst is None or dst.shape != a.shape or dst.dtype != a.dtype:
                dst = sim.cuda.device_array(a.shape, dtype=a.dtype)
                snap.arrays[k] = dst
            dst.copy_to_device(a)
        for k in [k for k in snap.arrays if k not in src]:
            del snap.arrays[k]
        snap.fields = tuple(sim.module.FIELDS)
        snap.time, snap.step, snap.dt = float(sim.time), int(sim.step_index), \
            float(sim.last_dt)
        return snap

    def host(self) -> ParticleState:
        """The kept state copied back."""
        a = {k: v.copy_to_host() for k, v in self.arrays.items()}
        extra = {k[6:]: v for k, v in a.items() if k.startswith("extra.")}
        for i, k in enumerate(self.fields):
            extra[k] = a["fld"][i]
        return ParticleState(a["x"], a["y"], a["u"], a["v"], a["rho"], a["m"], a["kind"],
                             a["id"], extra, z=a.get("z"), w=a.get("w"))


class CudaSimulation:
    """The particle state stepped by the CUDA kernels of a selection."""

    #: the reductions' starting values (the list check's maxima; the time step's min, max;
    #: the health checks' counts, maximum and sums)
    _RED_CHECK = np.zeros(3)
    _RED_DT = np.array([math.inf, 0.0, 0.0])
    _HEALTH0 = np.zeros(7)

    def __init__(self, state: ParticleState, pipeline, integrator, *, domain_lo, domain_hi,
                 beta: float, force_condition: bool, adjust_time_step: bool, delta_t: float,
                 max_delta_t: float = math.inf, cell_size_factor: float = 1.05,
                 dt_limit: float = math.inf, segments=(), planes=(), motions=None):
        from sphfoam.engine.cuda import device as D

        self.cuda = cuda_module()
        self.D = D
        self.pipeline = pipeline
        self.module = pipeline.module
        sel = pipeline.selection
        self.selection = sel
        if state.dim != sel.dim:
            raise ValueError(f"a {state.dim}-D state and a {sel.dim}-D pipeline")
        self.dim = sel.dim
        self._f8, self._working, self._scratch = _state_arrays(self.dim)
        #: the state's arrays an integrator's updates read or write as they are
        self._updated = {*self._f8, *self._working[:self.dim], "rho", "drho", "kind",
                         *(f"a{ax}" for ax in self._f8)}
        self.dtype = sel.dtype
        self.integrator = integrator
        self.h = pipeline.h
        reach = pipeline.support_radius
        self.beta = float(beta)
        self.force_condition = bool(force_condition)
        self.adjust_time_step = bool(adjust_time_step)
        self.delta_t = float(delta_t)
        self.max_delta_t = float(max_delta_t)
        self.model_dt_limit = float(dt_limit)
        if cell_size_factor < 1.0:
            raise ValueError("cellSizeFactor must be >= 1")
        self.cells = CellList(domain_lo, domain_hi, reach * cell_size_factor,
                              sel.periodic_x, sel.periodic_y, sel.periodic_z)
        self.skin = self.cells.cell_size - reach
        schedules = [m.schedule() for m in sel.models() if m.schedule() is not None]
        self.filter_schedule = (schedules[0] if schedules and
                                getattr(self.module, "HAS_FILTER", False) else None)
        self.filtered = False
        self.time = 0.0
        self.step_index = 0
        self.last_dt = float(delta_t)
        self.removals = []
        self.on_removal = None
        self.segments = list(segments)
        self.planes = list(planes)
        self.motions = dict(motions or {})
        self.list_built = 0
        self.list_reused = 0
        #: bytes copied host -> device and device -> host (the benchmark's traffic)
        self.bytes_h2d = 0
        self.bytes_d2h = 0
        #: seconds per stage when ``timers`` is set (synchronised: for benchmarks only)
        self.timers = None
        self._host = state
        self._upload(state)
        self.prm = pipeline.prm
        self.d_prm = self.cuda.to_device(pipeline.prm)
        self._nb = (None, None)
        self._pc = None
        self._ref = None
        self._prepassed = None
        self._evaluations = None
        self._pU = None
        self._kept: dict = {}
        self._red = self.cuda.device_array(3, dtype=np.float64)
        self._scan_scratch = None
        self.updates = None
        self._dstate = _DeviceState(self)
        self._stepping = _DeviceStepContext(self)
        self._dirty = False
        #: the health checks run on the device after every step (``health_scan``), their last
        #: good state is kept there (``keep_snapshot``)
        self._health = None
        self._snapshot_calls = 0
        #: the selected models' run-time hooks in their declared forms (attached here)
        from sphfoam.engine.cuda.hooks import DeviceHooks

        self.hooks = DeviceHooks(self)
        #: the device forms of the selected models' run-time hooks
        #: (:mod:`sphfoam.engine.cuda.forms`), called at the same points as on the CPU
        self.forms = device_forms(sel)
        #: what the device forms see of this simulation
        self.context = DeviceContext(self)
        for form in self.forms:
            form.attach(self.context)

    # --- host <-> device ------------------------------------------------------------------
    def _to(self, a, dtype):
        a = np.ascontiguousarray(a, dtype=dtype)
        self.bytes_h2d += a.nbytes
        return self.cuda.to_device(a)

    def _upload(self, st: ParticleState):
        self.n = st.n
        self.d = {}
        for k in self._f8:
            self.d[k] = self._to(getattr(st, k), np.float64)
        for k in self._working:
            self.d[k] = self._to(getattr(st, k), self.dtype)
        for k in _STATE_I8:
            self.d[k] = self._to(getattr(st, k), np.int64)
        for k in self._scratch:
            self.d[k] = self.cuda.device_array(self.n, dtype=self.dtype)
        self.d_extra = _DeviceExtra(self.cuda)
        fields = self.module.FIELDS
        for k, a in st.extra.items():
            if k not in fields:
                self.d_extra[k] = self._to(a, np.float64)
        self.d_fld = self._to(np.stack([st.extra[k] for k in fields]) if fields
                              else np.zeros((0, self.n)), np.float64)
        self.d_aux = self.zeros((len(self.module.AUX), self.n), self.dtype)

    def zeros(self, shape, dtype):
        """A device array of zeros, cleared on the device (nothing copied in)."""
        out = self.cuda.device_array(shape, dtype=dtype)
        if out.ndim == 2:
            self._launch(self.D.fill_rows, out.shape[1], out, 0)
        else:
            self._launch(self.D.fill, out.shape[0], out, 0)
        return out

    def _get(self, a):
        """``a`` copied back (counted; timed as ``copies`` when the timers are on)."""
        if self.timers is None:
            out = a.copy_to_host()
        else:
            self.cuda.synchronize()
            t0 = _time.perf_counter()
            out = a.copy_to_host()
            self.timers["copies"] = self.timers.get("copies", 0.0) + \
                _time.perf_counter() - t0
        self.bytes_d2h += out.nbytes
        return out

    def _put(self, dev, host):
        """The host array ``host`` into the device array ``dev`` (counted and timed as
        ``_get``)."""
        if self.timers is None:
            dev.copy_to_device(host)
        else:
            self.cuda.synchronize()
            t0 = _time.perf_counter()
            dev.copy_to_device(host)
            self.timers["copies"] = self.timers.get("copies", 0.0) + \
                _time.perf_counter() - t0
        self.bytes_h2d += host.nbytes

    @property
    def state(self) -> ParticleState:
        """The state copied back from the device (for writes and function objects)."""
        if self._dirty or self._host.n != self.n:
            d = self.d
            extra = {k: self._get(v) for k, v in self.d_extra.items()}
            fld = self._get(self.d_fld)
            for i, k in enumerate(self.module.FIELDS):
                extra[k] = fld[i]
            third = dict(z=self._get(d["z"]), w=self._get(d["w"])) if self.dim == 3 else {}
            st = ParticleState(*(self._get(d[k]) for k in ("x", "y", "u", "v", "rho", "m",
                                                           "kind", "id")), extra=extra,
                               **third)
            if self.dtype != np.float64:
                st.set_precision(self.dtype)
            for k in self._scratch:
                setattr(st, k, self._get(d[k]))
            self._host = st
            self._dirty = False
        return self._host

    def pressure(self) -> np.ndarray:
        self.eos()
        return self._get(self.d["p"])

    def summary(self) -> str:
        """What the selected models' device forms report at the end of a run."""
        return "; ".join(x for x in (f.summary() for f in self.forms
                                     if hasattr(f, "summary")) if x)

    # --- the models' device forms ---------------------------------------------------------
    def _before_evaluation(self):
        """Before every equation of state, rates or density pass: the declared forms
        (:mod:`sphfoam.engine.cuda.hooks`), then the device forms."""
        self.hooks.before_evaluation()
        self._forms("before_evaluation")

    def model_hook(self, model, name: str) -> None:
        """The run-time hook ``name`` of the selected ``model`` alone, now, by its device form
        (as :meth:`sphfoam.engine.simulation.Simulation.model_hook`); the host's copy of the
        state is then stale."""
        for form in self.forms:
            if getattr(form, "model", None) is model:
                fn = getattr(form, name, None)
                if fn is not None:
                    fn(self.context)
                    self._dirty = True
                return

    def _forms(self, name: str, *args):
        """Call ``name`` of every device form that has it."""
        for form in self.forms:
            fn = getattr(form, name, None)
            if fn is not None:
                fn(self.context, *args)

    def append(self, k: int) -> int:
        """``k`` particles more at the end of every device array (zeros: the caller fills
        them, e.g. mirror ghosts); returns the index of the first."""
        cu, D, n0 = self.cuda, self.D, self.n
        n1 = n0 + int(k)

        def grown(a):
            out = cu.device_array((a.shape[0], n1) if a.ndim == 2 else n1, dtype=a.dtype)
            self._launch(D.extend_rows if a.ndim == 2 else D.extend, n1, a, out)
            return out

        for key in list(self.d):
            self.d[key] = grown(self.d[key])
        for key in list(self.d_extra):
            dict.__setitem__(self.d_extra, key, grown(self.d_extra[key]))
        self.d_fld = grown(self.d_fld)
        self.n = n1
        self._dirty = True
        return n0

    def invalidate_neighbours(self):
        self._ref = None

    @property
    def energy_unit(self) -> str:
        """J per metre of span in 2-D, J in 3-D (the mass is per unit span in 2-D)."""
        return "J/m" if self.dim == 2 else "J"

    def kinetic_energy(self) -> float:
        st = self.state
        f = st.kind == FLUID
        return float(0.5 * np.sum(st.m[f] * sum(c[f] ** 2 for c in st.velocities)))

    @property
    def filter_every(self) -> int:
        return int(self.filter_schedule.interval) if self.filter_schedule else 0

    # --- timing ---------------------------------------------------------------------------
    def _timed(self, name, fn, *args):
        if self.timers is None:
            return fn(*args)
        self.cuda.synchronize()
        t0 = _time.perf_counter()
        out = fn(*args)
        self.cuda.synchronize()
        self.timers[name] = self.timers.get(name, 0.0) + _time.perf_counter() - t0
        return out

    def _launch(self, kernel, n, *args):
        kernel[self.D.blocks(n), self.D.THREADS](*args)

    def _third(self, *names):
        """The device arrays ``names`` of the third axis, and whether there is one: in 2-D,
        ``x`` in their place (the kernels read them only where ``three``)."""
        three = self.dim == 3
        return (*(self.d[k] if three else self.d["x"] for k in names), three)

    # --- the neighbour list -----------------------------------------------------------------
    def _list_still_valid(self) -> bool:
        ref = self._ref
        if ref is None or ref[0].shape[0] != self.n:
            return False
        cl = self.cells
        self._put(self._red, self._RED_CHECK)
        d = self.d
        z, w, three = self._third("z", "w")
        zr = ref[2] if three else ref[0]
        self._launch(self.D.displacement_reduce, self.n, d["x"], d["y"], z, ref[0], ref[1],
                     zr, d["u"], d["v"], w, cl.x0, cl.y0, cl.z0,
                     cl.x0 + cl.ncx * cl.cell_size, cl.y0 + cl.ncy * cl.cell_size,
                     cl.z0 + cl.ncz * cl.cell_size, cl.lx, cl.ly, cl.lz, three, self._red)
        d2, v2, out = self._get(self._red)
        if out:
            return False
        if not math.sqrt(d2) + 1.5 * math.sqrt(v2) * self.last_dt < 0.5 * self.skin:
            return False
        # a device form that adds particles says whether they still serve
        return all(f.keeps_neighbours(self.context) for f in self.forms
                   if hasattr(f, "add_particles"))

    def neighbour_update(self):
        """The neighbour update of this step, timed (``_timed``)."""
        self._timed("neighbours", self._update_neighbours)

    def _update_neighbours(self):
        """The list of this step: the previous one while it is valid, else bin, sort by
        cell (deterministic), drop particles that left and list the neighbours."""
        if self._list_still_valid():
            self.list_reused += 1
            return
        self.hooks.before_neighbours()
        cu, D, cl, d = self.cuda, self.D, self.cells, self.d
        n = self.n
        ncells = cl.ncells
        cell = cu.device_array(n, dtype=np.int64)
        counts = self.zeros(ncells + 1, np.int64)
        z, three = self._third("z")
        self._launch(D.bin_particles, n, d["x"], d["y"], z, cl.x0, cl.y0, cl.z0,
                     1.0 / cl.cell_size, cl.ncx, cl.ncy, cl.ncz, cl.lx, cl.ly, cl.lz, three,
                     cell, counts)
        for form in self.forms:
            if hasattr(form, "add_particles"):
                cell = form.add_particles(self.context, cell, counts)
        n = self.n
        start = cu.device_array(ncells + 2, dtype=np.int64)
        self._scan_scratch = D.exclusive_scan(counts, start, self._scan_scratch)
        fill = self.zeros(ncells + 1, np.int64)
        order = cu.device_array(n, dtype=np.int64)
        self._launch(D.scatter, n, cell, start, fill, order)
        self._launch(D.order_cells, ncells + 1, start, order)
        kept = int(self._get(start[ncells:ncells + 1])[0])   # particles inside the box
        for k in list(d):
            if k in self._scratch:
                continue
            out = cu.device_array_like(d[k])
            self._launch(D.permute, n, d[k], order, out)
            d[k] = out
        for k in list(self.d_extra):
            out = cu.device_array_like(self.d_extra[k])
            self._launch(D.permute, n, self.d_extra[k], order, out)
            dict.__setitem__(self.d_extra, k, out)
        if self.d_fld.shape[0]:
            out = cu.device_array_like(self.d_fld)
            self._launch(D.permute_rows, n, self.d_fld, order, out)
            self.d_fld = out
        if kept < n:
            self._remove(kept)
        self.cell_start = start[:ncells + 1]
        self._forms("after_sort", order)
        n = self.n
        count = cu.device_array(n, dtype=np.int64)
        grid = (*(d[k] for k in self._f8), d["kind"], bool(self.module.FLUID_PAIRS_ONLY),
                self.cell_start, *cl.grid(), self.d_prm, cl.cell_size * cl.cell_size)
        self._launch(self.module.count_neighbours, n, *grid, count)
        nb_start = cu.device_array(n + 1, dtype=np.int64)
        self._scan_scratch = D.exclusive_scan(count, nb_start, self._scan_scratch)
        total = int(self._get(nb_start[n:n + 1])[0])
        idx = self._nb[1]
        if idx is None or idx.shape[0] < total:
            idx = cu.device_array(int(total * 1.1) + 16, dtype=np.uint32)
        self._launch(self.module.fill_neighbours, n, *grid, nb_start, idx)
        self._nb = (nb_start, idx)
        self.pairs = total
        ref = tuple(cu.device_array(n, dtype=np.float64) for _ in self._f8)
        for r, k in zip(ref, self._f8):
            r.copy_to_device(d[k])
        self._ref = ref
        self.list_built += 1
        self._dirty = True

    def _remove(self, kept: int):
        """Particles binned outside the box (sorted last) leave the simulation; ghosts
        there (a device form's) are dropped without a report."""
        from sphfoam.engine.simulation import Removal

        d = self.d
        real = self._get(d["kind"][kept:]) != GHOST
        if real.any():
            ids = self._get(d["id"][kept:])[real]
            where = np.column_stack([self._get(d[k][kept:])[real] for k in self._f8])
            rem = Removal(self.time, int(ids.shape[0]), ids, where)
            self.removals.append(rem)
            if self.on_removal:
                self.on_removal(rem)
        for k in list(d):
            d[k] = d[k][:kept]
        for k in list(self.d_extra):
            dict.__setitem__(self.d_extra, k, self.d_extra[k][:kept])
        self.d_fld = self.d_fld[:, :kept]
        self.d_aux = self.d_aux[:, :kept]
        self._kept = {}
        self.n = kept

    # --- stages ---------------------------------------------------------------------------
    def _args(self):
        d = self.d
        nb_start, nb_idx = self._nb
        if self.d_aux.shape[1] != self.n:
            self.d_aux = self.zeros((len(self.module.AUX), self.n), self.dtype)
        args = (*(d[k] for k in self._f8), *(d[vel] for _, vel in components_of(self.dim)),
                d["rho"], d["p"], d["c"], d["m"], d["kind"], nb_start, nb_idx, self.d_prm,
                self.d_aux, self.d_fld)
        if self.module.PAIR_CACHE:
            if self._pc is None or self._pc.shape[1] != nb_idx.shape[0]:
                self._pc = self.cuda.device_array((len(self.module.PAIR_CACHE),
                                                   nb_idx.shape[0]), dtype=self.dtype)
            args += (self._pc,)
        return args

    def _prepass(self, args, stage="rates"):
        m = self.module
        if not m.N_PREPASS or stage not in m.PREPASS_BEFORE:
            return
        if m.PREPASS_ONCE:
            if self._prepassed:
                return
            if self._prepassed is not None:
                self._prepassed = True
        for i in range(m.N_PREPASS):
            self._timed("prepass", self._launch, getattr(m, f"prepass_{i}"), self.n, *args)

    def eos(self):
        self._before_evaluation()
        d = self.d
        self._timed("eos", self._launch, self.module.equation_of_state, self.n, d["rho"],
                    d["p"], d["c"], self.d_prm)

    def rates(self):
        self._before_evaluation()
        self._forms("before_passes")
        args = self._args()
        self._prepass(args)
        sigma = True
        if self._evaluations is not None:
            sigma = self._evaluations == 0 or not getattr(
                self.integrator, "time_step_from_first_evaluation", False)
            self._evaluations += 1
        d = self.d
        self._timed("rates", self._launch, self.module.rates, self.n, *args,
                    *(d[f"a{ax}"] for ax in self._f8), d["drho"], d["sigma"], sigma)
        self.hooks.run("after_rates")
        self._forms("after_rates")

    def density_rate(self):
        self._before_evaluation()
        self._forms("before_passes")
        args = self._args()
        self._prepass(args, "density")
        self._timed("density", self._launch, self.module.density_rate, self.n, *args,
                    self.d["drho"])
        self.hooks.run("after_density_rate")
        self._forms("after_density_rate")

    def step_pass(self):
        if getattr(self.module, "HAS_STEP", False):
            self._timed("step_pass", self._launch, self.module.step_pass, self.n,
                        *self._args())

    def filter_density(self):
        self.eos()
        args = self._args()
        self._prepass(args, "filter")
        out = self.cuda.device_array_like(self.d["rho"])
        self._timed("filter", self._launch, self.module.density_filter, self.n, *args, out)
        self.d["rho"] = out

    def time_step(self) -> float:
        """T(3.88)-(3.90) as a device reduction; one pair of scalars comes back."""
        if not self.adjust_time_step:
            return self.delta_t
        d = self.d
        self._put(self._red, self._RED_DT)
        az, three = self._third("az")
        self._timed("time_step", self._launch, self.D.time_step_reduce, self.n, self.h,
                    d["c"], d["sigma"], d["ax"], d["ay"], az, three, d["kind"], self._red)
        dmin, fmax, _ = self._get(self._red)
        if self.force_condition and fmax > 0.0:
            dmin = min(dmin, math.sqrt(self.h / math.sqrt(fmax)))
        return min(self.beta * dmin, self.max_delta_t, self.model_dt_limit)

    def advect(self):
        """The velocity positions move with: the velocity, or the selected models' declared
        corrections of it (XSPH, a shifting), in selection order."""
        U = tuple(self.d[vel] for _, vel in components_of(self.dim))
        self._pU = self.hooks.advection_velocity(U)

    def _extra(self, k):
        return self.d_extra[k] if k in self.d_extra else \
            self.d_fld[list(self.module.FIELDS).index(k)]

    def move_walls(self, t: float):
        """Every wall with a prescribed motion where it is at time ``t`` (a kernel over the
        particles of each wall entry: r = r0 + d(t), v = d'(t)); then the hooks' forms that
        follow walls (``walls_moved``) and ``before_evaluation``, as on the CPU."""
        if not self.motions:
            return
        offs = {w: m.displacement(t) for w, m in self.motions.items()}
        vels = {w: m.velocity(t) for w, m in self.motions.items()}
        if "patch" in self.d_extra or "patch" in self.module.FIELDS:
            d = self.d
            z, w, three = self._third("z", "w")
            r0 = [self._extra(f"{ax}0") for ax in self._f8]
            for which in self.motions:
                off = (tuple(offs[which]) + (0.0,))[:3]
                vel = (tuple(vels[which]) + (0.0,))[:3]
                self._timed("walls", self._launch, self.D.prescribe_patch, self.n, d["x"],
                            d["y"], z, d["u"], d["v"], w, self._extra("patch"), r0[0], r0[1],
                            r0[-1], float(which), *map(float, off), *map(float, vel), three)
        self.hooks.walls_moved(offs, vels)
        self._forms("walls_moved", offs, vels)
        self._before_evaluation()

    # --- the integrator's updates ---------------------------------------------------------
    def run_update(self, name: str, scalars: dict):
        if self.updates is None:
            from sphfoam.engine.cuda.build import build_updates

            self.updates = build_updates(self.integrator, self.dim)
            self._upd = {u.name: u for u in self.integrator.updates}
            self._kept_names = {}
            for g, prec in getattr(self.integrator, "kept", {}).items():
                for i, c in enumerate(components(g, self.dim)):
                    self._kept_names[c] = (g, i, prec)
            self._hist = {}
            for g, tmpl in getattr(self.integrator, "history", {}).items():
                self._hist.update(zip(components(g, self.dim),
                                      field_components(tmpl, self.dim)))
        upd = self._upd[name]
        args = [self._array(a) for a in self.updates.ARRAYS[name]]
        args += [scalars[s] for s in upd.scalars]
        self._timed("update", self._launch, getattr(self.updates, f"update_{name}"), self.n,
                    *args)
        self._dirty = True

    def _array(self, a):
        d = self.d
        if a in self._updated:
            return d[a]
        if a in self._kept_names:
            g, i, prec = self._kept_names[a]
            dt = self.dtype if prec == "working" else np.float64
            buf = self._kept.get(g)
            if buf is None or buf[0].shape[0] != self.n:
                buf = tuple(self.cuda.device_array(self.n, dtype=dt)
                            for _ in components(g, self.dim))
                self._kept[g] = buf
            return buf[i]
        if a in self._hist:
            k = self._hist[a]
            if k not in self.d_extra:
                self.d_extra[k] = np.zeros(self.n)
            return self.d_extra[k]
        adv = components("pU@", self.dim)
        if a in adv:
            return self._pU[adv.index(a)]
        raise ValueError(f"integrator {self.integrator.name!r}: unknown array {a!r}")

    # --- the health checks and the last good state, on the device -------------------------
    def health_scan(self, rho_lo: float, rho_hi: float, speed2_max: float) -> tuple:
        """:func:`sphfoam.engine.health.scan` as device reductions: (non-finite, densities
        out of range, too fast, largest speed^2, kinetic energy, mass, finite fluid), 56
        bytes back."""
        D, d, n = self.D, self.d, self.n
        nb = D.blocks(n)
        if self._health is None or self._health[1].shape[0] < nb:
            self._health = (self.cuda.device_array(7, dtype=np.float64),
                            self.cuda.device_array((nb, 2), dtype=np.float64))
        acc, partial = self._health
        self._put(acc, self._HEALTH0)
        three = self.dim == 3
        z, w = (d["z"], d["w"]) if three else (d["y"], d["v"])
        self._timed("health", self._launch, D.health_reduce, n, d["x"], d["y"], z, d["u"],
                    d["v"], w, d["rho"], d["m"], d["kind"], three, float(rho_lo),
                    float(rho_hi), float(speed2_max), acc, partial[:nb])
        D.sum_partials[1, D.THREADS](partial[:nb], acc)
        bad, n_rho, fast, fluid, s2max, ke, mass = self._get(acc)
        return int(bad), int(n_rho), int(fast), float(s2max), float(ke), float(mass), int(fluid)

    def keep_snapshot(self, kept):
        """The state as it is now, copied on the device into ``kept`` (a
        :class:`DeviceSnapshot`, reused; None: a new one), every ``SNAPSHOT_EVERY``-th call:
        the health monitor's last good state, copied back only after a failure."""
        self._snapshot_calls += 1
        if kept is not None and (self._snapshot_calls - 1) % SNAPSHOT_EVERY:
            return kept
        return DeviceSnapshot.of(self, kept)

    # --- stepping -------------------------------------------------------------------------
    def step(self, dt_remaining: float = math.inf) -> float:
        """Re-sort, filter the density when due, then one step of the integrator."""
        dt = advance(self, dt_remaining)
        self.hooks.run("after_step", self.last_dt)
        self._forms("after_step")
        self._dirty = True
        return dt
