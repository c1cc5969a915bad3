#!/usr/bin/env python
"""Threads on a shared machine: 1 thread, 2 threads and ``threads auto``, alone and beside a
busy process.

For each threading policy (numba's threading layer, the omp layer's wait policy, numba's
parallel chunk size) it starts a fresh Python per measurement (``OMP_WAIT_POLICY`` is read when
the OpenMP runtime loads, the layer when numba first runs a parallel loop), builds the case of
``bench_engine.py --case`` at about ``--size`` particles and times ``--seconds`` of stepping
with 1 thread, 2 threads and the adaptive controller of ``threads auto``
(``sphfoam.engine.threads.AdaptiveThreads``, driven between steps as the time loop drives it,
pool of 2 threads), first on the machine as it is and then while a competing process spins on
one core (``while True: pass``, the "other process holds a core" of issue 12).

    python benchmarks/bench_shared_core.py --case matched --size 90000 --repeats 3

``--repeats R`` runs every (policy, competitor, mode) once per round, R rounds back to back,
so that a change of the machine's load hits every configuration alike; the table gives the
median and the range. Each child records the 1-minute load average when it starts (the
header gives their range: on a machine loaded by other jobs "idle" is not idle).

Prints a Markdown table and writes ``benchmarks/results/shared-core-latest.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent

#: environment of each policy. The omp layer's runtime (libgomp) reads OMP_WAIT_POLICY /
#: GOMP_SPINCOUNT when it loads: unset, a waiting thread spins about 300 000 times (~1 ms)
#: and then sleeps; ``active`` spins 3e10 times (minutes: in effect it never sleeps);
#: ``passive`` sleeps at once. ``workqueue`` is numba's own pool (threads sleep on a
#: condition variable between regions); ``tbb`` needs the tbb package.
POLICIES = {
    "default": {},
    "active": {"OMP_WAIT_POLICY": "active"},
    "spin10k": {"GOMP_SPINCOUNT": "10000"},
    "passive": {"OMP_WAIT_POLICY": "passive"},
    "passive+chunked": {"OMP_WAIT_POLICY": "passive", "SPHFOAM_BENCH_CHUNK": "1024"},
    "workqueue": {"NUMBA_THREADING_LAYER": "workqueue"},
    "tbb": {"NUMBA_THREADING_LAYER": "tbb"},
}
POLICY_VARS = ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "SPHFOAM_BENCH_CHUNK", "NUMBA_THREADING_LAYER")
MODES = ("1", "2", "auto")


def child(case: str, size: int, seconds: float, mode: str) -> dict:
    sys.path.insert(0, str(HERE))
    load = os.getloadavg()[0]
    import numba
    import bench_engine as be
    from sphfoam.engine.threads import AdaptiveThreads

    sim, info = be.make_case_sim(case, size)
    pool = min(2, numba.config.NUMBA_NUM_THREADS)
    threads = pool if mode == "auto" else int(mode)
    numba.set_num_threads(threads)
    chunk = int(os.environ.get("SPHFOAM_BENCH_CHUNK", "0"))
    if chunk and threads > 1:
        # numba's dynamic blocks of `chunk` iterations instead of one equal block per thread
        numba.set_parallel_chunksize(chunk)
    for _ in range(10):
        sim.step()
    ctl = AdaptiveThreads(pool) if mode == "auto" else None
    clock = time.perf_counter
    steps = 0
    ends = []
    c0 = time.process_time()
    t0 = clock()
    while True:
        ts = clock()
        sim.step()
        te = clock()
        steps += 1
        ends.append(te - t0)
        if ctl is not None:
            new = ctl.record(te - ts)
            if new is not None:
                numba.set_num_threads(new)
        if te - t0 >= seconds and steps >= 5:
            break
    wall = clock() - t0
    cpu = time.process_time() - c0
    # the second half of the window (by time): the adaptive controller's steady state
    half = next(k for k, e in enumerate(ends) if e >= 0.5 * ends[-1])
    late = 1e3 * (ends[-1] - ends[half]) / max(1, steps - 1 - half)
    out = dict(n=info["n"], mode=mode, steps=steps, ms_per_step=1e3 * wall / steps,
               ms_per_step_late=late,
               cpu_per_wall=cpu / wall, layer=numba.threading_layer(),
               chunk=numba.get_parallel_chunksize(), load=load)
    if ctl is not None:
        out.update(share_max=ctl.steps[pool] / max(1, sum(ctl.steps.values())),
                   changes=len(ctl.changes), ended=ctl.n)
    return out


def run_child(policy_env, args, mode: str, competitor: bool):
    env = {k: v for k, v in os.environ.items() if k not in POLICY_VARS}
    env.update(policy_env)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO)] + [p for p in
                                         env.get("PYTHONPATH", "").split(os.pathsep) if p])
    spinner = None
    if competitor:
        spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        time.sleep(0.5)
    try:
        out = subprocess.run([sys.executable, __file__, "--_child", mode, "--case", args.case,
                              "--size", str(args.size), "--seconds", str(args.seconds)],
                             env=env, capture_output=True, text=True)
    finally:
        if spinner is not None:
            spinner.kill()
            spinner.wait()
    if out.returncode != 0:
        return {"error": out.stderr.strip().splitlines()[-1] if out.stderr.strip() else "failed"}
    return json.loads(out.stdout.strip().splitlines()[-1])


def _cell(rs: list[dict], key="ms_per_step", fmt="{:.1f}") -> str:
    vals = [r[key] for r in rs if key in r]
    if not vals:
        return "n/a"
    med = statistics.median(vals)
    if len(vals) == 1:
        return fmt.format(med)
    return f"{fmt.format(med)} ({fmt.format(min(vals))}-{fmt.format(max(vals))})"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default="matched")
    ap.add_argument("--size", type=int, default=90_000)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--policies", nargs="+", default=["default", "passive", "workqueue"],
                    choices=list(POLICIES))
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=list(MODES))
    ap.add_argument("--out", type=Path, default=HERE / "results" / "shared-core-latest.md")
    ap.add_argument("--_child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args._child is not None:
        print(json.dumps(child(args.case, args.size, args.seconds, args._child)))
        return
    res: dict = {}
    started = time.strftime("%Y-%m-%dT%H:%M:%S")
    for rnd in range(args.repeats):
        for pol in args.policies:
            for comp in (False, True):
                for mode in args.modes:
                    r = run_child(POLICIES[pol], args, mode, comp)
                    res.setdefault((pol, comp, mode), []).append(r)
                    print(rnd, pol, "competitor" if comp else "as-is", mode, r, flush=True)
    good = [r for rs in res.values() for r in rs if "error" not in r]
    loads = [r["load"] for r in good]
    n = good[0]["n"] if good else 0
    lines = [f"# Threads on a shared machine ({started})", "",
             f"Command: `bench_shared_core.py --case {args.case} --size {args.size} "
             f"--seconds {args.seconds} --repeats {args.repeats} --policies "
             f"{' '.join(args.policies)}`; N = {n:,}; {os.cpu_count()} cores; 1-minute load "
             f"average when each measurement started: {min(loads, default=0):.1f}-"
             f"{max(loads, default=0):.1f}. ms/step is wall time, median (range) of the "
             "repeats; *competitor*: another process spins on one core meanwhile; *auto*: "
             "`threads auto`'s controller (pool of 2), whose adaptation is inside the window "
             "(*2nd half*: ms/step over the second half of the window, after it); "
             "*at 2*: its share of steps at 2 threads.", "",
             ]
    head = ["policy"]
    for comp in ("", " competitor"):
        head += [(f"{m} thr" if m != "auto" else "auto") + comp for m in args.modes]
        head += [f"auto at 2{comp}"] if "auto" in args.modes else []
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for pol in args.policies:
        row = [pol]
        for comp in (False, True):
            for mode in args.modes:
                rs = res.get((pol, comp, mode), [])
                err = [r["error"] for r in rs if "error" in r]
                cell = _cell(rs) if not err else f"failed: {err[0][:60]}"
                if mode == "auto" and not err:
                    cell += f"; 2nd half {_cell(rs, 'ms_per_step_late')}"
                row.append(cell)
            if "auto" in args.modes:
                row.append(_cell(res.get((pol, comp, "auto"), []), "share_max", "{:.2f}"))
        lines.append("| " + " | ".join(row) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)


if __name__ == "__main__":
    main()
