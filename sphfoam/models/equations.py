"""SPH forms of the continuity and momentum equations (T §3.1-3.2)."""

from __future__ import annotations

from sphfoam.engine.terms import Term
from sphfoam.models.base import PipelineModel
from sphfoam.registry import register

#: the continuity equation runs for fluid particles and for wall particles whose density
#: evolves (wet walls), in the rates and the density-only pass
_CONTINUITY = dict(stages=("rates", "density"), applies=("fluid", "wetWall"))


class Continuity(PipelineModel):
    family = "continuity"
    prefix = "cont_"
    #: drho_a += ..., per neighbour (reads grad W and the continuity velocity uc_ab, vc_ab)
    drho_code: str
    #: drho_b += the same term for the pair (b, a) (uc_ba . grad_b W_ba = uc_ab . grad_a W_ab)
    reaction_code: str = ""

    def terms(self):
        return [Term("continuityVelocity", pair="U@c_ab = U@_ab", writes=("uc",),
                     parity="odd", **_CONTINUITY),
                Term("continuity", pair=self.drho_code, reads=("gradW", "uc"),
                     writes=("drho",), reaction=self.reaction_code, relative=True,
                     **_CONTINUITY)]


@register
class DifferenceForm(Continuity):
    name = "differenceForm"
    doc = "drho_a/dt = sum_b m_b v_ab . grad_a W_ab, T(3.18)"
    drho_code = "drho_a += mb * dot(U@c_ab, gW@)"
    reaction_code = "drho_b += ma * dot(U@c_ab, gW@)"


@register
class DensityWeighted(Continuity):
    name = "densityWeighted"
    doc = "drho_a/dt = rho_a sum_b (m_b / rho_b) v_ab . grad_a W_ab, T(3.17)"
    drho_code = "drho_a += rhoa * mb / rhob * dot(U@c_ab, gW@)"
    reaction_code = "drho_b += rhob * ma / rhoa * dot(U@c_ab, gW@)"


class Momentum(PipelineModel):
    family = "momentum"
    prefix = "mom_"
    #: lines run once per particle a before its pair loop
    init_code: str = ""
    #: the pressure term's symmetric pair coefficient F_ab: dv_a/dt -= m_b F_ab grad_a W_ab
    #: (and, for the pair (b, a), dv_b/dt += m_a F_ab grad_a W_ab, grad_b W_ba = -grad_a W_ab)
    force_code: str

    def terms(self):
        return [Term("pressureGradient", ("rates",), init=self.init_code,
                     force=self.force_code, reads=("gradW",), writes=("acc",))]


@register
class Symmetric(Momentum):
    name = "symmetric"
    doc = "dv_a/dt = -sum_b m_b (p_a/rho_a^2 + p_b/rho_b^2) grad_a W_ab, T(3.24), T(3.26)"
    init_code = "pa_rho2 = pa / (rhoa * rhoa)"
    force_code = "pa_rho2 + pb / (rhob * rhob)"


@register
class ColagrossiLandrini(Momentum):
    name = "colagrossiLandrini"
    doc = "dv_a/dt = -sum_b m_b (p_a + p_b)/(rho_a rho_b) grad_a W_ab, T(3.25)"
    force_code = "(pa + pb) / (rhoa * rhob)"
