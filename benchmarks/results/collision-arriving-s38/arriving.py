"""The collision's two waves as they arrive, and the potential flow's peak for them.

For each run folder of tutorials/solitaryCollision/studyDict.convergence: both crests'
heights at the written times 4 and 5 s (before the waves' fronts meet, about 6 s), read by
the fluid fraction 1/2 (sub-particle, exact on stretched lattices) and by the highest
particle + dx/2; then the fully nonlinear potential flow's peak for waves of the heights read
at 5 s (sphfoam.reference.wall_reflection.head_on_collision, HOS), against which the run's
own peak (the study's peakFraction) gives the collision's error apart from the waves'
growth on their way.

    python arriving.py RUN [RUN ...] > arriving.md
"""
import json
import sys
from pathlib import Path

import numpy as np

from sphfoam import api
from sphfoam.case.case import Case
from sphfoam.reference.wall_reflection import head_on_collision
from sphfoam.sampling.waves import fraction_surface

D, REF = 10.0, 5.377


def crests(case, t, kernel, h, dx):
    d = api.read_time(case, t)
    fl = d["type"] == 0
    x, y = d["positions"][fl, 0], d["positions"][fl, 1]
    vol = d["mass"][fl] / d["rho"][fl]
    out = []
    for side in (x < 0, x > 0):
        xc = x[np.argmax(np.where(side, y, -np.inf))]
        eta = fraction_surface(x, y, vol, xc + np.linspace(-2, 2, 41) * dx, kernel, h, dx,
                               still=D)
        near = np.abs(x - xc) < 2 * dx
        out.append((float(np.nanmax(eta)), float(y[near].max() + dx / 2 - D)))
    return out


print("| run | A = 3 m wave at 4 / 5 s, fraction (particle) | A = 2 m wave at 4 / 5 s, fraction (particle) "
      "| potential flow's peak for the 5-s heights | run's peak, fraction | its error against 5.377 | against the arriving waves' |")
print("|---|---|---|---|---|---|---|")
for run in sys.argv[1:]:
    case = Case(run)
    kernel = case.models.sph["kernel"]
    res = json.loads((Path(run) / "result.json").read_text())
    dx = float(res["dx"])
    h = kernel.h(dx)
    c4, c5 = crests(run, 4, kernel, h, dx), crests(run, 5, kernel, h, dx)
    pf = head_on_collision(c5[0][0] / D, c5[1][0] / D).peak * D
    row = (f"| {Path(run).name} | {c4[0][0]:.3f} / {c5[0][0]:.3f} ({c4[0][1]:.3f} / {c5[0][1]:.3f}) "
           f"| {c4[1][0]:.3f} / {c5[1][0]:.3f} ({c4[1][1]:.3f} / {c5[1][1]:.3f}) | {pf:.3f} ")
    if "peakFraction" not in res:      # the default reads its crest by the particles only
        print(row + "| | | |")
        continue
    peak = float(res["peakFraction"])
    print(row + f"| {peak:.3f} | {100 * (peak / REF - 1):+.2f} % | {100 * (peak / pf - 1):+.2f} % |")
