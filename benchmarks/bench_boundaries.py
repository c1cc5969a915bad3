"""Cost per particle-step of the wall models against stationary ghosts, inside one process.

    python benchmarks/bench_boundaries.py [THREADS] [ROUNDS]   (env BOUNDARIES=..., SEC=2,
                                                               TUTORIAL=damBreak3D, T0=0.3,
                                                               CLOCK=cpu)

The tutorial (damBreak3D at its own dx unless named) is set up once per boundary
(``stationaryGhosts,adami,mDBC`` unless named; an entry may set the boundary's options,
``mDBC:noSlip=no``), each simulation is stepped to T0 seconds of simulated time (the water
spread over the floor, the walls wet), then the simulations are stepped in turn for SEC
seconds each, ROUNDS rounds: the median time per particle-step of each and its ratio to
the first's. CLOCK=cpu (the default) times the process's CPU time, CLOCK=wall the wall
clock (with several threads: what a thread idle at a parallel loop's end costs). No
function objects, no writes.
"""
import os
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

from sphfoam.assemble import build_simulation
from sphfoam.case.case import Case
from sphfoam.case.edit import clone_case
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import read_state
from sphfoam.setup import setup_case

ROOT = Path(__file__).resolve().parent.parent


def make(tutorial: str, boundary: str, tmp: Path):
    """The simulation of ``boundary`` ("type" or "type:key=value,..." joined by ":")."""
    name, *opts = boundary.split(":")
    spec = {"type": name, **dict(o.split("=", 1) for o in opts)}
    d = clone_case(ROOT / "tutorials" / tutorial, tmp / boundary.replace(":", "_"),
                   {"system/controlDict:functions": {},
                    "constant/sphProperties:boundary": spec})
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    return build_simulation(case, ParticleState.from_fields(read_state(d / "0")))


def main():
    threads = int(sys.argv[1]) if len(sys.argv) > 1 else 1
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    sec = float(os.environ.get("SEC", "2"))
    t0 = float(os.environ.get("T0", "0.3"))
    tutorial = os.environ.get("TUTORIAL", "damBreak3D")
    names = os.environ.get("BOUNDARIES", "stationaryGhosts,adami,mDBC").split(",")
    clock = time.perf_counter if os.environ.get("CLOCK", "cpu") == "wall" else \
        time.process_time
    numba.set_num_threads(threads)
    tmp = Path(tempfile.mkdtemp(prefix="sphfoam-bench-walls-"))
    sims = {}
    for b in names:
        sim = make(tutorial, b, tmp)
        while sim.time < t0:
            sim.step()
        sims[b] = sim
    res = {b: [] for b in names}
    for _ in range(rounds):
        for b in names:
            sim = sims[b]
            c0, k = clock(), 0
            while clock() - c0 < sec:
                sim.step()
                k += 1
            res[b].append((clock() - c0) / k / sim.state.n * 1e6)
    base = float(np.median(res[names[0]]))
    print(f"{tutorial}, {threads} thread(s), from t = {t0:g} s, {rounds} rounds of {sec:g} s "
          f"({'wall clock' if clock is time.perf_counter else 'CPU time'})")
    for b in names:
        m = float(np.median(res[b]))
        st = sims[b].state
        print(f"{b:18s} n {st.n:7d} (fluid {st.n_fluid:6d})  {m:.3f} us/particle-step  "
              f"x{m / base:.2f}  (rounds {min(res[b]):.3f}-{max(res[b]):.3f})")


if __name__ == "__main__":
    main()
