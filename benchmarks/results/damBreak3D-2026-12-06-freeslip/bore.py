"""The wire gauges of damBreak3D runs against the measurement: RMS over 0-6 s, the reservoir's
mean level over 0.5-2.5 s, and when the return bore passes H3 and H4.

    python bore.py RUN ...      (a heightsWire.dat, or a folder holding one)
    python bore.py --level RUN ...  the mean error (simulated - measured) of each gauge over
                                    3.2-6 s instead: the late level
    python bore.py --until T RUN ... the RMS over 0-T s (a run that stopped early, and the
                                    runs it is compared with over the same time)

The bore's arrival at a gauge is the first time after t0 (H3: 1.85 s, H4: 2.4 s) that the
height exceeds its lowest value over t0 ... t0 + 0.6 s by 0.06 m.
"""
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
MEASURED = HERE.parents[2] / "tutorials/damBreak3D/validation/test_case_2_exp_data.dat"


def arrival(t, h, t0, rise=0.06):
    after = t > t0
    tt, hh = t[after], h[after]
    if not (tt < t0 + 0.6).any():
        return np.nan            # the run stopped before
    base = np.nanmin(hh[tt < t0 + 0.6])
    up = np.flatnonzero(hh > base + rise)
    return tt[up[0]] if up.size else np.nan


def level(name, t, hs, te, meas):
    late = (te >= 3.2) & (te <= min(6.0, t[-1]))
    err = [np.mean(np.interp(te, t, np.nan_to_num(h))[late] - m[late]) for h, m in
           zip(hs, meas)]
    print(f"{name:<28}" + " ".join(f"{e:+6.3f}" for e in err) + f" | {np.mean(err):+.3f}")


def row(name, t, hs, te, meas, until=6.0):
    rms = []
    for h, m in zip(hs, meas):
        hi = np.interp(te, t, np.nan_to_num(h))
        keep = te <= min(until, t[-1])
        rms.append(np.sqrt(np.mean((hi[keep] - m[keep]) ** 2)))
    mid = (t > 0.5) & (t < 2.5)
    print(f"{name:<28}" + " ".join(f"{r:6.3f}" for r in rms)
          + f" | {np.nanmean(hs[3][mid]):.3f}  {arrival(t, hs[2], 1.85):.2f}  "
          f"{arrival(t, hs[3], 2.4):.2f}")


def main(args):
    e = np.loadtxt(MEASURED, skiprows=1)
    te = e[:, 0]
    meas = [e[:, 11], e[:, 10], e[:, 9], e[:, 12]]   # H1, H2, H3, H4 (labels swapped)
    late = "--level" in args
    until = 6.0
    if "--until" in args:
        k = args.index("--until")
        until = float(args[k + 1])
        args = args[:k] + args[k + 2:]
    folders = [a for a in args if a != "--level"]
    print(f"{'run':<28}" + " ".join(f"{g:>6}" for g in ("H1", "H2", "H3", "H4"))
          + (" | mean error 3.2-6 s (m)" if late else " | H4 0.5-2.5 s  bore at H3  at H4"))
    if not late:
        row("measured", te, meas, te, meas)
    for f in folders:
        path = Path(f) if Path(f).is_file() else Path(f) / "heightsWire.dat"
        d = np.loadtxt(path)
        if late:
            level(str(f), d[:, 0], [d[:, i] for i in range(1, 5)], te, meas)
        else:
            row(str(f), d[:, 0], [d[:, i] for i in range(1, 5)], te, meas, until)


if __name__ == "__main__":
    main(sys.argv[1:])
