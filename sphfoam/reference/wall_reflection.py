"""Fully nonlinear reflection of a solitary wave at a vertical wall: the reference run-up.

The wall's run-up of an inviscid, irrotational wave is that of the head-on collision of two
equal waves (the wall is the collision's plane of symmetry). Weakly nonlinear theory gives
R/d = 2a + a^2/2 + 3a^3/4 (Su & Mirie 1980, third order, a = A/d); this module computes the
potential flow itself, so that SPH is measured against the equations it discretises rather
than against a truncated expansion.

Method: the higher-order spectral (HOS) method of West et al. (1987, JGR 92 C11, eqs. 4-11;
Dommermuth & Yue 1987) in finite depth, units g = d = 1, on a periodic domain holding the
incident wave at x = -X0 and its mirror image at +X0 (eta even, psi even). With
psi(x, t) = phi(x, eta, t) the surface potential and W = phi_z at the surface, Zakharov's
equations

    eta_t = -eta_x psi_x + (1 + eta_x^2) W,
    psi_t = -eta - psi_x^2 / 2 + (1 + eta_x^2) W^2 / 2,

are closed by expanding phi about z = 0 to order M: phi^(1) = psi,
phi^(m) = -sum_{k=1}^{m-1} eta^k/k! d_z^k phi^(m-k) (at z = 0), and
W_m = sum_{k=0}^{m-1} eta^k/k! d_z^(k+1) phi^(m-k), where d_z^k of a Fourier mode kappa is
|kappa|^k for even k and |kappa|^k tanh(|kappa|) for odd k (the bed at z = -1). The products
are truncated at order M as West et al.'s consistent scheme does: eta_x^2 W is kept to
order M, and W^2 as sum_{i+j<=M} W_i W_j. Fourth-order Runge-Kutta in time; each right-hand
side is filtered to wavenumbers below kmax (8/d by default, and at most 2/3 of the grid's):
the waves' spectra end below it, and round-off above it, multiplied by |kappa|^M, would grow.

Converged (orders 8, 10, 12; N, dt, kmax and the start halved or doubled) the run-up reads
R/d = 0.10133, 0.20555, 0.42413, 0.66020 and 0.9233 (+-0.001) at a = 0.05, 0.1, 0.2, 0.3 and
0.4: 0.02, 0.10, 0.44, 0.76 and 0.5 % below Su & Mirie's third order. The defaults (order 10,
modes up to kmax = 8/d) take a few seconds; above a = 0.4 the series stops converging.

:func:`head_on_collision` does the same for two unequal waves meeting head-on (P's collision
case, a = 0.3 and 0.2: a peak of 0.53771 d, against a1 + a2 = 0.5 and the third order's 0.54125).

The initial state is the exact (Euler) solitary wave of :mod:`sphfoam.reference.eulerwave`,
eta and psi = F x - c' alpha, so the incident wave is the steady wave of the same equations;
:func:`propagate` checks that it stays so. The run-up is the maximum of eta(0, t), located
by a parabola through the three samples around the largest.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from sphfoam.reference.eulerwave import euler_solution

#: largest A/d: the series converges to 1e-3 d at 0.4 (orders 8-12), to 2e-3 d only at 0.45,
#: and diverges at 0.5 as the run-up (1.2 d) nears the depth
MAX_EPS = 0.4


@dataclass(frozen=True)
class Reflection:
    """The wall's run-up R/d of a wave of height a = A/d, its time, and the numerics."""
    eps: float
    run_up: float            # R/d, the maximum of eta at the wall
    time: float              # when (units sqrt(d/g)), from the start with the crest at -X0
    X0: float                # the crest's distance from the wall at t = 0 (units d)
    order: int
    N: int
    dt: float
    volume_drift: float      # |int eta dx (end) - int eta dx (start)| / int eta dx (start)


class _HOS:
    """The periodic domain [-L/2, L/2) with N points, the wall (or symmetry plane) at x = 0."""

    def __init__(self, L: float, N: int, order: int, kmax: float):
        self.L, self.N, self.M = L, N, order
        self.x = (np.arange(N) - N // 2) * (L / N)
        k = 2.0 * math.pi * np.fft.rfftfreq(N, L / N)
        self.ik = 1j * k
        self.th = np.tanh(k)
        self.keep = k <= min(kmax, (2.0 / 3.0) * k[-1])
        # d_z^n at z = 0: |k|^n, times tanh(|k|) for odd n
        self.dz = [np.where(self.keep, k**n * (self.th if n % 2 else 1.0), 0.0)
                   for n in range(order + 1)]

    def _op(self, f_hat, n):
        return np.fft.irfft(f_hat * self.dz[n], self.N)

    def w_orders(self, eta, psi):
        """W_1 ... W_M, the vertical velocity at the surface order by order (West et al.)."""
        M = self.M
        powers = [np.ones_like(eta)]
        for k in range(1, M):
            powers.append(powers[-1] * eta / k)        # eta^k / k!
        phis_hat = [np.fft.rfft(psi)]                    # phi^(m) at z = 0, m = 1..M
        for m in range(2, M + 1):
            acc = np.zeros_like(eta)
            for k in range(1, m):
                acc -= powers[k] * self._op(phis_hat[m - k - 1], k)
            phis_hat.append(np.fft.rfft(acc))
        W = []
        for m in range(1, M + 1):
            acc = np.zeros_like(eta)
            for k in range(0, m):
                acc += powers[k] * self._op(phis_hat[m - k - 1], k + 1)
            W.append(acc)
        return W

    def rhs(self, eta, psi):
        M = self.M
        eh, ph = np.fft.rfft(eta), np.fft.rfft(psi)
        ex = np.fft.irfft(eh * self.ik, self.N)
        px = np.fft.irfft(ph * self.ik, self.N)
        W = self.w_orders(eta, psi)
        ex2 = ex * ex
        Wsum = np.sum(W, axis=0)
        Wlow = np.sum(W[: M - 2], axis=0) if M > 2 else 0.0
        W2 = np.zeros_like(eta)
        W2low = np.zeros_like(eta)
        for i in range(1, M):
            for j in range(1, M + 1 - i):
                prod = W[i - 1] * W[j - 1]
                W2 += prod
                if i + j <= M - 2:
                    W2low += prod
        deta = -ex * px + Wsum + ex2 * Wlow
        dpsi = -eta - 0.5 * px * px + 0.5 * W2 + 0.5 * ex2 * W2low
        return self.filter(deta), self.filter(dpsi)

    def filter(self, f):
        return np.fft.irfft(np.where(self.keep, np.fft.rfft(f), 0.0), self.N)

    def step(self, eta, psi, dt):
        k1 = self.rhs(eta, psi)
        k2 = self.rhs(eta + 0.5 * dt * k1[0], psi + 0.5 * dt * k1[1])
        k3 = self.rhs(eta + 0.5 * dt * k2[0], psi + 0.5 * dt * k2[1])
        k4 = self.rhs(eta + dt * k3[0], psi + dt * k3[1])
        eta = eta + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
        psi = psi + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        return eta, psi


def _wave(sol, x):
    """eta and psi of the exact wave with its crest at x = 0, on any x: the solved period's
    values inside it, the still level and the potential's end values +-(F - c') L/2 beyond."""
    inside = np.abs(x) < sol.x_half
    eta = np.zeros_like(x)
    psi = np.sign(x) * (sol.F - sol.cp) * sol.x_half
    eta[inside] = sol.surface(x[inside])
    psi[inside] = sol.surface_potential(x[inside])
    return eta, psi


def _layout(eps: float, decay: float):
    """X0 and L: the crest decay/kd from the wall, and decay/kd of tail behind it."""
    sol = euler_solution(eps)
    X0 = decay / sol.kd
    return sol, X0, 4.0 * X0


def propagate(eps: float, time: float, order: int = 10, N: int = 1024, dt: float = 0.05,
              decay: float = 16.0, kmax: float = 8.0):
    """One exact wave carried by the HOS equations for ``time``: returns (x, eta computed,
    eta exact at its new place). Their difference measures the method's error. psi steps by
    Delta across one wave, so the periodic domain carries it on a uniform current
    U = -Delta/L (psi + U x is periodic); the equations are Galilean invariant (W does not
    see U x), so the exact solution is the wave moving at F + U."""
    sol, X0, L = _layout(eps, decay)
    hos = _HOS(L, N, order, kmax)
    eta, psi = _wave(sol, hos.x)
    U = -_psi_step(sol) / L
    psi = psi + U * hos.x
    steps = max(1, round(time / dt))
    dt = time / steps
    for _ in range(steps):
        eta, psi = hos.step(eta, psi, dt)
    shifted = (hos.x - (sol.F + U) * time + 0.5 * L) % L - 0.5 * L
    return hos.x, eta, _wave(sol, shifted)[0]


def _psi_step(sol) -> float:
    """Delta, the step of psi across one exact wave: (F - c') L over its solved period."""
    return 2.0 * (sol.F - sol.cp) * sol.x_half


def _collide(eps1, eps2, order, N, dt, decay, kmax, at_wall: bool):
    """Wave eps1 from -X0 meets wave eps2 from +X0: (peak, its time, X0, volume drift). The
    peak is eta(0, t)'s (``at_wall``; equal waves) or the highest eta over x, each sample
    refined by a parabola, then in t. Unequal waves' potentials step by different amounts,
    so the periodic domain carries them on the uniform current U = -(Delta_1 - Delta_2)/L
    that makes psi periodic; the maximum elevation does not depend on the frame."""
    s1, s2 = euler_solution(eps1), euler_solution(eps2)
    X0 = decay / min(s1.kd, s2.kd)
    L = 4.0 * X0
    hos = _HOS(L, N, order, kmax)
    e1, p1 = _wave(s1, hos.x + X0)
    e2, p2 = _wave(s2, X0 - hos.x)
    eta, psi = e1 + e2, p1 + p2 - (_psi_step(s1) - _psi_step(s2)) / L * hos.x
    vol0 = float(eta.sum())
    wall = N // 2                                          # x = 0

    def sample(eta):
        if at_wall:
            return eta[wall]
        j = int(np.argmax(eta))
        return _parabola_peak(eta[j - 1], eta[j], eta[(j + 1) % N])[1]

    history = [sample(eta)]
    t_end = (1.6 if at_wall else 2.0) * X0 / min(s1.F, s2.F)
    for _ in range(int(math.ceil(t_end / dt))):
        eta, psi = hos.step(eta, psi, dt)
        history.append(sample(eta))
        if not math.isfinite(history[-1]):
            raise RuntimeError(f"HOS collision of A/d = {eps1:g} and {eps2:g} (order {order}, "
                               f"kmax {kmax:g}) diverged: lower kmax or order")
        top = max(history)
        if len(history) > 3 and history[-1] < history[-2] < history[-3] < top and \
                top > (2.0 if at_wall else 1.05) * max(eps1, eps2):   # past the peak
            break
    else:
        raise RuntimeError(f"HOS collision of A/d = {eps1:g} and {eps2:g}: no peak by "
                           f"t = {t_end:g}")
    h = np.asarray(history)
    i = int(np.argmax(h[1:-1])) + 1
    s, peak = _parabola_peak(h[i - 1], h[i], h[i + 1])
    return float(peak), float((i + s) * dt), float(X0), abs(float(eta.sum()) - vol0) / vol0


@functools.lru_cache(maxsize=16)
def wall_reflection(eps: float, order: int = 10, N: int = 1024, dt: float = 0.05,
                    decay: float = 16.0, kmax: float = 8.0) -> Reflection:
    """The maximum run-up of a solitary wave of height ``eps`` = A/d at a vertical wall, by
    the HOS method of West et al. (1987) from the exact wave (see the module docstring):
    the wave meets its mirror image, and eta(0, t) is the wall's.
    ``decay``: the crest starts decay/kd from the wall (the wave's tail e^(-decay) there)."""
    if not 0.0 < eps <= MAX_EPS:
        raise ValueError(f"wall_reflection needs 0 < A/d <= {MAX_EPS}, got {eps:g} (above it "
                         "the expansion about z = 0 diverges where the run-up nears the depth)")
    R, t, X0, drift = _collide(eps, eps, order, N, dt, decay, kmax, at_wall=True)
    return Reflection(eps=eps, run_up=R, time=t, X0=X0, order=order, N=N, dt=dt,
                      volume_drift=drift)


def su_mirie(eps: float) -> float:
    """Su & Mirie (1980), third order: R/d = 2a + a^2/2 + 3a^3/4."""
    return 2.0 * eps + 0.5 * eps**2 + 0.75 * eps**3


def _parabola_peak(a: float, b: float, c: float) -> tuple[float, float]:
    """(offset in samples, value) of the vertex of the parabola through three samples."""
    den = a - 2.0 * b + c
    s = 0.5 * (a - c) / den if den != 0.0 else 0.0
    return s, b - 0.25 * (a - c) * s


@dataclass(frozen=True)
class Collision:
    """The highest elevation of the head-on collision of two solitary waves a1, a2 (in d)."""
    eps1: float
    eps2: float
    peak: float              # max over x and t of eta / d
    time: float              # when (units sqrt(d/g)), from the crests at -X0 and +X0
    X0: float
    order: int
    N: int
    dt: float


@functools.lru_cache(maxsize=16)
def head_on_collision(eps1: float, eps2: float, order: int = 10, N: int = 2048,
                      dt: float = 0.05, decay: float = 16.0, kmax: float = 8.0) -> Collision:
    """The highest elevation reached when a wave of height ``eps1`` (moving right from -X0)
    meets one of ``eps2`` (moving left from +X0), by the HOS method as
    :func:`wall_reflection` (equal waves: the wall's run-up)."""
    for e in (eps1, eps2):
        if not 0.0 < e <= MAX_EPS:
            raise ValueError(f"head_on_collision needs 0 < A/d <= {MAX_EPS}, got {e:g}")
    peak, t, X0, _ = _collide(eps1, eps2, order, N, dt, decay, kmax, at_wall=False)
    return Collision(eps1=eps1, eps2=eps2, peak=peak, time=t, X0=X0, order=order, N=N, dt=dt)
