"""Riemann-solver SPH of Zhang, Hu & Adams (2017, JCP 335, 605-620,
doi:10.1016/j.jcp.2017.01.027): the low-dissipation weakly compressible scheme.

Each pair a, b is a one-dimensional Riemann problem along e_ab = -r_ab / |r_ab| (from a to
b): left state (rho_a, U_L = v_a . e_ab, p_a), right state (rho_b, U_R = v_b . e_ab, p_b).
The linearised (acoustic) solver gives

    U* = (U_L + U_R)/2 + (p_a - p_b) / (2 rho_bar c_bar)
    P* = (p_a + p_b)/2 + beta rho_bar (U_L - U_R) / 2

with rho_bar, c_bar the pair means. The acoustic solver has beta = c_bar; the low-dissipation
limiter of ZHA17 is beta = min(eta max(U_L - U_R, 0), c_bar): no dissipation where
the pair separates (U_L < U_R), eta (U_L - U_R) in weak compression, the acoustic value in
strong compression. The star states replace the pair averages of the continuity and momentum
equations:

    drho_a/dt = 2 rho_a sum_b (m_b / rho_b) (v_a - v*_ab) . grad_a W_ab,
                v*_ab = U* e_ab + ((v_a + v_b)/2 - (U_L + U_R)/2 e_ab)
    dv_a/dt   = -2 sum_b m_b P* / (rho_a rho_b) grad_a W_ab

The momentum equation is pair-antisymmetric (momentum is conserved to round-off). The two
halves are separate models, ``continuity riemann`` and ``momentum riemann``; ZHA17's scheme is
both selected, and each also works beside the other family's classical forms. With the
continuity velocity uc_ab (``uc``; v_ab unless XSPH corrects it),
v_a - v*_ab = uc_ab / 2 - (U* - (U_L + U_R)/2) e_ab.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from sphfoam.engine.terms import Term
from sphfoam.models.base import PipelineModel
from sphfoam.models.equations import Continuity
from sphfoam.registry import Coeffs, register

#: U_L - U_R = -(v_ab . r_ab) / |r_ab| and the pair means of the linearised solver (ZHA17)
_PAIR_STATE = """\
rs_r = math.sqrt(r2)
rs_du = -vdotr / rs_r
rs_rho = 0.5 * (rhoa + rhob)
rs_c = 0.5 * (ca + cb)
"""


@register
class RiemannContinuity(Continuity):
    """The continuity equation with the acoustic Riemann solver's U* (ZHA17).

    drho_a/dt = 2 rho_a sum_b m_b/rho_b (v_a - v*_ab) . grad_a W_ab, which is the
    density-weighted form T(3.17) plus the solver's dissipation
    -2 rho_a sum_b m_b/rho_b (p_a - p_b)/(2 rho_bar c_bar) e_ab . grad_a W_ab: a particle
    of higher pressure than its neighbours loses density. (Only P* is limited; U* keeps its
    acoustic form.) Across a wall particle b (any neighbour that is not fluid: wet walls,
    ``adami`` walls, mirror ghosts) the right state's pressure is the hydrostatic
    continuation of a's, p_R = p_a + rho_a g . (r_b - r_a) (ZHA17's fluid-wall Riemann
    problem), so a fluid at rest over a wall neither drains into it nor swells from it.
    The dissipation acts for fluid particles a; wet walls' density evolves by the
    density-weighted part alone.
    """

    name = "riemann"
    doc = ("drho_a/dt = 2 rho_a sum_b m_b/rho_b (v_a - v*) . grad_a W_ab with U* of the "
           "linearised Riemann solver, Zhang, Hu & Adams (2017, JCP 335)")
    drho_code = "drho_a += rhoa * mb / rhob * dot(U@c_ab, gW@)"
    #: -2 rho_a m_b/rho_b (U* - (U_L + U_R)/2) e_ab . grad_a W_ab, e_ab = -r_ab / |r_ab|
    dissipation_code = _PAIR_STATE + """\
if kindb == FLUID:
    rs_dp = pa - pb
else:
    rs_dp = rhoa * dot(g@, d@_ab)      # p_a - p_R
rs_ds = rs_dp / (rs_rho * rs_c * rs_r)
drho_a += rhoa * mb / rhob * rs_ds * dot(d@_ab, gW@)"""

    def terms(self):
        return [*super().terms(),
                Term("riemannDissipation", ("rates", "density"), pair=self.dissipation_code,
                     applies=("fluid",), reads=("gradW",),
                     writes=("drho",))]


@register
class RiemannMomentum(PipelineModel):
    """The momentum equation with the Riemann solver's P* and limiter (ZHA17).

    dv_a/dt = -2 sum_b m_b P*/(rho_a rho_b) grad_a W_ab, P* = (p_a + p_b)/2 +
    beta rho_bar (U_L - U_R)/2. ``limiter lowDissipation``: beta = min(eta max(U_L - U_R, 0),
    c_bar), so separating pairs feel p_bar alone (the form T(3.25)) and
    approaching ones a dissipation growing with the square of their approach speed;
    ``limiter none``: beta = c_bar, the acoustic solver's full dissipation (also in
    expansion, where it lowers P*).
    """

    family = "momentum"
    prefix = "mom_"
    name = "riemann"
    doc = ("dv_a/dt = -2 sum_b m_b P*/(rho_a rho_b) grad_a W_ab, P* of the linearised "
           "Riemann solver with the low-dissipation limiter beta = min(eta max(U_L - U_R, 0),"
           " c_bar), Zhang, Hu & Adams (2017, JCP 335)")

    class Coeffs(Coeffs):
        limiter: Literal["lowDissipation", "none"] = Field(
            "lowDissipation", description="`lowDissipation`: beta = min(eta max(U_L - U_R, "
            "0), c_bar), ZHA17; `none`: beta = c_bar, the acoustic solver")
        eta: float = Field(3.0, gt=0.0, description="eta of the limiter (3 in ZHA17)")

    def params(self, ctx):
        return {"mom_eta": self.coeffs.eta}

    def terms(self):
        if self.coeffs.limiter == "lowDissipation":
            beta = "rs_beta = min(mom_eta * max(rs_du, 0.0), rs_c)\n"
        else:
            beta = "rs_beta = rs_c\n"
        pair = (_PAIR_STATE + beta
                + "rs_pstar = 0.5 * (pa + pb) + 0.5 * rs_beta * rs_rho * rs_du\n"
                  "pterm = 2.0 * mb * rs_pstar / (rhoa * rhob)\n"
                  "acc_@ -= pterm * gW@")
        return [Term("pressureGradient", ("rates",), pair=pair, reads=("gradW",),
                     writes=("acc",))]
