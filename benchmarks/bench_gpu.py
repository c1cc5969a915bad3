"""The CUDA backend on the matched dam break (2-D or 3-D): throughput, time per stage,
host-device traffic and its time, device memory, compile time; the CPU backend of the same
commit beside.

    python benchmarks/bench_gpu.py [--dim 2] [--sizes 23k,400k,4M,16M] [--steps 50]
                                   [--precision double,single] [--budget 300]
                                   [--cpu-steps 20] [--no-cpu] [--out DIR]

Sizes are particle counts (fluid and walls); dx is scaled from the case's own (2-D:
benchmarks/cases/damBreakMatched, 22 411 particles at dx 0.01 m; 3-D: damBreakMatched3D,
131 308 at 0.02 m) as n^(-1/dim). Per size the particles are generated in memory
(:func:`sphfoam.setup.initial.generate_case`, nothing written), then per precision on the
device:

* a few steps to compile (the first step's time less a later one's: the compile time);
* ``--steps`` steps as the time loop runs them, the neighbour list rebuilt only when the
  displacement check asks ("list kept": from rest the first list serves the whole window);
* ``--steps`` steps with the list rebuilt at every step ("list rebuilt": bin, sort, permute,
  count, scan, fill each step, the worst case and DualSPHysics' practice);
* ``--steps`` steps with synchronised timers per stage, the host-device copies among them
  (which slows them a little: the stage table only).

Particle-steps/s and listed pairs/s are from the unsynchronised windows (synchronised at
their ends). A size whose set-up, at the last size's rate, would not fit ``--budget`` seconds
is skipped and says so. Writes ``gpu-<date>[-3d].json`` and ``.md`` into
``benchmarks/results/`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: (case, its particle count, its dx) per dimension
CASES = {2: (ROOT / "benchmarks" / "cases" / "damBreakMatched", 22411, 0.01),
         3: (ROOT / "benchmarks" / "cases" / "damBreakMatched3D", 131308, 0.02)}


def _size(s: str) -> int:
    s = s.strip().lower()
    mult = {"k": 1e3, "m": 1e6}.get(s[-1], 1)
    return int(float(s.rstrip("km")) * mult)


def _case(tmp: Path, dim: int, n: int, precision: str = "double"):
    """(the matched case scaled to about ``n`` particles in ``precision``, its dx)."""
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case

    src, base_n, base_dx = CASES[dim]
    dx = base_dx * (base_n / n) ** (1.0 / dim)
    d = tmp / f"matched{dim}d_{n}_{precision}"
    if not d.exists():
        clone_case(src, d, {"system/controlDict:functions": {},
                            "system/particleDict:dx": round(dx, 9),
                            "system/sphSchemes:precision": precision})
    return Case(d), dx


def generate(tmp: Path, dim: int, n: int):
    """(state, dx, set-up seconds) of the matched case scaled to about ``n`` particles,
    generated in memory."""
    from sphfoam.setup.initial import generate_case

    case, dx = _case(tmp, dim, n)
    t0 = time.perf_counter()
    case.validate()
    state = generate_case(case)
    return state, dx, time.perf_counter() - t0


def _simulation(tmp: Path, dim: int, n: int, state, backend: str, precision: str):
    """The simulation of a copy of ``state`` (the stepping changes its arrays)."""
    from sphfoam.assemble import build_simulation
    from sphfoam.engine.state import ParticleState

    case, _ = _case(tmp, dim, n, precision)
    three = state.dim == 3
    st = ParticleState(*(getattr(state, k).copy() for k in ("x", "y", "u", "v", "rho", "m",
                                                             "kind", "id")),
                       extra={k: a.copy() for k, a in state.extra.items()},
                       z=state.z.copy() if three else None, w=state.w.copy() if three else None)
    return build_simulation(case, st, backend=backend)


def _device_bytes(sim) -> int:
    arrays = list(sim.d.values()) + list(sim.d_extra.values()) + [sim.d_fld, sim.d_aux]
    arrays += [a for a in sim._nb if a is not None] + list(sim._ref or ())
    arrays += [a for g in sim._kept.values() for a in g]
    if sim._pc is not None:
        arrays.append(sim._pc)
    return int(sum(a.nbytes for a in arrays))


def _steps(sim, cuda, steps: int, rebuild: bool) -> tuple[float, int]:
    """``steps`` steps (the list rebuilt before each where ``rebuild``), synchronised at
    both ends: (wall seconds, listed pairs summed over the steps)."""
    pairs = 0
    cuda.synchronize()
    t0 = time.perf_counter()
    for _ in range(steps):
        if rebuild:
            sim.invalidate_neighbours()
        sim.step()
        pairs += sim.pairs
    cuda.synchronize()
    return time.perf_counter() - t0, pairs


def _window(sim, cuda, steps: int, rebuild: bool) -> dict:
    evals = getattr(sim.integrator, "force_evaluations_per_step", 1)
    h2d, d2h, built = sim.bytes_h2d, sim.bytes_d2h, sim.list_built
    wall, pairs = _steps(sim, cuda, steps, rebuild)
    return dict(step_ms=1e3 * wall / steps, particle_steps_per_s=sim.n * steps / wall,
                listed_pairs_per_s=pairs * evals / wall, lists_built=sim.list_built - built,
                h2d_bytes_per_step=(sim.bytes_h2d - h2d) / steps,
                d2h_bytes_per_step=(sim.bytes_d2h - d2h) / steps)


def bench_cuda(tmp: Path, dim: int, n: int, state, precision: str, steps: int) -> dict:
    from sphfoam.engine.cuda import cuda_module

    cuda = cuda_module()
    free0 = cuda.current_context().get_memory_info()[0]
    t0 = time.perf_counter()
    sim = _simulation(tmp, dim, n, state, "cuda", precision)
    upload_s = time.perf_counter() - t0
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
    out = dict(precision=precision, particles=int(sim.n), upload_s=upload_s,
               compile_s=max(first - one, 0.0))
    out["kept"] = _window(sim, cuda, steps, rebuild=False)
    out["rebuilt"] = _window(sim, cuda, steps, rebuild=True)
    out["device_bytes_per_particle"] = _device_bytes(sim) / sim.n
    out["device_memory_used_per_particle"] = \
        (free0 - cuda.current_context().get_memory_info()[0]) / sim.n
    for rebuild in (False, True):
        sim.timers = {}
        timed, _ = _steps(sim, cuda, steps, rebuild)
        key = "stages_rebuilt" if rebuild else "stages_kept"
        out[key] = {k: 1e3 * v / steps for k, v in sorted(sim.timers.items())}
        out[key]["total"] = 1e3 * timed / steps
    sim.timers = None
    out["sim_time"] = sim.time
    del sim
    return out


def bench_cpu(tmp: Path, dim: int, n: int, state, steps: int) -> dict:
    import numba

    sim = _simulation(tmp, dim, n, state, "cpu", "double")
    res = {"particles": int(sim.state.n)}
    for threads in sorted({1, numba.config.NUMBA_NUM_THREADS}):
        numba.set_num_threads(threads)
        for _ in range(3):
            sim.step()
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        wall = time.perf_counter() - t0
        res[f"threads_{threads}"] = dict(step_ms=1e3 * wall / steps,
                                         particle_steps_per_s=sim.state.n * steps / wall)
    return res


def _markdown(rep: dict) -> str:
    dim = rep["dim"]
    lines = [f"# bench_gpu: matched dam break ({dim}-D), {rep['date']}", "",
             f"device: {rep['device']}; commit {rep['commit']}; numba-cuda "
             f"{rep.get('numba_cuda', '?')}", "",
             "| particles | precision | list | step ms | particle-steps/s | listed pairs/s | "
             "x one CPU thread | copies % of step | H2D B/step | D2H B/step |",
             "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    cpu1 = rep.get("cpu", {}).get("threads_1", {}).get("particle_steps_per_s")
    for r in rep["cuda"]:
        if "error" in r or "skipped" in r:
            lines.append(f"| {r['requested']} | {r.get('precision', '')} | | "
                         f"{r.get('error') or r.get('skipped')} |")
            continue
        for mode in ("kept", "rebuilt"):
            w = r[mode]
            st = r.get(f"stages_{mode}", {})
            copies = 100.0 * st.get("copies", 0.0) / st["total"] if st.get("total") else 0.0
            ratio = f"{w['particle_steps_per_s'] / cpu1:.0f}" if cpu1 else "-"
            lines.append(f"| {r['particles']:,} | {r['precision']} | {mode} | "
                         f"{w['step_ms']:.3f} | {w['particle_steps_per_s']:.3g} | "
                         f"{w['listed_pairs_per_s']:.3g} | {ratio} | {copies:.2f} | "
                         f"{w['h2d_bytes_per_step']:.0f} | {w['d2h_bytes_per_step']:.0f} |")
    lines += ["", "| particles | precision | set-up s | upload s | compile s | "
              "device B/particle (arrays) | device B/particle (allocated) |",
              "|---:|---|---:|---:|---:|---:|---:|"]
    for r in rep["cuda"]:
        if "particles" in r:
            lines.append(f"| {r['particles']:,} | {r['precision']} | {r['setup_s']:.1f} | "
                         f"{r['upload_s']:.1f} | {r['compile_s']:.1f} | "
                         f"{r['device_bytes_per_particle']:.0f} | "
                         f"{r['device_memory_used_per_particle']:.0f} |")
    lines += ["", "time per stage (ms/step, synchronised timers; `neighbours`: the list "
              "check, and the rebuild when there is one; `copies`: every host-device copy):",
              ""]
    for r in rep["cuda"]:
        for mode in ("kept", "rebuilt"):
            st = r.get(f"stages_{mode}")
            if st:
                lines.append(f"- {r['particles']:,} {r['precision']}, list {mode}: " + ", ".join(
                    f"{k} {v:.3f}" for k, v in st.items()))
    if rep.get("cpu"):
        c = rep["cpu"]
        lines += ["", f"CPU backend, same commit and machine, {c['particles']:,} particles:"]
        for k, v in c.items():
            if k.startswith("threads_"):
                lines.append(f"- {k.replace('_', ' ')}: {v['step_ms']:.2f} ms/step, "
                             f"{v['particle_steps_per_s']:.3g} particle-steps/s")
    return "\n".join(lines) + "\n"


def main(argv=None):
    import tempfile

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dim", type=int, choices=(2, 3), default=2)
    ap.add_argument("--sizes", default="23k,400k,4M,16M")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--precision", default="double",
                    help="comma-separated: double, single")
    ap.add_argument("--budget", type=float, default=float("inf"),
                    help="seconds for the whole benchmark; a size whose set-up would not fit "
                    "is skipped")
    ap.add_argument("--cpu-steps", type=int, default=20)
    ap.add_argument("--no-cpu", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    a = ap.parse_args(argv)
    start = time.perf_counter()
    from sphfoam.engine.cuda import cuda_module

    cuda = cuda_module()
    try:
        dev = cuda.get_current_device().name
        dev = dev.decode() if isinstance(dev, bytes) else str(dev)
    except Exception as e:  # noqa: BLE001
        dev = f"unknown ({e})"
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip() or "?"
    except OSError:
        commit = "?"
    try:
        from importlib.metadata import version
        ncuda = version("numba-cuda")
    except Exception:  # noqa: BLE001
        ncuda = "?"
    rep = dict(date=datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
               device=dev, commit=commit, python=platform.python_version(),
               numba_cuda=ncuda, dim=a.dim, cuda=[])
    rate = None                       # set-up seconds per particle, from the last size
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if not a.no_cpu:
            n = CASES[a.dim][1]
            state, _, _ = generate(tmp, a.dim, n)
            rep["cpu"] = bench_cpu(tmp, a.dim, n, state, a.cpu_steps)
            print(json.dumps(rep["cpu"]), flush=True)
        for s in a.sizes.split(","):
            n = _size(s)
            left = a.budget - (time.perf_counter() - start)
            if rate is not None and 1.5 * rate * n > left:
                rep["cuda"].append(dict(requested=s, skipped=f"set-up ~{rate * n:.0f} s does "
                                        f"not fit the {left:.0f} s left"))
                print(json.dumps(rep["cuda"][-1]), flush=True)
                continue
            try:
                state, dx, setup_s = generate(tmp, a.dim, n)
                rate = setup_s / state.n
            except Exception as e:  # noqa: BLE001  (recorded: the other sizes still run)
                rep["cuda"].append(dict(requested=s, error=f"set-up: {type(e).__name__}: {e}"))
                continue
            for prec in a.precision.split(","):
                try:
                    r = bench_cuda(tmp, a.dim, n, state, prec, a.steps)
                    r.update(dx=dx, setup_s=setup_s)
                except Exception as e:  # noqa: BLE001  (recorded: the others still run)
                    r = dict(precision=prec, error=f"{type(e).__name__}: {e}")
                r["requested"] = s
                rep["cuda"].append(r)
                print(json.dumps(r), flush=True)
            del state
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = "gpu-" + rep["date"][:10] + ("-3d" if a.dim == 3 else "")
    (out / f"{stem}.json").write_text(json.dumps(rep, indent=1))
    (out / f"{stem}.md").write_text(_markdown(rep))
    print(_markdown(rep))


if __name__ == "__main__":
    main(sys.argv[1:])
