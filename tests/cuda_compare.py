"""Run a case on the CPU backend (gather over full lists) and on the CUDA backend and print
the largest relative difference of x, y, u, v, rho, m (z, w in 3-D) of the particles (ids
>= 0: not the mirror ghosts) after N steps, one JSON line per case (each field against its
largest magnitude, a velocity component against the velocity's largest component), with per
backend the lists built and reused, the ghosts and the models' summaries.

    python tests/cuda_compare.py CASE_DIR_OR_NAME [--dx DX] [--steps N] [--edits JSON]

Used by tests/test_cuda_backend.py under NUMBA_ENABLE_CUDASIM=1 (the simulator) and by
benchmarks/gpu_check.sh on a device.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _fields(sim):
    """Positions, velocities, density and mass of the particles (ids >= 0: ghosts are no
    particles; z, w too in 3-D) by id, and the ids."""
    st = sim.state
    order = np.argsort(st.id, kind="stable")
    order = order[st.id[order] >= 0]
    return {k: np.asarray(getattr(st, k), dtype=np.float64)[order]
            for k in (*"xyz"[:st.dim], *"uvw"[:st.dim], "rho", "m")}, st.id[order]


def compare(src: Path, edits: dict, steps: int) -> dict:
    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    with tempfile.TemporaryDirectory() as tmp:
        d = clone_case(src, Path(tmp) / src.name, dict({"system/controlDict:functions": {}},
                                                       **edits))
        case = Case(d)
        setup_case(case, log=lambda *_: None)
        res = {}
        sims = {}
        res["seconds"] = {}
        for backend in ("cpu", "cuda"):
            t0 = time.perf_counter()
            st = ParticleState.from_fields(read_state(d / "0"))
            sim = build_simulation(case, st, backend=backend)
            if backend == "cpu":
                sim.half_lists = False        # the gather, as the device runs it
            for _ in range(steps):
                sim.step()
            sims[backend] = sim
            res["seconds"][backend] = round(time.perf_counter() - t0, 1)
        (a, ia), (b, ib) = _fields(sims["cpu"]), _fields(sims["cuda"])
        res["n"] = int(ia.shape[0])
        res["same_ids"] = bool(ia.shape == ib.shape and (ia == ib).all())
        res["time_cpu"], res["time_cuda"] = sims["cpu"].time, sims["cuda"].time
        res["rel"], res["scale"] = {}, {}
        for k in a:
            # a velocity component relative to the largest of the velocity's components: one
            # that is zero by symmetry (v across a periodic span) holds round-off alone
            group = tuple("uvw") if k in "uvw" else (k,)
            scale = max(max(float(np.max(np.abs(a[g]))) for g in group if g in a), 1e-300)
            res["scale"][k] = scale
            res["rel"][k] = float(np.max(np.abs(a[k] - b[k]))) / scale if res["same_ids"] \
                else float("inf")
        res["dt_rel"] = abs(res["time_cpu"] - res["time_cuda"]) / max(res["time_cpu"], 1e-300)
        # lists built and reused, ghosts (kind 2) now, the models' summaries: per backend
        for k, get in (("built", lambda s: s.list_built), ("reused", lambda s: s.list_reused),
                       ("ghosts", lambda s: int((s.state.kind == 2).sum())),
                       ("summary", lambda s: s.summary())):
            res[k] = [get(sims["cpu"]), get(sims["cuda"])]
    return res


def main(argv):
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("case")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--dx", type=float, default=None)
    ap.add_argument("--edits", default="{}")
    a = ap.parse_args(argv)
    src = Path(a.case)
    if not src.exists():
        src = ROOT / "tutorials" / a.case
        if not src.exists():
            src = ROOT / "benchmarks" / "cases" / a.case
    edits = json.loads(a.edits)
    if a.dx:
        edits["system/particleDict:dx"] = a.dx
    try:
        out = compare(src, edits, a.steps)
    except Exception as e:  # noqa: BLE001  (reported as one line: the test reads it)
        out = {"error": f"{type(e).__name__}: {e}"}
    out["case"] = a.case
    print("RESULT " + json.dumps(out), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
