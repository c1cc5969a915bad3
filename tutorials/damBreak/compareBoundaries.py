#!/usr/bin/env python
"""The dam break of T §3.9.1 once per boundary model, side by side (T Figs 3.22-3.26).

    python compareBoundaries.py [--dx 0.005] [--T 3] [--boundaries hybrid stationaryGhosts]

Each boundary runs in ``compare/<boundary>/`` (a copy of this case with only
``boundary.type``, ``dx`` and ``endTime`` changed). The table ``compare/boundaries.md``
lists, at T = t sqrt(g/H0) = 1, 2, 3: the residual height H and the front Z against Martin &
Moyce (1952), the water left hanging on the drying back wall (``stuck``, particles) and the
gap between the surge and the dry bed (``gap``, in dx), plus steps and wall-clock time.
``compare/boundaries.png`` overlays Z(T) and H(T).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import sphfoam
from sphfoam import registry
from sphfoam.case.edit import clone_case
from sphfoam.sampling.damBreak import martin_moyce

HERE = Path(__file__).resolve().parent
H0, G = 0.25, 9.81


def run(boundary: str, dx: float, T_end: float, out: Path) -> dict:
    t_end = T_end / math.sqrt(G / H0)
    case = clone_case(HERE, out / boundary, {
        "constant/sphProperties:boundary": {"type": boundary},
        "system/particleDict:dx": dx,
        "system/controlDict:endTime": round(t_end, 6),
        "system/controlDict:writeInterval": round(t_end / 3, 6)})
    sphfoam.setup_case(case)
    t0 = time.perf_counter()
    rep = sphfoam.run(case)
    wall = time.perf_counter() - t0
    rows = np.loadtxt(case / "postProcessing" / "front" / "0" / "front.dat")
    return {"rows": rows, "steps": rep.steps, "wall": wall, "particles": rep.particles,
            "removed": rep.removed}


def at(rows, T, col):
    i = int(np.argmin(np.abs(rows[:, 1] - T)))
    return rows[i, col]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.005)
    ap.add_argument("--T", type=float, default=3.0, help="end time in T = t sqrt(g/H0)")
    ap.add_argument("--boundaries", nargs="*", default=registry.names("boundary"))
    ap.add_argument("--out", type=Path, default=HERE / "compare")
    a = ap.parse_args(argv)
    a.out.mkdir(exist_ok=True)
    front, height = martin_moyce()
    results = {}
    for b in a.boundaries:
        print(f"running {b} ...", flush=True)
        results[b] = run(b, a.dx, a.T, a.out)
    Ts = [T for T in (1.0, 2.0, 3.0) if T <= a.T + 1e-9]
    head = ["boundary"] + [f"H(T={T:g})" for T in Ts] + [f"Z(T={T:g})" for T in Ts] + \
        [f"stuck(T={T:g})" for T in Ts] + [f"gap/dx(T={T:g})" for T in Ts] + \
        ["steps", "wall s", "removed"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    mm = ["Martin & Moyce"] + [f"{np.interp(T, height[:, 0], height[:, 1]):.3f}" for T in Ts] + \
        [f"{np.interp(T, front[:, 0], front[:, 1]):.3f}" for T in Ts] + [""] * (2 * len(Ts) + 3)
    lines.append("| " + " | ".join(mm) + " |")
    for b, r in results.items():
        rows = r["rows"]
        cells = [b] + [f"{at(rows, T, 5):.3f}" for T in Ts] + [f"{at(rows, T, 3):.3f}" for T in Ts]
        cells += [f"{at(rows, T, 6):.0f}" for T in Ts] + [f"{at(rows, T, 7):.2f}" for T in Ts]
        cells += [str(r["steps"]), f"{r['wall']:.0f}", str(r["removed"])]
        lines.append("| " + " | ".join(cells) + " |")
    n_fluid = int(round((H0 / a.dx) ** 2))
    text = (f"Dam break (T 3.9.1), H0 = {H0} m, dx = {a.dx:g} m ({n_fluid} fluid particles), "
            f"to T = {a.T:g}\n\n" + "\n".join(lines) + "\n")
    (a.out / "boundaries.md").write_text(text)
    print(text)
    plot(results, a.out / "boundaries.png", a.dx)


def plot(results, path, dx):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    front, height = martin_moyce()
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for b, r in results.items():
        ax[0].plot(r["rows"][:, 1], r["rows"][:, 3], label=b)
        ax[1].plot(r["rows"][:, 1], r["rows"][:, 5], label=b)
    ax[0].plot(front[:, 0], front[:, 1], "k^", label="Martin & Moyce (1952)")
    ax[1].plot(height[:, 0], height[:, 1], "k^", label="Martin & Moyce (1952)")
    ax[0].set(xlabel="T", ylabel="Z", title=f"surge front, dx = {dx:g} m")
    ax[1].set(xlabel="T", ylabel="H", title="residual height")
    for x in ax:
        x.grid(alpha=0.3)
        x.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
