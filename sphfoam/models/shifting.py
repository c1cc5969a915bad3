"""Particle shifting (issue 13): positions move with v + delta_u, delta_u pushing particles
down the gradient of their concentration, so that they stay evenly spread (no voids, no
clumps, no tensile clustering) without any change to their velocity or momentum.

Family ``particleShifting``, selected beside a ``velocityCorrection`` (XSPH) or instead of it:
both act through the ``advection_velocity`` hook, applied in selection order (XSPH's v + dv,
then + delta_u).

Both models share

* a free-surface detection (``step`` stage, once per step): the smallest eigenvalue lambda_a of
  M_a = sum_b grad_a W_ab (x) r_ba V_b (1 for a full support, about 0.5 on a flat free surface,
  0 for an isolated particle), Marrone, Colagrossi, Le Touze & Graziani (2010, JCP 229),
  and the surface normal n_a = -L_a sum_b grad_a W_ab V_b / |...|, L_a = M_a^-1 (their
  renormalised gradient of the colour function); none (n_a = 0, the surface rule then
  leaves the shift whole) where |L_a nu_a| < 1e-6 / h, a full support whose sum is
  round-off and would point anywhere;
* the concentration gradient (``prepass`` stage, every evaluation; over every neighbour,
  walls included, so that a wall's particles fill the support), with the anti-clumping
  term of Monaghan (2000) as Lind et al. (2012) and Sun et al. (2017) write it,
  grad C_a = sum_b (1 + R (W_ab / W(dx))^n) grad_a W_ab V_b, R = 0.2, n = 4, with
  V_b = m_b / rho_b for fluid (and mirrored ghost) particles and V_b = dx^2 for wall particles:
  a rigid wall lattice stands for dx^2 a particle whatever density the boundary model gives
  it (evolved by the continuity equation for ``stationaryGhosts``, extrapolated for
  ``adami``). The anti-clumping term stirs still water: with R = 0.2 the still flume
  moves at 7 cm/s rms above its bed at d/dx = 20 before the wave arrives, and the wave loses
  4-5 % of its height over 16 m; R = 0 leaves the water still and the wave's height level,
  but a thin sheet climbing a wall then breaks up (docs/low-dissipation.md). ``surfaceR``
  weighs the term by its own R for a particle near the free surface (the surface rule's set
  below) and by R elsewhere: the anti-clumping part sum_b (W_ab/W(dx))^n grad_a W_ab V_b is
  then summed apart from the plain gradient and added with the particle's R at the end;
* the surface rule: a fluid particle with lambda_a < ``surfaceLambda`` (0.75, Marrone et al.'s
  bound of the interior) or with such a fluid neighbour is near the surface and keeps only the
  tangential part of its shift, delta_u - (delta_u . n_a) n_a (as Lind et al. 2012 do), so the
  surface is not smeared outwards. Wall particles are never shifted. With
  ``freeSurfaceLambda`` > 0 a fluid particle whose own lambda_a is below it (the surface row
  itself, the tip of a thin sheet) is not shifted at all; 0 (the default) leaves it to the
  tangential rule.

In 3-D (z up) the same equations in three dimensions, as the papers give them for any
dimension: M_a is 3 x 3 and lambda_a the smallest eigenvalue of its symmetric part, by the
closed form of the roots of a symmetric 3 x 3 matrix's characteristic cubic (Smith 1961,
CACM 4), with Marrone et al.'s same bounds (their criterion is stated for 2-D and 3-D);
n_a = -M_a^-1 nu_a / |...| with M_a^-1 = adj(M_a) / det M_a and the guard |det M_a| >
1e-3 |M_xx M_yy M_zz|; grad C, the anti-clumping term and the surface rule are written
once for the components (the tangential part is delta_u - (delta_u . n) n in 3-D as in 2-D),
a wall particle stands for dx^3, Lind's |v_a| has three components, and grad u_a of
``correctVelocity`` nine entries. Checked (tests/test_models_3d.py) on cubic lattices: no
shift of a uniform periodic one, a disordered one made more uniform, the faces of a block
found as its surface with outward normals (corners along the diagonal), the shift tangential
there.

The shift moves positions only: the momentum and continuity equations use v, so linear momentum
is unaffected (the Lagrangian re-meshing is an error of the order of the shift itself). With
``correctVelocity yes`` a fluid particle's velocity follows the flow to where the shift takes it:
du_a/dt gains (delta_u_a . grad) u_a, the first-order Taylor correction of Lind et al. (2012),
which is the convective term of the ALE equations of Sun, Colagrossi, Marrone, Antuono & Zhang
(2019, CMAME 348) for particles moving with u + delta_u; grad u_a = sum_b V_b (u_b - u_a)
grad_a W_ab over the fluid neighbours (walls' velocities are not the fluid's), summed in the same
pre-pass as grad C. ``correctDensity yes`` adds their density term, drho_a/dt += delta_u_a .
grad rho_a, the same way (in the rates and after the density-only pass).

With ``correctMass yes`` (and ``correctDensity yes``, which it needs) the shift also carries
mass between fluid particles, so that each particle's volume V_a = m_a / rho_a follows the
room its shifted position gives it: positions moving with u + delta_u make the arbitrary
Lagrangian-Eulerian (ALE) scheme of Vila (1999, Math. Models Methods Appl. Sci. 9) with the
shifting velocity as the transport velocity's departure from the flow, as Oger, Marrone, Le
Touze & de Leffe (2016, Comput. Phys. Commun. 200) combine them. Its conservation of mass for
the volume omega_a moving with v0 = u + delta_u,

    d(omega_a rho_a)/dt = -omega_a div(rho (u - v0))_a = omega_a div(rho delta_u)_a,

(Vila's mass equation; the papers' equation numbers were not at hand when this was written)
is written with the centred flux of their SPH-ALE form (no Riemann solver):

    dm_a/dt = V_a sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a W_ab   (fluid a, b),

antisymmetric in (a, b), so the fluid's mass is conserved to round-off. A particle's mass
is bounded below (``massFloor``): each pair's flux is scaled by a factor of its donor alone
(the particle it leaves, which the flux's sign tells), 1 while the donor holds at least 1.2
massFloor rho0 dx^d and falling linearly to 0 at massFloor rho0 dx^d, as flux-corrected
transport limits a cell's outflow to keep it positive (Zalesak 1979, J. Comput. Phys. 31).
The scaled flux is still antisymmetric (the donor of (b, a) is the donor of (a, b)), so the
mass stays conserved, and a light particle still receives mass. With the density's
own ALE term (``correctDensity``: drho_a/dt = -rho_a div u_a + delta_u_a . grad rho_a) the
volume then obeys dV_a/dt = V_a div(u + delta_u)_a: it grows where the shift spreads the
particles and shrinks where it packs them, as their spacing does, and the density stays the
flow's. Without it the shift moves the particles but not their volumes, and the two drift
apart (the flume's bulk at 0.994 of its volume by sum_b V_b W_ab, docs/low-dissipation.md).
The flux is summed in the rates pass (after the pre-pass that makes delta_u), and the mass of
the last evaluation's flux is added once per step, m_a += dt dm_a/dt, after the step
(``after_step``). It reads delta_u of the neighbours, so the rates pass gathers over full
lists where this is selected.

With ``consistentContinuity yes`` the density takes the continuity equation of the
consistent shifting of Sun, Colagrossi, Marrone, Antuono & Zhang (2019, CMAME 348), for
particles moving with u + delta_u and a mass kept by each:

    drho_a/dt += sum_b m_b (delta_u_a - delta_u_b) . grad_a W_ab
               + sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a W_ab,

the first the continuity's pair term T(3.18) with the shift's velocity (each density then
changes as its kernel sum does when the shift moves the particles: -rho div delta_u), the
second the shift's mass flux div(rho delta_u) in its sum form (the two together are
delta_u . grad rho in the continuum, and the first alone is unstable at walls and in still
water), over the neighbours the continuity sees (a wall's delta_u is 0), summed in the rates
pass and added after the rates and after the density-only pass (from the last rates
evaluation). It stops the packing drift of the density diffusion with the shift in still
water; at d/dx = 40 it needs the density filter to diffuse over the fluid alone (``walls
no``), without which the water's density rises and the run blows up
(docs/low-dissipation.md, *The packing drift in still water* and *What packs the
particles*). Not with ``correctDensity`` or ``correctMass``.
"""

from __future__ import annotations

from numba import njit, prange
from pydantic import Field, model_validator

from sphfoam.engine.fastmath import FASTMATH
from sphfoam.engine.hookforms import AdvectionCorrection, AuxAddition
from sphfoam.engine.stepping import components
from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.models.corrections import add_rate, corrected_velocity
from sphfoam.registry import Coeffs, register


class _ShiftCoeffs(Coeffs):
    R: float = Field(0.2, ge=0.0, description="strength R of the anti-clumping term "
                     "(1 + R (W_ab/W(dx))^n), 0.2 in Lind et al. 2012 and Sun et al. 2017; "
                     "0: none (still water stays still and a wave over a flat bed keeps its "
                     "height, but a thin sheet climbing a wall breaks up)")
    surfaceR: float | None = Field(None, ge=0.0, description=(
        "R for a particle near the free surface (the surface rule's particles: a thin sheet, "
        "the surface rows); R elsewhere. Unset (the default): R everywhere. R 0 with surfaceR "
        "0.2 keeps still water still and a wall-bound sheet together"))
    n: float = Field(4.0, gt=0.0, description="exponent n of the anti-clumping term (4)")
    surfaceLambda: float = Field(0.75, ge=0.0, le=1.0, description=(
        "a fluid particle whose lambda (smallest eigenvalue of sum grad W (x) r_ba V_b) or a "
        "fluid neighbour's is below this is near the free surface and is shifted only "
        "tangentially (0.75: Marrone et al. 2010's interior bound; 0: never)"))
    freeSurfaceLambda: float = Field(0.0, ge=0.0, le=1.0, description=(
        "a fluid particle whose own lambda is below this is on the free surface and is not "
        "shifted at all (0, the default: it is shifted tangentially like the particles "
        "next to it; 0.55 keeps a flat surface's first row, lambda ~ 0.5, and the tip of a "
        "sheet in place)"))
    correctVelocity: bool = Field(False, description=(
        "correct each fluid particle's velocity for its shift: du_a/dt += (delta_u_a . grad) "
        "u_a, the first-order Taylor correction of Lind et al. (2012) written as the "
        "convective term of the ALE form (Sun et al. 2019); grad u_a = sum_b V_b (u_b - u_a) "
        "grad_a W_ab over fluid neighbours. no (the default): the shift moves positions only"))
    correctDensity: bool = Field(False, description=(
        "correct each fluid particle's density for its shift: drho_a/dt += delta_u_a . grad "
        "rho_a (the same Taylor correction for the density; without it a particle shifted "
        "down a hydrostatic column is too light for its new depth by rho0 g dz / c0^2); "
        "grad rho_a = sum_b V_b (rho_b - rho_a) grad_a W_ab over fluid neighbours"))
    correctMass: bool = Field(False, description=(
        "carry mass with the shift, so that each particle's volume m/rho follows its shifted "
        "position: dm_a/dt = V_a sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a "
        "W_ab over fluid neighbours, the ALE mass flux of Vila (1999) / Oger et al. (2016) "
        "with the shift as the transport velocity's departure from the flow; conserves the "
        "fluid's mass to round-off. Needs correctDensity yes (the density's own ALE term)"))
    consistentContinuity: bool = Field(False, description=(
        "the continuity equation of Sun et al. (2019)'s consistent shifting: drho_a/dt += "
        "sum_b m_b (delta_u_a - delta_u_b) . grad_a W_ab (the continuity T(3.18) for "
        "particles moving with u + delta_u, so each density follows the room its shifted "
        "position gives it) + sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a W_ab "
        "(div(rho delta_u), the shift's mass flux kept in the density), over the "
        "continuity's neighbours (walls' delta_u = 0). no (the default): the shift moves the "
        "particles but not their densities. In still water it stops the packing drift; at "
        "d/dx = 40 it needs the density filter's walls no (docs/low-dissipation.md)"))
    massFloor: float = Field(0.5, gt=0.0, lt=0.8, description=(
        "correctMass: the least mass of a fluid particle, as a fraction of rho0 dx^d; the "
        "mass a particle gives fades linearly to nothing from 1.2 massFloor down to "
        "massFloor (what it receives is not limited), so the fluid's mass is still "
        "conserved"))

    @model_validator(mode="after")
    def _mass_needs_density(self):
        if "massFloor" in self.model_fields_set and not self.correctMass:
            raise ValueError("massFloor bounds the mass that correctMass carries: it "
                             "applies with correctMass yes only")
        if self.consistentContinuity and (self.correctDensity or self.correctMass):
            raise ValueError("consistentContinuity moves each particle's density with its "
                             "shift already (the continuity with u + delta_u and div(rho "
                             "delta_u)): it is not combined with correctDensity or "
                             "correctMass")
        if self.correctMass and not self.correctDensity:
            raise ValueError("correctMass needs correctDensity yes: the mass flux keeps the "
                             "volumes m/rho consistent with the shifted positions only "
                             "beside the density's ALE term delta_u . grad rho")
        return self


@njit(parallel=True, cache=True, fastmath=set(FASTMATH))
def add_to_fluid(target, rate, kind, dt):
    """target_a += dt rate_a for the fluid particles (kind 0); walls keep theirs (the mass
    correctMass carries, dt the step; the density rate of consistentContinuity, dt 1)."""
    for a in prange(target.shape[0]):
        if kind[a] == 0:
            target[a] += dt * rate[a]


def _sum_names(init: str) -> tuple[str, ...]:
    """The per-particle sums an ``init`` code sets to zero."""
    return tuple(line.split("=")[0].strip() for line in init.splitlines() if "=" in line)


def _mirrored(pair: str, init: str) -> str:
    """The reaction of a gradient's pair code: b's sum for the pair (b, a). For a gradient
    sum_b V_b (f_b - f_a) grad_a W_ab both factors change sign, so b's term is a's with a's
    volume and kind test: the sums (the names ``init`` sets) become their ``_b`` forms."""
    out = pair.replace("kindb", "kinda").replace("shift_vb", "shift_va")
    for name in _sum_names(init):
        out = out.replace(f"{name} ", f"{name}_b ")
    return out


class ParticleShifting(PipelineModel):
    """Shared terms (see the module docstring); a subclass sets the magnitude ``_COEF``: the
    code of ``shift_k`` with delta_u_a = -shift_k grad C_a."""

    family = "particleShifting"
    prefix = "shift_"
    _SURF = ("aux.shift_lambda", "aux.shift_n@")
    _DU = ("aux.shift_dU@",)
    _COEF: str
    #: the magnitude in 3-D (where it reads the speed: three components)
    _COEF_3D: str = ""
    #: the run-time hooks (the advection velocity, the corrections' rates) take 2 or 3
    #: components
    hook_dims = (2, 3)

    _DETECT_INIT = """\
shift_mxx = 0.0
shift_mxy = 0.0
shift_myx = 0.0
shift_myy = 0.0
shift_g@ = 0.0
"""
    # M = sum_b grad_a W_ab (x) r_ba V_b with r_ba = -r_ab; nu = sum_b grad_a W_ab V_b
    _DETECT_PAIR = """\
shift_vb = mb / rhob
shift_mxx -= gWx * dx_ab * shift_vb
shift_mxy -= gWx * dy_ab * shift_vb
shift_myx -= gWy * dx_ab * shift_vb
shift_myy -= gWy * dy_ab * shift_vb
shift_g@ += gW@ * shift_vb
"""
    _DETECT_FINAL = """\
shift_sxy = 0.5 * (shift_mxy + shift_myx)
shift_half = 0.5 * (shift_mxx - shift_myy)
aux[I_shift_lambda, a] = 0.5 * (shift_mxx + shift_myy) - math.sqrt(shift_half * shift_half
                                                                   + shift_sxy * shift_sxy)
shift_det = shift_mxx * shift_myy - shift_mxy * shift_myx
if abs(shift_det) > 1e-3 * abs(shift_mxx * shift_myy) and abs(shift_det) > 0.0:
    shift_nx = -(shift_myy * shift_gx - shift_mxy * shift_gy) / shift_det
    shift_ny = -(shift_mxx * shift_gy - shift_myx * shift_gx) / shift_det
else:
    shift_n@ = -shift_g@
shift_nn = math.sqrt(dot(shift_n@, shift_n@))
if shift_nn > shift_nmin:
    aux[I_shift_n@, a] = shift_n@ / shift_nn
else:
    aux[I_shift_n@, a] = 0.0
"""
    #: 3-D: M is 3 x 3 (nine entries); lambda_a the smallest eigenvalue of its symmetric
    #: part by the closed form for a symmetric 3 x 3 matrix (Smith 1961: the roots of the
    #: characteristic cubic as q + 2 p cos(phi + 2 pi k / 3)); n_a = -M^-1 nu / |...| with
    #: M^-1 = adj(M) / det M, the same guard as in 2-D (|det M| against |M_xx M_yy M_zz|)
    _DETECT_INIT_3D = """\
shift_mx@ = 0.0
shift_my@ = 0.0
shift_mz@ = 0.0
shift_g@ = 0.0
"""
    _DETECT_PAIR_3D = """\
shift_vb = mb / rhob
shift_mx@ -= gWx * d@_ab * shift_vb
shift_my@ -= gWy * d@_ab * shift_vb
shift_mz@ -= gWz * d@_ab * shift_vb
shift_g@ += gW@ * shift_vb
"""
    _DETECT_FINAL_3D = """\
shift_sxy = 0.5 * (shift_mxy + shift_myx)
shift_sxz = 0.5 * (shift_mxz + shift_mzx)
shift_syz = 0.5 * (shift_myz + shift_mzy)
shift_q = (shift_mxx + shift_myy + shift_mzz) / 3.0
shift_p1 = shift_sxy * shift_sxy + shift_sxz * shift_sxz + shift_syz * shift_syz
shift_bxx = shift_mxx - shift_q
shift_byy = shift_myy - shift_q
shift_bzz = shift_mzz - shift_q
shift_p2 = shift_bxx * shift_bxx + shift_byy * shift_byy + shift_bzz * shift_bzz + 2.0 * shift_p1
if shift_p2 > 0.0:
    shift_p = math.sqrt(shift_p2 / 6.0)
    shift_cr = 0.5 * (shift_bxx * (shift_byy * shift_bzz - shift_syz * shift_syz)
                     - shift_sxy * (shift_sxy * shift_bzz - shift_syz * shift_sxz)
                     + shift_sxz * (shift_sxy * shift_syz - shift_byy * shift_sxz)) / (
                         shift_p * shift_p * shift_p)
    shift_cr = min(1.0, max(-1.0, shift_cr))
    shift_phi = math.acos(shift_cr) / 3.0
    aux[I_shift_lambda, a] = shift_q + 2.0 * shift_p * math.cos(shift_phi
                                                                  + 2.0943951023931957)
else:
    aux[I_shift_lambda, a] = shift_q
shift_axx = shift_myy * shift_mzz - shift_myz * shift_mzy
shift_axy = shift_mxz * shift_mzy - shift_mxy * shift_mzz
shift_axz = shift_mxy * shift_myz - shift_mxz * shift_myy
shift_ayx = shift_myz * shift_mzx - shift_myx * shift_mzz
shift_ayy = shift_mxx * shift_mzz - shift_mxz * shift_mzx
shift_ayz = shift_mxz * shift_myx - shift_mxx * shift_myz
shift_azx = shift_myx * shift_mzy - shift_myy * shift_mzx
shift_azy = shift_mxy * shift_mzx - shift_mxx * shift_mzy
shift_azz = shift_mxx * shift_myy - shift_mxy * shift_myx
shift_det = shift_mxx * shift_axx + shift_mxy * shift_ayx + shift_mxz * shift_azx
if abs(shift_det) > 1e-3 * abs(shift_mxx * shift_myy * shift_mzz) and abs(shift_det) > 0.0:
    shift_nx = -(shift_axx * shift_gx + shift_axy * shift_gy + shift_axz * shift_gz) / shift_det
    shift_ny = -(shift_ayx * shift_gx + shift_ayy * shift_gy + shift_ayz * shift_gz) / shift_det
    shift_nz = -(shift_azx * shift_gx + shift_azy * shift_gy + shift_azz * shift_gz) / shift_det
else:
    shift_n@ = -shift_g@
shift_nn = math.sqrt(dot(shift_n@, shift_n@))
if shift_nn > shift_nmin:
    aux[I_shift_n@, a] = shift_n@ / shift_nn
else:
    aux[I_shift_n@, a] = 0.0
"""
    # shift_ns counts the fluid neighbours near the surface (a sum, so that the half-list
    # prepass can add b's count to it)
    _SHIFT_INIT = """\
shift_c@ = 0.0
shift_ns = 0.0
shift_iwdx = 1.0 / (kern_w * kernel_f(shift_qdx))
"""
    _SHIFT_PAIR = """\
shift_w = 1.0 + shift_r * (Wab * shift_iwdx) ** shift_n
shift_vb = mb / rhob if kindb != WALL else shift_vw
shift_c@ += shift_w * gW@ * shift_vb
if kindb == FLUID and aux[I_shift_lambda, b] < shift_lam:
    shift_ns += 1.0
"""
    #: with ``surfaceR``: the plain gradient and the anti-clumping part summed apart, so that
    #: the final code weighs the latter with R or surfaceR by whether a is near the surface
    _SPLIT_INIT = """\
shift_k@ = 0.0
"""
    _SPLIT_PAIR = """\
shift_w = (Wab * shift_iwdx) ** shift_n
shift_vb = mb / rhob if kindb != WALL else shift_vw
shift_c@ += gW@ * shift_vb
shift_k@ += shift_w * gW@ * shift_vb
if kindb == FLUID and aux[I_shift_lambda, b] < shift_lam:
    shift_ns += 1.0
"""
    _SPLIT_REACTION = """\
shift_va = ma / rhoa if kinda != WALL else shift_vw
shift_c@_b -= gW@ * shift_va
shift_k@_b -= shift_w * gW@ * shift_va
if kinda == FLUID and aux[I_shift_lambda, a] < shift_lam:
    shift_ns_b += 1.0
"""
    _SPLIT_FINAL = """\
shift_ra = shift_rs if shift_near else shift_r
shift_c@ += shift_ra * shift_k@
"""
    #: b's sums for the pair (b, a): grad_b W_ba = -gW@, V_a, and a near the surface (the
    #: anti-clumping factor shift_w is the pair's own, W_ba = W_ab)
    _SHIFT_REACTION = """\
shift_va = ma / rhoa if kinda != WALL else shift_vw
shift_c@_b -= shift_w * gW@ * shift_va
if kinda == FLUID and aux[I_shift_lambda, a] < shift_lam:
    shift_ns_b += 1.0
"""
    #: with correctVelocity: grad u_a = sum_b V_b (u_b - u_a) grad_a W_ab over fluid b (b's sum
    #: from the pair (b, a), V_a (u_a - u_b) grad_b W_ba, has the same sign: ``_mirrored``);
    #: appended to ``_SHIFT_PAIR``, whose shift_vb (m_b / rho_b for a fluid b) it reads
    _GRADU_INIT = """\
shift_gux = 0.0
shift_guy = 0.0
shift_gvx = 0.0
shift_gvy = 0.0
"""
    _GRADU_PAIR = """\
if kindb == FLUID:
    shift_gux -= u_ab * gWx * shift_vb
    shift_guy -= u_ab * gWy * shift_vb
    shift_gvx -= v_ab * gWx * shift_vb
    shift_gvy -= v_ab * gWy * shift_vb
"""
    #: 3-D: the nine entries of grad u (shift_gu@ = d u / d@, shift_gv@, shift_gw@)
    _GRADU_INIT_3D = """\
shift_gu@ = 0.0
shift_gv@ = 0.0
shift_gw@ = 0.0
"""
    _GRADU_PAIR_3D = """\
if kindb == FLUID:
    shift_gu@ -= u_ab * gW@ * shift_vb
    shift_gv@ -= v_ab * gW@ * shift_vb
    shift_gw@ -= w_ab * gW@ * shift_vb
"""
    #: with correctDensity: grad rho_a = sum_b V_b (rho_b - rho_a) grad_a W_ab over fluid b
    #: (b's sum from the pair (b, a) has the same sign: ``_mirrored``)
    _GRADRHO_INIT = """\
shift_gr@ = 0.0
"""
    _GRADRHO_PAIR = """\
if kindb == FLUID:
    shift_gr@ += (rhob - rhoa) * gW@ * shift_vb
"""
    _GRADRHO_FINAL = """\
if kind[a] == FLUID:
    aux[I_shift_drho, a] = dot(aux[I_shift_dU@, a], shift_gr@)
else:
    aux[I_shift_drho, a] = 0.0
"""
    #: (delta_u . grad) u, the acceleration ``after_rates`` adds
    _GRADU_FINAL = """\
if kind[a] == FLUID:
    aux[I_shift_ax, a] = aux[I_shift_du, a] * shift_gux + aux[I_shift_dv, a] * shift_guy
    aux[I_shift_ay, a] = aux[I_shift_du, a] * shift_gvx + aux[I_shift_dv, a] * shift_gvy
else:
    aux[I_shift_ax, a] = 0.0
    aux[I_shift_ay, a] = 0.0
"""
    _GRADU_FINAL_3D = """\
if kind[a] == FLUID:
    aux[I_shift_ax, a] = dot(aux[I_shift_dU@, a], shift_gu@)
    aux[I_shift_ay, a] = dot(aux[I_shift_dU@, a], shift_gv@)
    aux[I_shift_az, a] = dot(aux[I_shift_dU@, a], shift_gw@)
else:
    aux[I_shift_ax, a] = 0.0
    aux[I_shift_ay, a] = 0.0
    aux[I_shift_az, a] = 0.0
"""
    _SHIFT_FINAL = """\
shift_near = shift_ns > 0.0 or aux[I_shift_lambda, a] < shift_lam
{split}if kind[a] == FLUID:
{coef}
    shift_dU@ = -shift_k * shift_c@
    if shift_near:
        shift_dn = dot(shift_dU@, aux[I_shift_n@, a])
        shift_dU@ -= shift_dn * aux[I_shift_n@, a]
    if shift_lamf > 0.0 and aux[I_shift_lambda, a] < shift_lamf:
        shift_dU@ = 0.0
    aux[I_shift_dU@, a] = shift_dU@
else:
    aux[I_shift_dU@, a] = 0.0
"""

    #: with correctMass: the ALE mass flux, Vila (1999) / Oger et al. (2016), centred:
    #: dm_a/dt = V_a sum_b V_b (rho_a delta_u_a + rho_b delta_u_b) . grad_a W_ab over fluid b,
    #: in the rates pass, which follows the pre-pass that made delta_u of every particle
    #: each pair's flux scaled by its donor's limiter, min(max((m / (rho0 dx^d) - floor) /
    #: (0.2 floor), 0), 1): a's own where the flux leaves a (negative), b's where it leaves b
    _MASS_INIT = """\
shift_fa@ = rhoa * aux[I_shift_dU@, a]
shift_mf = 0.0
shift_ga = min(max((m[a] * shift_im0 - shift_mfl) * shift_mrp, 0.0), 1.0)
"""
    _MASS_PAIR = """\
if kindb == FLUID:
    shift_f@ = shift_fa@ + rhob * aux[I_shift_dU@, b]
    shift_g = mb / rhob * dot(shift_f@, gW@)
    if shift_g < 0.0:
        shift_g *= shift_ga
    else:
        shift_g *= min(max((mb * shift_im0 - shift_mfl) * shift_mrp, 0.0), 1.0)
    shift_mf += shift_g
"""
    _MASS_FINAL = """\
aux[I_shift_mdot, a] = m[a] / rhoa * shift_mf
"""

    #: with consistentContinuity, Sun et al. (2019): the continuity's pair term T(3.18)
    #: with the shift's velocity, m_b (delta_u_a - delta_u_b) . grad_a W_ab, and the shift's
    #: mass flux div(rho delta_u)_a in its sum form V_b (rho_a delta_u_a + rho_b delta_u_b) .
    #: grad_a W_ab, over the neighbours the continuity sees (a wall's delta_u is 0), in the
    #: rates pass after the pre-pass that made delta_u
    _CONSISTENT_INIT = """\
shift_va@ = aux[I_shift_dU@, a]
shift_fa@ = rhoa * shift_va@
shift_drc = 0.0
"""
    _CONSISTENT_PAIR = """\
shift_vb@ = aux[I_shift_dU@, b]
shift_w@ = shift_va@ - shift_vb@
shift_f@ = shift_fa@ + rhob * shift_vb@
shift_drc += mb * (dot(shift_w@, gW@) + dot(shift_f@, gW@) / rhob)
"""
    _CONSISTENT_FINAL = """\
aux[I_shift_drho_cont, a] = shift_drc
"""

    def imports(self):
        return ["import math"]

    def params(self, ctx: CaseContext):
        c = self.coeffs
        return {"shift_r": c.R, "shift_rs": c.R if c.surfaceR is None else c.surfaceR,
                "shift_n": c.n, "shift_lam": c.surfaceLambda,
                "shift_lamf": c.freeSurfaceLambda,
                # a wall particle's volume: dx^2 in 2-D, dx^3 in 3-D
                "shift_qdx": ctx.dx / ctx.h,
                # the smallest |L_a nu_a| taken as a direction: a full support's is round-off
                # (1e-15 / h) and points anywhere; the surface's is of order 1 / h
                "shift_nmin": 1e-6 / ctx.h,
                "shift_vw": ctx.dx * ctx.dx * (ctx.dx if ctx.dim == 3 else 1.0),
                **self.magnitude(ctx), **self._mass_limiter(ctx)}

    def _mass_limiter(self, ctx: CaseContext) -> dict[str, float]:
        """correctMass's limiter: 1 / (rho0 dx^d), the floor, 1 / its ramp (none without)."""
        c = self.coeffs
        if not c.correctMass:
            return {}
        return {"shift_im0": 1.0 / (ctx.rho0 * ctx.dx ** ctx.dim),
                "shift_mfl": c.massFloor, "shift_mrp": 1.0 / (0.2 * c.massFloor)}

    def magnitude(self, ctx: CaseContext) -> dict[str, float]:
        return {}

    def _shift_code(self, dim: int):
        """The shifting vector's (init, pair, reaction, final, writes, sums) in ``dim``
        dimensions: the 2-D text as before; in 3-D the same lines (written with ``@``) but
        the magnitude (|v| of three components) and grad u (nine entries)."""
        split = self._split
        coef = self._COEF if dim == 2 else self._COEF_3D
        final = (self._SHIFT_FINAL.replace("{coef}", "    " + coef)
                 .replace("{split}", self._SPLIT_FINAL if split else ""))
        # an integer exponent n (4, the default) written as a literal: numba then multiplies
        # (about 2 ns per pair) instead of calling pow (about 20 ns)
        n = self.coeffs.n
        pair = self._SPLIT_PAIR if split else self._SHIFT_PAIR
        if float(n).is_integer() and 1 <= n <= 16:
            pair = pair.replace("** shift_n", f"** {int(n)}")
        init, reaction, writes = self._SHIFT_INIT, self._SHIFT_REACTION, self._DU
        sums = ("shift_c@", "shift_ns")
        if split:
            init += self._SPLIT_INIT
            reaction = self._SPLIT_REACTION
            sums += _sum_names(self._SPLIT_INIT)
        gradu = ((self._GRADU_INIT, self._GRADU_PAIR, self._GRADU_FINAL,
                  ("aux.shift_ax", "aux.shift_ay")) if dim == 2 else
                 (self._GRADU_INIT_3D, self._GRADU_PAIR_3D, self._GRADU_FINAL_3D,
                  ("aux.shift_ax", "aux.shift_ay", "aux.shift_az")))
        # the corrections' gradients: sums of their own in the same pre-pass
        for on, g_init, g_pair, g_final, g_writes in (
                (self.coeffs.correctVelocity, *gradu),
                (self.coeffs.correctDensity, self._GRADRHO_INIT, self._GRADRHO_PAIR,
                 self._GRADRHO_FINAL, ("aux.shift_drho",))):
            if on:
                init += g_init
                pair += g_pair
                reaction += _mirrored(g_pair, g_init)
                final += g_final
                writes += g_writes
                sums += _sum_names(g_init)
        return init, pair, reaction, final, writes, sums

    def terms(self):
        code = {d: self._shift_code(d) for d in (2, 3)}
        init, pair, reaction, final, writes, sums = (
            {d: code[d][i] for d in (2, 3)} for i in range(6))
        terms = [Term("freeSurfaceDetection", ("step",),
                     init={2: self._DETECT_INIT, 3: self._DETECT_INIT_3D},
                     pair={2: self._DETECT_PAIR, 3: self._DETECT_PAIR_3D},
                     final={2: self._DETECT_FINAL, 3: self._DETECT_FINAL_3D},
                     applies=("fluid",), reads=("gradW",), writes=self._SURF),
                Term("shiftingVector", ("prepass",), init=init,
                     pair=pair, final=final, applies=("all",), sees=("all",),
                     reads=("W", "gradW", *self._SURF), writes=writes,
                     reaction=reaction, sums=sums,
                     nonfluid_discarded=True)]                   # walls are not shifted
        if self.coeffs.correctMass:          # the ALE mass flux: checked in 2-D only
            terms.append(Term("shiftMassFlux", ("rates",), init=self._MASS_INIT,
                              pair=self._MASS_PAIR, final=self._MASS_FINAL,
                              reads=("gradW", *self._DU), writes=("aux.shift_mdot",),
                              dims=(2,)))
        if self.coeffs.consistentContinuity:     # checked in 2-D only
            terms.append(Term("shiftContinuity", ("rates",), init=self._CONSISTENT_INIT,
                              pair=self._CONSISTENT_PAIR, final=self._CONSISTENT_FINAL,
                              reads=("gradW", *self._DU),
                              writes=("aux.shift_drho_cont",), dims=(2,)))
        return terms

    @property
    def _split(self) -> bool:
        """True where ``surfaceR`` differs from R: the anti-clumping part is summed apart."""
        c = self.coeffs
        return c.surfaceR is not None and c.surfaceR != c.R

    #: the hooks below, declared (``device_forms``): positions move with U + delta_u; the
    #: corrections' rates (delta_u . grad) u and delta_u . grad rho; the mass flux's dt dm/dt
    _ADVECTION = AdvectionCorrection("shift_dU@")
    _VELOCITY_RATE = AuxAddition("after_rates", "a@", "shift_a@")
    _DENSITY_RATE = AuxAddition("after_rates", "drho", "shift_drho")
    _DENSITY_ONLY_RATE = AuxAddition("after_density_rate", "drho", "shift_drho")
    _MASS = AuxAddition("after_step", "m", "shift_mdot", fluid_only=True)
    _CONTINUITY_RATE = AuxAddition("after_rates", "drho", "shift_drho_cont",
                                   fluid_only=True)
    _CONTINUITY_ONLY_RATE = AuxAddition("after_density_rate", "drho", "shift_drho_cont",
                                    fluid_only=True)

    def device_forms(self):
        c = self.coeffs
        return ((self._ADVECTION,)
                + ((self._VELOCITY_RATE,) if c.correctVelocity else ())
                + ((self._DENSITY_RATE, self._DENSITY_ONLY_RATE) if c.correctDensity else ())
                + ((self._MASS,) if c.correctMass else ())
                + ((self._CONTINUITY_RATE, self._CONTINUITY_ONLY_RATE)
                   if c.consistentContinuity else ()))

    def advection_velocity(self, run, *U):
        """Positions move with U + delta_u of the last pre-pass (walls: unchanged); ``U`` the
        velocity's components (u, v) or (u, v, w)."""
        dU = [run.aux(k) for k in components(self._ADVECTION.aux, len(U))]
        return corrected_velocity(self, run, U, dU)

    # the corrections' hooks exist only where they are selected (a model the case does not
    # select costs nothing: no call per evaluation)
    @property
    def after_rates(self):
        c = self.coeffs
        on = c.correctVelocity or c.correctDensity or c.consistentContinuity
        return self._add_rates if on else None

    @property
    def after_density_rate(self):
        c = self.coeffs
        return self._add_density_rate if (c.correctDensity or c.consistentContinuity) else None

    @property
    def after_step(self):
        return self._carry_mass if self.coeffs.correctMass else None

    def _carry_mass(self, run):
        """With ``correctMass``: m_a += dt dm_a/dt, the mass flux of the step's last rates
        evaluation over the step just taken (zero for walls)."""
        add_to_fluid(run.state.m, run.aux(self._MASS.aux), run.state.kind, run.last_dt)

    def _add_rates(self, run):
        """With ``correctVelocity``: du_a/dt += (delta_u_a . grad) u_a; with
        ``correctDensity``: drho_a/dt += delta_u_a . grad rho_a; both from the pre-pass of this
        evaluation (zero for walls)."""
        st = run.state
        if self.coeffs.correctVelocity:
            for acc, k in zip(st.accelerations,
                              components(self._VELOCITY_RATE.aux, len(st.accelerations))):
                add_rate(acc, run.aux(k))
        if self.coeffs.correctDensity:
            add_rate(st.drho, run.aux(self._DENSITY_RATE.aux))
        if self.coeffs.consistentContinuity:
            add_to_fluid(st.drho, run.aux(self._CONTINUITY_RATE.aux), st.kind, 1.0)

    def _add_density_rate(self, run):
        """With ``correctDensity``: the density-only pass gets delta_u . grad rho too, from
        the last pre-pass (whose delta_u moved the particles since); with
        ``consistentContinuity`` the shift's terms of the last rates evaluation, the same way."""
        if self.coeffs.correctDensity:
            add_rate(run.state.drho, run.aux(self._DENSITY_ONLY_RATE.aux))
        if self.coeffs.consistentContinuity:
            add_to_fluid(run.state.drho, run.aux(self._CONTINUITY_ONLY_RATE.aux),
                         run.state.kind, 1.0)


@register
class LindShifting(ParticleShifting):
    """Fickian shifting of Lind, Xu, Stansby & Rogers (2012, JCP 231):
    delta_r_a = -D grad C_a with D = A h |v_a| dt, i.e. the shifting velocity
    delta_u_a = delta_r_a / dt = -A h |v_a| grad C_a (independent of the step), A = 2 (their
    range 1 to 6); grad C with Monaghan's anti-clumping term and the surface rule of the module
    docstring. A particle at rest is not shifted.
    """

    name = "lindShifting"
    doc = ("Lind et al. (2012): delta_r = -A h |v| dt grad C, i.e. delta_u = -A h |v| grad C, grad C = sum_b "
           "(1 + R(W_ab/W(dx))^n) grad W_ab V_b; tangential only near the free surface")

    class Coeffs(_ShiftCoeffs):
        A: float = Field(2.0, gt=0.0, description="dimensionless shifting coefficient A of "
                         "D = A h |v| dt (Lind et al. 2012: 1 to 6)")

    _COEF = "shift_k = shift_ah * math.sqrt(ua * ua + va * va)"
    _COEF_3D = "shift_k = shift_ah * math.sqrt(ua * ua + va * va + wa * wa)"

    def magnitude(self, ctx):
        return {"shift_ah": self.coeffs.A * ctx.h}


@register
class DeltaPlusShifting(ParticleShifting):
    """delta+-SPH shifting of Sun, Colagrossi, Marrone & Zhang (2017, CMAME 315):
    delta_r_a = -CFL Ma (2h)^2 sum_b (1 + R (W_ab/W(dx))^n) grad_a W_ab V_b, written as a
    velocity with the acoustic time step of the same CFL number, dt = CFL h / c0:
    delta_u_a = -4 Ma c0 h grad C_a (the CFL cancels), Ma = U_max / c0 (0.1 for the usual
    c0 = 10 U_max). Independent of the particle's own speed; surface rule of the module
    docstring.
    """

    name = "deltaPlusShifting"
    doc = ("delta+-SPH shifting, Sun et al. (2017): delta_r = -CFL Ma (2h)^2 grad C, "
           "as delta_u = -4 Ma c0 h grad C; tangential only near the free surface")

    class Coeffs(_ShiftCoeffs):
        Ma: float = Field(0.1, gt=0.0, description="Mach number U_max / c0 of the flow (0.1 "
                          "for c0 = 10 U_max)")

    _COEF = "shift_k = shift_c"
    _COEF_3D = _COEF

    def magnitude(self, ctx):
        if not ctx.c0 > 0.0:
            raise ValueError("deltaPlusShifting needs the reference speed of sound c0 > 0")
        return {"shift_c": 4.0 * self.coeffs.Ma * ctx.c0 * ctx.h}


