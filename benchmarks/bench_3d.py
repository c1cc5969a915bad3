"""The 3-D matched dam break (issue 33): sphfoam's CPU engine against DualSPHysics 5.4.

The case is ``benchmarks/cases/damBreakMatched3D``: a column 1 m (x) x 0.5 m (y) x 1 m (z)
against the end wall of a tank 2 m x 0.5 m x 1.5 m high, dx = 0.02 m, 3 layers of wall
particles behind the floor and the four walls, Wendland C2 with h = 1.3 dx, Tait gamma = 7
with c0 = 20 sqrt(g 1 m), artificial viscosity alpha = 0.1, density-weighted continuity,
the Colagrossi-Landrini momentum form, stationary ghosts (DualSPHysics' DBC), Verlet with an
Euler step every 40, maxCo 0.2: 131 308 particles (62 500 fluid, 68 808 wall). Other sizes
scale dx.

Per size and thread count: a fresh set-up, ``--warmup`` steps, then steps until
``--seconds`` have passed; the rates are per CPU-second of the process (user + system of
all its threads: ``time.process_time``), so a loaded machine inflates them less than wall
time would. Particle-steps = particles x steps; pair interactions = the neighbour list's
ordered pairs (a, b), b != a within the support, which the loops evaluate (every pair of a
fluid particle; pairs of two still wall particles, which add exactly nothing, are left out
of the list as DualSPHysics leaves them out of its interactions), averaged over the window's
first and last list. Two threads: the speed-up is the wall time a step at one thread over
that at two. Bytes per particle: the simulation's arrays (state, extra fields, neighbour
list, cells) over the particle count. Compile: the pipeline generated and compiled in a new
process with an empty cache (cold) and again (cached).

    python benchmarks/bench_3d.py --sizes 131308 500000 2000000 --threads 1 2 --tag 3d
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
CASE = HERE / "cases" / "damBreakMatched3D"

#: DualSPHysics 5.4's CPU solver on exactly this case, measured on this machine kind (one
#: thread, user CPU, start-up cancelled; issue 33)
REFERENCE = dict(name="DualSPHysics 5.4 CPU", particle_steps=1.29e6, pairs=51e6,
                 neighbours_per_fluid=78.5)


def dx_for(total: int) -> float:
    """dx giving about ``total`` particles: fluid 1 x 0.5 x 1 m / dx^3 plus three layers
    under the 2 x 0.5 m floor and behind the four walls 1.5 m high."""
    from scipy.optimize import brentq

    def count(dx):
        L = 3 * dx
        fluid = (1.0 / dx) * (0.5 / dx) * (1.0 / dx)
        outer = (2 + 2 * L) * (0.5 + 2 * L) * (1.5 + L)
        return fluid + (outer - 2 * 0.5 * 1.5) / dx ** 3 - total

    return brentq(count, 1e-4, 0.5)


def make_sim(total: int):
    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.setup.initial import generate_case

    tmp = Path(tempfile.mkdtemp(prefix="sphfoam-bench3d-"))
    dx = 0.02 if abs(total - 131308) < 1000 else dx_for(total)
    case = Case(clone_case(CASE, tmp / "case", {"system/particleDict:dx": dx}))
    sim = build_simulation(case, generate_case(case))
    return sim, dx


def array_bytes(sim) -> float:
    st = sim.state
    names = st.persistent_f8 + ("kind", "id") + st.scratch
    total = sum(getattr(st, k).nbytes for k in names)
    total += sum(a.nbytes for a in st.extra.values())
    start, idx = sim._nb
    total += (start.nbytes if start is not None else 0) + (idx.nbytes if idx is not None else 0)
    total += sim.aux.nbytes + sim.cells.cell_start.nbytes
    half = getattr(sim, "_half", None)
    total += half.nbytes if half is not None else 0
    return total / st.n


def neighbours_per_fluid(sim) -> float:
    """Mean count of neighbours within the support of a fluid particle (scipy's k-d tree)."""
    import numpy as np
    from scipy.spatial import cKDTree

    st = sim.state
    pts = np.column_stack(st.positions)
    fluid = st.kind == 0
    tree = cKDTree(pts)
    r = sim.pipeline.support_radius * (1 - 1e-12)
    counts = tree.query_ball_point(pts[fluid], r, return_length=True) - 1
    return float(np.mean(counts))


def measure(sim, threads: int, seconds: float, warmup: int) -> dict:
    import numba

    numba.set_num_threads(threads)
    for _ in range(warmup):
        sim.step()
    pairs0 = int(sim._nb[0][-1])
    steps = 0
    c0, w0 = time.process_time(), time.perf_counter()
    while time.perf_counter() - w0 < seconds or steps < 3:
        sim.step()
        steps += 1
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    pairs = 0.5 * (pairs0 + int(sim._nb[0][-1]))
    n = sim.state.n
    return dict(threads=threads, steps=steps, cpu_s=cpu, wall_s=wall,
                ps_per_cpu_s=n * steps / cpu, ps_per_wall_s=n * steps / wall,
                pairs_per_step=pairs, pairs_per_cpu_s=pairs * steps / cpu,
                wall_ms_per_step=1e3 * wall / steps)


def compile_child() -> None:
    t0 = time.perf_counter()
    sim, _ = make_sim(3000)
    sim.step()
    print("JSON:" + json.dumps(dict(build_and_first_step_s=time.perf_counter() - t0,
                                    compile_seconds=sim.pipeline.compile_seconds,
                                    cache_hit=bool(sim.pipeline.cache_hit))))


def measure_compile() -> dict:
    out = {}
    with tempfile.TemporaryDirectory(prefix="sphfoam-bench3d-cache-") as cache:
        env = dict(os.environ, SPHFOAM_CACHE_DIR=str(Path(cache) / "sphfoam"),
                   NUMBA_CACHE_DIR=str(Path(cache) / "numba"))
        for label in ("cold", "cached"):
            cp = subprocess.run([sys.executable, str(Path(__file__).resolve()),
                                 "--_compile-child"], env=env, capture_output=True, text=True,
                                cwd=str(REPO))
            if cp.returncode != 0:
                raise RuntimeError(f"compile child failed:\n{cp.stdout}\n{cp.stderr}")
            line = [ln for ln in cp.stdout.splitlines() if ln.startswith("JSON:")][-1]
            out[label] = json.loads(line[5:])
    return out


def _m(v: float) -> str:
    return f"{v / 1e6:.2f} M"


def report(rows: list[dict], comp: dict | None) -> str:
    ref = REFERENCE
    lines = ["| particles (fluid) | dx (m) | neighbours / fluid particle | threads | "
             "particle-steps / CPU-s | pair interactions / CPU-s | vs DualSPHysics "
             f"({_m(ref['particle_steps'])}, {_m(ref['pairs'])}) | ms / step (wall) | "
             "2-thread speed-up | bytes / particle |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        for m in r["runs"]:
            one = next(x for x in r["runs"] if x["threads"] == 1) if any(
                x["threads"] == 1 for x in r["runs"]) else None
            speed = f"{one['wall_ms_per_step'] / m['wall_ms_per_step']:.2f}" \
                if one is not None and m["threads"] > 1 else ""
            lines.append(
                f"| {r['n']:,} ({r['n_fluid']:,}) | {r['dx']:.4g} | {r['nb_fluid']:.1f} | "
                f"{m['threads']} | {_m(m['ps_per_cpu_s'])} | {_m(m['pairs_per_cpu_s'])} | "
                f"{m['ps_per_cpu_s'] / ref['particle_steps']:.2f} x, "
                f"{m['pairs_per_cpu_s'] / ref['pairs']:.2f} x | {m['wall_ms_per_step']:.1f} | "
                f"{speed} | {r['bytes']:.0f} |")
    if comp:
        lines.append("")
        lines.append(f"Compile (new process, ~3 000 particles): cold "
                     f"{comp['cold']['compile_seconds']:.2f} s (build and first step "
                     f"{comp['cold']['build_and_first_step_s']:.1f} s), cached "
                     f"{comp['cached']['compile_seconds']:.2f} s.")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[131308])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--warmup", type=int, default=5)
    ap.add_argument("--no-compile", action="store_true", help="skip the compile timing")
    ap.add_argument("--tag", default=None, help="write results/engine3d-<tag>.{json,md}")
    ap.add_argument("--_compile-child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a._compile_child:
        compile_child()
        return
    rows = []
    for total in a.sizes:
        sim, dx = make_sim(total)
        row = dict(n=int(sim.state.n), n_fluid=int(sim.state.n_fluid), dx=dx,
                   nb_fluid=neighbours_per_fluid(sim), runs=[])
        for t in a.threads:
            row["runs"].append(measure(sim, t, a.seconds, a.warmup))
            print(json.dumps({k: v for k, v in row.items() if k != "runs"} | row["runs"][-1]),
                  flush=True)
        row["bytes"] = array_bytes(sim)
        rows.append(row)
        del sim
    comp = None if a.no_compile else measure_compile()
    text = report(rows, comp)
    print(text)
    if a.tag:
        out = HERE / "results"
        (out / f"engine3d-{a.tag}.json").write_text(json.dumps(dict(rows=rows, compile=comp,
                                                                    reference=REFERENCE),
                                                               indent=1))
        (out / f"engine3d-{a.tag}.md").write_text(
            "# The 3-D matched dam break\n\n`python benchmarks/bench_3d.py "
            + " ".join(argv if argv is not None else sys.argv[1:]) + "`\n\n" + text + "\n")


if __name__ == "__main__":
    main()
