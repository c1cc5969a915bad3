"""Solitary-wave theories: surface, velocity, pressure, celerity (the solution code; the
``waveTheory`` family that selects them is :mod:`sphfoam.models.wavetheory`).

Conventions shared by every theory: wave height ``A`` (crest elevation above still water) in
depth ``d``; x horizontal, the wave travelling in +x with its crest at x = x0 + c t; z measured
up from the bed (z = 0 bed, z = d still-water level); X = x - x0 - c t.  Thesis equations are
T(4.x), those of the corrected-SPH paper P(n) (there the depth is called H and the height A).
The thesis writes sqrt(g h) in T(4.7), T(4.15), T(4.16); h is the depth d.  Its McCowan and
Laitone velocities T(4.8), T(4.9), T(4.15) only make sense with z measured from the bed
(w = 0 at the bed, the surface streamline is T(4.6), and T(4.15) equals P(13)), although the
text says "from the still water level"; they are implemented with z from the bed.
"""

from __future__ import annotations

import abc

import math

import numpy as np
from scipy.optimize import brentq



def _sech(y):
    """sech(y) without overflow warnings (sech(700) is 0 to double precision anyway)."""
    return 1.0 / np.cosh(np.minimum(np.abs(y), 700.0))


class SolitaryWave(abc.ABC):
    """A solitary wave of height ``A`` in depth ``d``; subclasses give ``_eta(X)``,
    ``_u(X, z)``, ``_w(X, z)`` and, when the theory has one, ``_p(X, z)``.  Without an explicit
    dynamic pressure the pressure is hydrostatic below the local surface,
    p = rho g (d + eta - z).  The fields are meant for 0 <= z <= d + eta."""

    theory = "solitary"

    def __init__(self, A: float, d: float, g: float = 9.81, rho: float = 1000.0):
        if not (A > 0 and d > 0 and g > 0 and rho > 0):
            raise ValueError(f"need A > 0, d > 0, g > 0, rho > 0 (got A={A}, d={d}, g={g}, "
                             f"rho={rho})")
        self.A, self.d, self.g, self.rho = float(A), float(d), float(g), float(rho)
        self.eps = self.A / self.d
        self.c = self._celerity()

    # --- to be provided by a theory ----------------------------------------------------------
    #: spatial decay rate (1/m) of eta far from the crest, eta ~ exp(-decay |X|)
    decay: float

    @abc.abstractmethod
    def _celerity(self) -> float:
        ...

    @abc.abstractmethod
    def _eta(self, X):
        ...

    @abc.abstractmethod
    def _u(self, X, z):
        ...

    @abc.abstractmethod
    def _w(self, X, z):
        ...

    def _p(self, X, z):
        return self.rho * self.g * (self.d + self._eta(X) - z)

    # --- public, vectorised ------------------------------------------------------------------
    def _X(self, x, t, x0):
        return np.asarray(x, dtype=float) - x0 - self.c * t

    def _Xz(self, x, z, t, x0):
        return np.broadcast_arrays(self._X(x, t, x0), np.asarray(z, dtype=float))

    def eta(self, x, t=0.0, x0=0.0):
        """Free-surface elevation above still water (m)."""
        return self._eta(self._X(x, t, x0))

    def u(self, x, z, t=0.0, x0=0.0):
        """Horizontal velocity (m/s)."""
        return self._u(*self._Xz(x, z, t, x0))

    def w(self, x, z, t=0.0, x0=0.0):
        """Vertical velocity (m/s), positive up."""
        return self._w(*self._Xz(x, z, t, x0))

    def p(self, x, z, t=0.0, x0=0.0):
        """Gauge pressure (Pa)."""
        return self._p(*self._Xz(x, z, t, x0))

    def volume(self, n: int = 20001) -> float:
        """Excess volume per unit width, the integral of eta over x (m^2), by the trapezoidal
        rule on [-L, L] with exp(-decay L) = 4e-18 (spectrally accurate for these profiles)."""
        L = 40.0 / self.decay
        x = np.linspace(-L, L, n)
        return float(np.sum(self.eta(x)) * (x[1] - x[0]))

    def __repr__(self) -> str:
        return f"{type(self).__name__}(A={self.A}, d={self.d}, g={self.g}, c={self.c:.6g})"


class BoussinesqWave(SolitaryWave):
    """T(4.1)-(4.5); w = -z du/dx from continuity (Boussinesq gives none), which makes the
    field satisfy continuity and the kinematic surface condition exactly."""

    theory = "boussinesq"

    def __init__(self, A, d, g=9.81, rho=1000.0):
        super().__init__(A, d, g, rho)
        self.kappa = math.sqrt(0.75 * self.A / self.d**3)        # T(4.3)
        self.decay = 2.0 * self.kappa

    def _celerity(self):
        return math.sqrt(self.g * (self.d + self.A))              # T(4.4)

    def _eta(self, X):
        return self.A * _sech(self.kappa * X) ** 2                 # T(4.1), T(4.2)

    def _u(self, X, z):
        eta = self._eta(X)
        return self.c * eta / (self.d + eta) + 0.0 * z             # T(4.5), depth-uniform

    def _w(self, X, z):
        eta = self._eta(X)
        eta_x = -2.0 * self.kappa * eta * np.tanh(self.kappa * X)
        return -z * self.c * self.d * eta_x / (self.d + eta) ** 2  # -z du/dx


class KdV1Wave(SolitaryWave):
    """P(6)-(11), first-order KdV solitary wave (Wehausen & Laitone 1960), z from the bed."""

    theory = "kdv1"

    def __init__(self, A, d, g=9.81, rho=1000.0):
        super().__init__(A, d, g, rho)
        self.alpha = math.sqrt(0.75 * self.eps)                    # P(10): zeta = alpha X/d
        self.decay = 2.0 * self.alpha / self.d

    def _celerity(self):
        return math.sqrt(self.g * self.d) * (1.0 + 0.5 * self.eps)     # P(11)

    def _eta(self, X):
        return self.A * _sech(self.alpha * X / self.d) ** 2           # P(6)

    def _u(self, X, z):
        return math.sqrt(self.g * self.d) * self._eta(X) / self.d + 0.0 * z   # P(7)

    def _w(self, X, z):
        zeta = self.alpha * X / self.d
        return (math.sqrt(self.g * self.d) * math.sqrt(3.0) * (z / self.d) * self.eps**1.5
                * _sech(zeta) ** 2 * np.tanh(zeta))                 # P(8)

    def _p(self, X, z):
        return self.rho * self.g * (self.d + self._eta(X) - z)     # P(9), hydrostatic


class _SecondOrder(SolitaryWave):
    """Profile and celerity shared by Laitone T(4.12)-(4.14) and KdV2 P(12), (16), (17)."""

    def __init__(self, A, d, g=9.81, rho=1000.0):
        super().__init__(A, d, g, rho)
        e = self.eps
        self.alpha = math.sqrt(0.75 * e) * (1.0 - 0.625 * e)       # T(4.13), P(16)
        self.decay = 2.0 * self.alpha / self.d

    def _celerity(self):
        e = self.eps
        return math.sqrt(self.g * self.d) * (1.0 + 0.5 * e - 0.15 * e * e)   # T(4.14), P(17)

    def _s2(self, X):
        return _sech(self.alpha * X / self.d) ** 2

    def _eta(self, X):
        s2 = self._s2(X)
        return self.A * s2 * (1.0 - 0.75 * self.eps * (1.0 - s2))  # T(4.12), P(12)

    def _u(self, X, z):
        e, Z, s2 = self.eps, z / self.d, self._s2(X)
        return math.sqrt(self.g * self.d) * (                      # T(4.15) == P(13)
            e * (1.0 + e * (0.25 - 1.5 * Z * Z)) * s2 + e * e * (2.25 * Z * Z - 1.0) * s2 * s2)


class LaitoneWave(_SecondOrder):
    """T(4.12)-(4.16): w = -sqrt(g d) (z/d) d(eta)/dX, hydrostatic pressure (none given)."""

    theory = "laitone"

    def _w(self, X, z):
        e, zeta = self.eps, self.alpha * X / self.d
        s2, th = _sech(zeta) ** 2, np.tanh(zeta)
        deta_dX = (-2.0 * self.A * self.alpha / self.d * s2 * th
                   * (1.0 - 0.75 * e * (1.0 - 2.0 * s2)))
        return -math.sqrt(self.g * self.d) * (z / self.d) * deta_dX   # T(4.16)


class KdV2Wave(_SecondOrder):
    """P(12)-(17), second-order KdV solitary wave with its dynamic pressure P(15)."""

    theory = "kdv2"

    def _w(self, X, z):
        e, Z, zeta = self.eps, z / self.d, self.alpha * X / self.d
        s2, th, Y = _sech(zeta) ** 2, np.tanh(zeta), Z - 1.0
        return (math.sqrt(self.g * self.d) * math.sqrt(3.0) * Z * e**1.5 * s2 * th   # P(14)
                * (1.0 + e * (0.125 - Z - 0.5 * Y * Y)
                   - 0.5 * e * (1.0 - 6.0 * Y - 3.0 * Y * Y) * s2))

    def _p(self, X, z):
        e, Z, s2 = self.eps, z / self.d, self._s2(X)
        return self.rho * self.g * (self.d + self._eta(X) - z                    # P(15)
                                    - 0.75 * e * e * self.d * (Z * Z - 1.0)
                                    * (2.0 * s2 - 3.0 * s2 * s2))


class McCowanWave(SolitaryWave):
    """T(4.6)-(4.11) (McCowan 1891 as in Munk 1949), z from the bed; M, N solve T(4.10)-(4.11);
    eta solves the implicit T(4.6) by safeguarded Newton; hydrostatic pressure (none given)."""

    theory = "mcCowan"

    def __init__(self, A, d, g=9.81, rho=1000.0):
        e = A / d if d > 0 else float("nan")
        self.M, self.N = mccowan_MN(e) if A > 0 and d > 0 else (float("nan"),) * 2
        super().__init__(A, d, g, rho)
        self.decay = self.M / self.d

    def _celerity(self):
        return math.sqrt(self.g * self.d * math.tan(self.M) / self.M)   # T(4.7)

    def _eta(self, X):
        M, N = self.M, self.N
        C = np.cosh(np.minimum(np.abs(M * np.asarray(X, float) / self.d), 300.0))
        lo, hi = np.ones_like(C), np.full_like(C, 1.0 + self.eps)   # Y = 1 + eta/d in [1, 1+A/d]
        Y = hi.copy()
        for _ in range(100):
            sn, cs = np.sin(M * Y), np.cos(M * Y)
            F = Y - 1.0 - N / M * sn / (cs + C)                      # T(4.6)
            lo = np.where(F < 0, Y, lo)
            hi = np.where(F > 0, Y, hi)
            dF = 1.0 - N * (1.0 + C * cs) / (cs + C) ** 2            # = 1 - u/c at the surface
            Yn = Y - F / dF
            out = (Yn < lo) | (Yn > hi) | ~np.isfinite(Yn)
            Yn = np.where(out, 0.5 * (lo + hi), Yn)
            done = np.all(np.abs(Yn - Y) <= 1e-14)
            Y = Yn
            if done:
                break
        return self.d * (Y - 1.0)

    def _uw(self, X, z):
        a = np.minimum(np.abs(self.M * X / self.d), 300.0)
        ch, sh = np.cosh(a), np.sign(X) * np.sinh(a)
        cs, sn = np.cos(self.M * z / self.d), np.sin(self.M * z / self.d)
        den = (cs + ch) ** 2
        return (self.c * self.N * (1.0 + cs * ch) / den,              # T(4.8)
                self.c * self.N * sn * sh / den)                      # T(4.9)

    def _u(self, X, z):
        return self._uw(X, z)[0]

    def _w(self, X, z):
        return self._uw(X, z)[1]


def mccowan_residuals(M: float, N: float, eps: float) -> tuple[float, float]:
    """Residuals of T(4.10) N = 2/3 sin^2(M (1 + 2 eps/3)) and T(4.11)
    eps = (N/M) tan(M (1 + eps)/2), eps = A/d."""
    return (N - 2.0 / 3.0 * math.sin(M * (1.0 + 2.0 * eps / 3.0)) ** 2,
            N / M * math.tan(0.5 * M * (1.0 + eps)) - eps)


def mccowan_MN(eps: float) -> tuple[float, float]:
    """M and N of McCowan's wave for eps = A/d: the smallest root M in (0, pi/(1+eps)) of
    T(4.11) with N from T(4.10), by brentq to machine precision."""
    if not eps > 0:
        raise ValueError(f"A/d must be positive, got {eps}")

    def f(M):
        return mccowan_residuals(M, 2.0 / 3.0 * math.sin(M * (1.0 + 2.0 * eps / 3.0)) ** 2, eps)[1]

    Mmax = math.pi / (1.0 + eps)
    grid = np.linspace(0.0, Mmax, 2001)[1:-1]
    vals = np.array([f(m) for m in grid])
    k = np.flatnonzero((vals[:-1] < 0) & (vals[1:] >= 0))
    if k.size == 0:
        raise ValueError(f"no McCowan solution for A/d = {eps}")
    M = brentq(f, grid[k[0]], grid[k[0] + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps,
               maxiter=200)
    return M, 2.0 / 3.0 * math.sin(M * (1.0 + 2.0 * eps / 3.0)) ** 2


def _table(coeffs, eps, dims):
    """sum_i c_(i, ...) eps^i as an array indexed by the remaining keys (S and Y powers)."""
    from fractions import Fraction

    out = np.zeros(dims)
    for key, v in coeffs.items():
        out[key[1:]] += float(Fraction(v)) * eps ** key[0]
    return out


class FentonWave(SolitaryWave):
    """Fenton's (1972) ninth-order solitary wave: eta, u, w, p as polynomials in
    S = sech^2(alpha x/d) and z/d with the coefficients of :mod:`fenton_coeffs`, alpha and c as
    series in eps = A/d, z from the bed; the pressure is Bernoulli's truncated at eps^9."""

    theory = "fenton"

    def __init__(self, A, d, g=9.81, rho=1000.0):
        from fractions import Fraction

        from sphfoam.reference import fenton_coeffs as fc

        e = A / d if d > 0 else float("nan")
        self.alpha = (math.sqrt(0.75 * e) * sum(float(Fraction(a)) * e**i
                                               for i, a in enumerate(fc.ALPHA))
                      if A > 0 and d > 0 else float("nan"))
        self._F = sum(float(Fraction(c)) * e**i for i, c in enumerate(fc.C)) if e > 0 else 1.0
        n = fc.ORDER + 2
        self._eta_c = _table(fc.ETA, e, (n,)) if e > 0 else None
        self._u_c = _table(fc.U, e, (n, 2 * n)) if e > 0 else None
        self._w_c = _table(fc.W, e, (n, 2 * n)) if e > 0 else None
        self._p_c = _table(fc.P, e, (n, 2 * n)) if e > 0 else None
        super().__init__(A, d, g, rho)
        self.decay = 2.0 * self.alpha / self.d

    def _celerity(self):
        return self._F * math.sqrt(self.g * self.d)

    def _S(self, X):
        return _sech(self.alpha * np.asarray(X, float) / self.d) ** 2

    def _eta(self, X):
        return self.d * np.polynomial.polynomial.polyval(self._S(X), self._eta_c)

    def _u(self, X, z):
        return math.sqrt(self.g * self.d) * np.polynomial.polynomial.polyval2d(
            self._S(X), z / self.d, self._u_c)

    def _w(self, X, z):
        T = np.tanh(self.alpha * X / self.d)
        return math.sqrt(self.g * self.d) * self.alpha * T * np.polynomial.polynomial.polyval2d(
            self._S(X), z / self.d, self._w_c)

    def _p(self, X, z):
        Y = z / self.d
        return self.rho * self.g * self.d * (1.0 - Y + np.polynomial.polynomial.polyval2d(
            self._S(X), Y, self._p_c))


class EulerWave(SolitaryWave):
    """The exact (fully nonlinear, irrotational) solitary wave of :mod:`eulerwave`, solved once
    per A/d and cached; eta, u, w and the Bernoulli pressure from the conformal map, z from
    the bed.  Beyond the solved period (|X| > 40 decay lengths) the water is at rest."""

    theory = "euler"
    _CHUNK = 400

    def __init__(self, A, d, g=9.81, rho=1000.0):
        from sphfoam.reference.eulerwave import euler_solution

        if A > 0 and d > 0:
            self.sol = euler_solution(A / d)
        super().__init__(A, d, g, rho)
        self.decay = self.sol.kd / self.d

    def _celerity(self):
        return self.sol.F * math.sqrt(self.g * self.d)

    def _inside(self, X):
        Xd = np.atleast_1d(np.asarray(X, float)) / self.d
        return Xd, np.abs(Xd) < self.sol.x_half

    def _eta(self, X):
        Xd, inside = self._inside(X)
        out = np.zeros(Xd.shape)
        flat, idx = Xd.ravel(), np.flatnonzero(inside.ravel())
        res = out.ravel()
        for k in range(0, idx.size, 4 * self._CHUNK):
            j = idx[k:k + 4 * self._CHUNK]
            res[j] = self.sol.surface(flat[j])
        out = res.reshape(Xd.shape) * self.d
        return out if np.ndim(X) else float(out[0])

    def _fields(self, X, z):
        """(u, w, p) at (X, z), the last call's kept (``fields`` asks for all three)."""
        X, z = np.broadcast_arrays(np.asarray(X, float), np.asarray(z, float))
        last = getattr(self, "_last", None)
        if last is not None and last[0].shape == X.shape and np.array_equal(last[0], X) \
                and np.array_equal(last[1], z):
            return last[2]
        out = self._fields_new(X, z)
        self._last = (X.copy(), z.copy(), out)
        return out

    def _fields_new(self, X, z):
        Xd, inside = self._inside(X)
        zd = np.atleast_1d(z) / self.d - 1.0                     # y from still water
        u = np.zeros(Xd.size)
        w = np.zeros(Xd.size)
        p = -zd.ravel().copy()                                    # hydrostatic at rest
        idx = np.flatnonzero(inside.ravel())
        for k in range(0, idx.size, self._CHUNK):
            j = idx[k:k + self._CHUNK]
            u[j], w[j], p[j] = self.sol.fields(Xd.ravel()[j], zd.ravel()[j])
        sq = math.sqrt(self.g * self.d)
        shape = np.shape(X)
        return (u.reshape(shape) * sq, w.reshape(shape) * sq,
                p.reshape(shape) * self.rho * self.g * self.d)

    def _u(self, X, z):
        return self._fields(X, z)[0]

    def _w(self, X, z):
        return self._fields(X, z)[1]

    def _p(self, X, z):
        return self._fields(X, z)[2]

    def volume(self, n: int = 0) -> float:
        """Excess volume per unit width (m^2), spectrally from the solved surface."""
        return self.sol.volume * self.d**2
