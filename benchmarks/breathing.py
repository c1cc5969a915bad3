"""The start's breathing: the crest height's oscillation over the first seconds of a solitary
wave set up from theory (issue 35, "a quiet start").

Clones a tutorial to a temporary folder, replaces its function objects with one
``crestTracker`` (sub-particle ``surface fraction``, every ``--every`` s), runs it to
``--end`` and reports

    breathing = max - min of eta_c(t) - (a + b t)   over 0 <= t <= end,  in % of A,

the peak-to-peak of the crest elevation about its least-squares linear trend (the slow
growth or loss of the wave is the trend; the start's oscillation is what is left). The
reading at t = 0 is the set-up's own.

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/breathing.py solitaryWallRunup
    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/breathing.py solitaryCollision \
        --edit constant/setFieldsDict...   # any FILE:KEY=VALUE edits
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def breathing(t, eta, A):
    """Peak-to-peak of eta about its linear trend, in % of A; and the trend's slope (m/s)."""
    t, eta = np.asarray(t, float), np.asarray(eta, float)
    b, a = np.polyfit(t, eta, 1)
    r = eta - (a + b * t)
    return 100.0 * float(r.max() - r.min()) / A, float(b)


def acoustic_breathing(t, eta, A, period):
    """Peak-to-peak of eta about its running mean over one ``period`` (the column's acoustic
    period 4 (d + A)/c0), in % of A: the oscillation alone, whatever the slow trend (a wave
    that is not the scheme's own steady wave, e.g. KdV2's, grows for a second or so). Over
    the times where the centred window fits, [period/2, end - period/2]."""
    t, eta = np.asarray(t, float), np.asarray(eta, float)
    dt = min(0.005, period / 40)
    tt = np.arange(t[0], t[-1] + 1e-12, dt)
    ee = np.interp(tt, t, eta)
    n = max(1, int(round(period / dt)))
    mean = np.convolve(ee, np.ones(n) / n, mode="valid")
    r = ee[(n - 1) // 2:(n - 1) // 2 + mean.size] - mean
    return 100.0 * float(r.max() - r.min()) / A


def _value(text):
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def parse_edits(items):
    """``--edit FILE:KEY=VALUE`` arguments as clone_case's edits: VALUE a Python literal
    (a number, a list, a dict) or else the string itself."""
    edits = {}
    for s in items:
        k, v = s.split("=", 1)
        edits[k] = _value(v)
    return edits


def measure(tutorial, end=2.0, every=0.01, edits=None, surface="fraction", keep=None,
            echo=None, gauges=()):
    """Run ``tutorial`` (a name under tutorials/ or a path) with ``edits`` to ``end`` and
    return (t, x_c, eta_c, case folder) of its highest crest (``gauges``: also wave gauges at these x,
    ``postProcessing/gauges``, e.g. in still water)."""
    import sphfoam
    from sphfoam.case.case import Case

    src = Path(tutorial) if Path(tutorial).is_dir() else ROOT / "tutorials" / tutorial
    still = float(Case(src).particles.fluid[next(iter(Case(src).particles.fluid))].max[1])
    e = {"system/controlDict:endTime": end, "system/controlDict:writeInterval": end,
         "system/controlDict:functions": {"crest": {
             "type": "crestTracker", "still": still, "surface": surface,
             "writeControl": "runTime", "writeInterval": every}}}
    if gauges:
        e["system/controlDict:functions"]["gauges"] = {
            "type": "waveGauges", "x": list(gauges), "still": still, "surface": surface,
            "writeControl": "runTime", "writeInterval": every}
    e.update(edits or {})
    dst = Path(keep) if keep else Path(tempfile.mkdtemp(prefix="breathing-")) / src.name
    case = sphfoam.clone_case(src, dst, e)
    sphfoam.run(case, echo=echo)
    rows = np.loadtxt(Path(dst) / "postProcessing" / "crest" / "0" / "crest.dat", ndmin=2)
    return rows[:, 0], rows[:, 1], rows[:, 2], dst


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tutorial")
    ap.add_argument("--end", type=float, default=2.0)
    ap.add_argument("--every", type=float, default=0.01)
    ap.add_argument("--height", type=float, default=None,
                    help="A (m); default the largest wave of constant/waveProperties")
    ap.add_argument("--surface", default="fraction")
    ap.add_argument("--edit", action="append", default=[], metavar="FILE:KEY=VALUE")
    ap.add_argument("--keep", default=None, help="run in this folder and keep it")
    ap.add_argument("--gauges", type=float, nargs="*", default=(),
                    help="also wave gauges at these x (m), e.g. in still water")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    edits = parse_edits(a.edit)
    t, xc, ec, dst = measure(a.tutorial, a.end, a.every, edits, a.surface, a.keep,
                             gauges=a.gauges)
    if a.height is None:
        from sphfoam.case.case import Case
        src = Path(a.tutorial) if Path(a.tutorial).is_dir() else ROOT / "tutorials" / a.tutorial
        A = max(w.height for w, _ in Case(src).waves.values())
    else:
        A = a.height
    pp, slope = breathing(t, ec, A)
    from sphfoam.case.case import Case
    case = Case(dst)
    eos, ctx = case.models.sph["equationOfState"], case.context
    rho = ctx.rho0 * (1 + 1e-6)
    c0 = float(np.sqrt(eos.pressure(np.array([rho]), ctx)[0] / (rho - ctx.rho0)))
    box = next(iter(case.particles.fluid.values()))
    period = 4 * (box.max[1] - box.min[1] + A) / c0       # the column's acoustic period
    out = {"tutorial": a.tutorial, "edits": edits, "A": A, "breathing_pct": round(pp, 3),
           "acoustic_period_s": round(period, 4),
           "acoustic_breathing_pct": round(acoustic_breathing(t, ec, A, period), 3),
           "trend_m_per_s": round(slope, 5), "eta0": float(ec[0]),
           "min": float(ec.min()), "t_min": float(t[np.argmin(ec)]), "max": float(ec.max())}
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:>16}: {v}")
        for i in range(0, t.size, max(1, t.size // 40)):
            print(f"  t {t[i]:6.3f}  x_c {xc[i]:9.3f}  eta_c {ec[i]:7.4f}")
    return out


if __name__ == "__main__":
    sys.exit(main() and 0)
