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


def wet_dry_diagnostics(xf, yf, dx, wall_x, surge_start, bed_y):
    """(stuck, gap) of :class:`DamBreakFront`: particles hanging on the back wall 1.5 dx
    above the surface next to it, and the median height (in dx) of the lowest particle above
    the bed over the surge (NaN while the surge has not passed ``surge_start`` by 4 dx)."""
    near = (xf - wall_x >= 1.5 * dx) & (xf - wall_x < 4.0 * dx)
    surface = float(yf[near].max()) if near.any() else -np.inf
    stuck = int(np.count_nonzero((xf - wall_x < 1.5 * dx) & (yf > surface + 1.5 * dx)))
    front = float(xf.max())
    lo, hi = surge_start, front - 2.0 * dx
    if hi - lo < 4.0 * dx:
        return stuck, float("nan")
    nb = int((hi - lo) // (2.0 * dx))
    edges = lo + 2.0 * dx * np.arange(nb + 1)
    k = np.digitize(xf, edges) - 1
    ok = (k >= 0) & (k < nb)
    lowest = np.full(nb, np.inf)
    np.minimum.at(lowest, k[ok], yf[ok])
    lowest = lowest[np.isfinite(lowest)]
    return stuck, float(np.median(lowest - bed_y) / dx) if lowest.size else float("nan")


@register
class DamBreakFront(FunctionObject):
    """Z = (x_front - x_wall)/H0 and H = h/H0 against T = t sqrt(g/H0), T(3.81)-(3.83).

    x_front is the largest x of any fluid particle; h is the highest fluid particle within
    ``heightBand`` of the back wall (the thesis measures "a small distance away from the
    wall": with stationary ghosts a film of water stays on the wall itself, T Fig 3.20),
    plus dx/2 so that h = H0 at rest.

    Two wetting/drying diagnostics of T §3.9 (Figs 3.19-3.20) are written beside them:
    ``stuck``, the fluid particles within 1.5 dx of the back wall higher than 1.5 dx above the
    free surface next to them (the highest particle 1.5-4 dx from the wall): water left
    hanging on the drying wall (T Fig 3.20); and ``gap``, the height of the
    lowest fluid particle above the bed line (``bedY``), in dx, taken as the median over
    2 dx wide bins of the surge beyond the initial column (x > wallX + ``width``) and up to
    2 dx behind its front (at rest the first row sits 0.5 dx above the bed line).
    """

    name = "damBreakFront"
    doc = "surge front Z(T) and residual height H(T) of a collapsing column, T(3.81)-(3.83)"
    columns = ("time", "T", "z", "Z", "h", "H", "stuck", "gap")

    class Coeffs(FunctionObjectCoeffs):
        wallX: float = Field(description="x of the back wall the column leans on")
        H0: float = Field(gt=0, description="initial column height")
        heightBand: tuple[float, float] = Field(
            (0.0, 0.02), description="x range from the wall where h is measured (stationary "
            "ghosts leave a film on the wall itself, T Fig 3.20: start a few dx away)")
        width: float | None = Field(None, gt=0, description="initial column width (default "
                                    "H0, the square column of Martin & Moyce)")
        bedY: float = Field(0.0, description="y of the bed line")
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
        stuck, gap = wet_dry_diagnostics(xf, yf, self.ctx.dx, c.wallX,
                                         c.wallX + (c.width or c.H0), c.bedY)
        row = (sim.time, T, z, z / c.H0, hgt, hgt / c.H0, stuck, gap)
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
