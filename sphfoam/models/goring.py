"""Goring's (1978) piston-paddle trajectory for a Boussinesq solitary wave, T(4.17)-(4.24)."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, field_validator
from scipy.optimize import brentq

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


@register
class MassFluxPaddle(WaveMaker):
    """A piston paddle for any solitary-wave theory, by default the exact wave: the paddle
    moves with the wave's depth-mean velocity, dX/dt = U = c eta(s)/(d + eta(s)), the mass
    flux of the wave over the local depth (Goring's T(4.17) with the theory's own eta and c
    in place of Boussinesq's T(4.5)).  With s = c t' - X the distance of the crest beyond the
    paddle, ds/dt' = c d/(d + eta(s)), which integrates to the explicit parametric trajectory
    X(s) = (1/d) int_0^s eta,   t'(s) = (s + X(s))/c,
    so the stroke is the wave's volume / d (about 1.79 d at H/d = 0.5 for the exact wave,
    against Goring's sqrt(16 H d/3) = 1.63 d).  The motion is cut, as Goring's T(4.24), where
    X reaches ``fraction`` of the half-stroke either side of the crest; the paddle rests at
    X = 0 until ``delay``, the crest passes its mean position at delay + duration/2, and it
    then rests at X = ``travel`` = fraction x stroke.  With ``theory boussinesq`` the
    trajectory is Goring's T(4.20) exactly."""

    name = "massFlux"
    doc = "piston paddle moving with a solitary wave's depth-mean velocity c eta/(d + eta) " \
          "(stroke = volume/d), default the exact wave; Goring T(4.17) generalised"

    class Coeffs(Coeffs):
        height: float = Field(gt=0, description="solitary wave height H (m)")
        depth: float = Field(gt=0, description="still water depth d (m)")
        theory: str = Field("euler", description=(
            "the wave theory whose eta and c drive the paddle (sphfoam models waveTheory)"))
        fraction: float = Field(0.999, gt=0.5, lt=1.0, description=(
            "the motion runs while X is within this fraction of the half-stroke either side "
            "of the crest (0.999 as Goring's T(4.24))"))
        delay: float = Field(0.0, ge=0, description="time (s) at which the paddle starts")
        g: float = Field(9.81, gt=0, description="gravitational acceleration (m/s^2)")

        @field_validator("theory")
        @classmethod
        def _theory(cls, v):
            import sphfoam.registry as registry

            if v not in registry.names("waveTheory"):
                raise ValueError(str(registry.UnknownModel("waveTheory", v,
                                                           registry.names("waveTheory"))))
            return v

    def __init__(self, coeffs=None):
        from scipy.integrate import cumulative_simpson
        from scipy.interpolate import CubicSpline

        import sphfoam.registry as registry

        super().__init__(coeffs)
        c = self.coeffs
        wave = registry.build("waveTheory", {"type": c.theory}).solitary(c.height, c.depth,
                                                                         g=c.g)
        self.wave, self.celerity = wave, wave.c
        L = 40.0 / wave.decay
        s = np.linspace(-L, L, 4001)
        eta = wave.eta(s)
        X = cumulative_simpson(eta, x=s, initial=0.0) / c.depth
        X -= np.interp(0.0, s, X)                                        # X(0) = 0 at the crest
        self.stroke = float(X[-1] - X[0])                                 # volume / d
        half = 0.5 * c.fraction * self.stroke
        tp = (s + X) / self.celerity                                      # t'(s)
        self._X_of_t = CubicSpline(tp, X)
        self._s_of_t = CubicSpline(tp, s)
        t_lo = brentq(lambda t: float(self._X_of_t(t)) + half, tp[0], 0.0, xtol=1e-14)
        t_hi = brentq(lambda t: float(self._X_of_t(t)) - half, 0.0, tp[-1], xtol=1e-14)
        self._t0, self.duration = t_lo, t_hi - t_lo
        self.x0 = float(self._X_of_t(t_lo))
        self.travel = float(self._X_of_t(t_hi)) - self.x0

    def solitary_wave(self) -> tuple[float, float]:
        return float(self.coeffs.height), float(self.coeffs.depth)

    def _tp(self, t):
        return np.asarray(t, float) - self.coeffs.delay + self._t0

    def position(self, t):
        """X(t): 0 before the motion, X(s(t')) - X(start) during it, ``travel`` after."""
        tp = self._tp(t)
        inside = (tp > self._t0) & (tp < self._t0 + self.duration)
        X = np.where(tp <= self._t0, 0.0, self.travel)
        X = np.where(inside, self._X_of_t(np.clip(tp, self._t0, self._t0 + self.duration))
                     - self.x0, X)
        return float(X) if np.ndim(t) == 0 else X

    def velocity(self, t):
        """dX/dt = c eta(s)/(d + eta(s)) during the motion, 0 outside."""
        tp = self._tp(t)
        inside = (tp > self._t0) & (tp < self._t0 + self.duration)
        s = self._s_of_t(np.clip(tp, self._t0, self._t0 + self.duration))
        eta = self.wave.eta(np.atleast_1d(s)).reshape(np.shape(s))
        U = np.where(inside, self.celerity * eta / (self.coeffs.depth + eta), 0.0)
        return float(U) if np.ndim(t) == 0 else U
