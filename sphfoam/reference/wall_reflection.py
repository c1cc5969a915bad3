"""Fully nonlinear reflection of a solitary wave at a vertical wall: the reference run-up.

The wall's run-up of an inviscid, irrotational wave is that of the head-on collision of two
equal waves (the wall is the collision's plane of symmetry). Weakly nonlinear theory gives
R/d = 2a + a^2/2 + 3a^3/4 (Su & Mirie 1980, third order, a = A/d); this module computes the
potential flow itself, so that SPH is measured against the equations it discretises rather
than against a truncated expansion.

Method (up to a = 0.4): the higher-order spectral (HOS) method of West et al. (1987, JGR 92
C11, eqs. 4-11; Dommermuth & Yue 1987) in finite depth, units g = d = 1, on a periodic
domain holding the incident wave at x = -X0 and its mirror image at +X0 (eta even, psi
even). With
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

Above it, ``method="bie"`` (the default for a > 0.4) computes W exactly to the
discretisation by a boundary integral (Cauchy's formula for phi + i chi with the bed's
image, :mod:`sphfoam.reference.boundary_integral`; Vinje & Brevig 1981, Dold 1992, the
quadrature of Sidi & Israeli 1988) and steps Zakharov's equations in full, with only the
2/3 rule as filter (a dense solve for chi at x > 0 per stage; the wall makes the state
even). Where both converge they agree (N = 1024, dt = 0.05, decay 16):

    a      HOS (kmax 8)   BIE (kmax 8)   BIE (2/3 rule)
    0.1    0.2055528      0.2055528      0.2055528
    0.3    0.6602009      0.6601968      0.6602131      (HOS with kmax 16: 0.6602154)
    0.4    0.9234518      0.9230135      0.9237212      (HOS with kmax 16: 0.9222061)

(2e-5 relative at 0.3, 3e-4 at 0.4, where HOS itself moves by 1e-3 with kmax). At a = 0.5
the boundary integral gives R/d = 1.23839 (+-1e-5): 1.2383853 at N = 1024 (the default, dt =
0.05, start decay 16), 1.2383876 at N = 2048, 1.2383909 at dt = 0.025, 1.2383850 and
1.2383848 with the start at decay 20 and 24 (N scaled with L); the volume is conserved to
3e-16 (at a = 0.45, N = 1024: 1.07213, 0.24 % above the third order). It lies 1.6 % above Su
& Mirie's third order (1.21875): the run-up's crest is sharp, and a filter at kmax = 8/d
cuts it to 1.2274 (12/d: 1.2358, 16/d: 1.2376). The default call takes about 30 s on one
core. At a = 0.6 the crest at the wall steepens (slope 1.2, against 0.75 at a = 0.5) at its
peak and the computation blows up on 1024 points, so ``method="bie"`` stops at MAX_EPS_BIE =
0.5. :func:`propagate` with ``method="bie"`` carries the exact wave at a = 0.5 over 20
sqrt(d/g) with max |eta - exact| = 1.6e-6 d (N = 1024, dt = 0.05).

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

from sphfoam.reference.boundary_integral import DirichletToNeumann
from sphfoam.reference.eulerwave import euler_solution

#: largest A/d: the series converges to 1e-3 d at 0.4 (orders 8-12), to 2e-3 d only at 0.45,
#: and diverges at 0.5 as the run-up (1.2 d) nears the depth
MAX_EPS = 0.4

#: largest A/d of the boundary-integral method (``method="bie"``): converged there to 1e-5 d
#: (see the module docstring); at 0.6 the crest at the wall sharpens at its peak (slope > 1)
#: and the computation on 1024 points blows up (not established in between: the exact
#: wave's continuation fails at 0.55)
MAX_EPS_BIE = 0.5


@dataclass(frozen=True)
class Reflection:
    """The wall's run-up R/d of a wave of height a = A/d, its time, and the numerics."""
    eps: float
    run_up: float            # R/d, the maximum of eta at the wall
    time: float              # when (units sqrt(d/g)), from the start with the crest at -X0
    X0: float                # the crest's distance from the wall at t = 0 (units d)
    order: int               # the HOS order (0 for the boundary integral)
    N: int
    dt: float
    volume_drift: float      # |int eta dx (end) - int eta dx (start)| / int eta dx (start)
    method: str = "hos"      # "hos" or "bie"
    kmax: float = 8.0        # the filter's wavenumber (inf: 2/3 of the grid's only)


class _Zakharov:
    """The periodic domain [-L/2, L/2) with N points, the wall (or symmetry plane) at x = 0:
    the filter and the RK4 step of Zakharov's equations; ``rhs`` from the subclass."""

    def __init__(self, L: float, N: int, kmax: float):
        self.L, self.N = L, N
        self.x = (np.arange(N) - N // 2) * (L / N)
        self.k = k = 2.0 * math.pi * np.fft.rfftfreq(N, L / N)
        self.ik = 1j * k
        self.keep = k <= min(kmax, (2.0 / 3.0) * k[-1])

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


class _HOS(_Zakharov):
    """W by West et al.'s order-``order`` expansion about z = 0."""

    def __init__(self, L: float, N: int, order: int, kmax: float):
        super().__init__(L, N, kmax)
        self.M = order
        k = self.k
        self.th = np.tanh(k)
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


class _BIE(_Zakharov):
    """W exact to the discretisation, by the boundary integral of
    :mod:`sphfoam.reference.boundary_integral`; Zakharov's equations in full. ``even``: the
    state is even about x = 0 (the wall), and the integral equation is solved on x > 0."""

    def __init__(self, L: float, N: int, kmax: float, even: bool = False):
        super().__init__(L, N, kmax)
        self.dtn = DirichletToNeumann(L, N)
        self.even = even

    def rhs(self, eta, psi):
        ex = np.fft.irfft(np.fft.rfft(eta) * self.ik, self.N)
        px = np.fft.irfft(np.fft.rfft(psi) * self.ik, self.N)
        with np.errstate(over="ignore", invalid="ignore"):   # a blow-up is reported as one
            W = self.dtn.vertical_velocity(eta, psi, even=self.even, eta_x=ex, psi_x=px)
        s = 1.0 + ex * ex
        deta = -ex * px + s * W
        dpsi = -eta - 0.5 * px * px + 0.5 * s * W * W
        return self.filter(deta), self.filter(dpsi)


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
              decay: float = 16.0, kmax: float | None = None, method: str = "hos"):
    """One exact wave carried by Zakharov's equations for ``time``: returns (x, eta computed,
    eta exact at its new place). Their difference measures the method's error. psi steps by
    Delta across one wave, so the periodic domain carries it on a uniform current
    U = -Delta/L (psi + U x is periodic); the equations are Galilean invariant (W does not
    see U x), so the exact solution is the wave moving at F + U. ``method``: "hos" (West et
    al., order ``order``) or "bie" (the boundary integral); ``kmax`` as
    :func:`wall_reflection`."""
    sol, X0, L = _layout(eps, decay)
    hos = _solver(method, L, N, order, _kmax(method, kmax))
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


def _method(method: str | None, *eps: float) -> str:
    """The method asked for, or (None) HOS where it converges and the boundary integral above;
    refuses amplitudes outside the method's range."""
    if method is None:
        method = "hos" if max(eps) <= MAX_EPS else "bie"
    if method not in ("hos", "bie"):
        raise ValueError(f"method must be 'hos' or 'bie', got {method!r}")
    top = MAX_EPS if method == "hos" else MAX_EPS_BIE
    for e in eps:
        if not 0.0 < e <= top:
            why = ("the expansion about z = 0 diverges where the run-up nears the depth; "
                   f"method='bie' reaches {MAX_EPS_BIE}") if method == "hos" else (
                   "the crest at the wall sharpens towards a jet: at 0.6 the computation "
                   "blows up at the peak")
            raise ValueError(f"{method.upper()} needs 0 < A/d <= {top}, got {e:g} ({why})")
    return method


def _kmax(method: str, kmax: float | None) -> float:
    """The filter's default: 8/d for HOS (its round-off grows as |k|^M above), none but the
    2/3 rule for the boundary integral (a sharp run-up needs the modes above 8/d)."""
    if kmax is not None:
        return kmax
    return 8.0 if method == "hos" else math.inf


def _solver(method: str, L: float, N: int, order: int, kmax: float, even: bool = False):
    if method == "hos":
        return _HOS(L, N, order, kmax)
    if method == "bie":
        return _BIE(L, N, kmax, even=even)
    raise ValueError(f"method must be 'hos' or 'bie', got {method!r}")


def _collide(eps1, eps2, order, N, dt, decay, kmax, at_wall: bool, method: str = "hos"):
    """Wave eps1 from -X0 meets wave eps2 from +X0: (peak, its time, X0, volume drift). The
    peak is eta(0, t)'s (``at_wall``; equal waves) or the highest eta over x, each sample
    refined by a parabola, then in t. Unequal waves' potentials step by different amounts,
    so the periodic domain carries them on the uniform current U = -(Delta_1 - Delta_2)/L
    that makes psi periodic; the maximum elevation does not depend on the frame."""
    s1, s2 = euler_solution(eps1), euler_solution(eps2)
    X0 = decay / min(s1.kd, s2.kd)
    L = 4.0 * X0
    hos = _solver(method, L, N, order, kmax, even=at_wall and eps1 == eps2)
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
            raise RuntimeError(
                f"HOS collision of A/d = {eps1:g} and {eps2:g} (order {order}, kmax {kmax:g}) "
                "diverged: lower kmax or order" if method == "hos" else
                f"BIE collision of A/d = {eps1:g} and {eps2:g} (N = {N}) diverged: the crest "
                "sharpened beyond the grid (towards a jet or breaking)")
        top = max(history)
        if len(history) > 3 and history[-1] < history[-2] < history[-3] < top and \
                top > (2.0 if at_wall else 1.05) * max(eps1, eps2):   # past the peak
            break
    else:
        raise RuntimeError(f"{method.upper()} collision of A/d = {eps1:g} and {eps2:g}: no peak by "
                           f"t = {t_end:g}")
    h = np.asarray(history)
    i = int(np.argmax(h[1:-1])) + 1
    s, peak = _parabola_peak(h[i - 1], h[i], h[i + 1])
    return float(peak), float((i + s) * dt), float(X0), abs(float(eta.sum()) - vol0) / vol0


@functools.lru_cache(maxsize=16)
def wall_reflection(eps: float, order: int = 10, N: int = 1024, dt: float = 0.05,
                    decay: float = 16.0, kmax: float | None = None,
                    method: str | None = None) -> Reflection:
    """The maximum run-up of a solitary wave of height ``eps`` = A/d at a vertical wall, from
    the exact wave (see the module docstring): the wave meets its mirror image, and eta(0, t)
    is the wall's. ``method``: "hos" (West et al. 1987, order ``order``; A/d <= MAX_EPS),
    "bie" (W by the boundary integral; A/d <= MAX_EPS_BIE), or None: HOS up to MAX_EPS and
    the boundary integral above. ``decay``: the crest starts decay/kd from the wall (the
    wave's tail e^(-decay) there). ``kmax``: the filter, 8/d for HOS and none beyond the
    2/3 rule for the boundary integral by default."""
    method = _method(method, eps)
    kmax = _kmax(method, kmax)
    R, t, X0, drift = _collide(eps, eps, order, N, dt, decay, kmax, at_wall=True,
                               method=method)
    return Reflection(eps=eps, run_up=R, time=t, X0=X0, order=order if method == "hos" else 0,
                      N=N, dt=dt, volume_drift=drift, method=method, kmax=kmax)


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
    order: int               # the HOS order (0 for the boundary integral)
    N: int
    dt: float
    method: str = "hos"


@functools.lru_cache(maxsize=16)
def head_on_collision(eps1: float, eps2: float, order: int = 10, N: int | None = None,
                      dt: float = 0.05, decay: float = 16.0, kmax: float | None = None,
                      method: str | None = None) -> Collision:
    """The highest elevation reached when a wave of height ``eps1`` (moving right from -X0)
    meets one of ``eps2`` (moving left from +X0), by the method of :func:`wall_reflection`
    (equal waves: the wall's run-up). ``N``: 2048 for HOS and 1024 for the boundary
    integral by default (its dense solve, on the full domain here, costs N^3)."""
    method = _method(method, eps1, eps2)
    kmax = _kmax(method, kmax)
    if N is None:
        N = 2048 if method == "hos" else 1024
    peak, t, X0, _ = _collide(eps1, eps2, order, N, dt, decay, kmax, at_wall=False,
                              method=method)
    return Collision(eps1=eps1, eps2=eps2, peak=peak, time=t, X0=X0,
                     order=order if method == "hos" else 0, N=N, dt=dt, method=method)
