"""Wave-maker trajectories X(t) of a piston paddle (``pistonPaddle`` motion)."""

from __future__ import annotations

import abc

import math

from pydantic import Field

from sphfoam.registry import Coeffs, Model, register


class WaveMaker(Model, abc.ABC):
    family = "waveMaker"

    @abc.abstractmethod
    def position(self, t: float) -> float:
        """Paddle displacement X(t) from its rest position (m)."""

    @abc.abstractmethod
    def velocity(self, t: float) -> float:
        """dX/dt (m/s)."""

    def solitary_wave(self) -> tuple[float, float] | None:
        """(H, d) of the solitary wave this maker generates, for metrics and plots; None for
        a maker that makes no single solitary wave."""
        return None


@register
class Sinusoidal(WaveMaker):
    """A sinusoidal piston, X(t) = r(t) S/2 sin(2 pi t / T), ramped up smoothly over
    ``rampTime`` with r = (1 - cos(pi t / rampTime))/2 so that it starts from rest."""

    name = "sinusoidal"
    doc = "sinusoidal piston X = r(t) S/2 sin(2 pi t/T) with a smooth ramp-up"

    class Coeffs(Coeffs):
        stroke: float = Field(gt=0, description="full stroke S (m), twice the amplitude")
        period: float = Field(gt=0, description="period T (s)")
        rampTime: float = Field(0.0, ge=0, description="ramp-up time (s); 0 = impulsive start")

    def _ramp(self, t):
        tr = self.coeffs.rampTime
        if tr <= 0 or t >= tr:
            return 1.0, 0.0
        if t <= 0:
            return 0.0, 0.0
        return 0.5 * (1 - math.cos(math.pi * t / tr)), 0.5 * math.pi / tr * math.sin(math.pi * t / tr)

    def position(self, t):
        if t <= 0:
            return 0.0
        r, _ = self._ramp(t)
        w = 2 * math.pi / self.coeffs.period
        return r * 0.5 * self.coeffs.stroke * math.sin(w * t)

    def velocity(self, t):
        if t <= 0 and self.coeffs.rampTime > 0:
            return 0.0
        t = max(t, 0.0)
        r, dr = self._ramp(t)
        w = 2 * math.pi / self.coeffs.period
        a = 0.5 * self.coeffs.stroke
        return r * a * w * math.cos(w * t) + dr * a * math.sin(w * t)
