"""Precision study (issues 12 and 34): single against double on the dam break and the flume,
on either backend.

    python benchmarks/precision_study.py [--backend cpu|cuda] [--out FILE.json]
                                         [--dam-dx 0.01]

damBreak at dx = 0.01 (1 693 particles) to t = 0.4 s: the front, the largest x of the fluid
(the leading edge Z of T(3.81), in m from the wall at x = 0), at t = 0.1, 0.2, 0.3, 0.4 s;
solitaryWave as set up (5 933 particles) to t = 2 s: the crest, the largest y of the fluid,
at t = 0.5, 1, 1.5, 2 s. Both precisions from the same set-up. Time: CPU seconds of the
stepping on the CPU backend (process time, one thread unless NUMBA_NUM_THREADS says
otherwise), wall seconds on the CUDA backend (synchronised). Prints a table and writes the
JSON (default /tmp/sphfoam-precision-study.json).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

TUT = Path(__file__).resolve().parent.parent / "tutorials"


def run(tut: str, edits: dict, backend: str, t_end: float, probes, metric) -> dict:
    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.setup import setup_case

    tmp = Path(tempfile.mkdtemp())
    d = clone_case(TUT / tut, tmp / tut, dict({"system/controlDict:functions": {}}, **edits))
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")),
                           backend=backend)
    sync = (lambda: __import__("numba").cuda.synchronize()) if backend == "cuda" else \
        (lambda: None)
    clock = time.perf_counter if backend == "cuda" else time.process_time
    sim.step()
    sim.step()                        # compiled
    out, k, steps = [], 0, 0
    sync()
    c0 = clock()
    while sim.time < t_end:
        dt_rem = probes[k] - sim.time if k < len(probes) else np.inf
        sim.step(dt_rem)
        steps += 1
        if k < len(probes) and sim.time >= probes[k] - 1e-12:
            out.append(metric(sim))
            k += 1
    sync()
    sec = clock() - c0
    n = int(sim.state.n)
    return dict(n=n, steps=steps, seconds=sec, us_per_particle_step=1e6 * sec / (steps * n),
                values=out)


def front(sim) -> float:
    from sphfoam.engine.state import FLUID

    st = sim.state
    return float(np.max(st.x[st.kind == FLUID]))


def crest(sim) -> float:
    from sphfoam.engine.state import FLUID

    st = sim.state
    return float(np.max(st.y[st.kind == FLUID]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--backend", default="cpu", choices=("cpu", "cuda"))
    ap.add_argument("--dam-dx", type=float, default=0.01)
    ap.add_argument("--out", default="/tmp/sphfoam-precision-study.json")
    a = ap.parse_args(argv)
    cases = [("damBreak", {"system/particleDict:dx": a.dam_dx}, 0.4, [0.1, 0.2, 0.3, 0.4],
              front, "front x (m)"),
             ("solitaryWave", {}, 2.0, [0.5, 1.0, 1.5, 2.0], crest, "crest y (m)")]
    res = {}
    for tut, edits, t_end, probes, metric, what in cases:
        for prec in ("double", "single"):
            r = run(tut, dict(edits, **{"system/sphSchemes:precision": prec}), a.backend,
                    t_end, probes, metric)
            r.update(probes=probes, quantity=what)
            res[f"{tut}/{prec}"] = r
            print(tut, prec, json.dumps(r), flush=True)
    Path(a.out).write_text(json.dumps(dict(backend=a.backend, cases=res), indent=1))
    print(f"\n| case | precision | particles | steps | {'wall' if a.backend == 'cuda' else 'CPU'}"
          " s | us/particle-step | values | largest difference from double |")
    print("|---|---|---:|---:|---:|---:|---|---:|")
    for key, r in res.items():
        tut, prec = key.split("/")
        ref = res[f"{tut}/double"]["values"]
        diff = max(abs(x - y) for x, y in zip(r["values"], ref)) if ref else float("nan")
        print(f"| {tut} | {prec} | {r['n']} | {r['steps']} | {r['seconds']:.1f} | "
              f"{r['us_per_particle_step']:.3f} | "
              f"{', '.join(f'{v:.4f}' for v in r['values'])} | {diff:.2e} m |")


if __name__ == "__main__":
    main()
