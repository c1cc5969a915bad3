"""The time loop of a run: start time, steps, writes, function objects, health checks,
progress, the log, Ctrl-C and blow-ups. Python acts once per step (or per write); the particle
work is all in the compiled pipeline and the integrators' numba kernels.
"""

from __future__ import annotations

import math
import shutil
import time as wallclock
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sphfoam._version import __version__
from sphfoam.assemble import build_simulation
from sphfoam.case.case import Case
from sphfoam.case.times import time_name
from sphfoam.engine.health import BlowUp, Diagnosis, HealthMonitor, Region
from sphfoam.engine.schedule import Schedule
from sphfoam.engine.state import GHOST, ParticleState
from sphfoam.engine.threads import RunThreads, check_setting
from sphfoam.io.fields import has_particles, read_state
from sphfoam.io.timedirs import (case_lock, check_time_dir, read_time_value, recover,
                                 start_folder, write_time)
from sphfoam.setup.settling import setup_case


class Log:
    """``log.sphfoam`` in the case (appended on restart) plus an optional echo."""

    def __init__(self, path: Path, echo=None):
        self.fh = path.open("a")
        self.echo = echo

    def __call__(self, msg: str):
        self.fh.write(msg + "\n")
        self.fh.flush()
        if self.echo:
            self.echo(msg)

    def close(self):
        self.fh.close()


@dataclass
class RunReport:
    start_time: float
    end_time: float
    steps: int
    particles: int
    compile_seconds: float
    cache_hit: bool
    run_seconds: float
    written: list[str] = field(default_factory=list)
    removed: int = 0
    #: why the run stopped early (see sphfoam.engine.health), None if it reached its end
    failure: Diagnosis | None = None

    @property
    def particle_steps_per_second(self) -> float:
        return self.particles * self.steps / max(self.run_seconds, 1e-12)


def run_case(case: Case | str | Path, *, progress: bool = True, echo=print,
             end_time: float | None = None, console=None,
             threads: int | str | None = None) -> RunReport:
    """Run a case from its start time to endTime (or ``end_time``). ``console``: the rich
    console the progress bar draws on; give ``echo`` that prints on the same console so
    log lines appear above the bar instead of being glued to it. ``threads`` (``"auto"`` or
    a number >= 1) overrides controlDict ``threads`` (see :mod:`sphfoam.engine.threads`)."""
    if threads is not None:
        check_setting(threads, "threads")
    case = case if isinstance(case, Case) else Case(case)
    case.validate()
    c = case.control
    with case_lock(case.path):
        log = Log(case.path / "log.sphfoam", echo)
        try:
            return _run(case, c, log, progress,
                        end_time if end_time is not None else c.endTime, console, threads)
        finally:
            log.close()


class Interrupted(KeyboardInterrupt):
    """Ctrl-C ended the run; ``written`` is the time directory holding the state at the
    interruption, or None when it was not written (a second Ctrl-C stops at once, mid-step,
    or during that write); ``latest`` is the latest complete time directory either way."""

    def __init__(self, written: str | None, latest: str | None):
        super().__init__(written)
        self.written, self.latest = written, latest


def _run(case, c, log, progress, t_end, console=None, threads=None) -> RunReport:
    log(f"sphfoam {__version__}: case {case.path}")
    recover(case.path, log)
    folder = start_folder(case, log)
    if folder is None:
        log("no particles in any time directory: running setup first")
        setup_case(case, log)
        folder = case.path / "0"
    t0, index = read_time_value(folder)
    state = ParticleState.from_fields(read_state(folder, case.dimension))
    log(f"starting from time {folder.name} ({state.n} particles, {state.n_fluid} fluid)")
    sim = build_simulation(case, state)
    sim.time, sim.step_index = t0, index
    sel = sim.pipeline.selection
    log(f"models: {sel.describe()}, integrator={case.models.integrator.name}")
    log(f"h = {case.context.h:g} m, c0 = {case.context.c0:.4g} m/s, maxCo = {c.maxCo:g}")
    log(f"pipeline: {sim.pipeline.source_path}")
    log(f"compile: {sim.pipeline.compile_seconds:.2f} s "
        f"({'loaded from cache' if sim.pipeline.cache_hit else 'compiled'})")

    def on_removal(rem):
        log(f"time {sim.time:.6g}: removed {rem.count} particle(s) that left the domain "
            f"near {Region.point(rem.where.mean(axis=0))}; ids {rem.ids[:10].tolist()}"
            f"{' ...' if rem.count > 10 else ''}")

    sim.on_removal = on_removal
    functions = case.models.functions
    start_name = folder.name
    for fo in functions.values():
        fo.start(case, case.context, start_name)
        if sim.step_index == 0:    # the initial state; a restart samples on its schedule only
            fo.execute(sim)

    report = RunReport(t0, t_end, 0, state.n, sim.pipeline.compile_seconds,
                       sim.pipeline.cache_hit, 0.0)
    monitor = HealthMonitor.from_case(case)
    monitor.start(sim)
    written: list[Path] = []
    writes = write_schedule(c)
    eps = 1e-9 * max(c.writeInterval, 1e-300)
    bar = _Progress(progress, t0, t_end, state.n, console)
    pool = RunThreads(c.threads if threads is None else threads,
                      f"system/controlDict threads {c.threads}" if threads is None else
                      f"run option -j/threads={threads}; controlDict threads {c.threads} not used",
                      log)
    clock = wallclock.perf_counter
    wall0 = clock()
    stop = _StopRequest()
    try:
        while sim.time < t_end - eps:
            if stop.requested:
                raise KeyboardInterrupt
            lands = c.writeControl == "adjustableRunTime"
            target = min(writes.next_time(sim.time), t_end) if lands else t_end
            remaining = target - sim.time
            t_prev = sim.time
            t_step = clock()
            dt = sim.step(remaining)
            pool.after_step(clock() - t_step, sim.time)
            landed = dt >= remaining * (1 - 1e-12)
            if landed:
                sim.time = target          # land exactly, so restarts see the same time
            report.steps += 1
            diagnosis = monitor.check(sim, dt, landed)
            if diagnosis is not None:          # nothing of this step is written or sampled
                report.failure = diagnosis
                _blow_up(case, sim, monitor, diagnosis, start_name, log)
                raise BlowUp(diagnosis, report)
            wrote = writes.due(sim.step_index, sim.time, t_prev) or sim.time >= t_end - eps
            if wrote:
                try:
                    written.append(_write(case, sim, log))
                except OSError as e:
                    _log_quietly(log, f"could not write the state at time {sim.time:.6g}: "
                                 f"{e.strerror or e}; the time directories written before "
                                 "are complete (restart from the latest)")
                    raise
                sim.invalidate_neighbours()
                _purge(written, c.purgeWrite)
            for fo in functions.values():
                if fo.due(sim, wrote, t_prev):
                    fo.execute(sim)
            bar.update(sim, dt)                # (it redraws at most every 0.2 s)
    except KeyboardInterrupt:
        done = _written_already(case, sim, start_name)
        if done is not None and (not written or written[-1] != done):
            written.append(done)          # the interrupt landed after the atomic rename
        latest = written[-1].name if written else start_name
        if stop.hard and done is None:    # a second Ctrl-C: stopped at once, maybe mid-step
            log(f"interrupted twice at time {sim.time:.6g}: stopped at once; the current "
                f"state was NOT written (latest complete time directory: {latest})")
            raise Interrupted(None, latest) from None
        # the first Ctrl-C only raises a flag (see _StopRequest): the state is a whole step
        if done is None:
            log(f"interrupted at time {sim.time:.6g}: writing the current state")
            try:
                written.append(_write(case, sim, log))
            except KeyboardInterrupt:     # the write is atomic: complete or not there at all
                done = _written_already(case, sim, start_name)
                if done is None:
                    log(f"interrupted again while writing: the current state was NOT "
                        f"written (latest complete time directory: {latest})")
                    raise Interrupted(None, latest) from None
                written.append(done)
        raise Interrupted(written[-1].name, written[-1].name) from None
    finally:
        stop.restore()
        bar.close()
        pool.end()
        report.run_seconds = wallclock.perf_counter() - wall0
        report.end_time = sim.time if report.failure is None else report.failure.time
        report.particles = int(np.count_nonzero(sim.state.kind != GHOST))
        report.removed = sum(r.count for r in sim.removals)
        report.written = [p.name for p in written]
        for fo in functions.values():
            fo.end()
    log(f"end: time {sim.time:.6g} after {report.steps} steps in {report.run_seconds:.2f} s "
        f"({report.particle_steps_per_second:.3g} particle-steps/s); "
        f"removed {report.removed} particle(s)"
        + (f"; {sim.summary()}" if sim.summary() else ""))
    return report


def write_schedule(control) -> Schedule:
    """When time directories are written (controlDict writeControl, writeInterval)."""
    ctl = "runTime" if control.writeControl == "adjustableRunTime" else control.writeControl
    return Schedule(ctl, control.writeInterval)


def _blow_up(case, sim, monitor: HealthMonitor, diagnosis: Diagnosis, start_name: str,
             log) -> None:
    """Write the last good state and the diagnosis, and log it (the caller raises)."""
    snap = monitor.snapshot
    c = case.control
    name = None
    for prec in range(c.timePrecision, 18):
        candidate = time_name(snap.time, prec)
        folder = case.path / candidate
        if not has_particles(folder):
            name = candidate
            break
        t, index = read_time_value(folder)
        if index == snap.step and math.isclose(t, snap.time, rel_tol=1e-12, abs_tol=1e-300):
            break                  # written already (a write time or the start): the same state
    else:
        name = time_name(snap.time, 17)
    if name is not None:
        folder = write_time(case, snap.state(), snap.time, snap.step, snap.dt,
                            p=snap.pressure(sim), name=name)
    diagnosis.last_good = folder.name
    out = case.path / "postProcessing" / "stability" / start_name
    out.mkdir(parents=True, exist_ok=True)
    dat = out / "diagnosis.dat"
    rows = diagnosis.entries()
    width = max(len(k) for k, _ in rows) + 4
    dat.write_text(f"# sphfoam {__version__}: stability diagnosis of case {case.path}\n"
                   f"# the run stopped at time {diagnosis.fail_time:.9g} "
                   f"(step {diagnosis.step}): {diagnosis.title}\n"
                   f"# key value\n" + "".join(f"{k:<{width}}{v}\n" for k, v in rows))
    diagnosis.file = str(dat)
    for line in diagnosis.lines():
        log(f"BLOW-UP: {line}")
    log(f"BLOW-UP: diagnosis written to {dat.relative_to(case.path)}; `sphfoam run` with "
        f"startFrom latestTime restarts from time {folder.name}")


def _write(case, sim, log) -> Path:
    folder = write_time(case, sim.state, sim.time, sim.step_index, sim.last_dt,
                        p=sim.pressure())
    log(f"time {folder.name}: written (step {sim.step_index}, dt {sim.last_dt:.4g}, "
        f"KE {sim.kinetic_energy():.4g} {sim.energy_unit})")
    return folder


def _written_already(case, sim, start_name: str) -> Path | None:
    """The time directory of the current step if it is complete on disk: a Ctrl-C that
    lands after the atomic rename of a write but before the write returns leaves it whole.
    The start's own directory does not count (the run wrote nothing)."""
    folder = case.path / time_name(sim.time, case.control.timePrecision)
    if folder.name == start_name:
        return None
    try:
        if has_particles(folder) and read_time_value(folder)[1] == sim.step_index \
                and check_time_dir(folder)[0] is None:
            return folder
    except (OSError, ValueError):
        pass
    return None


def _log_quietly(log, msg: str) -> None:
    """Log ``msg`` if the log can still be written (not on a full or read-only disk)."""
    try:
        log(msg)
    except OSError:
        pass


def _purge(written: list[Path], keep: int):
    if keep > 0:
        while len(written) > keep:
            shutil.rmtree(written.pop(0), ignore_errors=True)


class _StopRequest:
    """Ctrl-C sets a flag the time loop checks between steps, so a step is never cut in half
    and the state written on interruption restarts exactly. A second Ctrl-C stops at once.

    A second Ctrl-C that lands inside a finaliser (``__del__``, e.g. numba's compiler freeing
    an LLVM object) cannot propagate: Python would print it as an "Exception ignored"
    traceback and go on. The flags are set already, so the loop stops at the next step
    boundary with the same message; the hook only keeps that traceback off the screen."""

    def __init__(self):
        import signal
        import sys
        import threading

        self.requested = False
        self.hard = False
        self._previous = None
        self._unraisable = None
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
            self._unraisable = sys.unraisablehook
            sys.unraisablehook = self._quiet_interrupt

    def _quiet_interrupt(self, unraisable):
        if not (self.requested and isinstance(unraisable.exc_value, KeyboardInterrupt)):
            self._unraisable(unraisable)

    def _handle(self, signum, frame):
        if self.requested:
            self.hard = True
            raise KeyboardInterrupt
        self.requested = True

    def restore(self):
        import signal
        import sys

        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
        if getattr(self, "_unraisable", None) is not None:
            sys.unraisablehook = self._unraisable


def _particles(sim) -> int:
    """The particle count, without copying a device backend's state back."""
    n = getattr(sim, "n", None)
    return int(n) if n is not None else sim.state.n


class _Progress:
    """A rich progress bar: sim time, step, dt, steps/s, particles, ETA. It draws on
    ``console`` (rich's own by default); log lines printed on that console while it runs go
    above it. Updates are throttled to 5 a second; :meth:`close` draws the final state (100 %
    at the end time) before the bar stops."""

    def __init__(self, enabled, t0, t_end, n, console=None):
        self.enabled = enabled
        self.t0, self.t_end = t0, t_end
        self.last = 0.0
        if not enabled:
            return
        from rich.progress import (BarColumn, Progress, TaskProgressColumn, TextColumn,
                                   TimeElapsedColumn, TimeRemainingColumn)

        self.p = Progress(TextColumn("[bold]t = {task.fields[t]:.5g} s"), BarColumn(),
                          TaskProgressColumn(),
                          TextColumn("step {task.fields[step]}  dt {task.fields[dt]:.3g} s  "
                                     "{task.fields[rate]:.0f} steps/s  {task.fields[n]} particles"),
                          TimeElapsedColumn(), TimeRemainingColumn(), console=console)
        self.p.start()
        self.total = max(t_end - t0, 1e-300)
        self.task = self.p.add_task("run", total=self.total, t=t0, step=0,
                                    dt=0.0, rate=0.0, n=n)
        self.w0 = wallclock.perf_counter()
        self.steps = 0
        self.state = None

    def _fields(self, sim, dt, now):
        done = self.total if sim.time >= self.t_end * (1 - 1e-12) else sim.time - self.t0
        return dict(completed=min(done, self.total), t=sim.time, step=sim.step_index, dt=dt,
                    rate=self.steps / max(now - self.w0, 1e-9), n=_particles(sim))

    def update(self, sim, dt):
        if not self.enabled:
            return
        self.steps += 1
        self.state = (sim, dt)
        now = wallclock.perf_counter()
        if now - self.last < 0.2:
            return
        self.last = now
        self.p.update(self.task, **self._fields(sim, dt, now))

    def close(self):
        if self.enabled:
            if self.state is not None:
                self.p.update(self.task, **self._fields(*self.state, wallclock.perf_counter()))
            self.p.refresh()
            self.p.stop()
