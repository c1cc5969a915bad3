#!/usr/bin/env python
"""Threads on a shared machine: one and two threads, alone and beside a busy process.

For each threading policy (the omp layer's wait policy and numba's parallel chunk size) it
starts a fresh Python (``OMP_WAIT_POLICY`` is read when the OpenMP runtime loads), builds the
case of ``bench_engine.py --case`` at about ``--size`` particles and times ``--seconds`` of
stepping with 1 and 2 threads, first on the idle machine and then while a competing process
spins on one core (``while True: pass``, the "other process holds a core" of issue 12).

    python benchmarks/bench_shared_core.py --case matched --size 90000

Prints a Markdown table (ms/step, speed-up of 2 threads over 1, and the slowdown that the
competitor causes) and writes ``benchmarks/results/shared-core-latest.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: environment of each policy; the OpenMP runtime reads OMP_WAIT_POLICY / GOMP_SPINCOUNT when
#: it loads. ``active`` is libgomp's own default (spin ~300 000 times before sleeping).
POLICIES = {
    "active": {"OMP_WAIT_POLICY": "active"},
    "spin10k": {"GOMP_SPINCOUNT": "10000"},
    "passive": {"OMP_WAIT_POLICY": "passive"},
    "passive+chunked": {"OMP_WAIT_POLICY": "passive", "SPHFOAM_BENCH_CHUNK": "1024"},
}


def child(case: str, size: int, seconds: float, threads: int) -> dict:
    sys.path.insert(0, str(HERE))
    import numba
    import bench_engine as be

    sim, info = be.make_case_sim(case, size)
    numba.set_num_threads(threads)
    chunk = int(os.environ.get("SPHFOAM_BENCH_CHUNK", "0"))
    if chunk and threads > 1:
        # numba's dynamic blocks of `chunk` iterations instead of one equal block per thread
        numba.set_parallel_chunksize(chunk)
    for _ in range(10):
        sim.step()
    t0 = time.perf_counter()
    c0 = time.process_time()
    times = be.timed_steps(sim, seconds)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    return dict(n=info["n"], threads=threads, steps=len(times), ms_per_step=1e3 * wall / len(times),
                cpu_util=cpu / (wall * threads), layer=numba.threading_layer(),
                chunk=numba.get_parallel_chunksize())


def run_child(policy_env, args, threads, competitor: bool):
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "SPHFOAM_BENCH_CHUNK")}
    env.update(policy_env)
    spinner = None
    if competitor:
        spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        time.sleep(0.5)
    try:
        out = subprocess.run([sys.executable, __file__, "--_child", str(threads), "--case", args.case,
                              "--size", str(args.size), "--seconds", str(args.seconds)],
                             env=env, capture_output=True, text=True, check=True)
    finally:
        if spinner is not None:
            spinner.kill()
            spinner.wait()
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default="matched")
    ap.add_argument("--size", type=int, default=90_000)
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--policies", nargs="+", default=list(POLICIES), choices=list(POLICIES))
    ap.add_argument("--out", type=Path, default=HERE / "results" / "shared-core-latest.md")
    ap.add_argument("--_child", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args._child is not None:
        print(json.dumps(child(args.case, args.size, args.seconds, args._child)))
        return
    rows = []
    for pol in args.policies:
        r = {}
        for comp in (False, True):
            for thr in (1, 2):
                r[(comp, thr)] = run_child(POLICIES[pol], args, thr, comp)
                print(pol, "competitor" if comp else "idle", thr, r[(comp, thr)], flush=True)
        rows.append((pol, r))
    lines = [f"# Threads on a shared machine ({time.strftime('%Y-%m-%dT%H:%M:%S')})", "",
             f"Command: `bench_shared_core.py --case {args.case} --size {args.size} "
             f"--seconds {args.seconds}`; N = {rows[0][1][(False, 1)]['n']:,}, layer "
             f"{rows[0][1][(False, 1)]['layer']}. ms/step is wall time; *competitor*: another "
             "process spins on one core meanwhile.", "",
             "| policy | 1 thr idle | 2 thr idle | speed-up idle | 1 thr competitor | 2 thr competitor "
             "| speed-up competitor | 2 thr: competitor / idle |",
             "|---|---|---|---|---|---|---|---|"]
    for pol, r in rows:
        a, b, c, d = (r[(False, 1)]["ms_per_step"], r[(False, 2)]["ms_per_step"],
                      r[(True, 1)]["ms_per_step"], r[(True, 2)]["ms_per_step"])
        lines.append(f"| {pol} | {a:.2f} | {b:.2f} | {a / b:.2f} | {c:.2f} | {d:.2f} | {c / d:.2f} "
                     f"| {d / b:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)


if __name__ == "__main__":
    main()
