"""Every tutorial's model selection on the CUDA backend against the CPU backend, on a device:
a few hundred steps each at a coarse dx (``tests/cuda_compare.py``, one process per case,
run side by side), then one table.

    python benchmarks/gpu_compare.py [--jobs 8] [--timeout 300] [--out FILE.json]
                                     [--only NAME,...]

Each row: the particles, the steps, the largest difference of x, y(, z), u, v(, w) and rho
between the backends relative to each field's largest magnitude, and the difference of the
times reached. Double precision passes below ``TOL_DOUBLE`` (round-off, grown over the
steps: fused multiply-adds on the device against the CPU's fastmath), single below
``TOL_SINGLE``. A case the backend refuses says by what.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOL_DOUBLE = 1e-8
TOL_SINGLE = 1e-3

#: (label, case, dx, steps, edits): every tutorial, the matched case, and single precision
CASES = [
    ("damBreakMatched", "damBreakMatched", 0.04, 300, {}),
    ("damBreakMatched single", "damBreakMatched", 0.04, 300,
     {"system/sphSchemes:precision": "single"}),
    ("damBreak", "damBreak", 0.02, 300, {}),
    ("damBreakObstacle", "damBreakObstacle", 0.02, 300, {}),
    ("hydrostaticTank", "hydrostaticTank", 0.04, 300, {}),
    ("wavePaddle", "wavePaddle", 0.04, 300, {}),
    ("solitaryWave", "solitaryWave", 0.1, 300, {}),
    ("couette", "couette", None, 300, {}),
    ("poiseuille", "poiseuille", None, 300, {}),
    ("turbulentChannel", "turbulentChannel", None, 300, {}),
    # the hooks' declared forms together: Adami's walls, XSPH, delta+ shifting with its
    # velocity, density and mass corrections (the suite's row: tests/test_cuda_backend.py)
    ("adami + xsph + deltaPlusShifting", "damBreakMatched", 0.04, 300,
     json.loads((ROOT / "tests" / "cuda_hook_forms.json").read_text())),
    ("solitaryBeach", "solitaryBeach", 0.05, 300, {}),
    ("solitaryCollision", "solitaryCollision", 1.25, 300, {}),
    ("solitaryWallRunup", "solitaryWallRunup", 1.25, 300, {}),
    ("hydrostaticTank3D", "hydrostaticTank3D", 0.05, 200, {}),
    # the tutorial with the symplectic integrator (its own Verlet is the matched cases')
    ("damBreak3D symplectic", "damBreak3D", 0.1, 200,
     {"system/sphSchemes:integrator": {"type": "symplectic"}}),
    ("solitaryWave3D", "solitaryWave3D", 0.05, 100, {}),
    # mDBC's device form: free slip in 3-D (the box's edges and corners), no slip in 2-D
    ("damBreak3D mDBC free slip", "damBreak3D", 0.1, 200,
     {"constant/sphProperties:boundary": {"type": "mDBC", "noSlip": "no"}}),
    ("damBreak mDBC", "damBreak", 0.02, 300, {"constant/sphProperties:boundary":
                                              {"type": "mDBC"}}),
    # mirrored ghosts across a 3-D box tank's faces (edge and vertex ghosts)
    ("damBreakMatched3D mirrorGhosts", "damBreakMatched3D", 0.05, 200,
     {"constant/sphProperties:boundary": {"type": "mirrorGhosts"}}),
]


def _one(label, case, dx, steps, edits, timeout) -> dict:
    cmd = [sys.executable, str(ROOT / "tests" / "cuda_compare.py"), case, "--steps",
           str(steps), "--edits", json.dumps(edits)] + (["--dx", str(dx)] if dx else [])
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    try:
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
        lines = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
        res = json.loads(lines[-1][7:]) if lines else \
            {"error": (p.stdout[-800:] + p.stderr[-1500:]).strip()}
    except subprocess.TimeoutExpired:
        res = {"error": f"timed out after {timeout} s"}
    res.update(label=label, steps=steps, dx=dx)
    tol = TOL_SINGLE if "single" in json.dumps(edits) else TOL_DOUBLE
    res["tol"] = tol
    res["pass"] = ("error" not in res and res.get("same_ids", False)
                   and max(res["rel"].values()) < tol and res["dt_rel"] < tol)
    print(json.dumps(res), flush=True)
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--jobs", type=int, default=8)
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--only", default="")
    ap.add_argument("--out", default="/tmp/sphfoam-gpu-compare.json")
    a = ap.parse_args(argv)
    only = set(filter(None, a.only.split(",")))
    todo = [c for c in CASES if not only or c[0] in only]
    with ThreadPoolExecutor(a.jobs) as ex:
        res = list(ex.map(lambda c: _one(*c, a.timeout), todo))
    Path(a.out).write_text(json.dumps(res, indent=1))
    print("\n| case | particles | steps | largest relative difference | time reached | "
          "result |")
    print("|---|---:|---:|---|---:|---|")
    for r in res:
        if "error" in r:
            print(f"| {r['label']} | | {r['steps']} | {r['error'][-300:]!r} | | refused or "
                  "failed |")
            continue
        worst = max(r["rel"], key=r["rel"].get)
        print(f"| {r['label']} | {r['n']} | {r['steps']} | {r['rel'][worst]:.1e} ({worst}) | "
              f"{r['dt_rel']:.1e} | {'pass' if r['pass'] else 'FAIL'} (< {r['tol']:g}) |")
    sys.exit(0 if all(r["pass"] for r in res) else 1)


if __name__ == "__main__":
    main()
