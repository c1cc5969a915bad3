"""Viscous terms of the momentum equation (T §3.4)."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field

from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register


#: viscous terms see fluid, ghosts and, at a no-slip boundary, wet and dry walls
VISCOUS_SEES = ("fluid", "ghost", "wetWall", "viscousWall")


class Viscosity(PipelineModel):
    family = "viscosity"
    prefix = "visc_"
    #: per neighbour, adding the viscous term to acc_@ ("" = none)
    pair_code: str = ""
    #: per particle a before its loop
    init_code: str = ""
    reads: tuple[str, ...] = ("gradW",)
    #: the term of the pair (b, a), added to acc_b_@ ("" = the gather only)
    reaction_code: str = ""
    #: instead of pair and reaction code: a symmetric pair coefficient Pi_ab (= Pi_ba) with
    #: dv_a/dt -= m_b Pi_ab grad_a W_ab (``Term.force``)
    force_code: str = ""

    def terms(self):
        if self.force_code:
            return [Term("viscosity", ("rates",), init=self.init_code, force=self.force_code,
                         sees=VISCOUS_SEES, reads=self.reads, writes=("acc",), viscous=True)]
        if not self.pair_code:
            return []
        return [Term("viscosity", ("rates",), init=self.init_code, pair=self.pair_code,
                     sees=VISCOUS_SEES, reads=self.reads, writes=("acc",),
                     reaction=self.reaction_code, viscous=True)]


@register
class NoViscosity(Viscosity):
    name = "none"
    doc = "inviscid: no viscous term (costs nothing)"


@register
class Artificial(Viscosity):
    """Monaghan's artificial viscosity with the usual sign: approaching pairs repel.

    T(3.32) writes Pi_ab grad W with the sign folded in; here acc_a -= m_b Pi_ab grad_a W_ab
    with Pi_ab = -alpha h (c_a + c_b)/(rho_a + rho_b) v_ab.r_ab / (r_ab^2 + eps h^2) >= 0.
    """

    name = "artificial"
    doc = "artificial viscosity, Monaghan (1992), T(3.32): acts only on approaching pairs"

    class Coeffs(Coeffs):
        alpha: float = Field(0.1, ge=0.0, description="dimensionless coefficient alpha")

    def params(self, ctx):
        return {"visc_alpha": self.coeffs.alpha}

    # min(vdotr, 0) instead of a branch: receding pairs add an exact 0.0 (the same sums),
    # and the loop has no data-dependent branch to mispredict (about half the pairs of a
    # flow with pressure waves approach). Pi_ba = Pi_ab (v_ba . r_ba = v_ab . r_ab)
    force_code = "-visc_alpha * h * (ca + cb) / (rhoa + rhob) * min(vdotr, 0.0) / (r2 + eta2)"


@register
class Laminar(Viscosity):
    name = "laminar"
    doc = ("laminar viscosity of Morris et al. (1997), T(3.38): "
           "sum_b m_b (mu_a + mu_b)/(rho_a rho_b) r_ab.grad_a W_ab / (r_ab^2 + eps h^2) v_ab")

    def params(self, ctx):
        # mu_a = mu_b = rho0 nu for water, so (mu_a + mu_b) = 2 rho0 nu
        return {"visc_mu2": 2.0 * ctx.rho0 * ctx.nu}

    def dt_limit(self, ctx: CaseContext) -> float:
        """Viscous diffusion limit of Morris et al. (1997), dt <= 0.125 h^2 / nu.

        An addition to the CFL and force conditions T(3.88)-(3.90) (which do not see the
        viscosity): for low-Reynolds channel flows such as Poiseuille flow (nu = 1e-6 m^2/s,
        h = 3.25e-4 m gives 0.0132 s) it is the binding limit.
        """
        if ctx.nu <= 0.0:
            return math.inf
        return 0.125 * ctx.h * ctx.h / ctx.nu

    pair_code = ("lam = mb * visc_mu2 / (rhoa * rhob) * dot(d@_ab, gW@) / (r2 + eta2)\n"
                 "acc_@ += lam * U@_ab")
    # r_ba . grad_b W_ba = r_ab . grad_a W_ab, v_ba = -v_ab
    reaction_code = ("lam_b = ma * visc_mu2 / (rhob * rhoa) * dot(d@_ab, gW@) / "
                     "(r2 + eta2)\n"
                     "acc_b_@ -= lam_b * U@_ab")


#: SPH velocity gradient of particle a, T(3.37) with the sign of T(3.61) / T(3.14):
#: dv^i/dx^j = sum_b m_b / rho_b (v_b^i - v_a^i) dW_ab/dx_a^j = -sum_b m_b / rho_b v_ab^i ...
_GRADIENT_INIT = """\
{p}_dudx = 0.0
{p}_dudy = 0.0
{p}_dvdx = 0.0
{p}_dvdy = 0.0
"""
_GRADIENT_PAIR = """\
{p}_vb = mb / rhob
{p}_dudx -= {p}_vb * u_ab * gWx
{p}_dudy -= {p}_vb * u_ab * gWy
{p}_dvdx -= {p}_vb * v_ab * gWx
{p}_dvdy -= {p}_vb * v_ab * gWy
"""


def _gradient_3d(p: str) -> tuple[str, str]:
    """(init, pair) of the 3-D velocity gradient: the nine entries ``{p}_dudx`` ...
    ``{p}_dwdz`` (the same sum, T(3.37)/(3.61), in d = 3)."""
    init = "".join(f"{p}_d{c}d{x} = 0.0\n" for c in "uvw" for x in "xyz")
    pair = f"{p}_vb = mb / rhob\n" + "".join(
        f"{p}_d{c}d{x} -= {p}_vb * {c}_ab * gW{x}\n" for c in "uvw" for x in "xyz")
    return init, pair


def velocity_gradient_term(p: str, final, writes) -> Term:
    """The pre-pass of T(3.37)/(3.61): the SPH velocity gradient of every particle (walls
    included, over every neighbour) into ``{p}_dudx`` ... ``{p}_dvdy`` (2-D) or ``{p}_dudx``
    ... ``{p}_dwdz`` (3-D), then ``final`` (a string, or {dimension: string} where what
    follows from the gradient is per dimension; a 2-D string alone: the term is 2-D)."""
    if not isinstance(final, dict):
        final = {2: final}
    init3, pair3 = _gradient_3d(p)
    init = {2: _GRADIENT_INIT.format(p=p), 3: init3}
    pair = {2: _GRADIENT_PAIR.format(p=p), 3: pair3}
    return Term("velocityGradient", ("prepass",), init={d: init[d] for d in final},
                pair={d: pair[d] for d in final}, final=final, applies=("all",),
                sees=("all",), reads=("gradW",), writes=writes)


@register
class ImprovedArtificial(Viscosity):
    """Artificial viscosity of T(3.32) scaled by (k_a + k_b)/2, which switches it off in shear.

    k_a = |div v_a| / (|div v_a| + sqrt(S_ij S_ij) + 1e-4 c_a / h) (Colagrossi & Landrini
    2003, T(3.35)-(3.36)) or, with ``switch balsara``, |div v_a| / (|div v_a| + |curl v_a| +
    1e-4 c_a / h) (Balsara 1995, T(3.34)). The velocity gradient is the SPH sum of T(3.37) with
    the sign of T(3.14)/(3.61), dv^i/dx^j = sum_b m_b/rho_b (v_b^i - v_a^i) dW_ab/dx_a^j,
    evaluated in the pre-pass for every particle (walls included); k_a is stored in ``visc_k``.
    Pure shear (div v = 0) gives k = 0; an isotropic compression gives k = 2/(2 + sqrt 2)
    ~ 0.59 with the strain-rate switch and k ~ 1 with Balsara's. In 3-D: the nine entries of
    the gradient, div v their trace, S_ij S_ij over the 3 x 3 strain rate and |curl v| the
    norm of the vorticity vector (T(3.34)-(3.37) in d = 3).
    """

    name = "improvedArtificial"
    doc = ("artificial viscosity with a shear switch, T(3.33): Pi_ab of T(3.32) times "
           "(k_a + k_b)/2, k_a from T(3.35)-(3.37) (Colagrossi & Landrini) or T(3.34) (Balsara)")

    class Coeffs(Coeffs):
        alpha: float = Field(0.1, ge=0.0, description="dimensionless coefficient alpha of "
                             "T(3.33)")
        switch: Literal["colagrossiLandrini", "balsara"] = Field(
            "colagrossiLandrini", description="k_a: `colagrossiLandrini` uses the strain rate "
            "sqrt(S_ij S_ij), T(3.35); `balsara` the vorticity |curl v|, T(3.34)")

    reads = ("gradW", "aux.visc_k")

    def terms(self):
        return [velocity_gradient_term("ivd", self.switch_code(), ("aux.visc_k",)),
                *super().terms()]

    def switch_code(self) -> dict[int, str]:
        """k_a of T(3.34) or T(3.35)-(3.36) from the velocity gradient, into aux visc_k, per
        dimension: in 3-D div v = du/dx + dv/dy + dw/dz, |curl v| the norm of the whole
        vorticity vector and S_ij S_ij the sum over the nine entries (the general-dimension
        forms of T(3.34)-(3.36))."""
        tail = ("ivd_den = ivd_div + ivd_other + 1e-4 * ca * inv_h\n"
                "aux[I_visc_k, a] = ivd_div / ivd_den if ivd_den > 0.0 else 0.0")
        if self.coeffs.switch == "balsara":
            other = "ivd_other = abs(ivd_dvdx - ivd_dudy)                  # |curl v|, T(3.34)\n"
            other3 = ("ivd_cx = ivd_dwdy - ivd_dvdz\n"
                      "ivd_cy = ivd_dudz - ivd_dwdx\n"
                      "ivd_cz = ivd_dvdx - ivd_dudy\n"
                      "ivd_other = math.sqrt(ivd_cx * ivd_cx + ivd_cy * ivd_cy"
                      " + ivd_cz * ivd_cz)   # |curl v|, T(3.34)\n")
        else:
            other = ("ivd_sxy = 0.5 * (ivd_dudy + ivd_dvdx)\n"
                     "ivd_other = math.sqrt(ivd_dudx * ivd_dudx + ivd_dvdy * ivd_dvdy"
                     " + 2.0 * ivd_sxy * ivd_sxy)   # sqrt(S_ij S_ij), T(3.35)-(3.36)\n")
            other3 = ("ivd_sxy = 0.5 * (ivd_dudy + ivd_dvdx)\n"
                      "ivd_sxz = 0.5 * (ivd_dudz + ivd_dwdx)\n"
                      "ivd_syz = 0.5 * (ivd_dvdz + ivd_dwdy)\n"
                      "ivd_other = math.sqrt(ivd_dudx * ivd_dudx + ivd_dvdy * ivd_dvdy"
                      " + ivd_dwdz * ivd_dwdz + 2.0 * (ivd_sxy * ivd_sxy + ivd_sxz * ivd_sxz"
                      " + ivd_syz * ivd_syz))   # sqrt(S_ij S_ij), T(3.35)-(3.36)\n")
        return {2: "ivd_div = abs(ivd_dudx + ivd_dvdy)\n" + other + tail,
                3: "ivd_div = abs(ivd_dudx + ivd_dvdy + ivd_dwdz)\n" + other3 + tail}

    def params(self, ctx):
        return {"visc_alpha": self.coeffs.alpha}

    init_code = "ivd_ka = aux[I_visc_k, a]"
    pair_code = ("if vdotr < 0.0:\n"
                 "    pi_ab = (-visc_alpha * h * (ca + cb) / (rhoa + rhob)\n"
                 "             * 0.5 * (ivd_ka + aux[I_visc_k, b]) * vdotr / (r2 + eta2))\n"
                 "    acc_@ -= mb * pi_ab * gW@")
