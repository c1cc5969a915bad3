"""Viscous terms of the momentum equation (T §3.4)."""

from __future__ import annotations

from pydantic import Field

from sphfoam.models.base import PipelineModel
from sphfoam.registry import Coeffs, register


class Viscosity(PipelineModel):
    family = "viscosity"
    prefix = "visc_"
    pair_code: str = ""


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

    pair_code = ("if vdotr < 0.0:\n"
                 "    pi_ab = -visc_alpha * h * (ca + cb) / (rhoa + rhob) * vdotr / (r2 + eta2)\n"
                 "    acc_x -= mb * pi_ab * gWx\n"
                 "    acc_y -= mb * pi_ab * gWy")


@register
class Laminar(Viscosity):
    name = "laminar"
    doc = ("laminar viscosity of Morris et al. (1997), T(3.38): "
           "sum_b m_b (mu_a + mu_b)/(rho_a rho_b) r_ab.grad_a W_ab / (r_ab^2 + eps h^2) v_ab")

    def params(self, ctx):
        # mu_a = mu_b = rho0 nu for water, so (mu_a + mu_b) = 2 rho0 nu
        return {"visc_mu2": 2.0 * ctx.rho0 * ctx.nu}

    pair_code = ("lam = mb * visc_mu2 / (rhoa * rhob) * (dx_ab * gWx + dy_ab * gWy) / (r2 + eta2)\n"
                 "acc_x += lam * u_ab\n"
                 "acc_y += lam * v_ab")
