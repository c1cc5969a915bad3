"""SPH forms of the continuity and momentum equations (T §3.1-3.2)."""

from __future__ import annotations

from sphfoam.models.base import PipelineModel
from sphfoam.registry import register


class Continuity(PipelineModel):
    family = "continuity"
    prefix = "cont_"
    #: lines run inside the pair loop, adding to drho_a
    pair_code: str


@register
class DifferenceForm(Continuity):
    name = "differenceForm"
    doc = "drho_a/dt = sum_b m_b v_ab . grad_a W_ab, T(3.18)"
    pair_code = "drho_a += mb * (uc_ab * gWx + vc_ab * gWy)"


@register
class DensityWeighted(Continuity):
    name = "densityWeighted"
    doc = "drho_a/dt = rho_a sum_b (m_b / rho_b) v_ab . grad_a W_ab, T(3.17)"
    pair_code = "drho_a += rhoa * mb / rhob * (uc_ab * gWx + vc_ab * gWy)"


class Momentum(PipelineModel):
    family = "momentum"
    prefix = "mom_"
    #: lines run once per particle a before its pair loop
    particle_code: str = ""
    #: lines run inside the pair loop, adding the pressure term to acc_x, acc_y
    pair_code: str


@register
class Symmetric(Momentum):
    name = "symmetric"
    doc = "dv_a/dt = -sum_b m_b (p_a/rho_a^2 + p_b/rho_b^2) grad_a W_ab, T(3.24), T(3.26)"
    particle_code = "pa_rho2 = pa / (rhoa * rhoa)"
    pair_code = ("pterm = mb * (pa_rho2 + pb / (rhob * rhob))\n"
                 "acc_x -= pterm * gWx\n"
                 "acc_y -= pterm * gWy")


@register
class ColagrossiLandrini(Momentum):
    name = "colagrossiLandrini"
    doc = "dv_a/dt = -sum_b m_b (p_a + p_b)/(rho_a rho_b) grad_a W_ab, T(3.25)"
    pair_code = ("pterm = mb * (pa + pb) / (rhoa * rhob)\n"
                 "acc_x -= pterm * gWx\n"
                 "acc_y -= pterm * gWy")
