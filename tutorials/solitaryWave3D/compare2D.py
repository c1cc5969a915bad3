"""The 3-D flume against the 2-D tutorial at the same dx: the crest height and arrival time
at every gauge, their mean over 2-18 m and the celerity fitted to the crests' arrival
between 2 and 18 m.

    python compare2D.py [PATH_TO_THE_2D_RUN] [--gauges NAME]

PATH_TO_THE_2D_RUN defaults to ../solitaryWave/study/case11, the 2-D flume with this case's
models (the thesis's optimum: Shepard every 40 steps, Goring's paddle; the 2-D tutorial's
default is the low-dissipation set-up since issue 35), made by

    sphfoam study ../solitaryWave/studyDict --only case11

(run it first); NAME is the waveGauges
object both runs have (default: gauges, the tutorials' own; e.g. a `surface fraction` one
added to both). Exits 1 if a gauge's crest height or the celerity differs by more than 1 %.
"""

import argparse
from pathlib import Path

import numpy as np

here = Path(__file__).resolve().parent
ap = argparse.ArgumentParser()
ap.add_argument("other", nargs="?", type=Path,
                default=here.parent / "solitaryWave" / "study" / "case11")
ap.add_argument("--gauges", default="gauges")
args = ap.parse_args()


def crests(case: Path, name: str):
    """x of each gauge, its crest height and the crest's time (a parabola through the
    highest sample and its neighbours)."""
    files = sorted((case / "postProcessing" / name).glob(f"*/{name}.dat"),
                   key=lambda p: float(p.parent.name))
    if not files:
        raise SystemExit(f"{case}: no postProcessing/{name} (run the case first)")
    data = np.vstack([np.loadtxt(f, ndmin=2) for f in files])
    with files[-1].open() as fh:
        cols = [ln for ln in fh if ln.startswith("#")][-1].lstrip("# ").split()
    x = np.array([float(c[4:-1].split(",")[0]) for c in cols[1:]])
    t, eta = data[:, 0], data[:, 1:]
    height, when = [], []
    for k in range(eta.shape[1]):
        i = int(np.clip(np.nanargmax(eta[:, k]), 1, len(t) - 2))
        y0, y1, y2 = eta[i - 1:i + 2, k]
        den = y0 - 2 * y1 + y2
        s = 0.5 * (y0 - y2) / den if den != 0 else 0.0
        height.append(y1 - 0.25 * (y0 - y2) * s)
        when.append(t[i] + s * (t[i + 1] - t[i]))
    return x, np.array(height), np.array(when)


x3, h3, t3 = crests(here, args.gauges)
x2, h2, t2 = crests(args.other, args.gauges)
fit = (x3 >= 2) & (x3 <= 18)
c3 = np.polyfit(t3[fit], x3[fit], 1)[0]
c2 = np.polyfit(t2[fit], x2[fit], 1)[0]
print("x (m)\tH 2-D (m)\tH 3-D (m)\tdiff %\tt 2-D (s)\tt 3-D (s)")
for k in range(len(x3)):
    print(f"{x3[k]:g}\t{h2[k]:.4f}\t{h3[k]:.4f}\t{100 * (h3[k] / h2[k] - 1):+.2f}\t"
          f"{t2[k]:.3f}\t{t3[k]:.3f}")
m2, m3 = h2[fit].mean(), h3[fit].mean()
print(f"mean crest 2-18 m: 2-D {m2:.4f} m, 3-D {m3:.4f} m ({100 * (m3 / m2 - 1):+.2f} %)")
print(f"celerity 2-18 m: 2-D {c2:.4f} m/s, 3-D {c3:.4f} m/s ({100 * (c3 / c2 - 1):+.2f} %)")
worst = max(np.abs(h3 / h2 - 1).max(), abs(c3 / c2 - 1))
raise SystemExit(0 if worst <= 0.01 else 1)
