"""Wall time a step of a bench_engine --case case at one and two threads, in one process.

    python benchmarks/bench_thread_steps.py CASE [N] [SEC]

The case is built (about N particles, default 90 000) and stepped 10 times; then it is
stepped for SEC seconds (default 4) of wall time at 1, 2, 1 and 2 threads in turn, and the
mean wall time a step of each stretch printed. Stepping one simulation at both counts in
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
sim, info = be.make_case_sim(case, N)
for _ in range(10):
    sim.step()
for thr in (1, 2, 1, 2):
    numba.set_num_threads(thr)
    t = time.perf_counter()
    k = 0
    while time.perf_counter() - t < SEC:
        sim.step()
        k += 1
    print(f"{case} n {info['n']} threads {thr}: {(time.perf_counter() - t) / k * 1e3:.2f} ms/step")
