"""The health checks on the CUDA backend (run by tests/test_cuda_backend.py under
NUMBA_ENABLE_CUDASIM=1): the device reductions against the host scan of the same state, a
NaN put into the device state caught at the next check, and the last good state kept on the
device equal to the state of its step. Prints one RESULT line of JSON."""

from __future__ import annotations

import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def main() -> dict:
    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.health import HealthMonitor, scan, scan_arrays
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.setup import setup_case

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = clone_case(ROOT / "benchmarks" / "cases" / "damBreakMatched", Path(tmp) / "m",
                       {"system/controlDict:functions": {}, "system/particleDict:dx": 0.1})
        case = Case(d)
        setup_case(case, log=lambda *_: None)
        sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")),
                               backend="cuda")
        mon = HealthMonitor.from_case(case)
        st0 = sim.state
        x0 = st0.x[np.argsort(st0.id)].copy()
        mon.start(sim)                    # the first snapshot: the start, kept on the device
        out["passed"] = []
        for _ in range(3):
            dt = sim.step()
            out["passed"].append(mon.check(sim, dt) is None)
        lo, hi, v2 = 0.9 * 1000.0, 1.1 * 1000.0, 0.0     # every moving fluid particle fast
        dev = sim.health_scan(lo, hi, v2)
        st = sim.state
        x, y, z, u, v, w, three = scan_arrays(st)
        host = scan(x, y, z, u, v, w, st.rho, st.m, st.kind, three, lo, hi, v2)
        out["device"] = [float(a) for a in dev]
        out["host"] = [float(a) for a in host]
        # the last good state: the start (kept every SNAPSHOT_EVERY passing checks)
        kept = mon.snapshot.state()
        out["kept_time"] = mon.snapshot.time
        out["kept_equals_start"] = bool(kept.n == st0.n and
                                        np.array_equal(kept.x[np.argsort(kept.id)], x0))
        # a NaN in the device's density: caught by the next check, named by its id
        rho = sim.d["rho"].copy_to_host()
        rho[7] = math.nan
        sim.d["rho"].copy_to_device(rho)
        sim._dirty = True                 # (as a step leaves it)
        out["nan_id"] = int(sim.d["id"].copy_to_host()[7])
        diag = mon.check(sim, sim.last_dt)
        out["nan_kind"] = diag.kind if diag else None
        out["nan_ids"] = diag.ids if diag else []
    return out


if __name__ == "__main__":
    try:
        res = main()
    except Exception as e:  # noqa: BLE001  (reported as one line: the test reads it)
        import traceback

        res = {"error": f"{type(e).__name__}: {e}", "trace": traceback.format_exc()[-3000:]}
    print("RESULT " + json.dumps(res), flush=True)
    sys.exit(0)
