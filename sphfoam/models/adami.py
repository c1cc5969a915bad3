"""The generalised wall boundary of Adami, Hu & Adams (2012, JCP 231, 7057-7075).

Rows of wall particles behind the wall line (as for ``stationaryGhosts``) whose state is
extrapolated from the fluid before every evaluation of the rates:

* pressure, AHA12 eq. (27): p_w = (sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf)
  / sum_f W_wf, over the fluid neighbours f of wall particle w (r_wf = r_w - r_f); a wall
  particle with no fluid neighbour has p_w = 0;
* density from the inverse equation of state, rho_w = rho0 (1 + p_w / B)^(1/gamma) (Tait,
  T(3.27));
* velocity from the Shepard average of the fluid's, u~_f = sum_f u_f W_wf / sum_f W_wf,
  mirrored about the prescribed wall velocity U_w: no slip, u_w = 2 U_w - u~_f (AHA12
  eq. (22)); free slip, the fluid's tangential velocity u~_f,t with the normal component
  mirrored, 2 U_w,n - u~_f,n (at a corner particle, with no single normal, the no-slip form).

Fluid particles then see the wall particles as neighbours of kind ``ghost``: every term
(continuity, momentum, viscosity) treats them as fluid with the extrapolated p, rho and
velocity. (AHA12 use the extrapolated velocity in the viscous term only and the prescribed
one in the continuity equation; here every term sees one velocity, whose normal component
is the mirror image of the fluid's as for ``mirrorGhosts``, T(3.78).) The prescribed wall
velocity (the wall particle's velocity as set up, e.g. a sliding wall's constant
``velocity``, or its wall entry's motion) is put back on the wall particles before and after
each evaluation and after each step (run-time hooks): the integrators move the wall
particles with it, never with the extrapolated one, and written fields show it. The wall
acceleration a_w of eq. (27) is taken as zero: exact for fixed walls, an approximation for
moving ones.

In 3-D the no-slip form runs as written (the sums over the 3-D neighbours, u, v and w). The
free-slip form reads the walls' normals, which the 3-D set-up writes for box and block walls
(plane faces on the lattice: per axis, the sign of each face's normal the particle belongs
to): each component along a face's normal is mirrored, 2 U_w,k - u~_f,k, and each other one
is the fluid's, u~_f,k; on an edge or at a vertex every face's component is mirrored, the
mirror image across both or all three planes.
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from sphfoam.engine.hookforms import WallVelocity
from sphfoam.engine.state import WALL
from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext
from sphfoam.models.boundaries import Boundary
from sphfoam.registry import Coeffs, register

_INIT = """\
bnd_wsum = 0.0
bnd_sp = 0.0
bnd_sU@ = 0.0
"""

#: over fluid neighbours f of wall particle a: AHA12 eq. (27) with a_w = 0 and the Shepard sums
_PAIR = """\
bnd_wsum += Wab
bnd_sp += (pb + rhob * dot(g@, d@_ab)) * Wab
bnd_sU@ += (U@a - U@_ab) * Wab
"""

_FINAL = """\
if bnd_wsum > 0.0:
    bnd_pw = bnd_sp / bnd_wsum
    bnd_U@f = bnd_sU@ / bnd_wsum
else:
    bnd_pw = 0.0
    bnd_U@f = U@a
p[a] = bnd_pw
rho[a] = eos_rho0 * max(1.0 + bnd_pw / eos_B, 1e-6) ** (1.0 / eos_gamma)
"""

_NO_SLIP = """\
U@[a] = 2.0 * U@a - bnd_U@f
"""

#: 3-D, axis-aligned walls: fld[F_n@, a] is nonzero along the normal of each face of a
_FREE_SLIP_3D = """\
U@[a] = 2.0 * U@a - bnd_U@f if fld[F_n@, a] != 0.0 else bnd_U@f
"""

_FREE_SLIP = """\
if fld[F_corner, a] > 0.5:
    U@[a] = 2.0 * U@a - bnd_U@f
else:
    bnd_n@ = fld[F_n@, a]
    bnd_dn = dot(U@a - bnd_U@f, bnd_n@)
    U@[a] = bnd_U@f + 2.0 * bnd_dn * bnd_n@
"""


@register
class Adami(Boundary):
    """Wall particles with pressure, density and velocity extrapolated from the fluid
    (see the module docstring)."""

    name = "adami"
    doc = ("wall-particle rows with p extrapolated from the fluid, Adami, Hu & Adams (2012) "
           "eq. (27), rho by the inverse EOS, no-slip u_w = 2 U_w - u~_f (eq. 22) or free slip")
    #: the hooks handle w in 3-D
    hook_dims = (2, 3)

    @property
    def wall_fields(self) -> tuple[str, ...]:
        """The wall normal and corner flag, which only the free-slip form reads (nz in 3-D:
        box and block walls)."""
        return () if self.coeffs.noSlip else ("nx", "ny", "nz", "corner")

    class Coeffs(Coeffs):
        noSlip: bool = Field(True, description="no slip: u_w = 2 U_w - u~_f, AHA12 eq. (22); "
                             "no: free slip (the fluid's tangential velocity, the normal one "
                             "mirrored; in 3-D on box and block walls)")

    def params(self, ctx: CaseContext):
        return {}

    def neighbour_kinds(self):
        """Every wall particle is a ghost: fluid to every term, with its extrapolated
        state; its own density and velocity do not evolve."""
        return {"ghost": "else"}

    def terms(self):
        if self.coeffs.noSlip:
            final, reads = _FINAL + _NO_SLIP, ("W",)
        else:
            final = {2: _FINAL + _FREE_SLIP, 3: _FINAL + _FREE_SLIP_3D}
            reads = ("W", "field.nx", "field.ny", "field.nz", "field.corner")
        return [Term("wallState", ("prepass",), init=_INIT, pair=_PAIR, final=final,
                     applies=("wall",), sees=("fluid",), reads=reads,
                     writes=("rho", "u"), corrects=("p",), weighted=False)]

    # --- run-time hooks (sphfoam.models.base) ---------------------------------------------
    def device_forms(self):
        """The hooks below, declared: the prescribed wall velocity put back."""
        return (WallVelocity(),)

    def attach(self, run):
        """Record each wall particle's velocity as set up (zero, or a wall entry's constant
        ``velocity``), by particle id: the prescribed velocity of walls without a motion."""
        st = run.state
        wall = st.kind == WALL
        n_id = int(st.id[wall].max()) + 1 if wall.any() else 0
        self._U0 = []
        for u in st.velocities:
            u0 = np.zeros(n_id)
            u0[st.id[wall]] = u[wall]
            self._U0.append(u0)
        self._velocities = {}

    def walls_moved(self, run, offsets, velocities):
        self._velocities = dict(velocities)

    def _prescribed_velocity(self, run):
        """Put the prescribed velocity back on every wall particle (as set up, or its wall
        entry's motion): the prepass overwrote it with the extrapolated one."""
        st = run.state
        wall = st.kind == WALL
        ids = st.id[wall]
        for u, u0 in zip(st.velocities, self._U0):
            u[wall] = u0[ids]
        if self._velocities and "patch" in st.extra:
            patch = st.extra["patch"]
            for which, vel in self._velocities.items():
                on = wall & (patch == float(which))
                for u, uu in zip(st.velocities, vel):
                    u[on] = uu

    def before_evaluation(self, run):
        self._prescribed_velocity(run)

    #: after the passes too, before the integrator's update: the update moves wall particles
    #: with their velocity, which the prepass set to the extrapolated one
    after_rates = after_density_rate = after_step = before_evaluation
