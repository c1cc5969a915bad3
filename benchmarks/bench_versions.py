#!/usr/bin/env python
"""Cost per particle-step of two checkouts of sphfoam on the same case, interleaved.

    python benchmarks/bench_versions.py OLD NEW [--case matched] [--sizes 23000 90000]
                                               [--threads 1 2] [--rounds 5] [--seconds 2]

OLD and NEW are checkouts (folders holding ``sphfoam/`` and ``benchmarks/``), e.g. a
``git worktree`` of the commit before a redesign and this one. For every size and thread
count each round runs one child process per checkout, in turn (OLD, NEW, OLD, NEW, ...): it
builds the case with that checkout's own ``bench_engine.make_case_sim`` (compiled once
before the rounds, so the children load machine code from the cache), takes 10 steps, then
steps for ``--seconds`` of CPU time and prints its CPU microseconds per particle-step.
Interleaving the checkouts makes their ratio robust to a host whose speed drifts; the
table gives each one's median and the ratio NEW / OLD (below 1: NEW is faster).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

CHILD = """
import json, os, sys, time
sys.path.insert(0, os.path.join(os.getcwd(), "benchmarks"))
import numba
import bench_engine as be
numba.set_num_threads({threads})
sim, info = be.make_case_sim({case!r}, {size})
for _ in range(10):
    sim.step()
t0 = time.process_time(); k = 0
while time.process_time() - t0 < {seconds}:
    sim.step(); k += 1
print(json.dumps(dict(us=(time.process_time() - t0) / k / info["n"] * 1e6, n=info["n"],
                      steps=k)))
"""


def child(checkout: Path, case: str, size: int, threads: int, seconds: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(checkout))
    code = CHILD.format(case=case, size=size, threads=threads, seconds=seconds)
    out = subprocess.run([sys.executable, "-c", code], cwd=checkout, env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--case", default="matched")
    ap.add_argument("--sizes", type=int, nargs="+", default=[23000, 90000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=2.0)
    a = ap.parse_args(argv)
    rows = []
    for size in a.sizes:
        for threads in a.threads:
            for which in (a.old, a.new):           # compile (or load) once, untimed
                child(which.resolve(), a.case, size, threads, 0.1)
            res = {"old": [], "new": []}
            for _ in range(a.rounds):
                for key, which in (("old", a.old), ("new", a.new)):
                    r = child(which.resolve(), a.case, size, threads, a.seconds)
                    res[key].append(r["us"])
            old, new = statistics.median(res["old"]), statistics.median(res["new"])
            rows.append(dict(case=a.case, n=r["n"], threads=threads, old_us=old, new_us=new,
                             ratio=new / old, old_rounds=res["old"], new_rounds=res["new"]))
            print(f"{a.case} n {r['n']:7d} threads {threads}: old {old:.4f} new {new:.4f} "
                  f"us/particle-step, new/old {new / old:.3f} "
                  f"(old {min(res['old']):.4f}-{max(res['old']):.4f}, "
                  f"new {min(res['new']):.4f}-{max(res['new']):.4f})", flush=True)
    print(json.dumps(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
