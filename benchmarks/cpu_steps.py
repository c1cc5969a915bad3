"""Process CPU time per step of a ``--case`` case of bench_engine.py, for before/after
comparisons on a loaded machine (time slicing does not inflate CPU time).

    python benchmarks/cpu_steps.py matched 23000 300          # case, particles, steps
    python benchmarks/cpu_steps.py matched 23000 300 --gather # half lists off

Builds the case as ``bench_engine.make_case_sim`` does, runs 10 warm-up steps, then times
the steps with ``time.process_time``. Run it with NUMBA_NUM_THREADS=1 for one thread.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_engine as be  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", choices=sorted(be.CASE_DIRS))
    ap.add_argument("n", type=int, help="particles (about)")
    ap.add_argument("steps", type=int)
    ap.add_argument("--warmup", type=int, default=10)
    ap.add_argument("--gather", action="store_true", help="gather over full lists only")
    args = ap.parse_args(argv)
    be.CASE = args.case
    sim, info = be.make_case_sim(args.case, args.n)
    if hasattr(sim, "half_lists"):
        sim.half_lists = not args.gather
        sim.invalidate_neighbours()
    for _ in range(args.warmup):
        sim.step()
    t0, w0 = time.process_time(), time.perf_counter()
    for _ in range(args.steps):
        sim.step()
    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
    n = info["n"]
    half = getattr(sim, "_half", None) is not None
    print(f"{args.case} N={n} steps={args.steps} half lists={half}: "
          f"CPU {1e3 * cpu / args.steps:.3f} ms/step (wall {1e3 * wall / args.steps:.3f}), "
          f"{n * args.steps / cpu / 1e6:.3f} M particle-steps per CPU-second")
    return 0


if __name__ == "__main__":
    sys.exit(main())
