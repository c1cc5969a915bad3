"""Solid-wall representations (T §3.8-3.9, P §4).

Five ways to keep water out of a wall, as the thesis compares them, and two later ones
(their own modules):

==========================  ===================  =============================================
model                       wall particles       how the fluid feels the wall
==========================  ===================  =============================================
``stationaryGhosts``        rows behind the wall pressure and viscosity of wall particles whose
                                                 density evolves by pairing (Violeau & Issa)
``repulsiveMonaghanKos``    one row, dx/2 behind normal force T(3.70)-(3.72), viscosity
``repulsiveMonaghan2003``   one row, dx/2 behind normal force T(3.73)-(3.76), viscosity
``mirrorGhosts``            none (segments)      fluid near a wall mirrored across it each
                                                 step, T(3.77)-(3.80) (free- or no-slip)
``hybrid``                  rows behind the wall stationary ghosts where wet, Monaghan-Kos
                                                 force (range dx) where dry, T §3.9
``adami`` (``adami``)       rows behind the wall pressure extrapolated from the fluid, AHA12
``mDBC`` (``mdbc``)         rows behind the wall stationary ghosts whose density is the fluid's
                                                 fit at their mirror image (English et al. 2022)
==========================  ===================  =============================================

Where the fluid pair loop meets a wall neighbour ``b`` the repulsive forms read the wall
normal ``fld[F_nx, b], fld[F_ny, b]`` (into the fluid) stored per wall particle by the set-up
(``sphfoam.case.geometry``). Corner treatment: a wall particle at a corner vertex (flag
``corner``) has no single normal, so it repels radially, along r_ab, with chi = 1 (the force
of a point rather than of a wall); its neighbours along either wall act with their own normals.

In three dimensions (axis-aligned walls: ``box`` tanks and ``block`` solids) the wall
particles of a face lie on a square lattice of side dx, and the tangential weight is the
product of the hat functions of T(3.76) along the face's two axes, chi = (1 - |t_1|/dx)+
(1 - |t_2|/dx)+, which sums to one over the face as chi(x) does along a 2-D wall. A particle
on an edge or at a vertex belongs to the lattices of its two or three faces and acts once
for each, along each face's normal (``n`` holds, per axis, the sign of the normal of each
face it belongs to): the force on a fluid particle beside two faces is the sum of the two
faces' forces, with no extra radial push (a 2-D corner's radial force, repeated along every
particle of an edge, would push the whole edge row of fluid off the walls).
"""

from __future__ import annotations

import textwrap
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from sphfoam.engine.state import GHOST, kept_arrays
from sphfoam.engine.terms import Term, collect
from sphfoam.models import mirror as gh
from sphfoam.models import mirror3d as m3
from sphfoam.models import walllaw as wl
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register


class Boundary(PipelineModel):
    family = "boundary"
    prefix = "bnd_"
    #: where set-up puts wall particles: "rows" (rows behind the wall line, cell centred, the
    #: first dx/2 behind it and dx from the first fluid row) or "none"
    wall_placement: str = "rows"
    #: rows of wall particles (None: the ``layers`` of each wall entry)
    wall_layers: int | None = None
    #: per-particle fields (set-up writes them for wall particles) the generated code reads
    #: as ``fld[F_<name>, b]``
    wall_fields: tuple[str, ...] = ()
    #: whether the boundary keeps particles of mass 0 in the neighbour list (dormant mirror
    #: ghosts); the generated maximum of T(3.89) then skips them (sphfoam.engine.bodies)
    massless_ghosts: bool = False
    #: True when the boundary leaves the wall particles' velocities as set up (they change
    #: only with prescribed motions); False when it computes them (mirrored ghosts, a
    #: generalised wall's extrapolated velocity)
    keeps_wall_velocity: bool = False

    @property
    def particle_fields(self) -> tuple[str, ...]:
        return self.wall_fields


class _NoSlip(Coeffs):
    noSlip: bool = Field(True, description="wall particles enter the viscous term (no-slip, "
                         "as in the thesis); no: free-slip")


@register
class StationaryGhosts(Boundary):
    """Violeau & Issa (2007): fixed rows of wall particles with evolving density.

    The wall particles never move; their density obeys the same continuity equation as the
    fluid, by symmetry of the pairs they form with fluid particles (T §3.8), their pressure
    follows from the equation of state, and fluid particles feel them through the ordinary
    pressure and viscous terms. Zero wall velocity gives a no-slip wall; with ``noSlip no``
    the wall particles stay out of the viscous terms (the viscosity's and the SPS stress),
    a free-slip wall: DualSPHysics' DBC with ViscoBoundFactor 0.
    """

    name = "stationaryGhosts"
    doc = "fixed wall-particle rows whose density evolves by pairing with fluid, T §3.8"
    keeps_wall_velocity = True

    class Coeffs(_NoSlip):
        clampDensity: bool = Field(False, description=(
            "yes: a wall particle's density is raised to rho0 wherever it falls below, before "
            "every evaluation, so a wall never pulls water (p >= 0 on the walls: DualSPHysics' "
            "DBC keeps its boundary particles at rho0 or above 'to prevent absorption of fluid "
            "particles by boundaries'); no: the density as the continuity equation gives it, "
            "negative pressures included"))

    def neighbour_kinds(self):
        """Every wall particle is wet: it enters every term as a fluid particle would (the
        viscous ones only no-slip), and its density evolves by the continuity equation."""
        return {"wetWall": "else", "viscousWetWall": self.coeffs.noSlip}

    def terms(self):
        """With ``clampDensity``: rho_w = max(rho_w, rho0), and then p_w = 0 and c_w = c0
        (Tait's at rho0), before every evaluation."""
        if not self.coeffs.clampDensity:
            return []
        return [Term("wallDensityFloor", ("prepass",), final=_DENSITY_FLOOR,
                     applies=("wall",), sees=(), writes=("rho",), corrects=("p", "c"))]


#: a wall particle below the reference density is set to it (Tait: p(rho0) = 0, c = c0)
_DENSITY_FLOOR = """if rho[a] < eos_rho0:
    rho[a] = eos_rho0
    p[a] = 0.0
    c[a] = eos_c0
"""


#: wall normal of neighbour b and the normal / tangential distances of a from it; a corner
#: particle repels radially (its normal is the direction b -> a and chi = 1)
_GEOMETRY = """\
bn@ = fld[F_n@, b]
if fld[F_corner, b] > 0.5:
    rab = math.sqrt(r2)
    bn@ = d@_ab / rab
    yn = rab
    chi = 1.0
else:
    yn = dot(d@_ab, bn@)
    xt = abs(dy_ab * bnx - dx_ab * bny)
    chi = 1.0 - xt / bnd_dx if xt < bnd_dx else 0.0
"""

#: 3-D, axis-aligned walls: n holds, per axis, the sign of the normal of each face the wall
#: particle b belongs to (one on a face, two on an edge, three at a vertex); for each such face
#: the force acts along its normal with yn the distance from b's plane and chi the product
#: of the hat weights T(3.76) along the face's two axes, for a fluid particle in front of b's
#: plane (yn > 0: one beside another face of a block, below its top's plane, is not pushed up)
_HAT = "(1.0 - abs(d{0}_ab) / bnd_dx if abs(d{0}_ab) < bnd_dx else 0.0)"


def _faces_3d(force: str) -> str:
    """The 3-D pair code: ``force`` once for each face of the lattice b belongs to."""
    out = []
    for ax, (o1, o2) in (("x", "yz"), ("y", "xz"), ("z", "xy")):
        out.append(f"if fld[F_n{ax}, b] != 0.0 and d{ax}_ab * fld[F_n{ax}, b] > 0.0:\n"
                   f"    bn@ = 0.0\n"
                   f"    bn{ax} = fld[F_n{ax}, b]\n"
                   f"    yn = d{ax}_ab * bn{ax}\n"
                   f"    chi = {_HAT.format(o1)} * {_HAT.format(o2)}\n"
                   + textwrap.indent(force, "    "))
    return "".join(out)


#: Monaghan & Kos (1999), T(3.70)-(3.72): f = n Gamma(y) chi(x), Gamma = A (1 - q)/sqrt(q),
#: q = y / range, A = (0.01 c0^2 + beta c0 v_n)/h with v_n the speed of approach (beta = 1 when
#: approaching, else 0). y is floored at bnd_ymin so a particle that crossed the line is pushed
#: back with a large but finite force.
_MONAGHAN_KOS_FORCE = """\
if chi > 0.0 and yn < bnd_range:
    qn = max(yn, bnd_ymin) / bnd_range
    vn = -dot(U@_ab, bn@)
    amk = bnd_a0
    if vn > 0.0:
        amk += bnd_c0 * vn * inv_h
    gam = amk * (1.0 - qn) / math.sqrt(qn) * chi
    acc_@ += gam * bn@
"""

#: Monaghan et al. (2003), T(3.73)-(3.76): f_ab = m_b/(m_a + m_b) Gamma(y) chi(x) n_b,
#: q = y/h, beta = 0.02 c0^2 / y.
_MONAGHAN_2003_FORCE = """\
if chi > 0.0 and yn < 2.0 * h:
    ye = max(yn, bnd_ymin)
    qn = ye * inv_h
    bet = bnd_b0 / ye
    if qn < 2.0 / 3.0:
        gam = 2.0 / 3.0 * bet
    elif qn < 1.0:
        gam = bet * (2.0 * qn - 1.5 * qn * qn)
    else:
        gam = 0.5 * bet * (2.0 - qn) * (2.0 - qn)
    ma = m[a]
    gam *= mb / (ma + mb) * chi
    acc_@ += gam * bn@
"""


#: the forces per dimension: the geometry above, then the force
_MONAGHAN_KOS = {2: _GEOMETRY + _MONAGHAN_KOS_FORCE, 3: _faces_3d(_MONAGHAN_KOS_FORCE)}
_MONAGHAN_2003 = {2: _GEOMETRY + _MONAGHAN_2003_FORCE, 3: _faces_3d(_MONAGHAN_2003_FORCE)}

#: the wall fields the repulsive forces read (nz in 3-D only: terms.THREE_D_FIELDS)
_GEOMETRY_READS = ("field.nx", "field.ny", "field.nz", "field.corner")


class _Repulsive(Boundary):
    wall_layers = 1
    wall_fields = ("nx", "ny", "nz", "corner", "wallDist")
    force_code: dict = {}

    class Coeffs(_NoSlip):
        pass

    def neighbour_kinds(self):
        """Every wall particle is dry: it pushes (``force_code``) and, no-slip, rubs."""
        return {"dryWall": "else", "viscousWall": self.coeffs.noSlip}

    def terms(self):
        return [Term("wallForce", ("rates",), pair=self.force_code, sees=("dryWall",),
                     reads=_GEOMETRY_READS, writes=("acc",), weighted=False)]


@register
class RepulsiveMonaghanKos(_Repulsive):
    """Monaghan & Kos (1999) repulsive wall, T(3.70)-(3.72).

    One row of wall particles dx/2 behind the wall line, spacing dx, so the first fluid row
    is dx from them (Monaghan's arrangement; the wall line is halfway, as for the other
    particle boundaries). A wall particle b pushes a fluid
    particle a along the wall normal with Gamma(y) chi(x): Gamma = A (1 - q)/sqrt(q) for
    q = y / (2 dx) < 1, A = (0.01 c0^2 + beta c0 v_n) / h, where v_n is the speed at which a
    approaches the wall (beta = 1 when approaching, 0 otherwise) and chi(x) = 1 - x/dx the
    tangential weight T(3.76), which sums to one along a wall of particles dx apart, so the
    force does not ripple as a particle slides along it. Wall particles take no part in
    continuity or pressure; with ``noSlip yes`` they enter the viscous term (T §3.8).
    """

    name = "repulsiveMonaghanKos"
    doc = "repulsive wall force of Monaghan & Kos (1999), T(3.70)-(3.72), one wall row"
    force_code = _MONAGHAN_KOS

    class Coeffs(_NoSlip):
        range: float = Field(2.0, gt=0.0, le=3.0, description="reach of the force in dx "
                             "(q = y / (range dx)); 2 in T(3.71)")

    def params(self, ctx: CaseContext):
        return {"bnd_dx": ctx.dx, "bnd_range": self.coeffs.range * ctx.dx,
                "bnd_ymin": 0.02 * ctx.dx, "bnd_a0": 0.01 * ctx.c0 ** 2 / ctx.h,
                "bnd_c0": ctx.c0}


@register
class RepulsiveMonaghan2003(_Repulsive):
    """Monaghan, Kos & Issa (2003) repulsive wall, T(3.73)-(3.76).

    Force per unit mass on fluid particle a from wall particle b:
    f_ab = m_b/(m_a + m_b) Gamma(y) chi(x) n_b, with Gamma the kernel-gradient-like profile of
    T(3.75) in q = y/h (zero beyond 2h), beta = 0.02 c0^2 / y, and chi(x) = 1 - x/dx, T(3.76).
    Walls are fixed (or moved by a prescribed motion), so the reaction T(3.74) on the wall is
    not integrated. Corners as described in the module docstring.
    """

    name = "repulsiveMonaghan2003"
    doc = "repulsive wall force of Monaghan et al. (2003), T(3.73)-(3.76), one wall row"
    force_code = _MONAGHAN_2003

    def params(self, ctx: CaseContext):
        return {"bnd_dx": ctx.dx, "bnd_ymin": 0.02 * ctx.dx, "bnd_b0": 0.02 * ctx.c0 ** 2}


@register
class MirrorGhosts(Boundary):
    """Mirrored ghost particles, T(3.77)-(3.80) (Colagrossi & Landrini 2003; P §4).

    Every step each fluid particle closer to a wall segment than the kernel support is
    reflected across it: x_G = 2 x_w - x_a, p_G = p_a (rho_G = rho_a, m_G = m_a). The normal
    velocity is reflected about the wall's, u_nG = 2 U_n - u_na, T(3.78); the tangential one is
    kept, u_sG = u_sa (free slip, T(3.79)), or with ``noSlip yes`` reflected likewise,
    u_sG = 2 U_s - u_sa. In the corner between two perpendicular walls a particle near both is
    also reflected across both (the corner ghost). Ghosts follow their particle through the
    stages of a step. Exact for straight walls and right-angled corners; at other angles only
    the single reflections are made (T §3.8 on the limits of the method).

    Beyond the thesis: ``pressure hydrostatic`` gives each ghost p_G = p_a + rho_a g.(x_G -
    x_a), the wall's Neumann condition dp/dn = rho g.n (the wall's own acceleration left
    out), in place of T(3.80)'s p_G = p_a, under which the rows next to a bed settle
    compressed; ``wallLaw`` adds the shear stress of the law of the wall (T(3.84)-(3.85), or
    a prescribed U+) to a free-slip wall, as a boundary integral over the wall line (see
    ``after_rates``).

    In 3-D the walls are the closed faces of ``box`` tanks (planes, ``sphfoam.case.geometry.
    planes_of``), with edge and vertex ghosts (``sphfoam.models.mirror3d``); other wall
    shapes and ``wallLaw`` are refused there by name.
    """

    name = "mirrorGhosts"
    doc = ("fluid mirrored across straight walls each step, T(3.77)-(3.80); free- or no-slip; "
           "pressure hydrostatic: p_G = p_a + rho_a g.(x_G - x_a); wallLaw: the law of the "
           "wall's shear stress T(3.84)-(3.85) on a free-slip wall; 3-D: across the faces "
           "of box tanks, with edge and vertex ghosts")
    wall_placement = "none"
    massless_ghosts = True
    hook_dims = (2, 3)
    device_form = "sphfoam.models.mirror_cuda:MirrorGhostsDevice"
    #: the device form mirrors across 2-D segments and the faces of 3-D box tanks
    device_dims = (2, 3)
    device_hooks = ("attach", "before_neighbours", "add_particles", "keeps_neighbours",
                    "after_sort", "before_evaluation", "after_rates", "walls_moved",
                    "after_step", "summary")

    class Coeffs(wl.LawCoeffs):
        noSlip: bool = Field(False, description="reflect the tangential velocity too "
                             "(no-slip); no: T(3.79), free slip as in P section 4")
        pressure: Literal["mirror", "hydrostatic"] = Field(
            "mirror", description="ghost pressure: `mirror` p_G = p_a, T(3.80); "
            "`hydrostatic` p_G = p_a + rho_a g.(x_G - x_a), the wall's Neumann condition "
            "dp/dn = rho g.n (Adami, Hu & Adams 2012, eq. (27), its hydrostatic part)")

        @model_validator(mode="after")
        def _free_slip_law(self):
            if self.wallLaw != "none" and self.noSlip:
                raise ValueError(f"wallLaw {self.wallLaw} is the wall stress of a free-slip "
                                 "wall: set noSlip no (a no-slip ghost already imposes the "
                                 "viscous stress of zero wall velocity)")
            return self

    def dimension_problem(self, dim: int) -> str | None:
        """In 3-D the wall law is refused: its stress integrates the kernel along a line."""
        if dim == 3 and self.coeffs.wallLaw != "none":
            return (f"wallLaw {self.coeffs.wallLaw} has no 3-D form (its wall stress "
                    "integrates the kernel along a wall line): use wallLaw none in 3-D")
        return None

    def neighbour_kinds(self):
        """Ghosts are every non-fluid neighbour; they enter every term as fluid."""
        return {"ghost": "else"}

    def params(self, ctx: CaseContext) -> dict[str, float]:
        """The viscosity the smooth wall law reads (the wall stress is added after the rates,
        :meth:`after_rates`, which takes it from the pipeline's coefficients)."""
        return {"bnd_wlnu": ctx.nu} if self.coeffs.wallLaw == "smooth" else {}

    # --- the wall shear stress (``wallLaw``) ------------------------------------------------
    # A free-slip mirror wall exerts no tangential force. With ``wallLaw`` the wall exerts the
    # shear stress of the law of the wall, tau_w = rho u*^2 (T(3.84)-(3.85), T §3.10), as a
    # boundary integral (in the manner of the boundary-integral walls of Kulasegaram et al.
    # 2004 and Ferrand et al. 2013): the stress on the wall line, spread over the fluid by
    # the kernel, dv_a/dt = -(2/rho_a) int_wall tau_w W(x_a - x_w) ds. With tau_w taken from
    # particle a itself (its tangential velocity relative to the wall at its distance d_a)
    # the integral is 2 Phi(d_a) u*_a^2, Phi the kernel integrated along the line
    # (:func:`sphfoam.models.mirror.line_kernel`); over a plane wall under uniform fluid the
    # particles' forces add up to exactly tau_w per unit length, at any resolution (the factor
    # 2: the fluid fills half of the kernel's support). Unlike the stress of a no-slip ghost,
    # u_t/d across a particle spacing, this does not grow as dx shrinks: the law stands for
    # the boundary layer no SPH resolution of a beach reaches.
    @property
    def after_rates(self):
        return self._wall_shear if self.coeffs.wallLaw != "none" else None

    def _wall_shear(self, run):
        st = run.state
        gh.wall_shear(st.x, st.y, st.u, st.v, st.kind, self.seg, self.reach, *self._shear,
                      st.ax, st.ay)

    # --- run-time hooks (sphfoam.models.base) ---------------------------------------------
    # Ghosts are made when the neighbour list is built, for every fluid particle within the
    # list radius R (the cell side) of a segment, projecting onto it extended by the skin
    # R - support, and kept (refreshed) while the list is reused. At the start of each step
    # (the neighbour update) a ghost is *active* when it meets the criterion of T(3.77), within
    # the support and projecting onto the segment itself: exactly the ghosts a rebuild would
    # make. Dormant ones carry mass 0 through the step, so that they add exactly 0.0 to every
    # mass-weighted sum; ``keeps_neighbours`` asks for a rebuild when the active set is not
    # that of a rebuild (a particle qualifies without a ghost), or when a dormant ghost is
    # within the support of a fluid particle (only where the walls are not convex: the toe of
    # a beach, where it happens at nearly every step) and a selected term would not cancel it
    # (``Term.weighted``; the generated maximum of T(3.89) skips massless neighbours, and no
    # term of the registry that sees ghosts is unweighted).
    def attach(self, run):
        self.three = run.selection.dim == 3
        if self.three and not run.planes:
            raise ValueError("mirrorGhosts in 3-D needs a box tank with a closed face in "
                             "system/particleDict")
        if not self.three and not run.segments:
            raise ValueError("mirrorGhosts needs walls in system/particleDict")
        self.reach = run.support_radius
        #: ghosts are made within the list radius, for particles projecting within the skin
        self.build_reach = max(run.cells.cell_size, self.reach)
        self.margin = self.build_reach - self.reach
        if self.three:
            #: the closed faces of the box tanks (sphfoam.models.mirror3d)
            self.planes = list(run.planes)
            self.pl = m3.plane_array(self.planes)
        else:
            self.seg = gh.segment_array(run.segments)
            self.corners = gh.corner_pairs(run.segments, 1e-9 * max(1.0, self.reach))
        self._ghost = None
        self._active = None
        self.pushed_back = 0
        c = self.coeffs
        prm = run.coefficients()
        #: (Phi table, law, its coefficient) of :func:`sphfoam.models.mirror.wall_shear`
        #: (2-D: ``dimension_problem`` refuses a wall law in 3-D)
        self._shear = None
        if c.wallLaw != "none":
            coef = {"smooth": prm.get("bnd_wlnu"), "rough": c.ks,
                    "prescribedUPlus": c.UPlus}[c.wallLaw]
            self._shear = (gh.line_kernel(run.selection.kernel.W, run.h, self.reach),
                           gh.WALL_SHEAR_LAWS[c.wallLaw], float(coef))
        g = ("gx", "gy", "gz") if self.three else ("gx", "gy")
        self._hydro = (False, *(0.0 for _ in g), 1.0, 1.0, 1.0)
        if c.pressure == "hydrostatic":
            if "eos_B" not in prm:
                raise ValueError("mirrorGhosts pressure hydrostatic needs the tait equation "
                                 "of state")
            self._hydro = (True, *(prm[k] for k in g), prm["eos_rho0"], prm["eos_B"],
                           prm["eos_gamma"])
        #: the selected terms that see ghosts and add what a massless neighbour does not
        #: cancel (Term.weighted False): only for them must a dormant ghost stay out of the
        #: support of a fluid particle (the maximum of T(3.89) skips massless neighbours)
        self.unweighted = [t.who() for t in collect(run.selection.models())
                           if not t.weighted and set(t.sees) & {"ghost", "all"}]

    # --- the walls' geometry: 2-D segments (models.mirror), 3-D planes (models.mirror3d) ----
    def _positions(self, st) -> tuple:
        return (st.x, st.y, st.z) if self.three else (st.x, st.y)

    def _count(self, st, reach, count, margin=0.0):
        """How many ghosts each particle makes within ``reach`` (into ``count``)."""
        if self.three:
            m3.count_ghosts(st.x, st.y, st.z, st.kind, self.pl, reach, count, margin)
        else:
            gh.count_ghosts(st.x, st.y, st.kind, self.seg, self.corners, reach, count, margin)

    def _fill(self, st, offset, ng) -> tuple:
        """(src, walls): each ghost's particle and the walls it mirrors it across (two
        columns of segments in 2-D, three of faces in 3-D; -1 for none)."""
        src = np.empty(ng, dtype=np.int64)
        walls = tuple(np.empty(ng, dtype=np.int64) for _ in range(3 if self.three else 2))
        if self.three:
            m3.fill_ghosts(st.x, st.y, st.z, st.kind, self.pl, self.build_reach, offset, src,
                           *walls, self.margin)
        else:
            gh.fill_ghosts(st.x, st.y, st.kind, self.seg, self.corners, self.build_reach,
                           offset, src, *walls, self.margin)
        return src, walls

    def _refresh(self, st, gidx, src, walls, active):
        if self.three:
            m3.refresh_ghosts(st.x, st.y, st.z, st.u, st.v, st.w, st.rho, st.m, gidx, src,
                              *walls, self.pl, self.coeffs.noSlip, active, *self._hydro)
        else:
            gh.refresh_ghosts(st.x, st.y, st.u, st.v, st.rho, st.m, gidx, src, *walls,
                              self.seg, self.coeffs.noSlip, active, *self._hydro)

    def _activity(self, st, src, walls, active) -> int:
        if self.three:
            return m3.ghost_activity(st.x, st.y, st.z, src, *walls, self.pl, self.reach,
                                     active)
        return gh.ghost_activity(st.x, st.y, src, *walls, self.seg, self.reach, active)

    def _dormant_near_fluid(self, st, gidx, nb_start, nb_idx, support2) -> bool:
        if self.three:
            return m3.dormant_ghost_near_fluid(st.x, st.y, st.z, st.kind, gidx, self._active,
                                               nb_start, nb_idx, support2)
        return gh.dormant_ghost_near_fluid(st.x, st.y, st.kind, gidx, self._active, nb_start,
                                           nb_idx, support2)

    def before_neighbours(self, run):
        st = run.state
        if (st.kind == GHOST).any():
            st.keep(st.kind != GHOST)
        self._ghost = None

    def add_particles(self, run, cell):
        """Mirror every fluid particle near a wall across it (T(3.77)); ghosts that fall
        outside the cell grid are dropped (their particle is at the edge)."""
        st = run.state
        count = np.zeros(st.n, dtype=np.int64)
        self._count(st, self.build_reach, count, self.margin)
        offset = np.zeros(st.n, dtype=np.int64)
        np.cumsum(count[:-1], out=offset[1:])
        ng = int(count.sum())
        src, walls = self._fill(st, offset, ng)
        n0 = st.n
        zero = np.zeros(ng)
        st.append(zero, zero, zero, zero, zero, zero, np.full(ng, GHOST), -1 - st.id[src],
                  **(dict(z=zero, w=zero) if self.three else {}))
        gidx = np.arange(n0, n0 + ng)
        self._refresh(st, gidx, src, walls, np.ones(ng, dtype=np.bool_))
        gcell, gout = run.cells.bin(*(a[n0:] for a in self._positions(st)))
        if gout:
            keep = np.concatenate([np.ones(n0, dtype=bool), gcell >= 0])
            st.keep(keep)
            kg = gcell >= 0
            gcell = gcell[kg]
            gidx, src = np.arange(n0, n0 + int(kg.sum())), src[kg]
            walls = tuple(w[kg] for w in walls)
        self._active = np.empty(src.shape[0], dtype=np.bool_)
        self._activity(st, src, walls, self._active)
        self._ghost = (gidx, src, *walls)
        self.before_evaluation(run)          # dormant ghosts: mass 0
        return gcell

    def after_sort(self, run, order):
        inv = np.empty_like(order)
        inv[order] = np.arange(order.size)
        gidx, src, *walls = self._ghost
        self._ghost = (inv[gidx], inv[src], *walls)

    def keeps_neighbours(self, run) -> bool:
        """Whether the ghosts of the last build still serve this step (see above): the
        active ones are exactly those a rebuild would make, and no dormant one is within
        the support of a fluid particle. Sets which ghosts are active for this step."""
        if self._ghost is None:
            return False
        st = run.state
        gidx, src, *walls = self._ghost
        n_on = self._activity(st, src, walls, self._active)
        count = kept_arrays(self, "_count_buf", 1, st.n, np.int64)[0]   # every entry written
        self._count(st, self.reach, count)
        if int(count.sum()) != n_on:
            return False
        self.before_evaluation(run)
        if not self.unweighted:
            return True
        nb_start, nb_idx = run.neighbours
        return not self._dormant_near_fluid(st, gidx, nb_start, nb_idx,
                                            self.reach ** 2 * (1.0 + 1e-12))

    def before_evaluation(self, run):
        if self._ghost is not None:
            gidx, src, *walls = self._ghost
            self._refresh(run.state, gidx, src, walls, self._active)

    def walls_moved(self, run, offsets, velocities):
        if self.three:
            self.pl = m3.plane_array(self.planes, offsets, velocities)
            return
        self.seg = gh.segment_array(run.segments, offsets, velocities)

    def after_step(self, run):
        """A particle that crossed a mirror wall during the step goes back before anything
        (a write, a function object, the next step) sees it."""
        st = run.state
        if self.three:
            self.pushed_back += m3.push_back(st.x, st.y, st.z, st.u, st.v, st.w, st.kind,
                                             self.pl, self.reach)
            return
        self.pushed_back += gh.push_back(st.x, st.y, st.u, st.v, st.kind, self.seg,
                                         self.reach)

    def summary(self) -> str:
        n = getattr(self, "pushed_back", 0)
        return f"{n} put back across a mirror wall" if n else ""


@register
class Hybrid(Boundary):
    """The hybrid wet/dry boundary of T §3.9: stationary ghosts where wet, repulsive where dry.

    Wall particles sit in rows behind the wall as for ``stationaryGhosts``. Once per step each
    wall particle counts the fluid particles inside its kernel support. It is *wet* when that
    count reaches its required number of pairs, ``ceil(wetFraction * nFull)``, where ``nFull``
    (written by the set-up) is the number of lattice sites on the fluid side of it within the
    support: the pairs it would form fully submerged. nFull is smaller in a corner (a 90 degree
    fan of fluid instead of 180), which is the corner dependence of T §3.9. A wet particle
    behaves as a stationary ghost (density evolves, pressure and viscosity act). A dry one
    has its density reset to rho0 (zero pressure) and its continuity switched off; if it is
    a boundary particle (the first row, closer than dx to the wall) it pushes fluid with the
    Monaghan & Kos force T(3.71)-(3.72) acting only closer than dx and enters the viscous
    term; deeper dry rows are ignored. The switch back happens when the count falls below the
    requirement. (T §3.9 lets the boundary particle decide for the ghost rows behind it; here
    each particle counts its own pairs against its own nFull, which needs no bookkeeping of
    which row belongs to which particle; the rows behind a boundary particle switch with it
    within a step or two.)
    """

    name = "hybrid"
    doc = ("hybrid wet/dry boundary, T §3.9: stationary ghosts once a wall particle has its "
           "required fluid pairs, Monaghan-Kos force within dx while dry")
    wall_fields = ("nx", "ny", "nz", "corner", "wallDist", "nFull")

    class Coeffs(_NoSlip):
        wetFraction: float = Field(0.75, gt=0.0, le=1.0, description=(
            "required pairs as a fraction of the fully submerged count nFull"))

    def params(self, ctx: CaseContext):
        return {"bnd_dx": ctx.dx, "bnd_range": ctx.dx, "bnd_ymin": 0.02 * ctx.dx,
                "bnd_a0": 0.01 * ctx.c0 ** 2 / ctx.h, "bnd_c0": ctx.c0,
                "bnd_frac": self.coeffs.wetFraction, "bnd_rho0": ctx.rho0}

    _STEP_FINAL = """\
bnd_need = math.ceil(bnd_frac * fld[F_nFull, a] - 1e-9)
if bnd_need > 0 and bnd_count >= bnd_need:
    aux[I_bnd_wet, a] = 1.0
else:
    aux[I_bnd_wet, a] = 0.0
    rho[a] = bnd_rho0
"""

    def neighbour_kinds(self):
        """Wet walls (the once-per-step count) act as fluid; dry boundary particles (closer
        than dx to the wall) push and, no-slip, rub; deeper dry rows are ignored."""
        return {"wetWall": "aux[I_bnd_wet, {i}] > 0.5",
                "dryWall": "fld[F_wallDist, {i}] < bnd_dx",
                "viscousWall": self.coeffs.noSlip}

    def terms(self):
        return [Term("wetDry", ("step",), applies=("wall",), sees=("fluid",),
                     init="bnd_count = 0", pair="bnd_count += 1", final=self._STEP_FINAL,
                     reads=("field.nFull",), writes=("aux.bnd_wet", "rho"), weighted=False),
                Term("wallForce", ("rates",), pair=_MONAGHAN_KOS, sees=("dryWall",),
                     reads=_GEOMETRY_READS, writes=("acc",), weighted=False)]
