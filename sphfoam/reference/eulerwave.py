"""The fully nonlinear (Euler) solitary wave, computed once per A/d and cached (``euler``).

Steady irrotational flow in the frame of the wave, solved in the conformal strip
-d' <= beta <= 0 of zeta = alpha + i beta as in Clamond & Dutykh (2013, Comput. Fluids 84,
"Fast accurate computation of the fully nonlinear solitary surface gravity waves", §2): the
physical plane is z = x + i y = zeta + f(zeta) with the surface at beta = 0 (y = eta) and the
bed y = -d at beta = -d'.  Units g = d = 1, y from the still-water level.

* The surface elevation eta~(alpha) on a periodic grid of length L (so long that
  eta ~ exp(-k |x|) is below 1e-16 at its ends, F^2 = tan(k)/k) determines the map:
  x~(alpha) = alpha + C{eta~}, C with symbol -i coth(k d') (Clamond & Dutykh (2.6)), and
  d' = d + <eta~> keeps the bed at y = -d.
* The complex potential is W = -c' zeta (surface and bed are streamlines); the flux c' d' = c d
  of still water gives c' = c d/d'.
* Bernoulli at the surface, |dW/dz|^2 / 2 + g eta = c^2 / 2 (still water far away), reads
  (c^2 - 2 g eta~) (x~_alpha^2 + eta~_alpha^2) = c'^2 (Clamond & Dutykh (2.8), in the form
  before Babenko's rearrangement).  It is solved, with eta~(0) = A fixing the wave and
  eta~ even, by Newton's method (exact Jacobian by complex-step differentiation), with
  continuation in A/d for high waves.

Inside the fluid the point zeta of a physical (x, y) is found by Newton on z(zeta); then the
velocity in the wave frame is u - i w = -c' / z'(zeta), in the laboratory frame u + c, and the
pressure is Bernoulli's p/rho = c^2/2 - |u - c, w|^2/2 - g y.  The result is exact to the
solver tolerance (1e-13) and the spectral truncation, checked in tests by the Bernoulli and
kinematic conditions off the grid and against published celerities.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.optimize import brentq

#: largest A/d computed (the highest wave is A/d = 0.8332, Longuet-Higgins & Fenton 1974; the
#: crest then sharpens to 120 degrees and needs far more modes than here)
MAX_EPS = 0.78


def tail_decay(F2: float) -> float:
    """k d of the tails eta ~ exp(-k |x|): the root of F^2 = tan(k d)/(k d) in (0, pi/2)
    (the linearised dispersion relation at the celerity)."""
    if not F2 > 1.0:
        raise ValueError(f"F^2 = {F2} must exceed 1")
    return brentq(lambda k: math.tan(k) / k - F2, 1e-12, 0.5 * math.pi - 1e-12, xtol=1e-15)


def _guess_F2(eps: float) -> float:
    """Grimshaw's (1971) third-order c^2/(g d) = 1 + eps - eps^2/20 - 3 eps^3/70."""
    return 1.0 + eps - eps**2 / 20.0 - 3.0 * eps**3 / 70.0


class _Grid:
    """Periodic grid alpha_j = j L/N in FFT order (crest at j = 0), wavenumbers, symbols."""

    def __init__(self, L: float, N: int):
        self.L, self.N = L, N
        self.dalpha = L / N
        j = np.arange(N)
        self.alpha = np.where(j < N // 2, j, j - N) * self.dalpha
        self.k = 2.0 * np.pi * np.fft.fftfreq(N, d=self.dalpha)
        self.ik = 1j * self.k
        self.ik[N // 2] = 0.0                       # Nyquist mode: real-to-real derivative
        self.half = N // 2 + 1                      # unknowns eta(alpha_j), j = 0..N/2

    def full(self, v):
        """Even extension of the values at j = 0..N/2 (along axis 0)."""
        return np.concatenate([v, v[-2:0:-1]], axis=0)

    def kcoth(self, dp):
        """Symbol k coth(k d') of the operator K = d/dalpha C (0 at k = 0)."""
        k = self.k
        out = np.zeros(k.shape, dtype=np.result_type(dp, float))
        nz = k != 0
        out[nz] = k[nz] / np.tanh(k[nz] * dp)
        return out


def _apply(grid: _Grid, y, sym):
    """Real operator with Fourier symbol ``sym`` applied along axis 0."""
    Y = np.fft.fft(y, axis=0)
    return np.fft.ifft(Y * (sym if y.ndim == 1 else sym[:, None]), axis=0).real


def _residual(grid: _Grid, v, c, eps, jacobian=False):
    """Bernoulli residual (c^2 - 2 eta~)(x~_a^2 + eta~_a^2) - c'^2 at alpha_j, j = 0..N/2, and
    the height condition eta~(0) - A; with ``jacobian`` also its exact derivative with respect
    to (eta~_0..eta~_{N/2}, c), d' = 1 + <eta~> and c' = c/d' included."""
    y = grid.full(v)
    dp = 1.0 + y.mean()
    cp2 = (c / dp) ** 2
    Ky = _apply(grid, y, grid.kcoth(dp))
    Dy = _apply(grid, y, grid.ik)
    S = (1.0 + Ky) ** 2 + Dy**2
    B = c * c - 2.0 * y
    R = np.concatenate([(B * S - cp2)[: grid.half], [v[0] - eps]])
    if not jacobian:
        return R
    n = grid.half
    E = grid.full(np.eye(n))                                   # (N, n): d y / d v
    wts = E.mean(axis=0)                                       # d <eta~> / d v
    k = grid.k
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        dsym = np.where(k != 0, -k * k / np.sinh(k * dp) ** 2, 0.0)   # d/dd' of k coth(k d')
    dKy = _apply(grid, E, grid.kcoth(dp)) + _apply(grid, y, dsym)[:, None] * wts[None, :]
    dDy = _apply(grid, E, grid.ik)
    dS = 2.0 * (1.0 + Ky)[:, None] * dKy + 2.0 * Dy[:, None] * dDy
    Jv = -2.0 * E * S[:, None] + B[:, None] * dS + (2.0 * cp2 / dp) * wts[None, :]
    Jc = 2.0 * c * S - 2.0 * c / dp**2
    J = np.zeros((n + 1, n + 1))
    J[:n, :n] = Jv[:n]
    J[:n, n] = Jc[:n]
    J[n, 0] = 1.0
    return R, J


def _newton(grid: _Grid, v, c, eps, tol=1e-13, maxit=40):
    n = grid.half
    for _ in range(maxit):
        R, J = _residual(grid, v, c, eps, jacobian=True)
        step = np.linalg.solve(J, -R)
        v = v + step[:n]
        c = c + step[n]
        if np.max(np.abs(step)) < tol:
            return v, c, float(np.max(np.abs(_residual(grid, v, c, eps))))
    raise RuntimeError(f"exact solitary wave: Newton did not converge for A/d = {eps} "
                       f"(last step {np.max(np.abs(step)):.2e})")


class EulerSolution:
    """The solved wave in units g = d = 1: surface eta~(alpha) on the grid, celerity F, the
    conformal depth d', Fourier amplitudes a_m of eta~ = <eta~> + sum a_m cos(k_m alpha)."""

    def __init__(self, eps: float, N: int | None = None):
        if not 0.0 < eps <= MAX_EPS:
            raise ValueError(f"exact solitary wave needs 0 < A/d <= {MAX_EPS}, got {eps:g}")
        self.eps = eps
        F2 = _guess_F2(eps)
        kd = tail_decay(F2)
        if N is None:
            N = 512 if eps <= 0.3 else 1024 if eps <= 0.6 else 2048
        L = 2.0 * 40.0 / kd
        grid = _Grid(L, N)
        # continuation in A/d from the KdV profile (Newton alone is safe up to about 0.35),
        # the intermediate waves on a grid half as fine, then spectrally interpolated
        # (steps of 0.1 up to 0.6, then of 0.03: a jump of 0.15 from 0.6 fails at 0.75)
        steps = [] if eps <= 0.35 else [e for e in np.arange(0.3, 0.65, 0.1) if e < eps - 0.05]
        if eps > 0.65:
            steps += [e for e in np.arange(0.63, eps, 0.03) if e < eps - 0.01]
        coarse = _Grid(L, N // 2)
        kk = math.sqrt(0.75 * eps) * (1.0 - 0.625 * eps)
        v = (steps[0] if steps else eps) / np.cosh(kk * (coarse if steps else grid).alpha[
            : (coarse if steps else grid).half]) ** 2
        c = math.sqrt(_guess_F2(steps[0] if steps else eps))
        for e in steps:
            v, c, _ = _newton(coarse, v * (e / v[0]), c, e)
        if steps:                                    # zero-padded Fourier interpolation
            Y = np.fft.rfft(coarse.full(v))
            Y[-1] *= 0.5
            y = np.fft.irfft(np.concatenate([Y, np.zeros(N // 2 - N // 4)]), n=N) * 2.0
            v = y[: grid.half] * (eps / y[0])
        v, c, res = _newton(grid, v, c, eps)
        self.grid, self.v, self.F, self.residual = grid, v, float(c), res
        y = grid.full(v)
        self.mean = float(y.mean())
        self.dp = 1.0 + self.mean
        self.cp = self.F / self.dp
        Y = np.fft.rfft(y) / N
        a = 2.0 * Y.real[1:]
        a[-1] *= 0.5                                  # Nyquist mode counted once
        keep = np.flatnonzero(np.abs(a) > 1e-17)
        m = keep[-1] + 1 if keep.size else 1
        self.a = a[:m]
        self.km = grid.k[1:m + 1].copy()
        self.kd = tail_decay(self.F**2)
        ya = np.fft.ifft(np.fft.fft(y) * grid.ik).real
        Ky = np.fft.ifft(np.fft.fft(y) * grid.kcoth(self.dp)).real
        self.volume = float(np.sum(y * (1.0 + Ky)) * grid.dalpha)      # int eta dx
        self.x_half = 0.5 * L                                           # physical half-period
        self._ya = ya

    # --- the map and its inverse ------------------------------------------------------------
    def z_of(self, zeta):
        """z(zeta) = zeta + i <eta~> + sum a_m sin(k_m w)/sinh(k_m d') and dz/dzeta, w = zeta +
        i d', with sin(k_m w)/sinh(k_m d') = i r^m (1 - q^2m)/(1 - e^(-2 k_m d')) and k_m
        cos(k_m w)/sinh(k_m d') = k_m r^m (1 + q^2m)/(1 - e^(-2 k_m d')), r = e^(-i dk zeta),
        q = e^(i dk w): |r|, |q| <= 1 in the fluid (no overflow), powers by cumulative products
        (k_m = m dk)."""
        dk = self.km[0]
        m = self.km.size
        R = np.cumprod(np.broadcast_to(np.exp(-1j * dk * zeta)[:, None], (zeta.size, m)), axis=1)
        RQ = R * np.cumprod(np.broadcast_to(np.exp(2j * dk * (zeta + 1j * self.dp))[:, None],
                                            (zeta.size, m)), axis=1)
        c1, c2 = self._c12
        # elementwise sums, not BLAS: its threads contend on a loaded machine
        z = zeta + 1j * self.mean + 1j * ((R - RQ) * c1).sum(axis=1)
        dz = 1.0 + ((R + RQ) * c2).sum(axis=1)
        return z, dz

    @functools.cached_property
    def _c12(self):
        den = 1.0 - np.exp(-2.0 * self.km * self.dp)
        return (self.a / den).astype(complex), (self.a * self.km / den).astype(complex)

    def zeta_of(self, x, y):
        """zeta with z(zeta) = x + i y for |x| < L/2, by Newton from the surface guess."""
        xt, yt = self._table
        alpha0 = np.interp(x, xt, self._alpha_sorted)
        eta0 = np.interp(x, xt, yt)
        beta0 = (y + 1.0) / (1.0 + eta0) * self.dp - self.dp
        zeta = alpha0 + 1j * beta0
        target = x + 1j * y
        for _ in range(50):
            z, dz = self.z_of(zeta)
            step = (z - target) / dz
            zeta = zeta - step
            if np.max(np.abs(step), initial=0.0) < 1e-14:
                break
        return zeta

    def surface_alpha(self, x):
        """alpha of the surface point at physical |x| < L/2: Newton on x~(alpha) = x, with
        x~ = alpha + sum a_m coth(k_m d') sin(k_m alpha)."""
        x = np.asarray(x, float)
        xt, _ = self._table
        al = np.interp(x, xt, self._alpha_sorted)
        k, ac = self.km[None, :], (self.a / np.tanh(self.km * self.dp))
        for _ in range(50):
            s, c = np.sin(k * al[:, None]), np.cos(k * al[:, None])
            step = (al + (s * ac).sum(axis=1) - x) / (1.0 + (c * (ac * self.km)).sum(axis=1))
            al = al - step
            if np.max(np.abs(step), initial=0.0) < 1e-14:
                break
        return al

    def surface(self, x):
        """eta at physical |x| < L/2 (units of d): eta~ = <eta~> + sum a_m cos(k_m alpha) at
        the alpha of :meth:`surface_alpha`."""
        al = self.surface_alpha(x)
        return self.mean + (np.cos(self.km[None, :] * al[:, None]) * self.a).sum(axis=1)

    def surface_potential(self, x):
        """The laboratory-frame velocity potential on the surface, psi(x) = phi(x, eta(x)), at
        physical |x| < L/2 (units d sqrt(g d)): W = -c' zeta in the wave frame is -c' alpha on
        the surface, and phi = phi_wave + F x, so psi = F x - c' alpha; zero under the crest,
        odd in x, tending to +-(F - c') L/2 (its step across the wave) at the grid's ends."""
        x = np.asarray(x, float)
        return self.F * x - self.cp * self.surface_alpha(x)

    @functools.cached_property
    def _table(self):
        y = self.grid.full(self.v)
        k = self.grid.k
        with np.errstate(divide="ignore"):
            sym = np.where(k != 0, -1j / np.tanh(np.where(k == 0, 1.0, k * self.dp)), 0.0)
        xt = self.grid.alpha + np.fft.ifft(np.fft.fft(y) * sym).real
        o = np.argsort(xt)
        self._alpha_sorted = self.grid.alpha[o]
        return xt[o], y[o]

    def fields(self, x, y):
        """(u, w, p) in units sqrt(g d), rho g d at physical points, laboratory frame."""
        zeta = self.zeta_of(x, y)
        _, dz = self.z_of(zeta)
        V = -self.cp / dz                              # u - i w in the wave frame
        u = self.F + V.real
        w = -V.imag
        p = 0.5 * self.F**2 - 0.5 * np.abs(V) ** 2 - y
        return u, w, p


@functools.lru_cache(maxsize=32)
def euler_solution(eps: float) -> EulerSolution:
    """The cached exact solitary wave of height eps = A/d (units g = d = 1)."""
    return EulerSolution(float(eps))
