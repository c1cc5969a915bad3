"""Sub-particle-scale turbulence closures (T §3.5).

The ``none`` entry of the family lives in :mod:`sphfoam.models.noop` and adds nothing to the
pipeline.
"""

from __future__ import annotations

from pydantic import Field

from sphfoam.engine.terms import Term
from sphfoam.models.base import PipelineModel
from sphfoam.models.viscosity import velocity_gradient_term
from sphfoam.registry import Coeffs, register


class Turbulence(PipelineModel):
    family = "turbulence"
    prefix = "turb_"


@register
class SmagorinskySPS(Turbulence):
    """Smagorinsky sub-particle-scale stress of Dalrymple & Rogers (2006), T(3.56)-(3.61).

    Per particle (pre-pass, walls included): the SPH velocity gradient of T(3.61),
    dv^i/dx^j = -sum_b m_b/rho_b v_ab^i dW_ab/dx_a^j; S_ij of T(3.59); |S| = sqrt(2 S_ij S_ij);
    nu_t = (Cs dx)^2 |S| of T(3.60); and the SPS stress of T(3.58) divided by rho,
    tau_ij/rho = 2 nu_t (S_ij - S_kk delta_ij / 3) - (2/3) CI dx^2 |S|^2 delta_ij, stored in
    ``turb_txx``, ``turb_txy``, ``turb_tyy`` (m^2/s^2). The filter width is the initial particle
    spacing dx. The 1/3 and 2/3 are the thesis' (three-dimensional) factors, kept in 2-D.

    In the rates loop the divergence enters the momentum equation in the standard symmetric SPH
    form (1/rho grad . tau)_a = sum_b m_b (tau_a/rho_a^2 + tau_b/rho_b^2) . grad_a W_ab, which
    conserves linear momentum. It is *added* to dv/dt: with tau of T(3.58) (positive eddy
    viscosity) this is the diffusive sign; T(3.57) prints a minus in front of grad . tau, which
    with T(3.58) as written would be anti-diffusive.
    """

    name = "smagorinskySPS"
    doc = ("Smagorinsky SPS stress (Dalrymple & Rogers 2006), T(3.56)-(3.61): nu_t = (Cs dx)^2 "
           "|S|, tau of T(3.58), sum_b m_b (tau_a/rho_a^2 + tau_b/rho_b^2).grad_a W_ab")

    class Coeffs(Coeffs):
        Cs: float = Field(0.12, ge=0.0, description="Smagorinsky constant Cs of T(3.60)")
        CI: float = Field(0.0066, ge=0.0, description="constant CI of the isotropic term of "
                          "T(3.58)")

    _STRESS = """\
sps_sxy = 0.5 * (sps_dudy + sps_dvdx)                                  # T(3.59)
sps_s2 = 2.0 * (sps_dudx * sps_dudx + sps_dvdy * sps_dvdy + 2.0 * sps_sxy * sps_sxy)  # |S|^2
sps_nut = turb_cs2 * math.sqrt(sps_s2)                                 # T(3.60)
sps_iso = -(2.0 / 3.0) * sps_nut * (sps_dudx + sps_dvdy) - turb_blin * sps_s2   # T(3.58)
aux[I_turb_txx, a] = 2.0 * sps_nut * sps_dudx + sps_iso
aux[I_turb_txy, a] = 2.0 * sps_nut * sps_sxy
aux[I_turb_tyy, a] = 2.0 * sps_nut * sps_dvdy + sps_iso"""

    # tau/rho^2 of a = aux/rho_a, loaded once per particle
    _INIT = """\
sps_xx_a = aux[I_turb_txx, a] / rhoa
sps_xy_a = aux[I_turb_txy, a] / rhoa
sps_yy_a = aux[I_turb_tyy, a] / rhoa"""
    _PAIR = """\
sps_xx = sps_xx_a + aux[I_turb_txx, b] / rhob
sps_xy = sps_xy_a + aux[I_turb_txy, b] / rhob
sps_yy = sps_yy_a + aux[I_turb_tyy, b] / rhob
acc_x += mb * (sps_xx * gWx + sps_xy * gWy)
acc_y += mb * (sps_xy * gWx + sps_yy * gWy)"""

    _TAU = ("aux.turb_txx", "aux.turb_txy", "aux.turb_tyy")

    def terms(self):
        return [velocity_gradient_term("sps", self._STRESS, self._TAU),
                Term("spsStress", ("rates",), init=self._INIT, pair=self._PAIR, reads=("gradW", *self._TAU), writes=("acc",))]

    def params(self, ctx):
        return {"turb_cs2": (self.coeffs.Cs * ctx.dx) ** 2,
                "turb_blin": (2.0 / 3.0) * self.coeffs.CI * ctx.dx ** 2}
