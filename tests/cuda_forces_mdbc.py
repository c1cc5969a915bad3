"""``forces`` on free-slip mDBC walls through the CUDA backend against the CPU: the water of
a 2-D tank moving along the bed at 0.3 m/s, one step, then the bed's force read as the pair
passes see the walls (mDBC's ``before_passes`` by its device form on the device, then
``after_rates``). Prints one JSON line, ``RESULT {...}``: the largest difference of the
force row (pressure and viscous parts) relative to its largest magnitude, the viscous part
along the motion on each backend, and whether the wall particles' velocity is zero again
in the device's state. Run by tests/test_cuda_backend.py under NUMBA_ENABLE_CUDASIM=1.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

PARTICLES = """dx 0.02;
fluid { water { type box; min (0 0); max (0.5 0.2); } }
walls {
  bed { type polyline; points ((-0.06 0) (0.56 0)); side right; layers 3; }
  sides { type box; min (0 -0.06); max (0.5 0.6); layers 3; open (top bottom); }
}
"""


def main() -> dict:
    from sphfoam import registry
    from sphfoam.assemble import build_simulation
    from sphfoam.case.case import Case
    from sphfoam.case.edit import set_entry
    from sphfoam.engine.state import FLUID
    from sphfoam.setup.initial import generate_case

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        rows = {}
        for backend in ("cpu", "cuda"):
            case = Path(tmp) / backend
            shutil.copytree(ROOT / "tutorials" / "hydrostaticTank", case,
                            ignore=shutil.ignore_patterns("postProcessing", "[0-9]*"))
            pd = case / "system" / "particleDict"
            pd.write_text(pd.read_text().split("// * * * *")[0] + "// * * * * //\n"
                          + PARTICLES)
            set_entry(case, "constant/sphProperties", "boundary.type", "mDBC")
            set_entry(case, "constant/sphProperties", "boundary.noSlip", False)
            c = Case(case)
            c.validate()
            st = generate_case(c)
            st.p = c.models.sph["equationOfState"].pressure(st.rho, c.context)
            st.u[st.kind == FLUID] = 0.3
            sim = build_simulation(c, st, backend=backend)
            sim.step()
            fo = registry.build("functionObject", {"type": "forces", "patches": ["bed"]},
                                {"dim": c.dimension})
            fo.object_name = "bed"
            fo.start(c, c.context, "0")
            fo.execute(sim)
            fo.end()
            rows[backend] = np.loadtxt(fo.file)
            walls = sim.state.kind != FLUID
            out[f"walls_still_{backend}"] = bool(np.all(sim.state.u[walls] == 0.0))
        a, b = rows["cpu"][1:], rows["cuda"][1:]
        out["rel"] = float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-300))
        out["viscous_x"] = [float(rows["cpu"][7]), float(rows["cuda"][7])]
        out["pressure_y"] = [float(rows["cpu"][5]), float(rows["cuda"][5])]
    return out


if __name__ == "__main__":
    print("RESULT " + json.dumps(main()))
