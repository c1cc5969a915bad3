"""Goring's (1978) piston-paddle trajectory for a Boussinesq solitary wave, T(4.17)-(4.24)."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from sphfoam.models.wavemakers import WaveMaker
from sphfoam.registry import Coeffs, register

#: tanh^-1(0.999) of T(4.22) (the thesis rounds it to 3.80)
ATANH_0999 = math.atanh(0.999)


@register
class Goring(WaveMaker):
    """Goring's solitary-wave paddle: the paddle moves with the depth-uniform Boussinesq
    velocity dxi/dt = c eta/(d + eta) T(4.17), T(4.5), which integrates to the implicit
    xi = (H/(kappa d)) tanh(kappa (c t' - xi)) T(4.20), solved for theta = kappa (c t' - xi)
    by Newton-Raphson T(4.21); stroke S = 2H/(kappa d) = sqrt(16 H d/3) T(4.23), duration
    tau = (2/(kappa c))(atanh(0.999) + H/d) T(4.24), optionally 10 % longer.

    kappa = sqrt(3H/(4 d^3)) T(4.3) and c = sqrt(g (d + H)) T(4.4).  Goring's time t' and
    position xi have their origin under the crest (t' in [-tau/2, tau/2]); here
    t' = t - delay - tau/2 and X(t) = xi(t') - xi(-tau/2), so the paddle rests at X = 0 until
    ``delay``, moves during [delay, delay + tau] and then rests at X = ``travel`` =
    2 xi(tau/2), slightly less than the stroke S (0.999 S for the plain duration).  Position
    is continuous; the velocity jumps from 0 to c eta/(d + eta) with eta ~ 0.002 H at both ends
    (inherent in Goring's truncation).  The wave's crest passes the paddle's mean position
    X = travel/2 at t = delay + tau/2."""

    name = "goring"
    doc = "Goring piston-paddle trajectory for a solitary wave, T(4.17)-(4.24)"

    class Coeffs(Coeffs):
        height: float = Field(gt=0, description="solitary wave height H (m)")
        depth: float = Field(gt=0, description="still water depth d (m)")
        extended: bool = Field(False, description="lengthen the duration tau by 10 % "
                               "(Goring's suggestion to reduce trailing waves)")
        delay: float = Field(0.0, ge=0, description="time (s) at which the paddle starts")
        g: float = Field(9.81, gt=0, description="gravitational acceleration (m/s^2)")

    def __init__(self, coeffs=None):
        super().__init__(coeffs)
        H, d, g = self.coeffs.height, self.coeffs.depth, self.coeffs.g
        self.eps = H / d
        self.kappa = math.sqrt(0.75 * H / d**3)                          # T(4.3)
        self.celerity = math.sqrt(g * (d + H))                           # T(4.4)
        self.amplitude = H / (self.kappa * d)                            # xi(+inf), T(4.20)
        self.stroke = 2.0 * self.amplitude                               # T(4.23)
        tau = 2.0 / (self.kappa * self.celerity) * (ATANH_0999 + self.eps)   # T(4.24)
        self.duration = 1.1 * tau if self.coeffs.extended else tau
        self._half = 0.5 * self.duration
        self._theta = 0.0                                                # Newton warm start
        self.xi0 = self._xi(self._solve(-self._half))                    # xi(-tau/2) < 0
        self.travel = -2.0 * self.xi0                                    # final X (odd xi)

    # --- T(4.19)-(4.21) ----------------------------------------------------------------------
    def solitary_wave(self) -> tuple[float, float]:
        return float(self.coeffs.height), float(self.coeffs.depth)

    def _solve(self, tp: float) -> float:
        """theta(t') solving theta + (H/d) tanh(theta) = kappa c t' by Newton T(4.21),
        warm-started from the previous solution, to |d theta| <= 1e-12 (then quadratically
        converged far below)."""
        e, b = self.eps, self.kappa * self.celerity * tp
        th = self._theta
        for _ in range(100):
            sech2 = 1.0 / math.cosh(th) ** 2 if abs(th) < 350.0 else 0.0
            step = (th + e * math.tanh(th) - b) / (1.0 + e * sech2)
            th -= step
            if abs(step) <= 1e-12:
                break
        self._theta = th
        return th

    def _xi(self, theta: float) -> float:
        return self.amplitude * math.tanh(theta)                        # T(4.20)

    def _tp(self, t):
        return t - self.coeffs.delay - self._half

    def _map(self, f, t):
        if np.ndim(t):
            return np.array([f(float(ti)) for ti in np.ravel(t)]).reshape(np.shape(t))
        return f(float(t))

    def position(self, t):
        """X(t) = xi(t') - xi(-tau/2) during the motion, 0 before, ``travel`` after."""
        return self._map(self._position, t)

    def velocity(self, t):
        """dX/dt = c eta/(d + eta), eta = H sech^2 theta, T(4.17), T(4.18), T(4.5); 0 outside
        the motion."""
        return self._map(self._velocity, t)

    def _position(self, t):
        tp = self._tp(t)
        if tp <= -self._half:
            return 0.0
        if tp >= self._half:
            return self.travel
        return self._xi(self._solve(tp)) - self.xi0

    def _velocity(self, t):
        tp = self._tp(t)
        if not -self._half < tp < self._half:
            return 0.0
        eta = self.coeffs.height / math.cosh(self._solve(tp)) ** 2      # T(4.18)
        return self.celerity * eta / (self.coeffs.depth + eta)          # T(4.5)

    def residual(self, t, X):
        """Residual of T(4.20), xi - (H/(kappa d)) tanh(kappa (c t' - xi)) with xi = X + xi0,
        for delay <= t <= delay + tau (vectorised)."""
        xi = np.asarray(X, float) + self.xi0
        tp = self._tp(np.asarray(t, float))
        return xi - self.amplitude * np.tanh(self.kappa * (self.celerity * tp - xi))
