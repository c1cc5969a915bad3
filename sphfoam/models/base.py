"""What a model contributes to the generated pipeline.

The pipeline (``sphfoam.engine.codegen``) is Python source written for exactly the models a
case selects.  A model contributes *snippets* — a few lines of numba-compatible Python — at
named hooks, plus the imports those lines need and the scalar coefficients they read.

Names a snippet may read inside the pair loop of particle ``a`` with neighbour ``b``::

    a, b                  particle indices
    xa, ya, ua, va        position and velocity of a
    rhoa, pa, ca, rhob, pb, cb, mb, kindb
    dx_ab, dy_ab, r2, q              r_ab = r_a - r_b, |r_ab|^2, q = |r_ab| / h (r2 > 0)
    u_ab, v_ab, vdotr                v_ab = v_a - v_b and v_ab . r_ab
    gWx, gWy                         grad_a W_ab
    h, inv_h, eta2                   smoothing length, 1/h, (0.1 h)^2 guard of T(3.32), T(3.38)

and accumulate into ``acc_x, acc_y`` (dv_a/dt), ``drho_a`` (drho_a/dt), ``sigma_a`` (T(3.89)).
``Wab`` (the kernel value) is computed in a loop only when a snippet of that loop uses it.
Every coefficient a model needs is declared in :meth:`params` with a name that starts with the
model's prefix; the generated code binds ``name = prm[i]`` once per call.

Hooks (class attributes holding source text; empty means "nothing"):

``aux``                       names of per-particle fields the model computes in the pre-pass;
                              stored in ``aux[I_<name>, a]`` and readable for a and b later
``prepass_init``              per particle a, before its pre-pass neighbour loop
``prepass_pair``              per neighbour b in the pre-pass (plain kernel gradient)
``prepass_final``             per particle a after the loop: store ``aux[I_<name>, a] = ...``
``particle_code``             per fluid particle a, before its rates loop
``pair_code``                 per neighbour b of a fluid particle in the rates loop
``continuity_velocity_code``  redefines ``uc_ab, vc_ab``, the velocity difference continuity
                              uses (``u_ab, v_ab`` by default; XSPH corrects it)
``gradient_code``             replaces the kernel gradient ``gWx, gWy`` in the rates and
                              density loops (kernel corrections); may read ``aux`` of a
``filter_init/pair/final``    (densityFilter) a separate pass run every N steps that sets
                              ``rho_new`` for each fluid particle a
``eos_code``                  (equationOfState) sets ``p[a]`` and ``c[a]`` from ``rho[a]``

:meth:`dt_limit` lets a model cap the time step (e.g. viscous diffusion).
"""

from __future__ import annotations

from dataclasses import dataclass

from sphfoam.registry import Model


@dataclass(frozen=True)
class CaseContext:
    """Case-level quantities models derive their coefficients from."""

    dx: float          # initial particle spacing (system/particleDict)
    h: float           # smoothing length
    rho0: float        # reference density (constant/transportProperties)
    nu: float          # kinematic viscosity
    g: tuple[float, float]
    fluid_height: float  # height of the tallest fluid block, for v_max estimates
    c0: float = 0.0    # reference speed of sound (set once the equation of state is known)


class PipelineModel(Model):
    """A model that writes code into the generated pipeline (see the hooks above)."""

    prefix: str = ""
    aux: tuple[str, ...] = ()
    prepass_init: str = ""
    prepass_pair: str = ""
    prepass_final: str = ""
    particle_code: str = ""
    pair_code: str = ""
    continuity_velocity_code: str = ""
    gradient_code: str = ""

    def dt_limit(self, ctx: CaseContext) -> float:
        """Largest stable time step this model allows (inf: no limit of its own)."""
        return float("inf")

    def imports(self) -> list[str]:
        return []

    def params(self, ctx: CaseContext) -> dict[str, float]:
        return {}

    def selection_key(self) -> str:
        """What, besides the model's name, changes the generated source (none by default)."""
        return ""
