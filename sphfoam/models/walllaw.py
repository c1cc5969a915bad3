"""The turbulent wall condition of T §3.10 and §5.3.3 (Violeau & Issa 2007), T(3.84)-(3.87).

Selected beside the SPS closure (``turbulence { type smagorinskySPS; wallLaw smooth; }``,
:class:`sphfoam.models.turbulence.SmagorinskySPS`). Typical resolutions cannot resolve the
viscous sub-layer, so the wall particles are taken to lie a small distance delta from the
physical wall (delta = dx/10 by default, T §3.10), and the law of the wall holds in the fluid:

* smooth wall, T(3.84):  u_t = u* (ln(y u*/nu) / kappa + 5.2),
* rough wall,  T(3.85):  u_t = u* (ln(y/ks) / kappa + 8.5),
* prescribed U+ (T §5.3.3, best 1 < U+ < 2):  u_t = U+ u*,

with kappa = 0.41 and y the distance from the physical wall (delta in the thesis, which
applies the law at the wall particles). u_t is the tangential velocity of the fluid relative
to the wall particle a, the SPH interpolation of the fluid's velocity at a,
sum_b m_b/rho_b v_b W_ab / sum_b m_b/rho_b W_ab over its fluid neighbours b, minus v_a, with
its normal part removed (wall normal n stored by the set-up). That interpolation is the
velocity of the fluid at the kernel-weighted mean distance of those neighbours, so the law is
applied there, at y = delta + sum_b w_b n.(x_b - x_a) / sum_b w_b - (d_a - dx/2): the physical
wall delta behind the first wall row (d_a, the set-up's ``wallDist``, is dx/2 for the first
row). This is the first point of a grid wall function (T §5.3.3), and it makes u* exact for a
fluid whose velocity follows the law (the log's curvature across the kernel aside, < 1 %).
The thesis instead takes the law at delta and u* from the wall-normal gradient, T(3.86)-(3.87),
du/dn = u*/(kappa delta); at SPH resolution that gradient is the one across a particle spacing,
not the log layer's at delta, and gives u* too small by about delta/dx.

u* is solved on every wall particle, every evaluation (T §5.3.3: "at each time step"), in
numba: the smooth law by Newton's method (relative tolerance 1e-12), the others explicitly.
The smooth law meets the viscous sub-layer u+ = y+ at y+_c ~ 11.06; where y u_t/nu < y+_c^2
(the point inside the sub-layer) the linear law u_t = u*^2 y/nu is used instead, so u* is
defined, continuous and increasing in u_t for every u_t >= 0 (the standard wall function; the
thesis assumes the point outside the sub-layer).

The wall shear stress tau_w = rho u*^2, along the tangent t = u_t/|u_t|, replaces the SPS
stress of the wall particle, tau/rho = u*^2 (t n + n t) (the stress tensor of a shear flow
du_t/dn > 0 along the wall), and enters the fluid's momentum through the SPS divergence (T
§3.10: the condition acts through the wall particles, which stay where they are). For a wall
neighbour b the pair takes the wall's stress for both particles, sum_b m_b 2 tau_b/rho_b^2 .
grad_a W_ab: over the rows of a plane wall, sum_b V_b grad_a W_ab sums (over the fluid) to
-n/2 per unit wall length, so the wall exerts exactly -tau_w . n on the fluid (with the
symmetric tau_a/rho_a^2 + tau_b/rho_b^2 it would exert the mean of tau_w and the fluid's own
near-wall SPS stress).
"""

from __future__ import annotations

import math
from typing import Literal

from numba import njit
from pydantic import Field, model_validator

from sphfoam.engine.terms import Term
from sphfoam.registry import Coeffs

#: von Karman constant of T(3.84)-(3.85)
KAPPA = 0.41
#: the additive constants of the smooth, T(3.84), and rough, T(3.85), laws
B_SMOOTH = 5.2
B_ROUGH = 8.5
#: relative tolerance on u* of the Newton iteration on T(3.84)
TOLERANCE = 1e-12


def _crossing() -> float:
    """y+ where the linear sub-layer u+ = y+ meets the smooth log law T(3.84)."""
    y = 11.0
    for _ in range(200):
        y = math.log(y) / KAPPA + B_SMOOTH
    return y


#: y+_c of the sub-layer / log-law crossing (11.06 for kappa = 0.41, B = 5.2)
YPLUS_C = _crossing()


@njit(cache=True)
def smooth_ustar(ut, y, nu):
    """u* of the smooth-wall law T(3.84), u_t = u* (ln(y u*/nu)/kappa + 5.2), for the
    tangential velocity ut >= 0 at y from the wall; the linear sub-layer u_t = u*^2 y/nu
    where y ut/nu < y+_c^2. Newton's method from u* = ut/y+_c, which lies above the root
    (f(u*) = u*(ln(y u*/nu)/kappa + B) - ut is increasing and convex there), so the
    iterates decrease monotonically to it; stops at a relative step below TOLERANCE."""
    if ut <= 0.0:
        return 0.0
    if ut * y / nu < YPLUS_C * YPLUS_C:
        return math.sqrt(ut * nu / y)
    s = ut / YPLUS_C
    for _ in range(100):
        lg = math.log(y * s / nu) / KAPPA + B_SMOOTH
        step = (s * lg - ut) / (lg + 1.0 / KAPPA)
        s -= step
        if abs(step) <= TOLERANCE * s:
            break
    return s


@njit(cache=True)
def rough_ustar(ut, y, ks):
    """u* of the rough-wall law T(3.85), u_t = u* (ln(y/ks)/kappa + 8.5) (explicit); 0 where
    y is too close to the roughness for the law (ln(y/ks)/kappa + 8.5 <= 1)."""
    b = math.log(y / ks) / KAPPA + B_ROUGH
    return max(ut, 0.0) / b if b > 1.0 else 0.0


@njit(cache=True)
def uplus_ustar(ut, uplus):
    """u* of a prescribed U+ = u_t/u* (T §5.3.3)."""
    return max(ut, 0.0) / uplus


#: the call computing ``wl_us`` from ``wl_ut`` for each law
_CALLS = {
    "smooth": "wl_us = smooth_ustar(wl_ut, wl_y, turb_wlnu)",
    "rough": "wl_us = rough_ustar(wl_ut, wl_y, turb_wlks)",
    "prescribedUPlus": "wl_us = uplus_ustar(wl_ut, turb_wluplus)",
}
IMPORTS = {law: f"from sphfoam.models.walllaw import {call.split('= ')[1].split('(')[0]}"
           for law, call in _CALLS.items()}
LAWS = tuple(_CALLS)


class LawCoeffs(Coeffs):
    """The choice of law and its coefficient, shared by the turbulence closures' wall
    condition and the mirror ghosts' wall shear stress."""

    wallLaw: Literal["none", *LAWS] = Field(
        "none", description="the law of the wall, T §3.10: `smooth` T(3.84), `rough` T(3.85) "
        "(needs ks), `prescribedUPlus` u_t = UPlus u* (needs UPlus), `none` (nothing added)")
    ks: float | None = Field(None, gt=0.0, description="roughness length ks of T(3.85) "
                             "(m), wallLaw rough only")
    UPlus: float | None = Field(None, gt=0.0, description="prescribed U+ = u_t/u*, wallLaw "
                                "prescribedUPlus only (T §5.3.3: 1 < U+ < 2 best)")

    @model_validator(mode="after")
    def _law_coeffs(self):
        for law, key in (("rough", "ks"), ("prescribedUPlus", "UPlus")):
            given = getattr(self, key) is not None
            if self.wallLaw == law and not given:
                raise ValueError(f"wallLaw {law} needs {key}")
            if self.wallLaw != law and given:
                raise ValueError(f"{key} is used only with wallLaw {law} (wallLaw is "
                                 f"{self.wallLaw})")
        return self

_INIT = """\
wl_n@ = fld[F_n@, a]
wl_sw = 0.0
wl_sU@ = 0.0
wl_sn = 0.0"""
#: the SPH interpolation of the fluid's velocity relative to the wall particle a (the term
#: shares the pre-pass loop of the SPS velocity gradient, which sees every neighbour, so it
#: sees every neighbour too and takes the fluid ones, of the engine's kind FLUID)
_PAIR = """\
if kindb == FLUID:
    wl_w = mb / rhob * Wab
    wl_sw += wl_w
    wl_sU@ -= wl_w * U@_ab
    wl_sn -= wl_w * dot(d@_ab, wl_n@)     # n . (x_b - x_a)"""
_FINAL = """\
wl_us = 0.0
wl_tau = 0.0
wl_t@ = 0.0
if wl_sw > 0.0:
    # distance of the sample from the physical wall, delta behind the first wall row
    wl_y = turb_wldelta + wl_sn / wl_sw - (fld[F_wallDist, a] - turb_wld1)
    wl_U@ = wl_sU@ / wl_sw
    wl_un = dot(wl_U@, wl_n@)
    # the tangential velocity relative to the wall
    wl_t@ = wl_U@ - wl_un * wl_n@
    wl_ut = math.sqrt(dot(wl_t@, wl_t@))
    if wl_ut > 0.0 and wl_y > 0.0:
        {call}
        wl_tau = wl_us * wl_us / wl_ut            # u*^2 / |u_t|: times u_t, u*^2 t
aux[I_turb_txx, a] = 2.0 * wl_tau * wl_tx * wl_nx          # u*^2 (t n + n t)
aux[I_turb_txy, a] = wl_tau * (wl_tx * wl_ny + wl_ty * wl_nx)
aux[I_turb_tyy, a] = 2.0 * wl_tau * wl_ty * wl_ny
aux[I_turb_ustar, a] = wl_us"""


def wall_law_term(law: str) -> Term:
    """The pre-pass term of wall particles: u* from the law ``law`` and the SPS stress of the
    wall particle set to the wall shear stress (see the module docstring). It must come after
    the SPS stress of the wall particles (it overwrites it)."""
    return Term("wallLaw", ("prepass",), init=_INIT, pair=_PAIR,
                final=_FINAL.replace("{call}", _CALLS[law]), applies=("wall",),
                sees=("all",), reads=("W", "field.nx", "field.ny", "field.wallDist"),
                writes=("aux.turb_txx", "aux.turb_txy", "aux.turb_tyy", "aux.turb_ustar"),
                dims=(2,))
