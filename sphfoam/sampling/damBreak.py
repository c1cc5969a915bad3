"""Surge front and residual column height of a collapsing dam, T §3.9.1, T(3.81)-(3.83)."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from sphfoam.case.schemas import Vector2
from sphfoam.engine.state import FLUID
from sphfoam.registry import register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs

#: Martin & Moyce (1952), square column (n^2 = 1, a = H0), as digitised in the SPH
#: literature on the axes T = t sqrt(g/a): front Z = z/a ...
MM_FRONT = np.array([
    [0.43, 1.11], [0.62, 1.22], [0.80, 1.44], [0.97, 1.67], [1.14, 1.89], [1.29, 2.11],
    [1.45, 2.33], [1.62, 2.56], [1.76, 2.78], [1.93, 3.00], [2.07, 3.22], [2.24, 3.44],
    [2.40, 3.67], [2.54, 3.89], [2.71, 4.11], [2.87, 4.33], [3.04, 4.56], [3.21, 4.78],
    [3.29, 4.89], [3.32, 5.00]])
#: ... and residual height H = h/a
MM_HEIGHT = np.array([[0.0, 1.0], [0.80, 0.89], [1.29, 0.78], [1.74, 0.67], [2.15, 0.56],
                      [2.57, 0.44], [3.08, 0.33], [4.27, 0.22], [6.29, 0.11]])


def martin_moyce():
    """Front and height series on the thesis's axes T = t sqrt(g/H0), T(3.81)."""
    return MM_FRONT.copy(), MM_HEIGHT.copy()


@register
class DamBreakFront(FunctionObject):
    """Z = (x_front - x_wall)/H0 and H = h/H0 against T = t sqrt(g/H0), T(3.81)-(3.83).

    x_front is the largest x of any fluid particle; h is the highest fluid particle within
    ``heightBand`` of the back wall (the thesis measures "a small distance away from the
    wall": with stationary ghosts a film of water stays on the wall itself, T Fig 3.20),
    plus dx/2 so that h = H0 at rest.
    """

    name = "damBreakFront"
    doc = "surge front Z(T) and residual height H(T) of a collapsing column, T(3.81)-(3.83)"
    columns = ("time", "T", "z", "Z", "h", "H")

    class Coeffs(FunctionObjectCoeffs):
        wallX: float = Field(description="x of the back wall the column leans on")
        H0: float = Field(gt=0, description="initial column height")
        heightBand: tuple[float, float] = Field(
            (0.0, 0.02), description="x range from the wall where h is measured (stationary "
            "ghosts leave a film on the wall itself, T Fig 3.20: start a few dx away)")
        plot: bool = True

    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        self.rows = []

    def execute(self, sim):
        c, st = self.coeffs, sim.state
        f = st.kind == FLUID
        xf, yf = st.x[f], st.y[f]
        z = float(xf.max()) - c.wallX + 0.5 * self.ctx.dx
        band = (xf >= c.wallX + c.heightBand[0]) & (xf <= c.wallX + c.heightBand[1])
        hgt = float(yf[band].max()) + 0.5 * self.ctx.dx if band.any() else 0.0
        T = sim.time * math.sqrt(math.hypot(*self.ctx.g) / c.H0)
        row = (sim.time, T, z, z / c.H0, hgt, hgt / c.H0)
        self.rows.append(row)
        self.write_row(row)

    def end(self):
        super().end()
        if self.coeffs.plot and self.rows:
            self.plot()

    def plot(self):
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        r = np.array(self.rows)
        front, height = martin_moyce()
        fig, ax = plt.subplots(1, 2, figsize=(10, 4))
        ax[0].plot(r[:, 1], r[:, 3], "-", label=f"sphfoam, dx = {self.ctx.dx:g} m")
        ax[0].plot(front[:, 0], front[:, 1], "k^", label="Martin & Moyce (1952)")
        ax[0].set(xlabel=r"$T = t\sqrt{g/H_0}$", ylabel=r"$Z = z/H_0$", title="surge front")
        ax[1].plot(r[:, 1], r[:, 5], "-", label="sphfoam")
        ax[1].plot(height[:, 0], height[:, 1], "k^", label="Martin & Moyce (1952)")
        ax[1].set(xlabel=r"$T = t\sqrt{g/H_0}$", ylabel=r"$H = h/H_0$", title="residual height")
        for a in ax:
            a.grid(alpha=0.3)
            a.legend()
        fig.tight_layout()
        fig.savefig(self.folder / f"{self.object_name}.png", dpi=120)
        plt.close(fig)
