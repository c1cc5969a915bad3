"""Velocity and kernel corrections: XSPH, T(3.62)-(3.63)/P(36), and C-SPH, P(29)-(32).

Both work through the pre-pass of the generated pipeline (see ``sphfoam.models.base``): for
every particle a they loop over its neighbours with the plain kernel and store per-particle
fields in ``aux``, which the rates and density loops then read for a and b.
"""

from __future__ import annotations

from typing import Literal

from numba import njit, prange
from pydantic import Field

from sphfoam.engine.fastmath import FASTMATH
from sphfoam.engine.hookforms import AdvectionCorrection
from sphfoam.engine.state import kept_arrays
from sphfoam.engine.stepping import components
from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register


@njit(parallel=True, cache=True, fastmath=set(FASTMATH))
def add_correction(u, du, kind, out):
    """out = u + du for fluid particles (walls keep their prescribed velocity)."""
    for a in prange(u.shape[0]):
        out[a] = u[a] + du[a] if kind[a] == 0 else u[a]


def corrected_velocity(owner, run, U, dU):
    """U + dU of the fluid particles (walls: U), component by component (``U`` = (u, v) in
    2-D, (u, v, w) in 3-D, ``dU`` the corrections alike), in arrays ``owner`` keeps between
    calls, so that no step allocates: valid until the owner's next call."""
    buf = kept_arrays(owner, "_advection", len(U), U[0].shape[0], U[0].dtype)
    for u, du, out in zip(U, dU, buf):
        add_correction(u, du, run.state.kind, out)
    return buf


@njit(parallel=True, cache=True, fastmath=set(FASTMATH))
def add_rate(rate, extra):
    """rate += extra in place (a model's per-particle addition to a rate)."""
    for a in prange(rate.shape[0]):
        rate[a] += extra[a]


class VelocityCorrection(PipelineModel):
    family = "velocityCorrection"
    prefix = "vc_"


class KernelCorrection(PipelineModel):
    family = "kernelCorrection"
    prefix = "kc_"


@register
class XSPH(VelocityCorrection):
    """Monaghan's XSPH velocity correction, T(3.62)-(3.63), P(36).

    For each fluid particle a the pre-pass computes

        dv_a = epsilon sum_b (m_b / rhobar_ab) (v_b - v_a) W_ab,   rhobar_ab = (rho_a + rho_b) / 2

    over all its neighbours b (fluid and wall; a wall neighbour contributes its prescribed
    velocity) with the plain kernel W_ab.  The sign is Monaghan's: the correction pulls v_a
    towards the neighbours' mean velocity (T(3.63) as printed writes v_ab, P(36) writes m_a
    for m_b; both are misprints of this form).  Wall particles get dv = 0: they keep their
    prescribed velocity.

    The corrected velocity v_a + dv_a moves the particles (the ``advection_velocity`` hook) and enters
    the continuity equation, uc_ab = v_ab + dv_a - dv_b (T §3.6, "for consistency"); the
    momentum equation uses the uncorrected v, so linear and angular momentum are unaffected.
    Since m_a m_b / rhobar_ab W_ab is symmetric in a and b, sum_a m_a dv_a = 0 over the fluid
    particles when no wall is in range.  epsilon = 0.5 is the value of both T §3.6 ("usually
    chosen to be 0.5") and P §3 ("epsilon = 0.5 will be used").

    ``evaluation oncePerStep`` computes dv_a once per step, from the step's first state, and
    holds it through the step's later stages (the drifts and the continuity equation at the
    mid-step and at the end of monaghan2007's step): one pre-pass a step instead of three.
    dv_a changes over a step by O(dt), so does the scheme; the default, ``everyStage``, is
    T's and P's.
    """

    name = "xsph"
    doc = ("XSPH: positions and continuity use v_a + eps sum_b m_b/rhobar_ab v_ba W_ab, "
           "T(3.62)-(3.63), P(36)")
    _DV = ("aux.xsph_dU@",)

    class Coeffs(Coeffs):
        epsilon: float = Field(0.5, gt=0.0, le=1.0, description=(
            "strength of the smoothing, 0 < epsilon <= 1; 0.5 as in T §3.6 and P §3"))
        evaluation: Literal["everyStage", "oncePerStep"] = Field("everyStage", description=(
            "everyStage: dv_a afresh before every evaluation of a step (T, P); oncePerStep: "
            "from the step's first state, held through its later stages (one pre-pass a "
            "step instead of three with monaghan2007; the scheme changes at O(dt))"))

    _INIT = """\
xsph_sU@ = 0.0
"""
    _PAIR = """\
xsph_w = 2.0 * mb / (rhoa + rhob) * Wab
xsph_sU@ -= xsph_w * U@_ab
"""
    #: b's sums for the pair (b, a): m_a W_ba / rhobar (v_a - v_b), v_a - v_b = v_ab
    _REACTION = """\
xsph_w_b = 2.0 * ma / (rhoa + rhob) * Wab
xsph_sU@_b += xsph_w_b * U@_ab
"""
    _FINAL = """\
if kind[a] == FLUID:
    aux[I_xsph_dU@, a] = vc_eps * xsph_sU@
else:
    aux[I_xsph_dU@, a] = 0.0
"""
    _UC = """\
U@c_ab = U@_ab + aux[I_xsph_dU@, a] - aux[I_xsph_dU@, b]
"""

    def params(self, ctx: CaseContext):
        return {"vc_eps": self.coeffs.epsilon}

    def terms(self):
        return [Term("xsphVelocity", ("prepass",), init=self._INIT, pair=self._PAIR,
                     final=self._FINAL, applies=("all",), sees=("all",), reads=("W",),
                     writes=self._DV, reaction=self._REACTION, sums=("xsph_sU@",),
                     per_step=self.coeffs.evaluation == "oncePerStep",
                     nonfluid_discarded=True),                  # walls: dv = 0
                Term("xsphContinuity", ("rates", "density"), pair=self._UC,
                     applies=("fluid", "wetWall"), reads=self._DV, corrects=("uc",),
                     parity="odd")]

    #: the advection hook is written for any dimension (the velocity's components)
    hook_dims = (2, 3)
    #: positions move with v_a + dv_a, T(3.62): the hook below, declared
    _ADVECTION = AdvectionCorrection("xsph_dU@")

    def device_forms(self):
        return (self._ADVECTION,)

    def advection_velocity(self, run, *U):
        """Positions move with v_a + dv_a of the last pre-pass, T(3.62) (walls: their own);
        ``U`` the velocity's components (u, v) or (u, v, w)."""
        dU = [run.aux(k) for k in components(self._ADVECTION.aux, len(U))]
        return corrected_velocity(self, run, U, dU)


@register
class CSPH(KernelCorrection):
    """Corrected SPH of Staroszczyk (Belytschko et al. 1998), P(29)-(32).

    With x_ab = x_a - x_b, z_ab = z_a - z_b, P_ab = (1, x_ab, z_ab) and V_b = m_b / rho_b,
    P(29)-(32) read

        W~_ab          = (c11 + c12 x_ab + c13 z_ab) W^S_ab,    W^S_ab = W_ab / S_a,
        (grad_a W~)_x  = (c21 + c22 x_ab + c23 z_ab) W^S_ab,    S_a = sum_b V_b W_ab,
        (grad_a W~)_z  = (c31 + c32 x_ab + c33 z_ab) W^S_ab,
        A = sum_b V_b W^S_ab P_ab P_ab^T,

    with c fixed by the completeness conditions: the corrected kernel reproduces 1 and the
    linear functions, sum_b V_b W~_ab P_ab = (1, 0, 0), and the corrected gradient reproduces
    their gradients, sum_b V_b grad_a W~_ab f_b = grad f for every linear f.  Because
    f_b = f_a - grad f . r_ab, the latter means sum_b V_b (grad_a W~_ab) P_ab^T = (0, -1, 0) for
    x and (0, 0, -1) for z, so c = E A^-1 with E = diag(1, -1, -1).  (P(31) prints
    c^T = A^-1, which is the same statement with the moments taken in x_b - x_a, the
    convention of Belytschko et al.; with the x_ab of (29) the gradient rows change sign.)

    The Shepard factor cancels: A = M / S_a with M = sum_b V_b W_ab P_ab P_ab^T, so with
    B = M^-1 (symmetric)

        W~_ab = (B11 + B12 x_ab + B13 z_ab) W_ab,
        grad_a W~_ab = -(B12 + B22 x_ab + B23 z_ab,  B13 + B23 x_ab + B33 z_ab) W_ab.

    The pre-pass accumulates M (in coordinates scaled by h, so that its entries are O(1)),
    inverts it by cofactors and stores the six entries of B as ``csph_b11`` ... ``csph_b33``
    and a flag ``csph_ok``; the ``correctedGradient`` term corrects grad_a W_ab in the continuity, pressure
    and viscous terms of the rates and density loops (P: "used to replace respective standard
    SPH counterparts in the equations of continuity and motion").  The paper does not
    symmetrise: grad_a W~_ab uses the coefficients of a only, so momentum is no longer
    conserved exactly.

    Stability (``symmetric``): with grad_a W~_ab taken from a alone, the discrete divergence
    of the continuity equation and the discrete gradient of the momentum equation are no
    longer adjoint, and at a free surface the linearised acoustic operator has eigenvalues
    with a positive real part of the order of c0 / h (1.4 c0 / h for a free 12 x 12 block
    with Wendland C2, h = 1.3 dx; 0.9 c0 / h with the Gaussian, h = 1.33 dx).  A dam break of
    the damBreak tutorial's layout at dx = 12.5 mm blows up from its free surface within 0.02 s this way: alone
    (0.006 s), with XSPH, with delta-SPH, with an MLS re-initialisation every 20 steps, and
    in P's own set-up (Gaussian, h = 1.33 dx, XSPH, a Shepard filter every 20 steps; 0.017 s).
    ``symmetric yes`` uses the antisymmetric (grad~_a W_ab - grad~_b W_ba) / 2 instead
    (Bonet & Lok 1999): momentum is conserved, the linearised operator is neutral (purely
    imaginary spectrum) and the tutorial runs, at the price of the exact linear consistency.
    The default is ``symmetric yes`` (a selection must not blow up by default); P's exact,
    linear-consistent form is ``symmetric no``.

    In 3-D the same equations with P_ab = (1, x_ab, y_ab, z_ab): M is 4 x 4, inverted by
    its cofactors, its ten entries stored as ``csph_b11`` ... ``csph_b44``, and the guard is
    Hadamard's bound M11 M22 M33 M44.

    Neighbours: the sums run over the same neighbours b != a as the pair sums of the rates
    (grad W_aa = 0 for the standard kernel, so (24)-(25) have no self term).  Then
    sum_{b != a} V_b grad_a W~_ab = 0 and sum_{b != a} V_b grad_a W~_ab r_ab^T = -I exactly,
    i.e. both the difference form and the plain form of a gradient are exact for linear
    fields; W~ reproduces constants and linear fields over the same neighbours.  Fluid and
    wall particles are neighbours alike, and wall particles get their own coefficients.

    Singular A: a particle with fewer than three neighbours, or with neighbours (nearly) on
    one line, e.g. in spray, has a singular or ill-conditioned A.  The determinant is
    compared with Hadamard's bound, which is invariant to the units and to the Shepard
    scaling: det M <= M11 M22 M33, with equality for a full, symmetric support.  When
    det M < minDetRatio * M11 M22 M33 (1e-3 by default; the corner of a lattice block, a
    quarter support, has 0.05 to 0.15 for h = dx to 2 dx, an edge about 0.5) the particle
    falls back to the plain kernel gradient, ``csph_ok`` = 0 and its B entries are 0 (with
    ``symmetric``, its half of every pair gradient is the plain one).
    """

    name = "csph"
    aliases = ("cspH",)
    doc = ("C-SPH: Shepard kernel and first-order corrected gradient, c = A^-1 per particle, "
           "P(29)-(32)")
    _B = ("aux.csph_b11", "aux.csph_b12", "aux.csph_b13", "aux.csph_b22", "aux.csph_b23",
          "aux.csph_b33", "aux.csph_ok")

    class Coeffs(Coeffs):
        minDetRatio: float = Field(1e-3, gt=0.0, lt=1.0, description=(
            "a particle whose moment matrix has det A < minDetRatio * A11 A22 A33 (Hadamard's "
            "bound; 1 for a full support) keeps the plain kernel gradient"))
        symmetric: bool = Field(True, description=(
            "use (grad~_a W_ab - grad~_b W_ba) / 2 (Bonet & Lok 1999) instead of P(29)'s "
            "grad~_a W_ab: conserves momentum and is stable at a free surface (P's form is "
            "not), but no longer exact for linear fields"))

    _INIT = """\
csph_m11 = 0.0
csph_m12 = 0.0
csph_m13 = 0.0
csph_m22 = 0.0
csph_m23 = 0.0
csph_m33 = 0.0
"""
    _PAIR = """\
csph_vw = mb / rhob * Wab
csph_xs = dx_ab * inv_h
csph_zs = dy_ab * inv_h
csph_m11 += csph_vw
csph_m12 += csph_vw * csph_xs
csph_m13 += csph_vw * csph_zs
csph_m22 += csph_vw * csph_xs * csph_xs
csph_m23 += csph_vw * csph_xs * csph_zs
csph_m33 += csph_vw * csph_zs * csph_zs
"""
    _FINAL = """\
csph_k11 = csph_m22 * csph_m33 - csph_m23 * csph_m23
csph_k12 = csph_m13 * csph_m23 - csph_m12 * csph_m33
csph_k13 = csph_m12 * csph_m23 - csph_m13 * csph_m22
csph_det = csph_m11 * csph_k11 + csph_m12 * csph_k12 + csph_m13 * csph_k13
csph_had = csph_m11 * csph_m22 * csph_m33
if csph_had > 0.0 and csph_det > kc_detmin * csph_had:
    csph_inv = 1.0 / csph_det
    csph_ih2 = inv_h * inv_h
    aux[I_csph_b11, a] = csph_k11 * csph_inv
    aux[I_csph_b12, a] = csph_k12 * csph_inv * inv_h
    aux[I_csph_b13, a] = csph_k13 * csph_inv * inv_h
    aux[I_csph_b22, a] = (csph_m11 * csph_m33 - csph_m13 * csph_m13) * csph_inv * csph_ih2
    aux[I_csph_b23, a] = (csph_m12 * csph_m13 - csph_m11 * csph_m23) * csph_inv * csph_ih2
    aux[I_csph_b33, a] = (csph_m11 * csph_m22 - csph_m12 * csph_m12) * csph_inv * csph_ih2
    aux[I_csph_ok, a] = 1.0
else:
    aux[I_csph_b11, a] = 0.0
    aux[I_csph_b12, a] = 0.0
    aux[I_csph_b13, a] = 0.0
    aux[I_csph_b22, a] = 0.0
    aux[I_csph_b23, a] = 0.0
    aux[I_csph_b33, a] = 0.0
    aux[I_csph_ok, a] = 0.0
"""
    #: grad~_a W_ab of P(29)-(32): coefficients of a only (the kernel's plain gradient
    #: gWx, gWy stays where A is singular)
    _GRADIENT_A = """\
if aux[I_csph_ok, a] != 0.0:
    gWx = -(aux[I_csph_b12, a] + aux[I_csph_b22, a] * dx_ab + aux[I_csph_b23, a] * dy_ab) * Wab
    gWy = -(aux[I_csph_b13, a] + aux[I_csph_b23, a] * dx_ab + aux[I_csph_b33, a] * dy_ab) * Wab
"""
    #: (grad~_a W_ab - grad~_b W_ba) / 2, Bonet & Lok (1999); r_ba = -r_ab
    _GRADIENT_SYMMETRIC = """\
csph_px = gWx
csph_py = gWy
if aux[I_csph_ok, a] != 0.0:
    gWx = -(aux[I_csph_b12, a] + aux[I_csph_b22, a] * dx_ab + aux[I_csph_b23, a] * dy_ab) * Wab
    gWy = -(aux[I_csph_b13, a] + aux[I_csph_b23, a] * dx_ab + aux[I_csph_b33, a] * dy_ab) * Wab
if aux[I_csph_ok, b] != 0.0:
    gWx += (aux[I_csph_b12, b] - aux[I_csph_b22, b] * dx_ab - aux[I_csph_b23, b] * dy_ab) * Wab
    gWy += (aux[I_csph_b13, b] - aux[I_csph_b23, b] * dx_ab - aux[I_csph_b33, b] * dy_ab) * Wab
else:
    gWx += csph_px
    gWy += csph_py
gWx *= 0.5
gWy *= 0.5
"""

    #: 3-D: P_ab = (1, x_ab, y_ab, z_ab), M 4 x 4 and B = M^-1 (its ten entries)
    _B3 = tuple(f"aux.csph_b{i}{j}" for i in range(1, 5) for j in range(i, 5)) + \
        ("aux.csph_ok",)

    @staticmethod
    def _code_3d(part: str, symmetric: bool = True) -> str:
        """P(29)-(32) in three dimensions (the same equations with the basis (1, x, y, z)):
        ``part`` init, pair, final (M and its inverse by cofactors) or grad (the corrected
        gradient, of a alone or symmetrised)."""
        from sphfoam.models.filters import _det3, _sym

        idx = [(i, j) for i in range(1, 5) for j in range(i, 5)]
        if part == "init":
            return "".join(f"csph_m{i}{j} = 0.0\n" for i, j in idx)
        if part == "pair":
            out = ("csph_vw = mb / rhob * Wab\ncsph_p1 = 1.0\ncsph_p2 = dx_ab * inv_h\n"
                   "csph_p3 = dy_ab * inv_h\ncsph_p4 = dz_ab * inv_h\n")
            return out + "".join(f"csph_m{i}{j} += csph_vw * csph_p{i} * csph_p{j}\n"
                                 for i, j in idx)
        if part == "final":
            m = _sym("csph_m")
            out = []
            for i, j in idx:
                rows = [r for r in range(1, 5) if r != i]
                cols = [c for c in range(1, 5) if c != j]
                sign = "" if (i + j) % 2 == 0 else "-"
                out.append(f"csph_k{i}{j} = {sign}({_det3(m, rows, cols)})")
            out += ["csph_det = csph_m11 * csph_k11 + csph_m12 * csph_k12 + csph_m13 * csph_k13"
                    " + csph_m14 * csph_k14",
                    "csph_had = csph_m11 * csph_m22 * csph_m33 * csph_m44",
                    "if csph_had > 0.0 and csph_det > kc_detmin * csph_had:",
                    "    csph_inv = 1.0 / csph_det"]
            for i, j in idx:
                scale = " * inv_h" * ((i > 1) + (j > 1))
                out.append(f"    aux[I_csph_b{i}{j}, a] = csph_k{i}{j} * csph_inv{scale}")
            out += ["    aux[I_csph_ok, a] = 1.0", "else:"]
            out += [f"    aux[I_csph_b{i}{j}, a] = 0.0" for i, j in idx]
            out += ["    aux[I_csph_ok, a] = 0.0"]
            return "\n".join(out) + "\n"

        def b(i, j, who):
            return f"aux[I_csph_b{min(i, j)}{max(i, j)}, {who}]"

        def grad_a(k, who="a", sign=-1):
            # -(B_1k + B_2k x_ab + B_3k y_ab + B_4k z_ab) W for a; for b (r_ba = -r_ab):
            # +(B_1k - B_2k x_ab - B_3k y_ab - B_4k z_ab) W
            if sign < 0:
                return (f"-({b(1, k, who)} + {b(2, k, who)} * dx_ab + {b(3, k, who)} * dy_ab"
                        f" + {b(4, k, who)} * dz_ab) * Wab")
            return (f"({b(1, k, who)} - {b(2, k, who)} * dx_ab - {b(3, k, who)} * dy_ab"
                    f" - {b(4, k, who)} * dz_ab) * Wab")

        ax = {2: "x", 3: "y", 4: "z"}
        if not symmetric:
            return "if aux[I_csph_ok, a] != 0.0:\n" + "".join(
                f"    gW{ax[k]} = {grad_a(k)}\n" for k in (2, 3, 4))
        out = "".join(f"csph_p{ax[k]} = gW{ax[k]}\n" for k in (2, 3, 4))
        out += "if aux[I_csph_ok, a] != 0.0:\n" + "".join(
            f"    gW{ax[k]} = {grad_a(k)}\n" for k in (2, 3, 4))
        out += "if aux[I_csph_ok, b] != 0.0:\n" + "".join(
            f"    gW{ax[k]} += {grad_a(k, 'b', +1)}\n" for k in (2, 3, 4))
        out += "else:\n" + "".join(f"    gW{ax[k]} += csph_p{ax[k]}\n" for k in (2, 3, 4))
        return out + "".join(f"gW{ax[k]} *= 0.5\n" for k in (2, 3, 4))

    def terms(self):
        sym = self.coeffs.symmetric
        grad = self._GRADIENT_SYMMETRIC if sym else self._GRADIENT_A
        B = {2: self._B, 3: self._B3}
        return [Term("momentMatrix", ("prepass",),
                     init={2: self._INIT, 3: self._code_3d("init")},
                     pair={2: self._PAIR, 3: self._code_3d("pair")},
                     final={2: self._FINAL, 3: self._code_3d("final")}, applies=("all",),
                     sees=("all",), reads=("W",), writes=B),
                Term("correctedGradient", ("rates", "density"),
                     pair={2: grad, 3: self._code_3d("grad", sym)}, applies=("all",),
                     reads={d: ("W", *names) for d, names in B.items()},
                     corrects=("gradW",))]

    def params(self, ctx: CaseContext):
        return {"kc_detmin": self.coeffs.minDetRatio}
