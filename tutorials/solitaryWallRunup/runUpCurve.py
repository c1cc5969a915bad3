#!/usr/bin/env python
"""Maximum run-up on the wall against wave amplitude, eta_max/H vs A/H (P Fig. 7).

    python runUpCurve.py [--amplitudes 0.05 0.1 0.2 0.3 0.4 0.5 0.6] [--dx 0.625] [--left -150]

Each amplitude runs in ``runUp/A<A/H>/`` (a copy of this case with only the wave height,
vmax and dx changed) until the reflected crest has left the wall; ``runUp/runUp.dat`` and
``runUp/runUp.png`` hold eta_max/H against A/H, with the linear-theory line 2 A/H for
reference, the third-order theory of Su & Mirie (1980), R/H = 2a + a^2/2 + 3a^3/4, and the
fully nonlinear potential flow (sphfoam.reference.wall_reflection: the HOS method up to
A/H = 0.4, the boundary integral to 0.5; its column in runUp.dat is nan beyond).
``--left`` moves the tank's left end (the wave's crest starts at x = 0, the wall is at
x = 100 m); -60 m saves 40 % of the particles for A/H >= 0.2, but smaller waves are too
long for it (at A/H = 0.05 the initial wave still rises 0.18 m at x = -60 m).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import sphfoam
from sphfoam.case.edit import clone_case
from sphfoam.reference import wall_reflection as wr

HERE = Path(__file__).resolve().parent
DEPTH, WALL, G = 10.0, 100.0, 9.81


def run_one(ratio: float, dx: float, out: Path, left: float = -150.0) -> float:
    A = ratio * DEPTH
    c = math.sqrt(G * (DEPTH + A))
    t_end = WALL / c + 6.0 * DEPTH / c          # crest at the wall, then back 3 depths
    case = clone_case(HERE, out / f"A{ratio:g}", {
        "constant/waveProperties:waves.incident.height": A,
        "constant/sphProperties:equationOfState.vmax": round(c, 4),
        "system/particleDict:dx": dx,
        "system/particleDict:fluid.water.min": [left, 0.0],
        "system/particleDict:walls.tank.min": [left, 0.0],
        "system/controlDict:endTime": round(t_end, 3),
        "system/controlDict:writeInterval": round(t_end, 3)})
    sphfoam.setup_case(case)
    sphfoam.run(case)
    rows = np.loadtxt(case / "postProcessing" / "runUp" / "0" / "runUp.dat", ndmin=2)
    return float(np.nanmax(rows[:, 1])) / DEPTH


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--amplitudes", nargs="*", type=float,
                    default=[0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    ap.add_argument("--dx", type=float, default=0.625)
    ap.add_argument("--left", type=float, default=-150.0, help="x of the tank's left wall")
    ap.add_argument("--out", type=Path, default=HERE / "runUp")
    a = ap.parse_args(argv)
    out = a.out.resolve()
    if (out == HERE or HERE in out.parents) and out.relative_to(HERE).parts[:1] != ("runUp",):
        ap.error(f"--out {a.out}: inside the case {HERE} (other than its runUp/ folder) the "
                 "clones would copy themselves; choose a folder outside the case")
    try:
        a.out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        ap.error(f"--out {a.out}: {e.strerror}")
    rows = []
    for r in a.amplitudes:
        print(f"A/H = {r:g} ...", flush=True)
        rows.append((r, run_one(r, a.dx, a.out, a.left)))
        print(f"  eta_max/H = {rows[-1][1]:.4f}", flush=True)
    exact = [wr.wall_reflection(r).run_up if 0.0 < r <= wr.MAX_EPS_BIE else np.nan
             for r, _ in rows]
    arr = np.column_stack([np.array(rows), exact])
    np.savetxt(a.out / "runUp.dat", arr, header="A/H\teta_max/H\tpotentialFlow",
               delimiter="\t", fmt="%.6g")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(arr[:, 0], arr[:, 1], "o-", label=f"sphfoam, H/dx = {DEPTH / a.dx:g}")
    a_ = np.linspace(0.0, max(arr[:, 0].max(), 0.6), 61)
    ax.plot(a_, 2 * a_, "k:", label="2 A/H (linear reflection)")
    ax.plot(a_, 2 * a_ + a_**2 / 2 + 3 * a_**3 / 4, "k--",
            label="Su & Mirie (1980), third order")
    a_pf = np.arange(0.05, wr.MAX_EPS_BIE + 1e-9, 0.05)
    ax.plot(a_pf, [wr.wall_reflection(round(r, 12)).run_up for r in a_pf], "k-", lw=0.8,
            label="potential flow, fully nonlinear (HOS; boundary integral above 0.4)")
    ax.set(xlabel="A/H", ylabel=r"$\eta_{max}/H$", title="maximum run-up on a vertical wall")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out / "runUp.png", dpi=120)
    print(open(a.out / "runUp.dat").read())


if __name__ == "__main__":
    main()
