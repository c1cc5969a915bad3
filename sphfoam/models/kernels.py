"""Smoothing kernels, W(r, h) = alpha_d / h^d * f(q), q = |r| / h, in d = 2 or 3 dimensions.

Each kernel provides ``f(q)`` and ``df/dq / q`` as jitted functions (the second is finite at
q = 0 for all of them, so grad W = alpha_d / h^(d+2) * (df/dq / q) * r_ab needs no division
by r), and its normalisation in each dimension, T(3.4): alpha_2 = 1 / (2 pi int_0^kappa f q dq),
alpha_3 = 1 / (4 pi int_0^kappa f q^2 dq).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from pydantic import Field

from sphfoam.engine.fastmath import FASTMATH
from sphfoam.engine.terms import LOOP_STAGES, Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register

_JIT = dict(cache=True, fastmath=set(FASTMATH), inline="always")


# --- cubic spline, Monaghan & Lattanzio (1985), T(3.5), alpha_2 = 15 / (7 pi) -------------
# (f(0) = 2/3: alpha_3 = 3 / (2 pi), the 1 / pi of the form with f(0) = 1)
@njit(**_JIT)
def cubic_spline_f(q):
    t2 = max(2.0 - q, 0.0)
    t1 = max(1.0 - q, 0.0)
    return (t2 * t2 * t2 - 4.0 * t1 * t1 * t1) / 6.0


@njit(**_JIT)
def cubic_spline_dfdq_q(q):
    if q < 1.0:
        return -2.0 + 1.5 * q
    t2 = max(2.0 - q, 0.0)
    return -0.5 * t2 * t2 / q


# --- quintic spline, Morris et al. (1997), T(3.6), alpha_2 = 7 / (478 pi), alpha_3 = 1 / (120 pi)
@njit(**_JIT)
def quintic_f(q):
    t3 = max(3.0 - q, 0.0)
    t2 = max(2.0 - q, 0.0)
    t1 = max(1.0 - q, 0.0)
    return t3**5 - 6.0 * t2**5 + 15.0 * t1**5


@njit(**_JIT)
def quintic_dfdq_q(q):
    if q < 1.0:
        # -5(3-q)^4 + 30(2-q)^4 - 75(1-q)^4 = q (-120 + 120 q^2 - 50 q^3) ... expanded exactly:
        return -120.0 + q * q * (120.0 - 50.0 * q)
    t3 = max(3.0 - q, 0.0)
    t2 = max(2.0 - q, 0.0)
    return (-5.0 * t3**4 + 30.0 * t2**4) / q


# --- quartic spline, Violeau & Issa (2007), T(3.7), alpha_2 = 96 / (1199 pi), alpha_3 = 1 / (20 pi)
@njit(**_JIT)
def quartic_f(q):
    t5 = max(2.5 - q, 0.0)
    t3 = max(1.5 - q, 0.0)
    t1 = max(0.5 - q, 0.0)
    return t5**4 - 5.0 * t3**4 + 10.0 * t1**4


@njit(**_JIT)
def quartic_dfdq_q(q):
    if q < 0.5:
        # -4(2.5-q)^3 + 20(1.5-q)^3 - 40(0.5-q)^3 = q (-30 + 24 q^2) exactly
        return -30.0 + 24.0 * q * q
    t5 = max(2.5 - q, 0.0)
    t3 = max(1.5 - q, 0.0)
    return (-4.0 * t5**3 + 20.0 * t3**3) / q


# --- Wendland C2 (1995), alpha_2 = 7 / (4 pi), alpha_3 = 21 / (16 pi), support 2h ---------
@njit(**_JIT)
def wendland_c2_f(q):
    t = max(1.0 - 0.5 * q, 0.0)
    return t**4 * (2.0 * q + 1.0)


@njit(**_JIT)
def wendland_c2_dfdq_q(q):
    t = max(1.0 - 0.5 * q, 0.0)
    return -5.0 * t**3


# --- finite-support Gaussian, Colagrossi & Landrini (2003), P(26)-(28), support 3h ----------
#: exp(-Q^2) for Q = R / h = 3, the value the Gaussian is lowered by so that it vanishes at R
GAUSSIAN_Q = 3.0
GAUSSIAN_EXP_Q2 = math.exp(-GAUSSIAN_Q * GAUSSIAN_Q)


#: exp(-s) for 0 <= s < Q^2 without a call to the C library's exp (about 8 ns a pair in the
#: pair loops, against about 3.5 here): s = n / 64 + f, exp(-n / 64) from a table correctly
#: rounded (40-digit decimal arithmetic), exp(-f) for 0 <= f < 1/64 by its Taylor polynomial
#: of degree 7 (first omitted term (1/64)^8 / 8! < 1e-19). f is exact (Sterbenz), so the
#: result is within 1 ulp of exp(-s): the kernel differs from the library's at
#: round-off (tests/test_kernels.py)
EXP_STEPS = 64


def _exp_table() -> np.ndarray:
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 40
        return np.array([float((-Decimal(n) / EXP_STEPS).exp())
                         for n in range(int(GAUSSIAN_Q * GAUSSIAN_Q) * EXP_STEPS + 2)])


_EXP_TABLE = _exp_table()
_EXP_LAST = _EXP_TABLE.shape[0] - 1
_EXP_C = [(-1.0) ** k / math.factorial(k) for k in range(8)]
_E3, _E4, _E5, _E6, _E7 = _EXP_C[3:]


@njit(**_JIT)
def exp_neg(s):
    """exp(-s) for 0 <= s < 9 (the finite Gaussian's q^2)."""
    # clamped: a NaN or out-of-range s (a run blowing up) must not read outside the table
    n = min(max(int(s * EXP_STEPS), 0), _EXP_LAST)
    f = s - n * (1.0 / EXP_STEPS)
    # exp(-f) - 1, added as t + t g so that its rounding counts only at 1/64 of its weight
    g = -f * (1.0 - f * (0.5 + f * (_E3 + f * (_E4 + f * (_E5 + f * (_E6 + f * _E7))))))
    t = _EXP_TABLE[n]
    return t + t * g


@njit(**_JIT)
def gaussian_f_q2(q2):
    """f as a function of q^2 (the pair loops pass r^2 / h^2: no square root)."""
    if q2 >= GAUSSIAN_Q * GAUSSIAN_Q:
        return 0.0
    return exp_neg(q2) - GAUSSIAN_EXP_Q2


@njit(**_JIT)
def gaussian_dfdq_q_q2(q2):
    """(df/dq)/q as a function of q^2."""
    if q2 >= GAUSSIAN_Q * GAUSSIAN_Q:
        return 0.0
    return -2.0 * exp_neg(q2)


@njit(**_JIT)
def gaussian_f(q):
    return gaussian_f_q2(q * q)


@njit(**_JIT)
def gaussian_dfdq_q(q):
    return gaussian_dfdq_q_q2(q * q)


class Kernel(PipelineModel):
    """A compactly supported kernel; subclasses name their jitted ``f`` and ``dfdq_q``."""

    family = "kernel"
    prefix = "kern_"
    support: float      # kappa: W = 0 for q >= kappa
    alpha_2d: float     # normalisation in 2-D, 1 / (2 pi int f q dq)
    alpha_3d: float     # normalisation in 3-D, 1 / (4 pi int f q^2 dq)
    f_name: str
    dfdq_q_name: str

    class Coeffs(Coeffs):
        hdx: float = Field(1.3, gt=0.5, le=3.0, description="smoothing length h = hdx * dx")

    @property
    def f_jit(self):
        """The jitted f(q), for other numba code (sampling) to call."""
        return globals()[self.f_name]

    @property
    def dfdq_q_jit(self):
        """The jitted (df/dq)/q."""
        return globals()[self.dfdq_q_name]

    def f(self, q):
        return self.f_jit(q)

    def dfdq_q(self, q):
        return self.dfdq_q_jit(q)

    def imports(self):
        return [f"from sphfoam.models.kernels import {self.f_name} as kernel_f, "
                f"{self.dfdq_q_name} as kernel_dfdq_q"]

    def alpha(self, dim: int = 2) -> float:
        """alpha_d, the normalisation in ``dim`` dimensions."""
        if dim not in (2, 3):
            raise ValueError(f"dimension {dim}: valid are 2, 3")
        return self.alpha_2d if dim == 2 else self.alpha_3d

    def params(self, ctx: CaseContext):
        h, dim = ctx.h, ctx.dim
        alpha = self.alpha(dim)
        return {"kern_w": alpha / h**dim, "kern_gw": alpha / h**(dim + 2)}

    #: the pair code of W_ab and of the gradient factor fw (a kernel of q^2 alone passes
    #: r^2 / h^2 instead of q = |r| / h and saves the square root)
    _W_CODE = "Wab = kern_w * kernel_f(q)"
    _FW_CODE = "fw = kern_gw * kernel_dfdq_q(q)"

    def terms(self):
        """W_ab and grad_a W_ab = alpha_d / h^4 (df/dq / q) r_ab, wherever a term reads them."""
        return [Term("kernelValue", LOOP_STAGES, pair=self._W_CODE,
                     applies=("all",), writes=("W",), cache=("Wab",), parity="even"),
                Term("kernelGradient", LOOP_STAGES,
                     pair=self._FW_CODE + "\ngW@ = fw * d@_ab",
                     applies=("all",), writes=("gradW",), cache=("fw",), parity="odd")]

    def h(self, dx: float) -> float:
        """Smoothing length h = hdx dx."""
        return self.coeffs.hdx * dx

    def support_radius(self, h: float) -> float:
        """kappa h: W = 0 beyond it."""
        return self.support * h

    def W(self, r, h, dim: int = 2):
        """Kernel value for a numpy/scalar distance (tests and post-processing)."""
        q = np.asarray(r, dtype=float) / h
        return self.alpha(dim) / h**dim * np.vectorize(self.f_jit)(q)


@register
class CubicSpline(Kernel):
    name = "cubicSpline"
    doc = "cubic B-spline, Monaghan & Lattanzio (1985), T(3.5); support 2h"
    support = 2.0
    alpha_2d = 15.0 / (7.0 * math.pi)
    alpha_3d = 3.0 / (2.0 * math.pi)
    f_name, dfdq_q_name = "cubic_spline_f", "cubic_spline_dfdq_q"


@register
class Quartic(Kernel):
    name = "quartic"
    doc = "quartic spline, Violeau & Issa (2007), T(3.7); support 2.5h"
    support = 2.5
    alpha_2d = 96.0 / (1199.0 * math.pi)
    alpha_3d = 1.0 / (20.0 * math.pi)
    f_name, dfdq_q_name = "quartic_f", "quartic_dfdq_q"


@register
class Quintic(Kernel):
    name = "quintic"
    doc = "quintic spline, Morris et al. (1997), T(3.6); support 3h"
    support = 3.0
    alpha_2d = 7.0 / (478.0 * math.pi)
    alpha_3d = 1.0 / (120.0 * math.pi)
    f_name, dfdq_q_name = "quintic_f", "quintic_dfdq_q"


@register
class Gaussian(Kernel):
    """Finite-support Gaussian of Colagrossi & Landrini (2003), P(26)-(28).

    W = C / h^2 [exp(-q^2) - exp(-Q^2)] for q < Q = R / h = 3, 0 beyond; the shift makes W
    continuous (not its slope, -2 Q exp(-Q^2) ~ -7e-4 at q = Q).  P(28) normalises it:
    C = 1 / (2 pi int_0^Q [exp(-q^2) - exp(-Q^2)] q dq) = 1 / (pi (1 - (1 + Q^2) exp(-Q^2))),
    = 1.0012356234 / pi for Q = 3 as the paper states. Truncated and shifted the same way in
    3-D: C_3 = 1 / (4 pi int_0^Q [exp(-q^2) - exp(-Q^2)] q^2 dq)
    = 1 / (pi^(3/2) erf(Q) - 2 pi Q exp(-Q^2) - 4/3 pi Q^3 exp(-Q^2)).
    """

    name = "gaussian"
    doc = "finite-support Gaussian, Colagrossi & Landrini (2003), P(26)-(28); support 3h"
    support = GAUSSIAN_Q
    alpha_2d = 1.0 / (math.pi * (1.0 - (1.0 + GAUSSIAN_Q**2) * GAUSSIAN_EXP_Q2))
    alpha_3d = 1.0 / (math.pi**1.5 * math.erf(GAUSSIAN_Q) - math.pi * GAUSSIAN_EXP_Q2
                      * (2.0 * GAUSSIAN_Q + 4.0 / 3.0 * GAUSSIAN_Q**3))
    f_name, dfdq_q_name = "gaussian_f", "gaussian_dfdq_q"

    # a function of q^2 alone: the pair loops give it r^2 / h^2 and need no square root
    def imports(self):
        return ["from sphfoam.models.kernels import gaussian_f as kernel_f, "
                "gaussian_dfdq_q as kernel_dfdq_q, gaussian_f_q2, gaussian_dfdq_q_q2"]

    def params(self, ctx: CaseContext):
        return {**super().params(ctx), "kern_ih2": 1.0 / ctx.h**2}

    _W_CODE = "Wab = kern_w * gaussian_f_q2(r2 * kern_ih2)"
    _FW_CODE = "fw = kern_gw * gaussian_dfdq_q_q2(r2 * kern_ih2)"


@register
class WendlandC2(Kernel):
    name = "wendlandC2"
    doc = "Wendland C2 (1995), the default of modern SPH codes; support 2h"
    support = 2.0
    alpha_2d = 7.0 / (4.0 * math.pi)
    alpha_3d = 21.0 / (16.0 * math.pi)
    f_name, dfdq_q_name = "wendland_c2_f", "wendland_c2_dfdq_q"
