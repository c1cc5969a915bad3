"""Case-level quantities models derive their coefficients from (a neutral module: the case
layer builds it, models and the engine read it, and it imports neither)."""

from __future__ import annotations

from dataclasses import dataclass


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
    support: float = 0.0  # kernel support radius kappa h (m), set with the kernel
    dim: int = 2       # the dimension of the case: 2 (x, y) or 3 (x, y, z)

    @property
    def eta2(self) -> float:
        """(0.1 h)^2, the guard of T(3.32) and T(3.38)."""
        return 0.01 * self.h * self.h
