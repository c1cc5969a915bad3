"""Blow-up detection: cheap checks after every step and the last state that passed them.

After each step the runner asks :class:`HealthMonitor` whether the new state is sound. One
compiled pass over the particles counts non-finite values (fluid and wall particles; ghosts
are ignored), fluid densities outside ``densityRatio`` rho0 and fluid particles faster than
``maxSpeed`` c0, and sums the fluid kinetic energy; the runner adds the time step and the
particles removed for leaving the domain. A state that passes is copied into preallocated
arrays (:class:`Snapshot`), so when a later step fails the last good state can still be
written as a time directory. Offending particles are only located (a second pass) on failure.

Weakly-compressible SPH keeps rho/rho0 within a few per cent (densityVariation, T(3.31)) and
particle speeds near vmax = c0/10, so the default limits are far from a healthy run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from sphfoam.engine.state import FLUID, GHOST, PERSISTENT_I8, ParticleState

#: what can diverge, with the title a user reads
KINDS = {
    "nan": "non-finite values",
    "density": "density out of range",
    "escape": "particles escaping",
    "deltaT": "time step collapse",
    "energy": "kinetic energy growth",
}
#: most particle ids a diagnosis lists
MAX_IDS = 20
#: codes of :func:`offenders`
NONFINITE, DENSITY, SPEED = 0, 1, 2


# --- compiled passes (no fastmath: the NaN tests must survive) -----------------------------
@njit(cache=True)
def scan(x, y, z, u, v, w, rho, m, kind, three, rho_lo, rho_hi, speed2_max):
    """One pass over the particles; ghosts are skipped. ``three``: z and w are read (in
    2-D they stand for y and v and are not).

    Returns (non-finite positions, velocities or rho among fluid and wall particles, fluid
    densities outside [rho_lo, rho_hi], fluid particles with |v|^2 > speed2_max, the largest
    fluid |v|^2, fluid kinetic energy, fluid mass, finite fluid particles).
    """
    n_bad = 0
    n_rho = 0
    n_fast = 0
    s2max = 0.0
    ke = 0.0
    mass = 0.0
    n_fluid = 0
    for a in range(x.shape[0]):
        k = kind[a]
        if k == GHOST:
            continue
        if not _finite(x[a], y[a], z[a], u[a], v[a], w[a], rho[a], three):
            n_bad += 1
            continue
        if k != FLUID:
            continue
        n_fluid += 1
        r = rho[a]
        if not (r >= rho_lo and r <= rho_hi):
            n_rho += 1
        s2 = u[a] * u[a] + v[a] * v[a]
        if three:
            s2 += w[a] * w[a]
        if s2 > speed2_max:
            n_fast += 1
        s2max = max(s2max, s2)
        ke += 0.5 * m[a] * s2
        mass += m[a]
    return n_bad, n_rho, n_fast, s2max, ke, mass, n_fluid


@njit(cache=True, inline="always")
def _finite(xa, ya, za, ua, va, wa, rhoa, three):
    """Whether a particle's position, velocity and density are all finite: a sum of each
    times 0.0 is 0.0 exactly when none is NaN or infinite (without fast-math), with no
    branch per value. It takes the values, not the arrays and an index: through such a
    call the scan's loop runs several times slower."""
    zero = xa * 0.0 + ya * 0.0 + ua * 0.0 + va * 0.0 + rhoa * 0.0
    if three:
        zero += za * 0.0 + wa * 0.0
    return zero == 0.0


@njit(cache=True, inline="always")
def _speed2(u, v, w, three, a):
    s2 = u[a] * u[a] + v[a] * v[a]
    if three:
        s2 += w[a] * w[a]
    return s2


@njit(cache=True)
def offenders(x, y, z, u, v, w, rho, kind, three, what, rho_lo, rho_hi, speed2_max):
    """Indices of the particles failing check ``what`` (NONFINITE, DENSITY or SPEED), with
    the same rules as :func:`scan`."""
    out = np.empty(x.shape[0], dtype=np.int64)
    k = 0
    for a in range(x.shape[0]):
        if kind[a] == GHOST:
            continue
        finite = _finite(x[a], y[a], z[a], u[a], v[a], w[a], rho[a], three)
        if what == NONFINITE:
            bad = not finite
        elif not finite or kind[a] != FLUID:
            bad = False
        elif what == DENSITY:
            bad = not (rho[a] >= rho_lo and rho[a] <= rho_hi)
        else:
            bad = _speed2(u, v, w, three, a) > speed2_max
        if bad:
            out[k] = a
            k += 1
    return out[:k]


def scan_arrays(st) -> tuple:
    """(x, y, z, u, v, w, three) of a state for :func:`scan` and :func:`offenders`."""
    three = st.dim == 3
    return (st.x, st.y, st.z if three else st.y, st.u, st.v, st.w if three else st.v, three)


# --- the diagnosis -------------------------------------------------------------------------
@dataclass
class Region:
    """Where the offending particles are: centroid and bounding box, one component per
    axis (two or three)."""

    centroid: tuple[float, ...]
    lo: tuple[float, ...]
    hi: tuple[float, ...]

    @classmethod
    def of(cls, *coords: np.ndarray) -> "Region | None":
        ok = np.logical_and.reduce([np.isfinite(c) for c in coords])
        if not ok.any():
            return None
        coords = [c[ok] for c in coords]
        return cls(tuple(float(c.mean()) for c in coords), tuple(float(c.min()) for c in coords),
                   tuple(float(c.max()) for c in coords))

    @staticmethod
    def point(p, fmt: str = ".4g", sep: str = ", ") -> str:
        """``p`` as (a, b[, c])."""
        return "(" + sep.join(f"{v:{fmt}}" for v in p) + ")"

    def __str__(self) -> str:
        return (f"around {self.point(self.centroid)}, within {self.point(self.lo)} .. "
                f"{self.point(self.hi)}")


@dataclass
class Diagnosis:
    """What diverged, when, where and which particles."""

    kind: str                 # one of KINDS
    time: float               # last good time
    step: int                 # index of the step that failed
    fail_time: float          # time reached by that step
    message: str              # one line, with the numbers and the limit
    where: Region | None = None
    ids: list[int] = field(default_factory=list)   # at most MAX_IDS particle ids (origId)
    count: int = 0            # how many particles failed
    last_good: str | None = None   # time directory of the last good state (set by the runner)
    file: str | None = None        # the diagnosis.dat written (set by the runner)

    @property
    def title(self) -> str:
        return KINDS[self.kind]

    def lines(self) -> list[str]:
        """The diagnosis as log lines (no prefix)."""
        out = [f"{self.title} at step {self.step}, time {self.fail_time:.6g} s "
               f"(last good time {self.time:.6g} s)", self.message]
        if self.where is not None:
            out.append(f"where: {self.where}")
        if self.ids:
            more = f" (first {len(self.ids)} of {self.count})" if self.count > len(self.ids) else ""
            out.append(f"particles: ids {' '.join(map(str, self.ids))}{more}")
        if self.last_good:
            out.append(f"last good state: time directory {self.last_good}")
        return out

    def as_row(self) -> dict:
        """Columns for a study table."""
        return {"kind": self.kind, "time": self.time, "message": self.message}

    def entries(self) -> list[tuple[str, str]]:
        """Key/value pairs for postProcessing/stability/<time>/diagnosis.dat."""
        rows = [("kind", self.kind), ("what", f'"{self.title}"'), ("step", str(self.step)),
                ("time", f"{self.time:.9g}"), ("failTime", f"{self.fail_time:.9g}"),
                ("message", f'"{self.message}"'), ("count", str(self.count)),
                ("ids", "(" + " ".join(map(str, self.ids)) + ")")]
        if self.where is not None:
            w, pt = self.where, Region.point
            rows += [("centroid", pt(w.centroid, ".6g", " ")),
                     ("boundBox", f"{pt(w.lo, '.6g', ' ')} {pt(w.hi, '.6g', ' ')}")]
        rows.append(("lastGood", self.last_good or "none"))
        return rows


class BlowUp(RuntimeError):
    """A run stopped by the health checks; carries the diagnosis and the run report."""

    def __init__(self, diagnosis: Diagnosis, report=None):
        super().__init__(f"{diagnosis.title}: {diagnosis.message}")
        self.diagnosis = diagnosis
        self.report = report


@njit(parallel=True, cache=True)
def copy_into(dst, src):
    """dst[:] = src[:] on numba's threads (the snapshot copies some twenty arrays a step: on
    two threads about half numpy's single-threaded copy)."""
    for i in prange(src.shape[0]):
        dst[i] = src[i]


# --- the last good state -------------------------------------------------------------------
class Snapshot:
    """A copy of the persistent particle arrays (ghosts left out) with its time, step and dt.
    The arrays are reused from step to step; they are reallocated only when the particle
    count or the set of extra fields changes."""

    def __init__(self):
        self.arrays: dict[str, np.ndarray] = {}
        self.extra: tuple[str, ...] = ()
        self.n = -1
        self._device = None       # a device backend's copy (``keep_snapshot``)
        self.time = math.nan
        self.step = -1
        self.dt = math.nan

    def take(self, sim) -> None:
        keep = getattr(sim, "keep_snapshot", None)
        if keep is not None:
            # a device backend keeps it on the device (now and then), copied back on demand
            self._device = keep(self._device)
            self.arrays, self.n = {}, -1
            self.time, self.step, self.dt = self._device.time, self._device.step, \
                self._device.dt
            return
        st = sim.state
        real = st.kind != GHOST if getattr(sim, "mirror", False) else None
        n = st.n if real is None else int(np.count_nonzero(real))
        extra = tuple(st.extra)
        if n != self.n or extra != self.extra or self.arrays.get("u") is None or \
                self.arrays["u"].dtype != st.u.dtype:
            # in the state's own precision (sphSchemes precision: float32 velocities, density)
            self.arrays = {k: np.empty(n, dtype=getattr(st, k).dtype)
                           for k in st.persistent_f8}
            self.arrays.update({k: np.empty(n, dtype=np.float64) for k in extra})
            self.arrays.update({k: np.empty(n, dtype=np.int64) for k in PERSISTENT_I8})
            self.n, self.extra = n, extra
        for k in st.persistent_f8 + PERSISTENT_I8:
            self._copy(getattr(st, k), k, real)
        for k in extra:
            self._copy(st.extra[k], k, real)
        self.time, self.step, self.dt = float(sim.time), int(sim.step_index), float(sim.last_dt)

    def _copy(self, src, key, real):
        if real is None:
            copy_into(self.arrays[key], src)
        else:
            np.compress(real, src, out=self.arrays[key])

    def _host(self) -> None:
        """The device backend's copy brought back (ghosts left out), once."""
        if self._device is None or self.arrays:
            return
        st = self._device.host()
        real = st.kind != GHOST
        self.extra = tuple(st.extra)
        self.arrays = {k: getattr(st, k)[real] for k in st.persistent_f8 + PERSISTENT_I8}
        self.arrays.update({k: st.extra[k][real] for k in self.extra})
        self.n = int(np.count_nonzero(real))

    def state(self) -> ParticleState:
        """The snapshot as a ParticleState (copies, so the snapshot can be reused)."""
        self._host()
        a = {k: v.copy() for k, v in self.arrays.items()}
        return ParticleState(a["x"], a["y"], a["u"], a["v"], a["rho"], a["m"], a["kind"],
                             a["id"], {k: a[k] for k in self.extra}, z=a.get("z"),
                             w=a.get("w"))

    def pressure(self, sim) -> np.ndarray:
        """Pressure of the snapshot from the case's equation of state."""
        self._host()
        rho = self.arrays["rho"].copy()
        p, c = np.empty_like(rho), np.empty_like(rho)
        sim.pipeline.equation_of_state(rho, p, c, sim.prm)
        return p

    def positions_of(self, ids: np.ndarray) -> tuple[np.ndarray, ...]:
        """Positions in the snapshot of the particles with these ids (those it holds): x, y
        and, in 3-D, z."""
        self._host()
        hit = np.isin(self.arrays["id"], ids)
        return tuple(self.arrays[k][hit] for k in ("x", "y", "z") if k in self.arrays)


# --- the monitor ---------------------------------------------------------------------------
class HealthMonitor:
    """Runs the checks of controlDict ``stability`` after every step and keeps the last
    state that passed them. ``checks`` is a StabilityChecks (sphfoam.case.schemas)."""

    def __init__(self, checks, rho0: float, c0: float):
        self.enabled = bool(checks.enabled)
        self.ratio = (float(checks.densityRatio[0]), float(checks.densityRatio[1]))
        self.max_speed = float(checks.maxSpeed)
        self.max_escaped = float(checks.maxEscaped)
        self.min_dt = float(checks.minDeltaT)
        self.max_ke = float(checks.maxKineticEnergy)
        self.rho0 = float(rho0)
        self.c0 = float(c0)
        self.outflow = False        # an open tank side: removals are outflow, not escape
        self.snapshot = Snapshot()
        self.dt_ref: float | None = None
        self.n_fluid0 = 0
        self._removals0 = self._removals_seen = 0
        self._removed = 0

    @classmethod
    def from_case(cls, case) -> "HealthMonitor":
        """The checks of the case's controlDict ``stability`` with its rho0 and c0. A tank
        with an open side other than its top has an outflow: particles leaving the domain
        through it are not counted as escaping (the speed check still applies)."""
        mon = cls(case.control.stability, case.context.rho0, case.context.c0)
        mon.outflow = any(set(getattr(w, "open", ["top"])) - {"top"}
                          for w in case.particles.walls.values())
        return mon

    @property
    def speed_limit(self) -> float:
        return self.max_speed * self.c0

    def start(self, sim) -> None:
        """Remember the starting state (the last good state until a step passes)."""
        self.n_fluid0 = sim.state.n_fluid
        self._removals0 = self._removals_seen = len(sim.removals)
        self._removed = 0
        self.dt_ref = None
        self.snapshot.take(sim)

    def check(self, sim, dt: float, landed: bool = False) -> Diagnosis | None:
        """Check the state after a step of ``dt`` (``landed``: shortened to land on a write
        time, so not compared with the first step). None and a new snapshot if it passed."""
        diag = self._diagnose(sim, float(dt), landed)
        if diag is None:
            self.snapshot.take(sim)
        return diag

    # --- the checks ----------------------------------------------------------------------
    def _diagnose(self, sim, dt: float, landed: bool) -> Diagnosis | None:
        dt_bad = not math.isfinite(dt) or dt <= 0.0
        if not self.enabled:
            # a step that is not a positive number would never end the time loop: stop anyway
            return self._dt_failure(sim, self._dt_message(dt)) if dt_bad else None
        lo, hi = self.ratio[0] * self.rho0, self.ratio[1] * self.rho0
        vlim2 = self.speed_limit ** 2
        device_scan = getattr(sim, "health_scan", None)   # a device backend's reductions
        if device_scan is not None:
            n_bad, n_rho, n_fast, s2max, ke, mass, n_fluid = device_scan(lo, hi, vlim2)
        else:
            st = sim.state
            x, y, z, u, v, w, three = scan_arrays(st)
            n_bad, n_rho, n_fast, s2max, ke, mass, n_fluid = scan(
                x, y, z, u, v, w, st.rho, st.m, st.kind, three, lo, hi, vlim2)
        if n_bad:
            idx, st = self._offenders(sim, NONFINITE, lo, hi, vlim2)
            n_real = int(np.count_nonzero(st.kind != GHOST))
            fields = [k for k in ("x", "y", "z", "u", "v", "w", "rho")
                      if hasattr(st, k) and not np.isfinite(getattr(st, k)[idx]).all()]
            return self._particles(sim, "nan", idx,
                                   f"{n_bad} of {n_real} particles have a non-finite "
                                   f"{'/'.join(fields)} (NaN or infinity)")
        if dt_bad:
            return self._dt_failure(sim, self._dt_message(dt))
        if not landed and self.dt_ref is None:
            self.dt_ref = dt
        if not landed and dt < self.min_dt * self.dt_ref:
            return self._dt_failure(
                sim, f"the time step fell to {dt:.4g} s, {dt / self.dt_ref:.3g} of the run's "
                f"first step {self.dt_ref:.4g} s; limit minDeltaT = {self.min_dt:g}")
        if n_rho:
            idx, st = self._offenders(sim, DENSITY, lo, hi, vlim2)
            r = st.rho[idx] / self.rho0
            return self._particles(sim, "density", idx,
                                   f"{n_rho} fluid particles have rho/rho0 outside "
                                   f"densityRatio ({self.ratio[0]:g} {self.ratio[1]:g}): from "
                                   f"{r.min():.4g} to {r.max():.4g}")
        if n_fast:
            idx, _ = self._offenders(sim, SPEED, lo, hi, vlim2)
            return self._particles(sim, "escape", idx,
                                   f"{n_fast} fluid particles are faster than maxSpeed c0 = "
                                   f"{self.max_speed:g} x {self.c0:.4g} m/s: up to "
                                   f"{math.sqrt(s2max):.4g} m/s")
        removed = self._count_removed(sim)
        if not self.outflow and self.n_fluid0 and removed > self.max_escaped * self.n_fluid0:
            gone = sim.removals[self._removals0:]      # this run's removals
            ids = np.concatenate([r.ids for r in gone]) if gone else np.zeros(0, np.int64)
            where = np.concatenate([r.where for r in gone]) if gone else np.zeros((0, 2))
            return self._make(sim, "escape",
                              f"{removed} particles have left the domain box in this run, "
                              f"{100 * removed / self.n_fluid0:.3g} % of the {self.n_fluid0} "
                              f"fluid particles at its start; limit maxEscaped = "
                              f"{self.max_escaped:g}",
                              ids, Region.of(*where.T))
        ke_ref = 0.5 * mass * (0.1 * self.c0) ** 2
        if mass > 0 and ke > self.max_ke * ke_ref:
            st = sim.state
            s2 = np.where(st.kind == FLUID, sum(c ** 2 for c in st.velocities), -1.0)
            k = min(MAX_IDS, n_fluid)
            idx = np.argpartition(-s2, k - 1)[:k]
            idx = idx[np.argsort(-s2[idx])]
            return self._particles(sim, "energy", idx,
                                   f"fluid kinetic energy {ke:.4g} J/m is {ke / ke_ref:.3g} x "
                                   f"M (c0/10)^2 / 2 = {ke_ref:.4g} J/m (RMS speed "
                                   f"{math.sqrt(2 * ke / mass):.4g} m/s); limit "
                                   f"maxKineticEnergy = {self.max_ke:g}; the fastest "
                                   f"particles move at up to {math.sqrt(s2max):.4g} m/s")
        return None

    @staticmethod
    def _offenders(sim, what, lo, hi, vlim2):
        """(indices of the particles failing ``what``, the state they index)."""
        st = sim.state
        x, y, z, u, v, w, three = scan_arrays(st)
        return offenders(x, y, z, u, v, w, st.rho, st.kind, three, what, lo, hi, vlim2), st

    @staticmethod
    def _dt_message(dt: float) -> str:
        return f"the time step is {dt:g} s, not a positive number"

    def _count_removed(self, sim) -> int:
        for r in sim.removals[self._removals_seen:]:
            self._removed += r.count
        self._removals_seen = len(sim.removals)
        return self._removed

    def _dt_failure(self, sim, message: str) -> Diagnosis:
        """The particles that limit the step: smallest h/(c + sigma) or sqrt(h/|F|)."""
        st = sim.state
        h = float(getattr(sim, "h", 1.0))
        with np.errstate(all="ignore"):
            force = np.sqrt(sum(a.astype(np.float64) ** 2 for a in st.accelerations))
            local = np.minimum(h / (st.c + st.sigma), np.sqrt(h / force))
        local = np.where(np.isnan(local), -np.inf, local)
        local = np.where(st.kind == FLUID, local, np.inf)
        k = min(MAX_IDS, st.n_fluid)
        idx = np.argsort(local, kind="stable")[:k] if k else np.zeros(0, np.int64)
        return self._particles(sim, "deltaT", idx, message, count=len(idx))

    def _particles(self, sim, kind: str, idx: np.ndarray, message: str,
                   count: int | None = None) -> Diagnosis:
        """A diagnosis naming the particles at indices ``idx`` of the current state; where
        their positions are no longer finite, where they were in the last good state."""
        st = sim.state
        ids = st.id[idx]
        xs = [c[idx] for c in st.positions]
        ok = np.logical_and.reduce([np.isfinite(c) for c in xs])
        if not ok.all():
            then = self.snapshot.positions_of(ids[~ok])
            xs = [np.concatenate([c[ok], p]) for c, p in zip(xs, then)]
        return self._make(sim, kind, message, ids, Region.of(*xs),
                          len(idx) if count is None else count)

    def _make(self, sim, kind, message, ids, where, count=None) -> Diagnosis:
        ids = np.asarray(ids, dtype=np.int64)
        return Diagnosis(kind=kind, time=self.snapshot.time, step=int(sim.step_index),
                         fail_time=float(sim.time), message=message, where=where,
                         ids=[int(i) for i in ids[:MAX_IDS]],
                         count=len(ids) if count is None else int(count))
