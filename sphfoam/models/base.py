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
Every coefficient a model needs is declared in :meth:`params` with a name that starts with the
model's prefix; the generated code binds ``name = prm[i]`` once per call.
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
    """A model that writes code into the generated pipeline. Hooks return source text."""

    prefix: str = ""

    def imports(self) -> list[str]:
        return []

    def params(self, ctx: CaseContext) -> dict[str, float]:
        return {}

    def selection_key(self) -> str:
        """What, besides the model's name, changes the generated source (none by default)."""
        return ""
