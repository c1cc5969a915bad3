"""The CUDA backend (issue 34) against the CPU backend, under numba's CUDA simulator.

Each comparison runs in a subprocess with ``NUMBA_ENABLE_CUDASIM=1`` (it must be set before
numba.cuda is imported; the rest of the suite keeps the real numba.cuda): a tiny case, a few
steps on each backend (the CPU one gathering over full lists, as the device does), then x,
y, u, v, rho (z, w in 3-D) by particle id. The same neighbour lists in the same order, the
same sums in the same order: what differs is round-off, from the CPU's fastmath contraction
and reassociation (the simulator evaluates the kernels' Python in plain double arithmetic;
on a device, fused multiply-adds), so the fields agree to ``RTOL`` relative to each field's
largest magnitude (a velocity component: the velocity's largest component), and
the times reached exactly or to round-off.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba.cuda")

ROOT = Path(__file__).resolve().parent.parent
#: relative to each field's (the velocity's) largest magnitude, after the steps below
RTOL = 1e-9

#: solitaryWave3D cut to a flume 0.35 m long, 0.2 m high and one period (0.55 m) across,
#: two layers of wall particles, the density filter every step: about 600 particles
_SOLITARY_3D = {"system/particleDict:fluid.water.max": [0.2, 0.55, 0.2],
                "system/particleDict:walls.flume.min": [-0.15, 0, 0],
                "system/particleDict:walls.flume.max": [0.2, 0.55, 0.2],
                "system/particleDict:walls.flume.layers": 2,
                "system/particleDict:walls.paddle.max": [0, 0.55, 0.2],
                "system/particleDict:walls.paddle.layers": 2,
                "system/particleDict:domain.min": [-0.4, 0, -0.3],
                "system/particleDict:domain.max": [0.5, 0.55, 0.5],
                "constant/sphProperties:densityFilter.every": 1}

#: damBreakMatched3D cut to a cube of fluid 9 dx a side at dx = 0.1, no walls, periodic in
#: x, y and z (3 cells each): the walk of every particle outside the central cell wraps
_CUBE_3D = {"system/particleDict:walls": None,
            "system/particleDict:fluid.column.max": [0.9, 0.9, 0.9],
            "system/particleDict:domain": {"min": [0, 0, 0], "max": [0.9, 0.9, 0.9],
                                           "periodic": ["x", "y", "z"]}}

#: (case, dx, steps, edits): the matched case (always, about 25 s on the simulator); a
#: periodic one, couette at 11 columns across its period (always, about 20 s: the cell walk
#: and the pairs wrapped in x, the sliding wall); two 3-D ones, the cut solitaryWave3D
#: above (always, about 25 s: the 3 x 3 x 3 walk wrapped in y, the paddle's prescribed
#: motion in 3-D, the Shepard filter before the second step, Monaghan 2007) and the
#: periodic cube (always, about 15 s: the walk wrapped in z too); and the tutorial
#: selections the device supports that they do not cover (with SPHFOAM_SLOW_TESTS=1):
#: damBreak (quartic, symmetric, artificial viscosity, Monaghan 2007; about 40 s),
#: solitaryWave (laminar, Shepard filter, the paddle's prescribed motion; about 45 s),
#: damBreak3D (wendlandC2, the delta-SPH filter of Fourtakas, the symplectic integrator,
#: a block in the tank; about 35 s)
_SLOW = pytest.mark.skipif(os.environ.get("SPHFOAM_SLOW_TESTS") != "1",
                           reason="the CUDA simulator, 40 s: set SPHFOAM_SLOW_TESTS=1")
CASES = [("damBreakMatched", 0.1, 5, {}),
         ("couette", 0.0035 / 11, 3, {}),
         ("solitaryWave3D", 0.05, 2, _SOLITARY_3D),
         ("damBreakMatched3D", 0.1, 2, _CUBE_3D),
         pytest.param("damBreak", 0.02, 5, {}, marks=_SLOW),
         pytest.param("solitaryWave", 0.125, 3, {}, marks=_SLOW),
         pytest.param("damBreak3D", 0.2, 3, {}, marks=_SLOW)]


def _compare(case: str, dx, steps: int, edits: dict) -> dict:
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    cmd = [sys.executable, str(ROOT / "tests" / "cuda_compare.py"), case,
           "--steps", str(steps), "--edits", json.dumps(edits)] \
        + (["--dx", repr(dx)] if dx else [])
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT ")]
    assert line, out.stdout[-2000:] + out.stderr[-4000:]
    return json.loads(line[-1][7:])


@pytest.mark.parametrize("case, dx, steps, edits", CASES)
def test_cuda_matches_cpu_under_the_simulator(case, dx, steps, edits):
    res = _compare(case, dx, steps, edits)
    assert "error" not in res, res
    dim = 3 if case.endswith("3D") else 2
    assert sorted(res["rel"]) == sorted(["rho", *"xyz"[:dim], *"uvw"[:dim]]), res
    assert res["same_ids"]
    assert res["dt_rel"] < 1e-12, res
    for k, rel in res["rel"].items():
        assert rel < RTOL, (k, res)


def test_a_model_with_no_device_form_is_refused_by_name(tutorial):
    from sphfoam.assemble import selection
    from sphfoam.case.case import Case
    from sphfoam.engine.cuda.build import Unsupported, check_supported

    case = Case(tutorial("solitaryCollision"))
    with pytest.raises(Unsupported, match="boundary 'mirrorGhosts'"):
        check_supported(selection(case))
    with pytest.raises(Unsupported, match="velocityCorrection 'xsph'"):
        check_supported(selection(case))


def test_backend_is_a_checked_schemes_entry(tutorial):
    from sphfoam.case.case import Case

    assert Case(tutorial("damBreak")).schemes.backend == "cpu"
    assert Case(tutorial("damBreak", {"system/sphSchemes:backend": "cuda"})).schemes.backend \
        == "cuda"
    with pytest.raises(Exception, match="backend"):
        Case(tutorial("damBreak", {"system/sphSchemes:backend": "opencl"})).schemes


def test_health_checks_run_on_the_device():
    """The per-step checks as device reductions: the same counts and largest speed as the
    host scan of the same state, the sums to round-off; the last good state kept on the
    device (the start) comes back equal; a NaN is caught at the next check and named."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, str(ROOT / "tests" / "cuda_health.py")], env=env,
                         capture_output=True, text=True, timeout=900)
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT ")]
    assert line, out.stdout[-2000:] + out.stderr[-4000:]
    res = json.loads(line[-1][7:])
    assert "error" not in res, res
    assert res["passed"] == [True, True, True]
    dev, host = res["device"], res["host"]
    assert dev[:4] == host[:4] and dev[6] == host[6], res      # counts, largest speed^2
    assert dev[2] > 0                                          # the speed check counted
    for i in (4, 5):                                           # kinetic energy, mass
        assert abs(dev[i] - host[i]) <= 1e-12 * abs(host[i]), res
    assert res["kept_time"] == 0.0 and res["kept_equals_start"], res
    assert res["nan_kind"] == "nan" and res["nan_ids"] == [res["nan_id"]], res


def test_a_3d_case_is_served_and_a_motion_with_no_3d_form_is_refused_by_name(tutorial):
    from sphfoam.assemble import selection
    from sphfoam.case.case import Case
    from sphfoam.engine.cuda.build import Unsupported, check_supported, parameters
    from sphfoam import registry

    case = Case(tutorial("solitaryWave3D"))
    sel = selection(case)
    check_supported(sel, case.models.motions)       # the piston paddle has a 3-D form
    prm = parameters(sel, case.context, (-1.5, 0.0, -0.5), (23.0, 0.55, 2.5))
    assert prm["gz"] == case.context.g[2] and prm["ly"] == prm["half_ly"] * 2 == 0.55
    assert "lx" not in prm and "lz" not in prm
    table = registry.build("motion", {"type": "displacementTable",
                                      "table": [(0.0, (0.0, 0.0)), (1.0, (0.1, 0.0))]})
    with pytest.raises(Unsupported, match="motion 'displacementTable': no 3-D form"):
        check_supported(sel, {1: table})
