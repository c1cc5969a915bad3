"""Wall time a step of a bench_engine --case case at one and two threads, in one process.

    python benchmarks/bench_thread_steps.py CASE [N] [SEC] [TO]

The case is built (about N particles, default 90 000) and stepped 10 times, then on to the
simulated time TO (default 0); then it is stepped for SEC seconds (default 4) of wall time
at 1, 2, 1 and 2 threads in turn, and the mean wall time a step of each stretch printed.
CASE is a name of bench_engine's CASE_DIRS or a case directory, run at its own dx (N is then
ignored; its function objects are left out), e.g. the 3-D dam break once its water has
spread: ``python benchmarks/bench_thread_steps.py tutorials/damBreak3D 0 4 1.5``. Stepping one simulation at both counts in
turn puts both on the same stretch of the flow and the same host speed (the two-thread
speed-up of issue 12 is asked at >= 90 000 particles)."""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.getcwd(), "benchmarks"))
import numba  # noqa: E402

import bench_engine as be  # noqa: E402

case = sys.argv[1]
N = int(sys.argv[2]) if len(sys.argv) > 2 else 90000
SEC = float(sys.argv[3]) if len(sys.argv) > 3 else 4.0
TO = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
if os.path.isdir(case):
    import tempfile
    from pathlib import Path

    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.setup import setup_case

    d = clone_case(case, Path(tempfile.mkdtemp(prefix="sphfoam-bench-")) / "case",
                   {"system/controlDict:functions": {}})
    setup_case(Case(d), log=lambda *_: None)
    sim = build_simulation(Case(d), ParticleState.from_fields(read_state(d / "0")))
    info = {"n": sim.state.n}
    case = Path(case).name
else:
    sim, info = be.make_case_sim(case, N)
for _ in range(10):
    sim.step()
while sim.time < TO:
    sim.step()
for thr in (1, 2, 1, 2):
    numba.set_num_threads(thr)
    t = time.perf_counter()
    k = 0
    while time.perf_counter() - t < SEC:
        sim.step()
        k += 1
    print(f"{case} n {info['n']} t {sim.time:.3f} s threads {thr}: "
          f"{(time.perf_counter() - t) / k * 1e3:.2f} ms/step", flush=True)
