"""Precision study (issue 12): single against double on the dam break and the flume.

    python benchmarks/precision_study.py        # about 2 minutes of CPU on 2 cores

damBreak at dx = 0.01 (1693 particles) to t = 0.4 s: the front, the largest x of the fluid
(the leading edge Z of T(3.81), in m from the wall at x = 0), at t = 0.1, 0.2, 0.3, 0.4 s;
solitaryWave as set up (5933 particles) to t = 2 s: the crest, the largest y of the fluid,
at t = 0.5, 1, 1.5, 2 s. Both precisions from the same set-up; CPU seconds of the stepping
(process time, one thread). Writes /tmp/sphfoam-precision-study.json.
"""
import json
import tempfile
import time
from pathlib import Path
import numpy as np
from sphfoam.assemble import build_simulation
from sphfoam.setup import setup_case
from sphfoam.case.case import Case
from sphfoam.case.edit import clone_case
from sphfoam.engine.state import FLUID, ParticleState
from sphfoam.io.fields import read_state
TUT = Path(__file__).resolve().parent.parent / "tutorials"
def run(tut, edits, t_end, probes, metric):
    tmp = Path(tempfile.mkdtemp())
    d = clone_case(TUT / tut, tmp / tut, dict({"system/controlDict:functions": {}}, **edits))
    case = Case(d); setup_case(case, log=lambda *_: None)
    sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")))
    sim.step(); sim.step()
    out = []; k = 0; steps = 0
    c0 = time.process_time()
    while sim.time < t_end:
        dt_rem = probes[k] - sim.time if k < len(probes) else np.inf
        sim.step(dt_rem); steps += 1
        if k < len(probes) and sim.time >= probes[k] - 1e-12:
            out.append(metric(sim)); k += 1
    cpu = time.process_time() - c0
    return dict(n=int(sim.state.n), steps=steps, cpu_s=cpu, us_per_particle_step=1e6 * cpu / (steps * sim.state.n), values=out)
def front(sim):
    st = sim.state; f = st.kind == FLUID
    return float(np.max(st.x[f]))
def crest(sim):
    st = sim.state; f = st.kind == FLUID
    return float(np.max(st.y[f]))
res = {}
for prec in ("double", "single"):
    res[("damBreak", prec)] = run("damBreak", {"system/particleDict:dx": 0.01, "system/sphSchemes:precision": prec}, 0.4, [0.1, 0.2, 0.3, 0.4], front)
    print("damBreak", prec, res[("damBreak", prec)], flush=True)
for prec in ("double", "single"):
    res[("solitaryWave", prec)] = run("solitaryWave", {"system/sphSchemes:precision": prec}, 2.0, [0.5, 1.0, 1.5, 2.0], crest)
    print("solitaryWave", prec, res[("solitaryWave", prec)], flush=True)
json.dump({f"{a}/{b}": v for (a, b), v in res.items()}, open("/tmp/sphfoam-precision-study.json", "w"), indent=1)
