"""The CUDA backend on the matched dam break (2-D): throughput, time per stage, host-device
traffic, device memory, compile time; the CPU backend of the same commit beside at ~23 k.

    python benchmarks/bench_gpu.py [--sizes 23k,400k,4M,16M] [--steps 50] [--out DIR]
                                   [--cpu-steps 30] [--no-cpu]

Sizes are particle counts (fluid and walls); dx is scaled from the case's 0.01 m (22 411
particles) as 1/sqrt(n). Per size: the case set up on the host, then on the device a few
steps to compile (the first step's time less a later one's is the compile time), ``--steps``
timed steps (synchronised at their ends: particle-steps/s, listed pairs/s), and ``--steps``
more with synchronised timers per stage (which slows them a little: the stage table only).
Writes ``gpu-<date>.json`` and ``.md`` into ``benchmarks/results/`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "benchmarks" / "cases" / "damBreakMatched"
BASE_N, BASE_DX = 22411, 0.01


def _size(s: str) -> int:
    s = s.strip().lower()
    mult = {"k": 1e3, "m": 1e6}.get(s[-1], 1)
    return int(float(s.rstrip("km")) * mult)


def _setup(tmp: Path, n: int, backend: str):
    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    dx = BASE_DX * math.sqrt(BASE_N / n)
    d = tmp / f"matched_{n}"
    if not (d / "0").exists():
        clone_case(CASE, d, {"system/controlDict:functions": {},
                             "system/particleDict:dx": round(dx, 8)})
    case = Case(d)
    t0 = time.perf_counter()
    if not (d / "0" / "rho").exists():
        setup_case(case, log=lambda *_: None)
    setup_s = time.perf_counter() - t0
    st = ParticleState.from_fields(read_state(d / "0"))
    return build_simulation(case, st, backend=backend), dx, setup_s


def _device_bytes(sim) -> int:
    arrays = list(sim.d.values()) + list(sim.d_extra.values()) + [sim.d_fld, sim.d_aux]
    arrays += [a for a in sim._nb if a is not None] + list(sim._ref or ())
    arrays += [a for g in sim._kept.values() for a in g]
    if sim._pc is not None:
        arrays.append(sim._pc)
    return int(sum(a.nbytes for a in arrays))


def bench_cuda(tmp: Path, n: int, steps: int) -> dict:
    from sphfoam.engine.cuda import cuda_module

    cuda = cuda_module()

    sim, dx, setup_s = _setup(tmp, n, "cuda")
    evals = getattr(sim.integrator, "force_evaluations_per_step", 1)
    cuda.synchronize()
    t0 = time.perf_counter()
    sim.step()
    cuda.synchronize()
    first = time.perf_counter() - t0
    for _ in range(2):
        sim.step()
    cuda.synchronize()
    t0 = time.perf_counter()
    sim.step()
    cuda.synchronize()
    one = time.perf_counter() - t0
    h2d, d2h = sim.bytes_h2d, sim.bytes_d2h
    built = sim.list_built
    pairs = 0
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.step()
        pairs += sim.pairs
    cuda.synchronize()
    wall = time.perf_counter() - t0
    out = dict(particles=int(sim.n), dx=dx, steps=steps, setup_s=setup_s,
               compile_s=max(first - one, 0.0), step_ms=1e3 * wall / steps,
               particle_steps_per_s=sim.n * steps / wall,
               listed_pairs_per_s=pairs * evals / wall,
               lists_built=sim.list_built - built,
               h2d_bytes_per_step=(sim.bytes_h2d - h2d) / steps,
               d2h_bytes_per_step=(sim.bytes_d2h - d2h) / steps,
               device_bytes_per_particle=_device_bytes(sim) / sim.n,
               sim_time=sim.time)
    # one list build (bin, sort, permute, count, scan, fill), synchronised
    sim.invalidate_neighbours()
    cuda.synchronize()
    t0 = time.perf_counter()
    sim.neighbour_update()
    cuda.synchronize()
    out["list_build_ms"] = 1e3 * (time.perf_counter() - t0)
    sim.timers = {}
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.step()
    cuda.synchronize()
    timed = time.perf_counter() - t0
    out["stage_ms"] = {k: 1e3 * v / steps for k, v in sorted(sim.timers.items())}
    out["timed_step_ms"] = 1e3 * timed / steps
    return out


def bench_cpu(tmp: Path, n: int, steps: int) -> dict:
    import numba

    sim, dx, _ = _setup(tmp, n, "cpu")
    res = {}
    for threads in (1, numba.config.NUMBA_NUM_THREADS):
        numba.set_num_threads(threads)
        for _ in range(3):
            sim.step()
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        wall = time.perf_counter() - t0
        res[f"threads_{threads}"] = dict(step_ms=1e3 * wall / steps,
                                         particle_steps_per_s=sim.state.n * steps / wall)
    res["particles"] = int(sim.state.n)
    return res


def _markdown(rep: dict) -> str:
    lines = [f"# bench_gpu: matched dam break (2-D), {rep['date']}", "",
             f"device: {rep['device']}; commit {rep['commit']}", "",
             "| particles | step ms | particle-steps/s | listed pairs/s | compile s | "
             "H2D B/step | D2H B/step | device B/particle | lists built |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rep["cuda"]:
        if "error" in r:
            lines.append(f"| {r['requested']} | {r['error']} |")
            continue
        lines.append(f"| {r['particles']:,} | {r['step_ms']:.3f} | "
                     f"{r['particle_steps_per_s']:.3g} | {r['listed_pairs_per_s']:.3g} | "
                     f"{r['compile_s']:.1f} | {r['h2d_bytes_per_step']:.0f} | "
                     f"{r['d2h_bytes_per_step']:.0f} | {r['device_bytes_per_particle']:.0f} | "
                     f"{r['lists_built']} |")
    lines += ["", "time per stage (ms/step, synchronised timers; neighbours: the list check, "
              "or a rebuild when due):", ""]
    for r in rep["cuda"]:
        if "stage_ms" in r:
            lines.append(f"- {r['particles']:,}: " + ", ".join(
                f"{k} {v:.3f}" for k, v in r["stage_ms"].items())
                + f"; one list build {r.get('list_build_ms', float('nan')):.3f} ms")
    if rep.get("cpu"):
        c = rep["cpu"]
        lines += ["", f"CPU backend, same commit, {c['particles']:,} particles:"]
        for k, v in c.items():
            if k.startswith("threads_"):
                lines.append(f"- {k.replace('_', ' ')}: {v['step_ms']:.2f} ms/step, "
                             f"{v['particle_steps_per_s']:.3g} particle-steps/s")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="23k,400k,4M,16M")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--cpu-steps", type=int, default=30)
    ap.add_argument("--no-cpu", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    a = ap.parse_args(argv)
    from sphfoam.engine.cuda import cuda_module

    cuda = cuda_module()

    try:
        dev = cuda.get_current_device().name
        dev = dev.decode() if isinstance(dev, bytes) else str(dev)
    except Exception as e:  # noqa: BLE001
        dev = f"unknown ({e})"
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = "?"
    rep = dict(date=datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
               device=dev, commit=commit, python=platform.python_version(), cuda=[])
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for s in a.sizes.split(","):
            n = _size(s)
            try:
                r = bench_cuda(tmp, n, a.steps)
            except Exception as e:  # noqa: BLE001  (recorded: the other sizes still run)
                r = dict(error=f"{type(e).__name__}: {e}")
            r["requested"] = s
            rep["cuda"].append(r)
            print(json.dumps(r), flush=True)
        if not a.no_cpu:
            rep["cpu"] = bench_cpu(tmp, BASE_N, a.cpu_steps)
            print(json.dumps(rep["cpu"]), flush=True)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = "gpu-" + rep["date"][:10]
    (out / f"{stem}.json").write_text(json.dumps(rep, indent=1))
    (out / f"{stem}.md").write_text(_markdown(rep))
    print(_markdown(rep))


if __name__ == "__main__":
    main()
