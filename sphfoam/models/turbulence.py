"""Sub-particle-scale turbulence closures (T §3.5).

The ``none`` entry of the family lives in :mod:`sphfoam.models.noop` and adds nothing to the
pipeline.
"""

from __future__ import annotations

import math
from typing import ClassVar

from pydantic import Field, model_validator

import sphfoam.registry as registry
from sphfoam.case.errors import CaseError
from sphfoam.engine.hookforms import WallField
from sphfoam.engine.terms import Term
from sphfoam.models import walllaw as wl
from sphfoam.models.base import PipelineModel
from sphfoam.models.mirror import line_distance, nearest_line_distance, segment_array
from sphfoam.models.viscosity import velocity_gradient_term
from sphfoam.registry import Coeffs, register


class Turbulence(PipelineModel):
    family = "turbulence"
    prefix = "turb_"


class WallLawCoeffs(wl.LawCoeffs):
    """The turbulent wall condition's coefficients (T §3.10), shared by the closures."""

    #: whether ``wallDelta`` means something without a wall law (the mixing length's eta)
    delta_without_law: ClassVar[bool] = False

    wallDelta: float = Field(0.1, gt=0.0, description="distance delta of the wall "
                             "particles from the physical wall, in particle spacings dx "
                             "(T §3.10: dx/10)")

    @model_validator(mode="after")
    def _wall_delta(self):
        if self.wallLaw == "none" and "wallDelta" in self.model_fields_set and \
                not self.delta_without_law:
            raise ValueError("wallDelta is used only with a wallLaw (smooth, rough, "
                             "prescribedUPlus)")
        return self


@register
class SmagorinskySPS(Turbulence):
    """Smagorinsky sub-particle-scale stress of Dalrymple & Rogers (2006), T(3.56)-(3.61).

    Per particle (pre-pass, walls included): the SPH velocity gradient of T(3.61),
    dv^i/dx^j = -sum_b m_b/rho_b v_ab^i dW_ab/dx_a^j; S_ij of T(3.59); |S| = sqrt(2 S_ij S_ij);
    nu_t = (Cs dx)^2 |S| of T(3.60); and the SPS stress of T(3.58) divided by rho,
    tau_ij/rho = 2 nu_t (S_ij - S_kk delta_ij / 3) - (2/3) CI dx^2 |S|^2 delta_ij, stored in
    ``turb_txx``, ``turb_txy``, ``turb_tyy`` (m^2/s^2). The filter width is the initial particle
    spacing dx. The 1/3 and 2/3 are the thesis' (three-dimensional) factors, kept in 2-D. In
    3-D the same equations over the nine entries of the velocity gradient: the six entries
    ``turb_txx``, ``turb_txy``, ``turb_txz``, ``turb_tyy``, ``turb_tyz``, ``turb_tzz`` (the wall
    law is 2-D only: with ``wallLaw`` the model is refused in 3-D).

    In the rates loop the divergence enters the momentum equation in the standard symmetric SPH
    form (1/rho grad . tau)_a = sum_b m_b (tau_a/rho_a^2 + tau_b/rho_b^2) . grad_a W_ab, which
    conserves linear momentum. It is *added* to dv/dt: with tau of T(3.58) (positive eddy
    viscosity) this is the diffusive sign; T(3.57) prints a minus in front of grad . tau, which
    with T(3.58) as written would be anti-diffusive.

    ``wallLaw`` adds the turbulent wall condition of T §3.10, T(3.84)-(3.87) (Violeau & Issa
    2007; :mod:`sphfoam.models.walllaw`): on every wall particle the friction velocity u* from
    the law of the wall (``smooth`` T(3.84), ``rough`` T(3.85) with roughness ``ks``,
    ``prescribedUPlus`` u_t = ``UPlus`` u*, T §5.3.3) for the fluid's tangential velocity
    interpolated at the wall particle, the physical wall ``wallDelta`` dx behind the first
    wall row; the wall particle's stress becomes the wall shear stress
    tau/rho = u*^2 (t n + n t), which the fluid feels through the SPS divergence,
    a wall neighbour's stress taken for both particles of the pair, 2 tau_b/rho_b^2 (so that
    a plane wall exerts tau_w on the fluid, not the mean of tau_w and the fluid's own SPS stress).
    u* is stored in ``turb_ustar``. It needs wall particles the fluid sees as fluid (the
    boundaries ``stationaryGhosts`` and ``hybrid``). ``none`` (the default) adds nothing.
    """

    name = "smagorinskySPS"
    doc = ("Smagorinsky SPS stress (Dalrymple & Rogers 2006), T(3.56)-(3.61): nu_t = (Cs dx)^2 "
           "|S|, tau of T(3.58), sum_b m_b (tau_a/rho_a^2 + tau_b/rho_b^2).grad_a W_ab; "
           "wallLaw: the turbulent wall condition T(3.84)-(3.87)")

    class Coeffs(WallLawCoeffs):
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

    #: T(3.58)-(3.60) in three dimensions: the six entries of the symmetric tau/rho
    _STRESS_3D = """\
sps_sxy = 0.5 * (sps_dudy + sps_dvdx)                                  # T(3.59)
sps_sxz = 0.5 * (sps_dudz + sps_dwdx)
sps_syz = 0.5 * (sps_dvdz + sps_dwdy)
sps_s2 = 2.0 * (sps_dudx * sps_dudx + sps_dvdy * sps_dvdy + sps_dwdz * sps_dwdz
                + 2.0 * (sps_sxy * sps_sxy + sps_sxz * sps_sxz + sps_syz * sps_syz))  # |S|^2
sps_nut = turb_cs2 * math.sqrt(sps_s2)                                 # T(3.60)
sps_iso = -(2.0 / 3.0) * sps_nut * (sps_dudx + sps_dvdy + sps_dwdz) - turb_blin * sps_s2
aux[I_turb_txx, a] = 2.0 * sps_nut * sps_dudx + sps_iso
aux[I_turb_txy, a] = 2.0 * sps_nut * sps_sxy
aux[I_turb_txz, a] = 2.0 * sps_nut * sps_sxz
aux[I_turb_tyy, a] = 2.0 * sps_nut * sps_dvdy + sps_iso
aux[I_turb_tyz, a] = 2.0 * sps_nut * sps_syz
aux[I_turb_tzz, a] = 2.0 * sps_nut * sps_dwdz + sps_iso"""

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

    _INIT_3D = """\
sps_xx_a = aux[I_turb_txx, a] / rhoa
sps_xy_a = aux[I_turb_txy, a] / rhoa
sps_xz_a = aux[I_turb_txz, a] / rhoa
sps_yy_a = aux[I_turb_tyy, a] / rhoa
sps_yz_a = aux[I_turb_tyz, a] / rhoa
sps_zz_a = aux[I_turb_tzz, a] / rhoa"""
    _PAIR_3D = """\
sps_xx = sps_xx_a + aux[I_turb_txx, b] / rhob
sps_xy = sps_xy_a + aux[I_turb_txy, b] / rhob
sps_xz = sps_xz_a + aux[I_turb_txz, b] / rhob
sps_yy = sps_yy_a + aux[I_turb_tyy, b] / rhob
sps_yz = sps_yz_a + aux[I_turb_tyz, b] / rhob
sps_zz = sps_zz_a + aux[I_turb_tzz, b] / rhob
acc_x += mb * (sps_xx * gWx + sps_xy * gWy + sps_xz * gWz)
acc_y += mb * (sps_xy * gWx + sps_yy * gWy + sps_yz * gWz)
acc_z += mb * (sps_xz * gWx + sps_yz * gWy + sps_zz * gWz)"""

    #: with a wall law, a wall neighbour's stress is the wall shear stress, taken for both
    #: particles of the pair, so that a plane wall exerts exactly tau_w on the fluid
    _PAIR_WALL_LAW = """\
if kindb == FLUID:
    sps_xx = sps_xx_a + aux[I_turb_txx, b] / rhob
    sps_xy = sps_xy_a + aux[I_turb_txy, b] / rhob
    sps_yy = sps_yy_a + aux[I_turb_tyy, b] / rhob
else:
    sps_xx = 2.0 * aux[I_turb_txx, b] / rhob
    sps_xy = 2.0 * aux[I_turb_txy, b] / rhob
    sps_yy = 2.0 * aux[I_turb_tyy, b] / rhob
acc_x += mb * (sps_xx * gWx + sps_xy * gWy)
acc_y += mb * (sps_xy * gWx + sps_yy * gWy)"""

    _TAU = {2: ("aux.turb_txx", "aux.turb_txy", "aux.turb_tyy"),
            3: ("aux.turb_txx", "aux.turb_txy", "aux.turb_txz", "aux.turb_tyy",
                "aux.turb_tyz", "aux.turb_tzz")}

    @property
    def wall_law(self) -> str:
        return self.coeffs.wallLaw

    @property
    def particle_fields(self) -> tuple[str, ...]:
        """The wall normal and distance behind the wall line the wall law reads (written by
        the set-up for wall particles, sphfoam.case.geometry.wall_metadata)."""
        return ("nx", "ny", "wallDist") if self.wall_law != "none" else ()

    def terms(self):
        # 3-D: the general-dimension T(3.58)-(3.61); the wall law (its term) is 2-D only
        if self.wall_law == "none":
            init, pair = {2: self._INIT, 3: self._INIT_3D}, {2: self._PAIR, 3: self._PAIR_3D}
            stress = {2: self._STRESS, 3: self._STRESS_3D}
        else:
            init, pair, stress = {2: self._INIT}, {2: self._PAIR_WALL_LAW}, {2: self._STRESS}
        out = [velocity_gradient_term("sps", stress, self._TAU),
               Term("spsStress", ("rates",), init=init, pair=pair,
                    reads={d: ("gradW", *tau) for d, tau in self._TAU.items()},
                    writes=("acc",), viscous=True)]
        if self.wall_law != "none":
            out.append(wl.wall_law_term(self.wall_law))
        return out

    def imports(self):
        return [wl.IMPORTS[self.wall_law]] if self.wall_law != "none" else []

    def params(self, ctx):
        return {"turb_cs2": (self.coeffs.Cs * ctx.dx) ** 2,
                "turb_blin": (2.0 / 3.0) * self.coeffs.CI * ctx.dx ** 2,
                **self.wall_law_params(ctx)}

    def wall_law_params(self, ctx) -> dict[str, float]:
        """The coefficients of the wall law's term (none without a wall law)."""
        c = self.coeffs
        out = {}
        if c.wallLaw == "none":
            return out
        delta = c.wallDelta * ctx.dx
        out["turb_wldelta"] = delta
        out["turb_wld1"] = 0.5 * ctx.dx          # the first wall row's distance behind the wall line
        if c.wallLaw == "smooth":
            out["turb_wlnu"] = ctx.nu
        elif c.wallLaw == "rough":
            if math.log(delta / c.ks) / wl.KAPPA + wl.B_ROUGH <= 1.0:
                raise CaseError.single(
                    "constant/sphProperties", "turbulence.ks",
                    f"{c.ks:g} m is too large for delta = {delta:g} m (wallDelta dx): T(3.85) "
                    f"needs ln(delta/ks)/0.41 + 8.5 > 1, ks < "
                    f"{delta / math.exp(wl.KAPPA * (1.0 - wl.B_ROUGH)):.3g} m")
            out["turb_wlks"] = c.ks
        else:
            out["turb_wluplus"] = c.UPlus
        return out

    def selection_problems(self, sph: dict) -> list[tuple[str, str]]:
        """(key, message) for a boundary the wall law cannot work with: it needs wall
        particles that the fluid sees as fluid (kind wetWall), whose SPS stress it sets."""
        if self.wall_law == "none":
            return []
        bnd = sph.get("boundary")
        if bnd is None or _wall_law_boundary(bnd):
            return []
        ok = [n for n, cls in registry.families()["boundary"].items()
              if _wall_law_boundary(cls())]
        return [("wallLaw", f"wallLaw {self.wall_law} needs wall particles that enter the "
                 f"SPS stress as fluid; boundary {bnd.name} has none. Boundaries it works "
                 f"with: {', '.join(ok)}; or set wallLaw none"
                 + ("; mirrorGhosts takes the law of the wall as its own key, boundary "
                    "{ type mirrorGhosts; wallLaw ...; }" if bnd.name == "mirrorGhosts"
                    else ""))]


def _wall_law_boundary(bnd) -> bool:
    return bnd.wall_placement != "none" and "wetWall" in bnd.neighbour_kinds()


def _needs_walls(segments) -> None:
    """The mixing length is measured from the walls: a case without any is refused."""
    if not segments:
        raise CaseError.single("system/particleDict", "walls",
                               "turbulence mixingLength measures its mixing length from the "
                               "walls, and there are none")


@register
class MixingLength(SmagorinskySPS):
    """Prandtl's mixing-length eddy viscosity for wall-bounded flows, nu_t = l_m^2 |S|.

    The algebraic Reynolds-averaged closure (Pope 2000, §10.3; Violeau & Issa 2007 use
    mixing-length-based and k-epsilon closures for channel flows, T §5.3.2), in the stress
    machinery of the SPS model (velocity gradient T(3.61), S_ij T(3.59), |S| = sqrt(2 S_ij
    S_ij), tau/rho = 2 nu_t (S_ij - S_kk delta_ij/3), the symmetric divergence and the same
    turbulent wall condition ``wallLaw``), with the filter width Cs dx of T(3.60) replaced by
    the mixing length

        l_m = kappa eta sqrt(1 - eta/H)      (eta < H; 0 beyond; chosen as below),

    eta the particle's distance from the physical wall (``wallDelta`` dx behind the first wall
    row, as the wall law's) and H the ``outerLength`` (the half width of a closed channel, the
    depth of an open one; unset: l_m = kappa eta, the log layer's). In a fully developed
    channel the total shear stress falls linearly, tau = rho u*^2 (1 - eta/H), so this l_m
    makes l_m^2 (du/deta)^2 = u*^2 (1 - eta/H) hold for du/deta = u*/(kappa eta): the
    equilibrium profile is the log law up to the centre, the velocity-deficit law of T Fig
    3.15. The viscous sub-layer is not resolved (the first fluid row lies at y+ = dx u*/nu,
    ~ 800 in the tutorial, where van Driest's damping 1 - exp(-y+/26) is 1 to 1e-13); the
    wall law supplies the wall stress. No isotropic term (it would go into the pressure).

    eta = ``lineDist`` + dx/2 + delta, ``lineDist`` the signed distance of the particle to the
    nearest wall line of ``system/particleDict`` (written by the set-up, recomputed in numba
    from the wall segments, moved with prescribed motions, at every neighbour-list build:
    between builds no particle moves more than half the list's skin).

    The velocity gradient is taken over the fluid neighbours alone and corrected to first
    order (Bonet & Lok 1999): grad v = G L^-1, G = sum_b V_b (v_b - v_a) grad_a W_ab,
    L = sum_b V_b (x_b - x_a) grad_a W_ab (L = I in the bulk; uncorrected where det L < 0.1).
    The wall particles' zero velocity would give the first fluid row the gradient u/dx across
    the viscous sub-layer the wall law stands for (ten times the log layer's u*/(kappa eta) in
    the tutorial, a hundred times its stress): the wall's stress is the wall law's.
    """

    name = "mixingLength"
    doc = ("Prandtl mixing-length eddy viscosity (Pope 2000 §10.3), a Reynolds-averaged "
           "closure as Violeau & Issa (2007) use for channel flows: "
           "nu_t = l_m^2 |S|, l_m = kappa eta sqrt(1 - eta/H), eta the distance from the "
           "wall; stress, divergence and wallLaw as smagorinskySPS")

    class Coeffs(WallLawCoeffs):
        delta_without_law: ClassVar[bool] = True
        kappa: float = Field(0.41, gt=0.0, description="von Karman constant kappa of l_m")
        outerLength: float | None = Field(None, gt=0.0, description="outer length H of "
                                          "l_m = kappa eta sqrt(1 - eta/H) (m): the half "
                                          "width of a closed channel, the depth of an open "
                                          "one; unset: l_m = kappa eta")

    _STRESS = """\
sps_sxy = 0.5 * (sps_dudy + sps_dvdx)                                  # T(3.59)
sps_s2 = 2.0 * (sps_dudx * sps_dudx + sps_dvdy * sps_dvdy + 2.0 * sps_sxy * sps_sxy)  # |S|^2
ml_eta = fld[F_lineDist, a] + turb_mloff              # distance from the physical wall
ml_r = 1.0 - ml_eta * turb_mlinvh
ml_l = turb_kappa * ml_eta * math.sqrt(ml_r) if ml_eta > 0.0 and ml_r > 0.0 else 0.0
sps_nut = ml_l * ml_l * math.sqrt(sps_s2)                              # nu_t = l_m^2 |S|
sps_iso = -(2.0 / 3.0) * sps_nut * (sps_dudx + sps_dvdy)
aux[I_turb_txx, a] = 2.0 * sps_nut * sps_dudx + sps_iso
aux[I_turb_txy, a] = 2.0 * sps_nut * sps_sxy
aux[I_turb_tyy, a] = 2.0 * sps_nut * sps_dvdy + sps_iso"""

    @property
    def particle_fields(self) -> tuple[str, ...]:
        return ("lineDist",) + super().particle_fields

    #: the velocity gradient over the fluid neighbours, corrected to first order
    _GRAD_INIT = """\
sps_dudx = 0.0
sps_dudy = 0.0
sps_dvdx = 0.0
sps_dvdy = 0.0
ml_lxx = 0.0
ml_lxy = 0.0
ml_lyx = 0.0
ml_lyy = 0.0"""
    _GRAD_PAIR = """\
if kindb == FLUID:
    ml_vb = mb / rhob
    sps_dudx -= ml_vb * u_ab * gWx                 # G = sum_b V_b (v_b - v_a) grad_a W_ab
    sps_dudy -= ml_vb * u_ab * gWy
    sps_dvdx -= ml_vb * v_ab * gWx
    sps_dvdy -= ml_vb * v_ab * gWy
    ml_lxx -= ml_vb * dx_ab * gWx                  # L = sum_b V_b (x_b - x_a) grad_a W_ab
    ml_lxy -= ml_vb * dx_ab * gWy
    ml_lyx -= ml_vb * dy_ab * gWx
    ml_lyy -= ml_vb * dy_ab * gWy"""
    _GRAD_FINAL = """\
ml_det = ml_lxx * ml_lyy - ml_lxy * ml_lyx
if ml_det > 0.1:                                   # grad v = G L^-1 (exact for a linear v)
    ml_gux = (sps_dudx * ml_lyy - sps_dudy * ml_lyx) / ml_det
    sps_dudy = (sps_dudy * ml_lxx - sps_dudx * ml_lxy) / ml_det
    sps_dudx = ml_gux
    ml_gvx = (sps_dvdx * ml_lyy - sps_dvdy * ml_lyx) / ml_det
    sps_dvdy = (sps_dvdy * ml_lxx - sps_dvdx * ml_lxy) / ml_det
    sps_dvdx = ml_gvx
"""

    def terms(self):
        out = super().terms()
        out[0] = Term("mixingLengthGradient", ("prepass",), init=self._GRAD_INIT,
                      pair=self._GRAD_PAIR, final=self._GRAD_FINAL + self._STRESS,
                      applies=("all",), sees=("all",), reads=("gradW", "field.lineDist"),
                      writes=self._TAU, dims=(2,))
        return out

    def params(self, ctx):
        c = self.coeffs
        out = {"turb_kappa": c.kappa,
               "turb_mlinvh": 1.0 / c.outerLength if c.outerLength else 0.0,
               "turb_mloff": 0.5 * ctx.dx + c.wallDelta * ctx.dx}
        return {**out, **self.wall_law_params(ctx)}

    # --- run-time hooks: the wall distance of the moved particles ----------------------------
    #: the hooks below, declared (``device_forms``): lineDist from the walls' segments
    _LINE_DIST = WallField("lineDist", nearest_line_distance, segment_array,
                           check=_needs_walls)

    def device_forms(self):
        return (self._LINE_DIST,)

    def attach(self, run):
        _needs_walls(run.segments)
        self._seg = segment_array(run.segments)
        self._update(run)

    def walls_moved(self, run, offsets, velocities):
        self._seg = segment_array(run.segments, offsets, velocities)

    def before_neighbours(self, run):
        self._update(run)

    def keeps_neighbours(self, run):
        return True

    def _update(self, run):
        st = run.state
        line_distance(st.x, st.y, self._seg, st.extra[self._LINE_DIST.field])
