"""Equations of state: pressure (and sound speed) from density."""

from __future__ import annotations

import math
from typing import Literal

from numba import njit
from pydantic import Field

from sphfoam.engine.fastmath import FASTMATH
from sphfoam.engine.terms import Term
from sphfoam.models.base import CaseContext, PipelineModel
from sphfoam.registry import Coeffs, register

_JIT = dict(cache=True, fastmath=set(FASTMATH), inline="always")


@njit(**_JIT)
def tait_pressure(rho, rho0, B, gamma):
    """T(3.27): p = B ((rho / rho0)^gamma - 1)."""
    return B * ((rho / rho0) ** gamma - 1.0)


@njit(**_JIT)
def tait_sound_speed(rho, rho0, c0, gamma):
    """c = sqrt(dp/drho) = c0 (rho / rho0)^((gamma - 1) / 2), from T(3.27)-(3.29)."""
    return c0 * (rho / rho0) ** (0.5 * (gamma - 1.0))


def _power_code(base: str, n: int, out: str) -> str:
    """Lines setting ``out = base ** n`` by repeated squaring (n >= 1)."""
    lines, acc, sq, k = [], None, base, n
    step = 0
    while k:
        if k & 1:
            if acc is None:
                acc = sq
            else:
                lines.append(f"{out}_{step} = {acc} * {sq}")
                acc = f"{out}_{step}"
                step += 1
        k >>= 1
        if k:
            lines.append(f"{out}_s{step} = {sq} * {sq}")
            sq = f"{out}_s{step}"
            step += 1
    lines.append(f"{out} = {acc}")
    return "\n".join(lines) + "\n"


@register
class Tait(PipelineModel):
    """Weakly compressible Tait equation, B from the allowed density variation."""

    family = "equationOfState"
    name = "tait"
    doc = ("Tait/Batchelor p = B((rho/rho0)^gamma - 1), T(3.27); B = rho0 vmax^2 / "
           "(gamma |drho/rho|) from T(3.29)-(3.31)")
    prefix = "eos_"

    class Coeffs(Coeffs):
        gamma: float = Field(7.0, gt=1.0, description="stiffness exponent")
        vmax: float | Literal["auto"] = Field(
            "auto", description="estimate of the largest flow speed (m/s); auto = sqrt(2 g H)")
        densityVariation: float = Field(
            0.01, gt=0.0, lt=0.2, description="allowed |drho|/rho ~ vmax^2/c^2, T(3.30); 0.01 "
            "gives c = 10 vmax and the 100 of T(3.31)")
        speedOfSound: float | None = Field(
            None, gt=0.0, description="give c0 (m/s) directly instead of vmax/densityVariation")

    def vmax(self, ctx: CaseContext) -> float:
        if self.coeffs.vmax == "auto":
            gmag = math.hypot(*ctx.g)
            return math.sqrt(2.0 * gmag * max(ctx.fluid_height, 0.0)) or 1.0
        return float(self.coeffs.vmax)

    def c0(self, ctx: CaseContext) -> float:
        if self.coeffs.speedOfSound is not None:
            return float(self.coeffs.speedOfSound)
        return self.vmax(ctx) / math.sqrt(self.coeffs.densityVariation)

    def B(self, ctx: CaseContext) -> float:
        """T(3.29): c0^2 = gamma B / rho0."""
        return self.c0(ctx) ** 2 * ctx.rho0 / self.coeffs.gamma

    def imports(self):
        return ["from sphfoam.models.eos import tait_pressure as eos_pressure, "
                "tait_sound_speed as eos_sound_speed"]

    def params(self, ctx):
        return {"eos_rho0": ctx.rho0, "eos_B": self.B(ctx), "eos_c0": self.c0(ctx),
                "eos_gamma": self.coeffs.gamma}

    def terms(self):
        """p and c of every particle from its density, T(3.27)-(3.29). For an odd whole
        gamma (7, the usual), (rho/rho0)^gamma and the sound speed's (rho/rho0)^((gamma-1)/2)
        are products, not pow() calls (the same values to round-off, several times faster)."""
        g = float(self.coeffs.gamma)
        if g.is_integer() and int(g) % 2 == 1 and 3 <= g <= 15:
            half = (int(g) - 1) // 2
            code = ("eos_r = rho[a] / eos_rho0\n" + _power_code("eos_r", half, "eos_rh")
                    + "p[a] = eos_B * (eos_rh * eos_rh * eos_r - 1.0)\n"
                    "c[a] = eos_c0 * eos_rh")
        else:
            code = ("p[a] = eos_pressure(rho[a], eos_rho0, eos_B, eos_gamma)\n"
                    "c[a] = eos_sound_speed(rho[a], eos_rho0, eos_c0, eos_gamma)")
        return [Term("pressure", ("particle",), applies=("all",), writes=("p", "c"),
                     final=code)]

    def pressure(self, rho, ctx: CaseContext):
        """T(3.27) for a numpy array of densities (set-up, output)."""
        return self.B(ctx) * ((rho / ctx.rho0) ** self.coeffs.gamma - 1.0)

    def density(self, p, ctx: CaseContext):
        """Inverse of T(3.27), for hydrostatic initial states."""
        return ctx.rho0 * (1.0 + p / self.B(ctx)) ** (1.0 / self.coeffs.gamma)
