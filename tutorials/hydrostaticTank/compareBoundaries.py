#!/usr/bin/env python
"""The tank at rest once per boundary model: does the wall carry the column?

    python compareBoundaries.py [--dx 0.01] [--endTime 10] [--boundaries hybrid ...]

Each boundary runs in ``compare/<boundary>/`` (written 50 times). The table
``compare/boundaries.md`` lists: the bed pressure (the line through the fluid pressure of the
middle half of the tank, from one kernel support above the bed to mid-depth, at the bed)
against rho g H at the end and averaged over the last fifth of the run (a column bouncing
on its wall averages out), the bottom row's pressure against rho g (H - y), the fluid
particles found inside a wall over all written times, the kinetic energy and the rms
vertical velocity of the column's centre of mass over the last fifth, and steps and
wall-clock time.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import sphfoam
from sphfoam import registry
from sphfoam.case.case import Case
from sphfoam.case.edit import clone_case
from sphfoam.case.times import list_times
from sphfoam.io.fields import read_state
from sphfoam.sampling.hydrostatic import bed_pressure

HERE = Path(__file__).resolve().parent
H, W, RHO0, G = 0.4, 0.5, 1000.0, 9.81


def measure(case: Path, dx: float, reach: float) -> dict:
    crossed, beds, vcm = 0, [], []
    times = list_times(case)[1:]
    for _, folder in times:
        s = read_state(folder)
        f = s["type"] == 0
        x, y = s["positions"][f].T
        crossed = max(crossed, int(np.count_nonzero((x <= 0) | (x >= W) | (y <= 0))))
        bed, row, yrow = bed_pressure(x, y, s["p"][f], x0=0.0, width=W, depth=H, reach=reach,
                                      dx=dx)
        beds.append(bed / (RHO0 * G * H))
        vcm.append(float(s["U"][f][:, 1].mean()))
    last = max(1, len(times) // 5)
    u = s["U"][f]
    ke = 0.5 * float(np.sum(s["mass"][f] * (u ** 2).sum(axis=1)))
    return {"bed": beds[-1], "bed_mean": float(np.mean(beds[-last:])),
            "row": row / (RHO0 * G * (H - yrow)), "crossed": crossed, "ke": ke,
            "vcm": float(np.sqrt(np.mean(np.square(vcm[-last:]))))}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, default=0.01)
    ap.add_argument("--endTime", type=float, default=10.0)
    ap.add_argument("--boundaries", nargs="*", default=registry.names("boundary"))
    ap.add_argument("--out", type=Path, default=HERE / "compare")
    a = ap.parse_args(argv)
    a.out.mkdir(exist_ok=True)
    lines = ["| boundary | bed p / rho g H, end | bed p / rho g H, mean of last 1/5 | "
             "bottom row p / rho g (H-y) | in a wall | KE at end (J/m) | "
             "centre-of-mass v rms (m/s) | steps | wall s |", "|---|---|---|---|---|---|---|---|---|"]
    for b in a.boundaries:
        print(f"running {b} ...", flush=True)
        case = clone_case(HERE, a.out / b, {
            "constant/sphProperties:boundary": {"type": b},
            "system/particleDict:dx": a.dx,
            "system/controlDict:endTime": a.endTime,
            "system/controlDict:writeInterval": a.endTime / 50})
        c = Case(case)
        sphfoam.setup_case(c)
        reach = c.models.sph["kernel"].support * c.context.h
        t0 = time.perf_counter()
        rep = sphfoam.run(case)
        wall = time.perf_counter() - t0
        m = measure(case, a.dx, reach)
        lines.append(f"| {b} | {m['bed']:.4f} | {m['bed_mean']:.4f} | {m['row']:.3f} | "
                     f"{m['crossed']} | {m['ke']:.2e} | {m['vcm']:.1e} | {rep.steps} | "
                     f"{wall:.0f} |")
        print(lines[-1], flush=True)
    text = (f"Hydrostatic tank, H = {H} m, H/dx = {H / a.dx:g}, {a.endTime:g} s\n\n"
            + "\n".join(lines) + "\n")
    (a.out / "boundaries.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
