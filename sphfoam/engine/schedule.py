"""One schedule for everything attached to a run: time-directory writes, function objects,
density filters, health checks and progress.

A :class:`Schedule` is a pure function of the run's step index and simulated time (never of
a counter kept since the process started), so a run restarted from a written time does
everything at the same steps and times as an uninterrupted one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: controls: every ``interval`` steps of the run's step index; whenever the simulated time
#: crosses a multiple of ``interval`` (``runTime``; ``adjustableRunTime`` also lands the
#: time step on it); at every time-directory write; at every step
CONTROLS = ("timeStep", "runTime", "adjustableRunTime", "writeTime", "everyStep")

_EPS = 1e-9


@dataclass(frozen=True)
class Schedule:
    control: str = "everyStep"
    interval: float = 1.0

    def __post_init__(self):
        if self.control not in CONTROLS:
            raise ValueError(f"unknown schedule control {self.control!r}; valid: "
                             f"{', '.join(CONTROLS)}")
        if self.control in ("timeStep", "runTime", "adjustableRunTime") and \
                not (self.interval > 0 and math.isfinite(self.interval)):
            raise ValueError(f"schedule interval must be positive and finite, not "
                             f"{self.interval!r}")

    @classmethod
    def every(cls, steps: int) -> "Schedule":
        return cls("timeStep", int(steps))

    @property
    def by_time(self) -> bool:
        return self.control in ("runTime", "adjustableRunTime")

    def period_index(self, t: float) -> int:
        """Index of the interval ``t`` lies in (a time on a multiple counts as reached)."""
        return math.floor(t / self.interval + _EPS)

    def next_time(self, t: float) -> float:
        """The first multiple of the interval after ``t`` (time controls)."""
        return (self.period_index(t) + 1) * self.interval

    def due(self, step_index: int, time: float, previous_time: float,
            wrote: bool = False) -> bool:
        """Whether the step that brought the run from ``previous_time`` to ``time`` (its
        index after the step: ``step_index``) triggers this schedule."""
        if self.control == "everyStep":
            return True
        if self.control == "writeTime":
            return wrote
        if self.control == "timeStep":
            return step_index % int(self.interval) == 0
        return self.period_index(time) > self.period_index(previous_time)

    def due_before_step(self, step_index: int) -> bool:
        """For passes run at the start of a step (a density filter every N steps): due
        at step indices that are positive multiples of the interval."""
        if self.control != "timeStep":
            raise ValueError("a pass before a step is scheduled in steps (timeStep)")
        return step_index > 0 and step_index % int(self.interval) == 0
