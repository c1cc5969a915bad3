#!/usr/bin/env python
"""Wall stress of the turbulent channel from its momentum balance, and the log-law start.

The channel is periodic, so the only forces on the water are the body force F (constant/g)
and the walls: per unit length, M dU_b/dt = M F - 2 tau_w, with M the fluid's mass per unit
length and U_b its bulk (mass-mean) velocity. In a steady state tau_w = F M/2 = rho0 u*^2,
u* = sqrt(F l_f/2) with l_f = M/rho0 the width the fluid fills (39 dx = 0.975 m here: the
wall rows at y = 0 and 1 m are l apart, the fluid's rows dx .. 39 dx). This script reads U_b
from every written time directory and reports tau_w/(F M/2) = 1 - (dU_b/dt)/F, from a
least-squares slope of U_b(t) over each ``--window`` seconds and over the last one, into
``postProcessing/wallStress/wallStress.dat``. Over the last window it also reports the wall
stress the wall law sees: u* of the smooth law T(3.84) for the mean velocity of the first
fluid rows at their mean distance from the physical walls (y0 and y0 + l of the
velocityProfile), against sqrt(F l_f/2).

    python wallStress.py [CASE] [--window 20]
    python wallStress.py --log-law-start CASE     # rewrite CASE/0 (see below), then stop

``--log-law-start`` rewrites the fluid of ``CASE/0`` (set up by ``sphfoam setup``) at uniform
density rho0 and mass rho0 dx^2 (as ``../poiseuille/convergence.py --uniform-start``) moving
with the smooth-wall log law, u = u* (ln(eta u*/nu)/kappa + 5.2), eta the distance to the
nearer physical wall, u* = sqrt(F l_f/2): the steady state of the mixing-length closure with
the wall condition, which shortens the spin-up from a uniform start (the closure's diffusion
time H^2/nu_t ~ 150 s) to the run's own adjustment.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from sphfoam.case import foamdict
from sphfoam.case.case import Case
from sphfoam.case.times import list_times
from sphfoam.io.fields import has_particles, read_state
from sphfoam.models.walllaw import B_SMOOTH, KAPPA, smooth_ustar
from sphfoam.setup.channel import channel_width as _width
from sphfoam.setup.channel import profile_function, uniform_start

HERE = Path(__file__).resolve().parent


def walls(case: Path) -> tuple[float, float]:
    """y0 and l of the velocityProfile: the physical walls at y0 and y0 + l."""
    funcs = foamdict.read(case / "system" / "controlDict").get("functions", {}) or {}
    fo = funcs[profile_function(case)]
    return float(fo.get("y0", 0.0)), _width(case)


def force_balance_ustar(case: Path, state: dict) -> float:
    """u* = sqrt(F M/(2 rho0 L)): each wall carries half the body force on the fluid mass M
    per unit depth of the channel, periodic over L (T section 3.5.1)."""
    c = Case(case)
    dom = c.particles.domain
    mass = float(np.sum(state["mass"][state["type"] == 0]))
    return math.sqrt(abs(c.gravity[0]) * mass / (2.0 * c.context.rho0 *
                                                 (dom.max[0] - dom.min[0])))


def log_law_start(case: Path) -> float:
    c = Case(case)
    nu = c.transport.nu
    y0, width = walls(case)
    us = force_balance_ustar(case, read_state(Path(case) / "0"))

    def velocity(y):
        eta = np.clip(np.minimum(y - y0, y0 + width - y), 1e-6 * width, None)
        return us * (np.log(eta * us / nu) / KAPPA + B_SMOOTH)

    uniform_start(case, velocity)
    return us


def bulk_velocity(case: Path, first_row: bool = False):
    """Times and bulk velocities U_b of the written time directories; with ``first_row``
    also, per time, the mean u_x of the first fluid row at each wall and its mean distance
    eta from the physical walls (the particles within dx/2 of the first row's eta)."""
    c = Case(case)
    dx = c.context.dx
    y0, width = walls(case)
    times, ub, u1, eta1 = [], [], [], []
    for t, folder in [(t, d) for t, d in list_times(case) if has_particles(d)]:
        s = read_state(folder)
        fluid = s["type"] == 0
        m = s["mass"][fluid]
        times.append(float(t))
        ub.append(float(np.sum(m * s["U"][fluid, 0]) / np.sum(m)))
        y = s["positions"][fluid, 1]
        eta = np.minimum(y - y0, y0 + width - y)
        row = np.abs(eta - eta.min()) < 0.5 * dx
        u1.append(float(s["U"][fluid, 0][row].mean()))
        eta1.append(float(eta[row].mean()))
    if first_row:
        return np.array(times), np.array(ub), np.array(u1), np.array(eta1)
    return np.array(times), np.array(ub)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", nargs="?", type=Path, default=HERE)
    ap.add_argument("--window", type=float, default=20.0,
                    help="seconds of U_b(t) each slope is fitted over")
    ap.add_argument("--log-law-start", action="store_true",
                    help="rewrite CASE/0 moving with the log law, then stop")
    a = ap.parse_args(argv)
    if a.log_law_start:
        us = log_law_start(a.case)
        print(f"{a.case / '0'}: uniform density, u_x from the smooth log law, u* = {us:.4g} m/s")
        return 0
    c = Case(a.case)
    force = c.gravity[0]
    t, ub, u1, eta1 = bulk_velocity(a.case, first_row=True)
    if t.size < 3:
        raise SystemExit(f"{a.case}: fewer than 3 time directories")
    rows = []
    start = t[0]
    while start + a.window <= t[-1] + 1e-9:
        sel = (t >= start - 1e-9) & (t <= start + a.window + 1e-9)
        if sel.sum() >= 2:
            slope = np.polyfit(t[sel], ub[sel], 1)[0]
            rows.append((start + a.window, float(ub[sel].mean()), slope, 1.0 - slope / force))
        start += a.window
    last = (t >= t[-1] - a.window - 1e-9)
    slope = np.polyfit(t[last], ub[last], 1)[0]
    # the wall law T(3.84) at the first fluid rows over the last window: u* and tau_w
    us_theory = force_balance_ustar(a.case, read_state(a.case / "0"))
    us_law = smooth_ustar(float(u1[last].mean()), float(eta1[last].mean()), c.transport.nu)
    law_line = (f"# last {a.window:g} s, first fluid rows: u {u1[last].mean():.6g} m/s at "
                f"{eta1[last].mean():.6g} m from the wall, u* of T(3.84) {us_law:.6g} m/s "
                f"against sqrt(F l_f/2) = {us_theory:.6g} (ratio {us_law / us_theory:.4f}), "
                f"rho u*^2/(F M/2) {(us_law / us_theory) ** 2:.4f}")
    out = a.case / "postProcessing" / "wallStress"
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "wallStress.dat", "w") as fh:
        fh.write(f"# momentum balance of the channel: tau_w/(F M/2) = 1 - (dU_b/dt)/F, "
                 f"F = {force:g} m/s^2, slopes over {a.window:g} s\n")
        fh.write("# endOfWindow\tUbMean\tdUbdt\ttauRatio\n")
        for r in rows:
            fh.write("\t".join(f"{v:.6g}" for v in r) + "\n")
        fh.write(f"# last {a.window:g} s: U_b {ub[last].mean():.6g} m/s, dU_b/dt {slope:.4g} "
                 f"m/s^2, tau_w/(F M/2) {1.0 - slope / force:.4f}\n")
        fh.write(law_line + "\n")
    for r in rows:
        print(f"t <= {r[0]:8.4g} s: U_b {r[1]:.4f} m/s, dU_b/dt {r[2]:+.3e}, "
              f"tau_w/(F M/2) {r[3]:.3f}")
    print(f"last {a.window:g} s: tau_w/(F M/2) = {1.0 - slope / force:.3f} "
          f"(U_b {ub[last].mean():.4f} m/s); written {out / 'wallStress.dat'}")
    print(law_line[2:])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
