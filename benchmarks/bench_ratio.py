"""Cost per particle-step of bench_engine's --case cases against the first, inside one process.

    python benchmarks/bench_ratio.py [THREADS] [ROUNDS]      (env CASES=flume,wall,..., SEC=1)

Each case is built by bench_engine.make_case_sim (about 23 000 particles) and stepped for SEC
seconds of CPU time in turn, ROUNDS rounds; the median CPU time per particle-step of each case
and its ratio to the first case's. Stepping the cases in turn in one process makes the ratio
robust to a host whose speed drifts (a single bench_engine run per case is not)."""
import os, sys, time
sys.path.insert(0, os.path.join(os.getcwd(), "benchmarks"))
import numpy as np, numba
import bench_engine as be
thr = int(sys.argv[1]) if len(sys.argv) > 1 else 1
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 6
SEC = float(os.environ.get("SEC", "1.0"))
numba.set_num_threads(thr)
cases = os.environ.get("CASES", "flume,wall,wallOnce,wallBare,flumeLowDiss").split(",")
sims = {}
for c in cases:
    sim, info = be.make_case_sim(c, 23000)
    for _ in range(10):
        sim.step()
    sims[c] = (sim, info["n"])
res = {c: [] for c in cases}
for r in range(rounds):
    for c in cases:
        sim, n = sims[c]
        t0 = time.process_time(); k = 0
        while time.process_time() - t0 < SEC:
            sim.step(); k += 1
        res[c].append((time.process_time() - t0) / k / n * 1e6)
base = np.median(res[cases[0]])
for c in cases:
    m = np.median(res[c])
    print(f"{c:15s} n {sims[c][1]:6d}  {m:.3f} us/particle-step  x{m / base:.2f}  (rounds {min(res[c]):.3f}-{max(res[c]):.3f})")
