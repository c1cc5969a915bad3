"""numba's thread count during a run: pinned, or chosen as the run goes (controlDict
``threads auto;``, the default).

Why choose it at run time. A step runs about 16 parallel regions (the re-sort's gathers, the
equation of state, the pair loops, the integrator's updates), each ending at a barrier where
every thread waits for the slowest. When another process holds one of the cores, the thread
that shares that core gets only part of it, and each barrier waits for it (and for the
scheduler's time slice, milliseconds, when it was switched out): two threads then take longer
per step than one thread alone (measured: 26 ms against 18 ms at 89 000 particles on 2 cores,
``benchmarks/bench_shared_core.py``). No wait policy of the OpenMP runtime removes that: a
spinning wait keeps the idle speed-up but collapses under contention, a sleeping wait
(``OMP_WAIT_POLICY=passive``) does not collapse but loses 10-20 % on an idle machine. The
measure that does not guess is the run's own wall time per step.

:class:`AdaptiveThreads` does that with Python between steps (a clock read and a few
additions per step; ``numba.set_num_threads`` only sets the count the next parallel region
starts with, so changing it between steps races with nothing): it times windows of steps
(at least ``min_steps`` and ``window_seconds`` of stepping), now and then runs one window at
the next lower (or higher) count, and moves there when that window's mean time per step beats
the mean of the windows just before and after it, at the count it is running, by more than
``margin``. A probe that loses doubles the number of windows until the next one (up to
``max_gap``); a move resets it, so that a run that went to fewer threads because another
process was busy goes back within ``max_gap`` windows of that process stopping.

The count does not change the results: every parallel loop of the pipeline computes each
particle's values from its own gather in a fixed order (no sum across particles is split
among threads), and the serial reductions (time step, displacement check) run in one thread;
``tests/test_threads.py`` checks that 1 thread, 2 threads and an adaptive run give bit-identical
fields.
"""

from __future__ import annotations

import os
import sys
from collections import Counter
from dataclasses import dataclass

#: defaults of the adaptive controller (see AdaptiveThreads)
WINDOW_SECONDS = 0.5
MIN_WINDOW_STEPS = 8
WARMUP_STEPS = 3
MARGIN = 0.05
MAX_GAP = 32


@dataclass(frozen=True)
class Change:
    """A move of the adaptive controller: at ``step`` (steps of this run), ``new`` threads
    instead of ``old``; ``t_new`` and ``t_old`` the measured seconds per step at each."""

    step: int
    new: int
    old: int
    t_new: float
    t_old: float

    def describe(self) -> str:
        return (f"threads auto: {self.new} thread{'s' if self.new != 1 else ''} from now "
                f"({1e3 * self.t_new:.3g} ms/step against {1e3 * self.t_old:.3g} ms/step with "
                f"{self.old})")


class AdaptiveThreads:
    """Chooses the thread count, between 1 and ``n_max``, from measured step times.

    Call :meth:`record` after every step with its wall time (seconds); run the next step
    with :attr:`current` threads. The logic is pure Python on the numbers given, so a
    synthetic sequence of times tests it (``tests/test_threads.py``).

    Windows: ``warmup`` steps after each change of count are not measured (the first region
    at a new count wakes or parks pool threads); a window then closes after at least
    ``min_steps`` steps and ``window_seconds`` seconds. The cycle is base window(s) at the
    chosen count ``n``, one probe window at a neighbouring count, one window at ``n`` again;
    the probe wins when its mean is below ``(1 - margin)`` times the mean of the two windows
    at ``n`` that bracket it (a slow drift of the step cost, e.g. more neighbour-list
    rebuilds as the flow develops, cancels out).
    """

    def __init__(self, n_max: int, *, window_seconds: float | None = None,
                 min_steps: int | None = None, warmup: int | None = None,
                 margin: float | None = None, max_gap: int | None = None):
        if n_max < 1:
            raise ValueError(f"n_max must be >= 1, got {n_max}")

        def pick(value, default):       # None: the module's default at construction
            return default if value is None else value

        self.n_max = int(n_max)
        self.window_seconds = float(pick(window_seconds, WINDOW_SECONDS))
        self.min_steps = max(1, int(pick(min_steps, MIN_WINDOW_STEPS)))
        self.warmup = max(0, int(pick(warmup, WARMUP_STEPS)))
        self.margin = float(pick(margin, MARGIN))
        self.max_gap = max(1, int(pick(max_gap, MAX_GAP)))
        self.n = self.n_max            # the chosen count
        self.current = self.n_max      # the count of the coming step
        self.steps = Counter()         # steps run at each count
        self.changes: list[Change] = []
        self.tries = 0
        self._phase = "base"           # base | probe | after
        self._skip = self.warmup
        self._k = 0                    # steps and seconds of the open window
        self._sum = 0.0
        self._gap = 1                  # base windows before the next probe
        self._since = 0                # base windows since the last probe
        self._before = 0.0             # mean of the base window before the probe
        self._probe_n = 0
        self._probe_t = 0.0
        self._up = False               # direction of the next probe (alternates when both exist)
        self.step_count = 0

    # -- the measurement ------------------------------------------------------------------
    def record(self, seconds: float) -> int | None:
        """The wall time of the step just run at :attr:`current` threads; returns the count
        for the next step when it changes, else None."""
        self.step_count += 1
        self.steps[self.current] += 1
        if self.n_max == 1:
            return None
        if self._skip > 0:
            self._skip -= 1
            return None
        self._k += 1
        self._sum += float(seconds)
        if self._k < self.min_steps or self._sum < self.window_seconds:
            return None
        mean = self._sum / self._k
        self._k, self._sum = 0, 0.0
        return self._window(mean)

    def _candidate(self) -> int:
        lower, upper = self.n - 1, self.n + 1
        if lower < 1:
            return upper
        if upper > self.n_max:
            return lower
        self._up = not self._up
        return upper if self._up else lower

    def _set(self, n: int) -> int | None:
        if n == self.current:
            return None
        self.current = n
        self._skip = self.warmup
        return n

    def _window(self, mean: float) -> int | None:
        if self._phase == "base":
            self._since += 1
            if self._since < self._gap:
                return None
            self._before = mean
            self._probe_n = self._candidate()
            self._phase = "probe"
            self.tries += 1
            return self._set(self._probe_n)
        if self._phase == "probe":
            self._probe_t = mean
            self._phase = "after"
            return self._set(self.n)
        # after: the window at n right after the probe
        base = 0.5 * (self._before + mean)
        self._phase = "base"
        if self._probe_t < (1.0 - self.margin) * base:
            self.changes.append(Change(self.step_count, self._probe_n, self.n, self._probe_t, base))
            self.n = self._probe_n
            self._gap, self._since = 1, 0
            return self._set(self.n)
        self._gap = min(2 * self._gap, self.max_gap)
        self._since = 1               # this window counts as the first base window
        return None

    def summary(self) -> str:
        """One line: steps at each count, tries and changes."""
        per = ", ".join(f"{self.steps[n]} at {n}" for n in sorted(self.steps, reverse=True))
        return (f"threads auto: steps {per}; {self.tries} probe window(s), "
                f"{len(self.changes)} change(s); ended at {self.n}")


def pool_size() -> int:
    """Threads numba started (``NUMBA_NUM_THREADS``, by default the cores this process may
    use): the most any run can use."""
    import numba

    return int(numba.config.NUMBA_NUM_THREADS)


#: changes logged one by one; later ones are counted in the end-of-run summary only
LOGGED_CHANGES = 20


def check_setting(value, what: str):
    """``auto`` or a whole number >= 1; anything else is a ValueError naming ``what``."""
    if value == "auto" or (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
        return value
    raise ValueError(f"{what}: expected auto or a whole number of threads >= 1, got {value!r}")


class RunThreads:
    """The thread count of one run: pinned, or adaptive (:class:`AdaptiveThreads`).

    ``setting`` is controlDict ``threads`` or the caller's override (``sphfoam run -j``,
    ``sphfoam.run(threads=...)``); ``origin`` says where it came from, for the log. numba's
    count before the run is restored by :meth:`end`.
    """

    def __init__(self, setting, origin: str, log, **adaptive):
        import numba

        self._numba = numba
        self._log = log
        self._saved = numba.get_num_threads()
        pool = pool_size()
        self.adaptive: AdaptiveThreads | None = None
        if setting == "auto":
            n = pool
            if pool == 1:
                log(f"threads: 1 ({origin}; numba's pool has 1 thread: NUMBA_NUM_THREADS=1 "
                    "or one core)")
            else:
                self.adaptive = AdaptiveThreads(pool, **adaptive)
                a = self.adaptive
                log(f"threads: auto ({origin}), 1 to {pool} (numba's pool, NUMBA_NUM_THREADS): "
                    f"starting at {pool}; windows of >= {a.min_steps} steps and "
                    f"{a.window_seconds:g} s are timed, a neighbouring count is tried now and "
                    f"then and kept when > {100 * a.margin:g} % faster")
        else:
            n = min(int(setting), pool)
            capped = (f"; numba's pool has only {pool} (NUMBA_NUM_THREADS)"
                      if int(setting) > pool else "")
            log(f"threads: {n} ({origin}{capped})")
        numba.set_num_threads(n)
        log(f"threads: {layer_description()}")
        if (self.adaptive is not None and numba.threading_layer() == "omp"
                and os.environ.get("OMP_WAIT_POLICY", "").strip().lower() == "active"):
            log("threads auto: note: OMP_WAIT_POLICY=active keeps an OpenMP thread the run no "
                "longer uses spinning (for minutes), so fewer threads do not give its core "
                "back; unset it (libgomp's default spins briefly, then sleeps)")

    def after_step(self, seconds: float, time: float) -> None:
        """The wall time of the step just run (ends at simulation ``time``)."""
        a = self.adaptive
        if a is None:
            return
        new = a.record(seconds)
        if new is not None:
            self._numba.set_num_threads(new)
            last = a.changes[-1] if a.changes else None
            if last is not None and last.step == a.step_count and len(a.changes) <= LOGGED_CHANGES:
                self._log(f"time {time:.6g} (step {last.step} of this run): {last.describe()}"
                          + ("; later changes are counted at the end only"
                             if len(a.changes) == LOGGED_CHANGES else ""))

    @property
    def current(self) -> int:
        return self._numba.get_num_threads()

    def end(self) -> None:
        """Log the adaptive summary and restore numba's count from before the run."""
        if self.adaptive is not None:
            self._log(self.adaptive.summary())
        self._numba.set_num_threads(self._saved)


#: numba's threading layers in the order sphfoam asks for them (see prefer_omp)
LAYER_PRIORITY = ("omp", "tbb", "workqueue")


def prefer_omp() -> None:
    """Ask numba for its OpenMP layer first (numba's own order puts tbb first), so that a
    machine that happens to have tbb installed runs the layer these choices were measured
    with: libgomp with its default wait policy (a waiting thread spins ~300 000 times, then
    sleeps; benchmarks/README.md). Nothing is changed when ``NUMBA_THREADING_LAYER`` or
    ``NUMBA_THREADING_LAYER_PRIORITY`` is set, nor once numba has started its threads."""
    if os.environ.get("NUMBA_THREADING_LAYER") or os.environ.get("NUMBA_THREADING_LAYER_PRIORITY"):
        return
    os.environ["NUMBA_THREADING_LAYER_PRIORITY"] = " ".join(LAYER_PRIORITY)
    if "numba" in sys.modules:
        sys.modules["numba"].config.THREADING_LAYER_PRIORITY = list(LAYER_PRIORITY)


def layer_description() -> str:
    """numba's threading layer and, for omp, the wait policy in force (for the log)."""
    import numba

    numba.get_num_threads()           # starts numba's threads (and so its layer) if not yet
    layer = numba.threading_layer()
    if layer != "omp":
        return f"threading layer {layer}"
    pol = os.environ.get("OMP_WAIT_POLICY")
    spin = os.environ.get("GOMP_SPINCOUNT")
    how = (f"OMP_WAIT_POLICY={pol}" if pol else "libgomp's default wait: spin, then sleep")
    return f"threading layer omp ({how}{f', GOMP_SPINCOUNT={spin}' if spin else ''})"

