#!/usr/bin/env python
"""Maximum run-up on the wall against wave amplitude, eta_max/H vs A/H (P Fig. 7).

    python runUpCurve.py [--amplitudes 0.05 0.1 0.2 0.3 0.4 0.5 0.6] [--dx 0.625]

Each amplitude runs in ``runUp/A<A/H>/`` (a copy of this case with only the wave height,
vmax and dx changed) until the reflected crest has left the wall; ``runUp/runUp.dat`` and
``runUp/runUp.png`` hold eta_max/H against A/H, with the linear-theory line 2 A/H for
reference.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from sphfoam.case.case import Case
from sphfoam.case.edit import clone_case
from sphfoam.runner import run_case, setup_case

HERE = Path(__file__).resolve().parent
DEPTH, WALL, G = 10.0, 100.0, 9.81


def run_one(ratio: float, dx: float, out: Path) -> float:
    A = ratio * DEPTH
    c = math.sqrt(G * (DEPTH + A))
    t_end = WALL / c + 6.0 * DEPTH / c          # crest at the wall, then back 3 depths
    case = clone_case(HERE, out / f"A{ratio:g}", {
        "constant/waveProperties:waves.incident.height": A,
        "constant/sphProperties:equationOfState.vmax": round(c, 4),
        "system/particleDict:dx": dx,
        "system/controlDict:endTime": round(t_end, 3),
        "system/controlDict:writeInterval": round(t_end, 3)})
    setup_case(Case(case), log=lambda m: None)
    run_case(case, progress=False, echo=None)
    rows = np.loadtxt(case / "postProcessing" / "runUp" / "0" / "runUp.dat", ndmin=2)
    return float(np.nanmax(rows[:, 1])) / DEPTH


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--amplitudes", nargs="*", type=float,
                    default=[0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    ap.add_argument("--dx", type=float, default=0.625)
    ap.add_argument("--out", type=Path, default=HERE / "runUp")
    a = ap.parse_args(argv)
    a.out.mkdir(exist_ok=True)
    rows = []
    for r in a.amplitudes:
        print(f"A/H = {r:g} ...", flush=True)
        rows.append((r, run_one(r, a.dx, a.out)))
        print(f"  eta_max/H = {rows[-1][1]:.4f}", flush=True)
    arr = np.array(rows)
    np.savetxt(a.out / "runUp.dat", arr, header="A/H\teta_max/H", delimiter="\t", fmt="%.6g")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(arr[:, 0], arr[:, 1], "o-", label=f"sphfoam, H/dx = {DEPTH / a.dx:g}")
    ax.plot(arr[:, 0], 2 * arr[:, 0], "k--", label="2 A/H (linear reflection)")
    ax.set(xlabel="A/H", ylabel=r"$\eta_{max}/H$", title="maximum run-up on a vertical wall")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out / "runUp.png", dpi=120)
    print(open(a.out / "runUp.dat").read())


if __name__ == "__main__":
    main()
