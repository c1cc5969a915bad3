"""Analytical channel flows between parallel walls at y = 0 and y = l (T §3.4.1, §3.5.1).

* Start-up Poiseuille flow, T(3.42) (Morris et al. 1997), driven by a body force F per unit
  mass from rest, steady state T(3.40), u_max = F l^2 / (8 nu), T(3.41)::

      u(y, t) = F/(2 nu) y (l - y)
                - sum_{n>=0} 4 F l^2 / (nu pi^3 (2n+1)^3) sin((2n+1) pi y / l)
                                                   exp(-(2n+1)^2 pi^2 nu t / l^2)

* Start-up Couette flow, T(3.46), the wall at y = l moving at u0 from t = 0, steady state
  T(3.45)::

      u(y, t) = u0 y / l + sum_{n>=1} 2 u0 / (n pi) (-1)^n sin(n pi y / l)
                                                 exp(-n^2 pi^2 nu t / l^2)

* The velocity-deficit (log) law of a turbulent channel (T §3.5.1, Fig 3.15).

:func:`poiseuille` and :func:`couette` converge to ``tol`` (1e-12 of the velocity scale by
default) at every t >= 0. For nu t / l^2 not too small they sum the series above with as
many terms as the truncation bound asks; for very small times, where the series would need
more than ``max_terms`` terms (it converges only like n^-2 (Poiseuille) or n^-1 (Couette)
at t = 0), they switch to the equivalent sum over images of the Stokes-layer solutions,
which converges fastest there. :func:`poiseuille_series` and :func:`couette_series` are the
plain partial sums with a given number of terms.

Pure numpy (and ``math.erfc`` for the images).
"""

from __future__ import annotations

import math

import numpy as np

#: von Karman constant of the log law
KAPPA = 0.41

_CHUNK = 4096


def _as_y(y) -> np.ndarray:
    return np.asarray(y, dtype=float)


# --- steady states -------------------------------------------------------------------------
def poiseuille_steady(y, F: float, nu: float, l: float) -> np.ndarray:
    """T(3.40): u(y) = F/(2 nu) y (l - y)."""
    y = _as_y(y)
    return F / (2.0 * nu) * y * (l - y)


def poiseuille_umax(F: float, nu: float, l: float) -> float:
    """T(3.41): u_max = F l^2 / (8 nu), on the centreline."""
    return F * l * l / (8.0 * nu)


def couette_steady(y, u0: float, l: float) -> np.ndarray:
    """T(3.45): u(y) = u0 y / l."""
    return u0 * _as_y(y) / l


# --- plain partial sums of the series --------------------------------------------------------
def _sine_series(y, l, k, coef, rate, t):
    """sum_j coef_j sin(k_j pi y / l) exp(-rate_j t), over the arrays k, coef, rate (chunked)."""
    y = _as_y(y)
    flat = y.reshape(-1)
    out = np.zeros(flat.shape)
    theta = np.pi * flat / l
    for s in range(0, k.size, _CHUNK):
        kk, cc, rr = k[s:s + _CHUNK], coef[s:s + _CHUNK], rate[s:s + _CHUNK]
        w = cc * np.exp(-rr * t)
        out += np.sin(np.outer(theta, kk)) @ w
    return out.reshape(y.shape)


def poiseuille_series(y, t: float, F: float, nu: float, l: float, nterms: int) -> np.ndarray:
    """T(3.42) with the terms n = 0 .. nterms-1 of the sum."""
    k = 2.0 * np.arange(int(nterms)) + 1.0
    coef = 4.0 * F * l * l / (nu * np.pi ** 3 * k ** 3)
    rate = k * k * np.pi ** 2 * nu / (l * l)
    return poiseuille_steady(y, F, nu, l) - _sine_series(y, l, k, coef, rate, t)


def couette_series(y, t: float, u0: float, nu: float, l: float, nterms: int) -> np.ndarray:
    """T(3.46) with the terms n = 1 .. nterms of the sum."""
    n = np.arange(1, int(nterms) + 1, dtype=float)
    coef = 2.0 * u0 / (n * np.pi) * np.where(n % 2 == 0, 1.0, -1.0)
    rate = n * n * np.pi ** 2 * nu / (l * l)
    return couette_steady(y, u0, l) + _sine_series(y, l, n, coef, rate, t)


# --- number of terms for a tolerance ------------------------------------------------------------
def _terms_needed(a: float, tol: float, power: int, kmax: int) -> int | None:
    """Smallest K such that the tail sum_{k>=K} k^-power exp(-a k^2) is below ``tol``
    (bounded by exp(-a K^2) (K^-power + K^(1-power)/(power-1)), or by exp(-a K^2)/(1 -
    exp(-a(2K+1))) K^-power for power = 1); None when that needs K > kmax."""

    def tail(K):
        e = math.exp(-a * K * K)
        if power > 1:
            return e * (K ** -power + K ** (1 - power) / (power - 1))
        return e / (K * -math.expm1(-a * (2 * K + 1))) if a > 0 else math.inf

    if tail(kmax) > tol:
        return None
    lo, hi = 1, kmax
    while lo < hi:
        mid = (lo + hi) // 2
        if tail(mid) > tol:
            lo = mid + 1
        else:
            hi = mid
    return lo


# --- converged solutions ------------------------------------------------------------------------
_erfc = np.vectorize(math.erfc, otypes=[float])


def _i2erfc(z):
    """Second repeated integral of erfc: ((1 + 2 z^2) erfc z - 2 z exp(-z^2)/sqrt(pi)) / 4."""
    return ((1.0 + 2.0 * z * z) * _erfc(z) - 2.0 * z * np.exp(-z * z) / math.sqrt(math.pi)) / 4.0


def _image_terms(s: float, spacing: float, tol: float) -> int:
    """Images m = 0 .. M-1 so that erfc(M spacing / s) is below tol (s = 2 sqrt(nu t))."""
    zmax = 1.0
    while math.erfc(zmax) > tol:
        zmax += 0.5
    return int(math.ceil(zmax * s / spacing)) + 2


def poiseuille(y, t: float, F: float, nu: float, l: float, *, tol: float = 1e-12,
               max_terms: int = 20000) -> np.ndarray:
    """Start-up Poiseuille flow T(3.42), converged to ``tol`` times u_max at every t >= 0."""
    y = _as_y(y)
    if t < 0:
        raise ValueError("t must be >= 0")
    umax = poiseuille_umax(F, nu, l)
    a = math.pi ** 2 * nu * t / (l * l)
    # series: the term of k = 2n+1 is (32/pi^3) u_max k^-3 exp(-a k^2); odd k only, so the
    # tail over all k >= K bounds it
    K = _terms_needed(a, tol * math.pi ** 3 / 32.0, 3, 2 * max_terms + 1) if a > 0 else None
    if K is not None:
        return poiseuille_series(y, t, F, nu, l, (K + 1) // 2 + 1)
    # images: u = F t - F t 4 sum_m (-1)^m [i2erfc((m l + y)/s) + i2erfc(((m+1) l - y)/s)]
    # (the wall value F t of u' = F t - u, carried into the slab by alternating images)
    if t == 0:
        return np.zeros(y.shape)
    s = 2.0 * math.sqrt(nu * t)
    M = _image_terms(s, l, tol * umax / max(F * t, 1e-300))
    acc = np.zeros(y.shape)
    for m in range(M):
        sign = 1.0 if m % 2 == 0 else -1.0
        acc += sign * (_i2erfc((m * l + y) / s) + _i2erfc(((m + 1) * l - y) / s))
    return F * t * (1.0 - 4.0 * acc)


def couette(y, t: float, u0: float, nu: float, l: float, *, tol: float = 1e-12,
            max_terms: int = 20000) -> np.ndarray:
    """Start-up Couette flow T(3.46), converged to ``tol`` times |u0| at every t >= 0."""
    y = _as_y(y)
    if t < 0:
        raise ValueError("t must be >= 0")
    a = math.pi ** 2 * nu * t / (l * l)
    # series: |term n| <= (2/pi) |u0| n^-1 exp(-a n^2)
    K = _terms_needed(a, tol * math.pi / 2.0, 1, max_terms) if a > 0 else None
    if K is not None:
        return couette_series(y, t, u0, nu, l, K + 1)
    # images: u = u0 sum_m [erfc((2 m l + eta)/s) - erfc((2 (m+1) l - eta)/s)], eta = l - y
    eta = l - y
    if t == 0:
        return np.where(eta <= 0.0, float(u0), 0.0) + 0.0 * y
    s = 2.0 * math.sqrt(nu * t)
    M = _image_terms(s, 2.0 * l, tol)
    acc = np.zeros(y.shape)
    for m in range(M):
        acc += _erfc((2 * m * l + eta) / s) - _erfc((2 * (m + 1) * l - eta) / s)
    return u0 * acc


# --- turbulent channel ------------------------------------------------------------------------
def friction_velocity(F: float, l: float) -> float:
    """u* = sqrt(tau_w / rho) = sqrt(F l / 2): the body force on half the channel is carried
    by the shear stress on one wall (steady state)."""
    return math.sqrt(abs(F) * l / 2.0)


def velocity_deficit(y, u_centre: float, u_star: float, l: float,
                     kappa: float = KAPPA) -> np.ndarray:
    """Velocity-deficit (log) law of a channel, T Fig 3.15:
    (u_c - u) / u* = -(1/kappa) ln(eta / y0), eta = distance to the nearer wall, y0 = l/2."""
    y = _as_y(y)
    eta = np.minimum(y, l - y)
    with np.errstate(divide="ignore"):
        return u_centre + u_star / kappa * np.log(np.maximum(eta, 0.0) / (0.5 * l))
