#!/usr/bin/env python
"""Wall stress of the turbulent channel from its momentum balance, and the log-law start.

The channel is periodic, so the only forces on the water are the body force F (constant/g)
and the walls: per unit length, rho l dU_b/dt = rho F l - 2 tau_w, with U_b the bulk (mean)
velocity of the fluid. In a steady state tau_w = rho F l/2 = rho u*^2. This script reads U_b
from every written time directory and reports tau_w / (rho F l/2) = 1 - (dU_b/dt)/F, from a
least-squares slope of U_b(t) over each ``--window`` seconds and over the last one, into
``postProcessing/wallStress/wallStress.dat``.

    python wallStress.py [CASE] [--window 20]
    python wallStress.py --log-law-start CASE     # rewrite CASE/0 (see below), then stop

``--log-law-start`` rewrites the fluid of ``CASE/0`` (set up by ``sphfoam setup``) at uniform
density rho0 and mass rho0 dx^2 (as ``../poiseuille/convergence.py --uniform-start``) moving
with the smooth-wall log law, u = u* (ln(eta u*/nu)/kappa + 5.2), eta the distance to the
nearer wall, u* = sqrt(F l/2): the steady state the wall condition aims at, which shortens
the spin-up from a uniform start (about l U_b/(4 u*^2) ~ 200 s) to the run's own adjustment.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "poiseuille"))

from convergence import _width, uniform_start  # noqa: E402

from sphfoam.case.case import Case  # noqa: E402
from sphfoam.io.fields import read_state  # noqa: E402
from sphfoam.case.times import list_times  # noqa: E402
from sphfoam.io.fields import has_particles  # noqa: E402
from sphfoam.models.walllaw import B_SMOOTH, KAPPA  # noqa: E402
from sphfoam.sampling import channel_theory as ct  # noqa: E402


def log_law_start(case: Path) -> float:
    c = Case(case)
    force, width, nu = c.gravity[0], _width(case), c.transport.nu
    us = ct.friction_velocity(force, width)

    def velocity(y):
        eta = np.clip(np.minimum(y, width - y), 1e-6 * width, None)
        return us * (np.log(eta * us / nu) / KAPPA + B_SMOOTH)

    uniform_start(case, velocity)
    return us


def bulk_velocity(case: Path) -> tuple[np.ndarray, np.ndarray]:
    times, ub = [], []
    for t, folder in [(t, d) for t, d in list_times(case) if has_particles(d)]:
        s = read_state(folder)
        fluid = s["type"] == 0
        m = s["mass"][fluid]
        times.append(float(t))
        ub.append(float(np.sum(m * s["U"][fluid, 0]) / np.sum(m)))
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
    t, ub = bulk_velocity(a.case)
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
    out = a.case / "postProcessing" / "wallStress"
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "wallStress.dat", "w") as fh:
        fh.write(f"# momentum balance of the channel: tau_w/(rho F l/2) = 1 - (dU_b/dt)/F, "
                 f"F = {force:g} m/s^2, slopes over {a.window:g} s\n")
        fh.write("# endOfWindow\tUbMean\tdUbdt\ttauRatio\n")
        for r in rows:
            fh.write("\t".join(f"{v:.6g}" for v in r) + "\n")
        fh.write(f"# last {a.window:g} s: U_b {ub[last].mean():.6g} m/s, dU_b/dt {slope:.4g} "
                 f"m/s^2, tau_w/(rho F l/2) {1.0 - slope / force:.4f}\n")
    for r in rows:
        print(f"t <= {r[0]:8.4g} s: U_b {r[1]:.4f} m/s, dU_b/dt {r[2]:+.3e}, "
              f"tau_w/(rho F l/2) {r[3]:.3f}")
    print(f"last {a.window:g} s: tau_w/(rho F l/2) = {1.0 - slope / force:.3f} "
          f"(U_b {ub[last].mean():.4f} m/s); written {out / 'wallStress.dat'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
