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

#: damBreak3D with the symplectic integrator (the tutorial's is Verlet, covered by the
#: matched cases): the simulator's one symplectic run
_SYMPLECTIC = {"system/sphSchemes:integrator": {"type": "symplectic"}}

#: (case, dx, steps, edits), always: the matched case (about 20 s on the simulator) and the
#: cut solitaryWave3D above (about 25 s: the 3 x 3 x 3 walk wrapped in y, the paddle's
#: prescribed motion in 3-D, the Shepard filter before the second step, Monaghan 2007);
#: with SPHFOAM_SLOW_TESTS=1 (15-45 s each): couette at 11 columns across its period (the
#: walk and the pairs wrapped in x, the sliding wall), the periodic cube (the walk wrapped
#: in z too), and the tutorial selections the others do not cover: damBreak (quartic,
#: symmetric, artificial viscosity, Monaghan 2007), solitaryWave (laminar, Fourtakas's
#: delta-SPH, delta+ shifting with its surface rule on a still lattice, the paddle's
#: prescribed motion), damBreak3D (wendlandC2, the delta-SPH filter of Fourtakas, the
#: symplectic integrator, a block in the tank)
_SLOW = pytest.mark.skipif(os.environ.get("SPHFOAM_SLOW_TESTS") != "1",
                           reason="the CUDA simulator, 40 s: set SPHFOAM_SLOW_TESTS=1")
CASES = [("damBreakMatched", 0.1, 3, {}),
         pytest.param("couette", 0.0035 / 11, 3, {}, marks=_SLOW),
         ("solitaryWave3D", 0.05, 2, _SOLITARY_3D),
         pytest.param("damBreakMatched3D", 0.1, 2, _CUBE_3D, marks=_SLOW),
         pytest.param("damBreak", 0.02, 5, {}, marks=_SLOW),
         pytest.param("solitaryWave", 0.125, 3, {}, marks=_SLOW),
         pytest.param("damBreak3D", 0.2, 3, _SYMPLECTIC, marks=_SLOW)]


def _simulated(script: str, *args: str) -> dict:
    """``RESULT {...}`` of ``tests/<script>`` run under the simulator (a subprocess)."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    cmd = [sys.executable, str(ROOT / "tests" / script), *args]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT ")]
    assert line, out.stdout[-2000:] + out.stderr[-4000:]
    return json.loads(line[-1][7:])


def _compare(case: str, dx, steps: int, edits: dict | None = None) -> dict:
    return _simulated("cuda_compare.py", case, "--steps", str(steps),
                      *(["--dx", repr(dx)] if dx else []),
                      *(["--edits", json.dumps(edits)] if edits else []))


def _assert_matches(res, dim: int = 2):
    assert "error" not in res, res
    assert sorted(res["rel"]) == sorted(["rho", "m", *"xyz"[:dim], *"uvw"[:dim]]), res
    assert res["same_ids"]
    assert res["dt_rel"] < 1e-12, res
    for k, rel in res["rel"].items():
        assert rel < RTOL, (k, res)


#: the models whose run-time hooks run on the device in their declared forms
#: (sphfoam.engine.hookforms), each about 15-25 s on the simulator: Adami's boundary, XSPH
#: then a delta+ shifting with its three corrections under monaghan2007 (the walls'
#: velocity put back before every evaluation and after the step, advection U + dv +
#: delta_u, after_rates, after_density_rate, after_step's mass) on 50 fluid particles; the
#: mixing length's wall distance on the turbulent channel cut to half its height (300
#: particles).
#: surfaceLambda 0: on a block of 5 x 10 particles every one is near the surface, and the
#: normal of an interior particle of the lattice is the direction of its round-off (nu ~ 0),
#: which the tangential rule would turn into differences of order one
#: the turbulent channel cut to half its height (the mixing length's wall distance; its
#: device form alone: test_a_wall_field_is_made_at_attach_and_at_every_list_build)
_CHANNEL = {"system/particleDict:fluid.channel.max": [0.3, 0.4875],
            "system/particleDict:walls.top.points": [[0, 0.4875], [0.3, 0.4875]],
            "system/particleDict:domain.max": [0.3, 0.6],
            "constant/sphProperties:turbulence.outerLength": 0.25}

#: the hooks' declared forms together (also benchmarks/gpu_compare.py's row)
HOOK_FORMS = json.loads((ROOT / "tests" / "cuda_hook_forms.json").read_text())

HOOK_CASES = [
    ("damBreakMatched", 0.2, 3, HOOK_FORMS),
    # Sun et al. (2019)'s consistent continuity: its pair term in the rates pass, added after
    # the rates and the density-only pass
    ("damBreakMatched", 0.2, 3, {
        "system/sphSchemes:integrator": {"type": "monaghan2007"},
        "constant/sphProperties:particleShifting": {
            "type": "deltaPlusShifting", "surfaceLambda": 0, "consistentContinuity": "yes"}}),
    # DBC with the walls' density clamped at rho0 (a prepass term that sets rho, p and c of
    # the wall particles in place, with no neighbour loop)
    ("damBreakMatched", 0.2, 3, {
        "constant/sphProperties:boundary": {"type": "stationaryGhosts", "noSlip": "no",
                                            "clampDensity": "yes"}}),
    # Fourtakas et al.'s diffusion over the fluid alone (walls no): its pair term sees the
    # fluid and ghosts only
    ("damBreakMatched", 0.2, 3, {
        "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH", "walls": "no"}}),
    pytest.param("turbulentChannel", None, 3, _CHANNEL, marks=_SLOW),
    # Adami's walls on a 3 m flume with the paddle's motion: its wall entry's velocity put
    # back on the paddle's particles (walls_moved), 35 s
    pytest.param("solitaryWave", 0.125, 3, {
        "constant/sphProperties:boundary": {"type": "adami"},
        "system/particleDict:fluid.water.max": [3, 0.5],
        "system/particleDict:walls.flume.max": [3, 1.2]}, marks=_SLOW),
    # Adami's free slip in 3-D: the box and block faces' normals (the tank, the box)
    pytest.param("damBreak3D", 0.2, 3, {
        "constant/sphProperties:boundary": {"type": "adami", "noSlip": "no"}}, marks=_SLOW),
    # mDBC (its device form, sphfoam.models.mdbc_cuda), 20-40 s each: free slip with the
    # list built at every step (cellSizeFactor 1: no skin), so the ghost nodes' lists are
    # made again after each sort (218 particles); no slip; free slip in 3-D with the box in
    # the tank (its edges' and corners' nodes), 1 598 particles, 100 s
    ("damBreakMatched", 0.2, 3, {
        "constant/sphProperties:boundary": {"type": "mDBC", "noSlip": "no"},
        "system/sphSchemes:neighbourSearch.cellSizeFactor": 1.0}),
    pytest.param("damBreakMatched", 0.2, 3, {
        "constant/sphProperties:boundary": {"type": "mDBC"}}, marks=_SLOW),
    pytest.param("damBreak3D", 0.2, 3, {
        "constant/sphProperties:boundary": {"type": "mDBC", "noSlip": "no"}}, marks=_SLOW)]


@pytest.mark.parametrize("case, dx, steps, edits", CASES + HOOK_CASES)
def test_cuda_matches_cpu_under_the_simulator(case, dx, steps, edits):
    _assert_matches(_compare(case, dx, steps, edits), 3 if case.endswith("3D") else 2)


def test_forces_on_free_slip_mdbc_walls_on_the_device_as_on_the_cpu():
    """``forces`` on a free-slip mDBC bed after a step (tests/cuda_forces_mdbc.py, 15 s):
    through the device form's ``before_passes`` and ``after_rates`` it reads the walls'
    velocities as the device's passes see them, the same row as the CPU's (the viscous
    part along the motion about a tenth of the no-slip bed's 1 N/m), and the walls are still
    again in the device's state afterwards."""
    res = _simulated("cuda_forces_mdbc.py")
    assert res["walls_still_cpu"] and res["walls_still_cuda"], res
    assert res["rel"] < RTOL, res
    assert abs(res["viscous_x"][1]) < 0.2, res


#: solitaryBeach (mirrorGhosts, pressure hydrostatic, wallLaw smooth, the moving paddle) at
#: dx = 0.15 m: 172 particles, 191 ghosts, 9 of them in the corner of the paddle and the bed
_BEACH = ("solitaryBeach", 0.15)


def test_mirror_ghosts_match_cpu_under_the_simulator():
    """Seven steps of the beach on one list (the ghosts' activity and count checked on the
    device each step): ghosts made in the skin beyond the support are dormant (mass 0), and
    a particle crosses the bed and is put back (the summaries say so)."""
    res = _compare(*_BEACH, 7)
    _assert_matches(res)
    assert res["built"] == [1, 1] and res["reused"] == [6, 6], res
    assert res["ghosts"][0] == res["ghosts"][1] > 0, res
    assert res["summary"][0] == res["summary"][1] == "1 put back across a mirror wall", res


def test_mirror_kernels_match_the_cpu_loops_under_the_simulator():
    """Each kernel of the mirror ghosts' device form against the CPU's loop on made-up
    particles near two moving walls meeting in a corner (tests/cuda_mirror_kernels.py):
    the ghosts' count and table, their state (free slip and no-slip, p_G = p_a and
    hydrostatic), their activity, the push-back and the wall shear of the three laws; in
    double precision and in single."""
    res = _simulated("cuda_mirror_kernels.py")
    assert "error" not in res, res
    # every branch taken: corner ghosts, dormant ones, particles pushed back and sheared
    assert min(res["ghosts"], res["corner_ghosts"], res["dormant"], res["pushed"],
               res["sheared_0"], res["sheared_1"], res["sheared_2"]) > 0, res
    for k in ("count", "table", "activity", "push_back"):
        assert res[k] == 0.0, (k, res)
    for k in ("state", "shear"):
        assert res[k] < RTOL, (k, res)
    # single precision: stored in float32 from the same double arithmetic (a few ulps)
    for k in ("state_single", "push_back_single", "shear_single"):
        assert res[k] < 1e-6, (k, res)


def test_mirror3d_kernels_match_the_cpu_loops_under_the_simulator():
    """Each 3-D kernel of the mirror ghosts' device form against the CPU's loop
    (sphfoam.models.mirror3d) on made-up particles in the corner of a box tank whose three
    faces move (tests/cuda_mirror3d_kernels.py, 8 s): the ghosts' count and table, their
    state (free slip and no-slip, p_G = p_a and hydrostatic), their activity, the ghosts a
    build would make, the dormant ones' fluid neighbours and the push-back; in double
    precision and in single."""
    res = _simulated("cuda_mirror3d_kernels.py")
    assert "error" not in res, res
    # every branch taken: edge and vertex ghosts, dormant ones near fluid, pushed back
    assert min(res["ghosts"], res["edge_ghosts"], res["vertex_ghosts"], res["dormant"],
               res["dormant_near_count"], res["pushed"]) > 0, res
    for k in ("count", "table", "activity", "dormant_near", "push_back"):
        assert res[k] == 0.0, (k, res)
    assert res["state"] < RTOL, res
    for k in ("state_single", "push_back_single"):
        assert res[k] < 1e-6, (k, res)


@pytest.mark.parametrize("case, dx, steps, edits", [
    # the tank at rest, no slip and p_G hydrostatic: face, edge and vertex ghosts made,
    # then kept for the second step (64 particles, 636 ghosts, 20-35 s)
    ("hydrostaticTank3D", 0.1, 2, {"constant/sphProperties:boundary": {
        "type": "mirrorGhosts", "noSlip": "yes", "pressure": "hydrostatic"}}),
    # the 3-D matched dam break, free slip, the list (and the ghosts) built at every step
    # (500 particles, 1 359 ghosts, 140 s)
    pytest.param("damBreakMatched3D", 0.1, 4, {
        "constant/sphProperties:boundary": {"type": "mirrorGhosts"},
        "system/sphSchemes:neighbourSearch.cellSizeFactor": 1.0}, marks=_SLOW)])
def test_mirror_ghosts_in_3d_match_cpu_under_the_simulator(case, dx, steps, edits):
    res = _compare(case, dx, steps, edits)
    _assert_matches(res, 3)
    assert res["ghosts"][0] == res["ghosts"][1] > 0, res
    assert res["built"][0] == res["built"][1] and res["reused"][0] == res["reused"][1], res


def test_free_slip_mirror_ghosts_and_xsph_match_cpu_under_the_simulator(p_wall):
    """solitaryWallRunup with P's set-up: mirrorGhosts (free slip, p_G = p_a: T(3.77)-(3.80)
    as printed) and XSPH at dx = 5 m (104 particles, 136 ghosts), with a skin of 0.2 % of
    the support: the list built at every step (the last build's ghosts retired among the particles, new
    ones made, sorted and mapped through the sort)."""
    res = _compare("solitaryWallRunup", 5.0, 3,
                   {**p_wall, "system/sphSchemes:neighbourSearch.cellSizeFactor": 1.002})
    _assert_matches(res)
    assert res["built"] == [3, 3], res
    assert res["ghosts"][0] == res["ghosts"][1] > 0, res


@_SLOW
def test_mirror_ghosts_outside_the_grid_are_dropped_as_on_the_cpu():
    """A box that cuts the ghosts below the bed: they are dropped at each build, not
    reported as particles that left; the count check then rebuilds the list every step."""
    res = _compare(*_BEACH, 3, {"system/particleDict:domain": {"min": [-1.0, -0.1],
                                                               "max": [18.5, 2.0]}})
    _assert_matches(res)
    assert res["built"] == [3, 3], res
    assert res["ghosts"][0] == res["ghosts"][1] > 0, res


#: mixingLength's wall distance on the device: a state whose lineDist is zero gets it at
#: the build of the simulation (attach); particles moved on the device get theirs anew at
#: the next build of the list (before_neighbours); both as line_distance on the host
_WALL_FIELD = """
import json, sys, tempfile
from pathlib import Path
import numpy as np
from sphfoam.assemble import build_simulation
from sphfoam.case.case import Case
from sphfoam.case.edit import clone_case
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import read_state
from sphfoam.models.mirror import line_distance, segment_array
from sphfoam.setup import setup_case

d = clone_case(Path(sys.argv[1]), Path(tempfile.mkdtemp()) / "c", json.loads(sys.argv[2]))
case = Case(d)
setup_case(case, log=lambda *_: None)
st = ParticleState.from_fields(read_state(d / "0"))
st.extra["lineDist"][:] = 0.0
sim = build_simulation(case, st, backend="cuda")
seg = segment_array(sim.segments)

def error():
    s = sim.state
    want = np.empty(s.n)
    line_distance(s.x, s.y, seg, want)
    return float(np.max(np.abs(s.extra["lineDist"] - want)))

out = {"attach": error()}
y = sim.d["y"].copy_to_host()
y += 0.004 * np.sin(40.0 * sim.d["x"].copy_to_host())
sim.d["y"].copy_to_device(y)
sim._dirty = True
out["moved"] = error()
sim.invalidate_neighbours()
sim.neighbour_update()
out["built"] = error()
print("RESULT " + json.dumps(out))
"""


def test_a_wall_field_is_made_at_attach_and_at_every_list_build():
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", _WALL_FIELD,
                          str(ROOT / "tutorials" / "turbulentChannel"),
                          json.dumps(_CHANNEL)],
                         env=env, capture_output=True, text=True, timeout=600)
    line = [x for x in out.stdout.splitlines() if x.startswith("RESULT ")]
    assert line, out.stdout[-2000:] + out.stderr[-4000:]
    res = json.loads(line[-1][7:])
    assert res["attach"] < 1e-12 and res["built"] < 1e-12, res
    assert res["moved"] > 1e-3, res          # the move changed the distances


def test_a_model_with_no_device_form_is_refused_by_name(tutorial, monkeypatch):
    from sphfoam.assemble import selection
    from sphfoam.case.case import Case
    from sphfoam.engine.cuda.build import Unsupported, check_supported
    from sphfoam.models.adami import Adami

    # every tutorial's selection has device forms of its hooks (P's collision: mirror
    # ghosts, XSPH, MLS)
    check_supported(selection(Case(tutorial("solitaryCollision"))))
    # a model's hooks without their declared forms: refused, naming the hooks
    sel = selection(Case(tutorial("damBreak", {
        "constant/sphProperties:boundary": {"type": "adami"}})))
    check_supported(sel)
    # mirrored ghosts in 3-D: the device form mirrors across box tanks' faces too; a device
    # form written for fewer dimensions than its model is refused by name in the others
    sel3 = selection(Case(tutorial("hydrostaticTank3D", {
        "constant/sphProperties:boundary": {"type": "mirrorGhosts"}})))
    check_supported(sel3)
    monkeypatch.setattr(type(sel3.boundary), "device_dims", (2,))
    with pytest.raises(Unsupported, match=r"boundary 'mirrorGhosts': its device form has no "
                       r"3-D form"):
        check_supported(sel3)
    monkeypatch.setattr(Adami, "device_forms", lambda self: ())
    with pytest.raises(Unsupported, match=r"boundary 'adami': its run-time hooks \(attach, "
                       r"before_evaluation, after_rates, after_density_rate, walls_moved, "
                       r"after_step\)"):
        check_supported(sel)


def test_models_with_declared_hook_forms_are_not_refused(tutorial):
    from sphfoam.assemble import selection
    from sphfoam.case.case import Case
    from sphfoam.engine.cuda.build import refusals

    for shifting in ("deltaPlusShifting", "lindShifting"):
        sel = selection(Case(tutorial("damBreak", {
            "constant/sphProperties:velocityCorrection": {"type": "xsph"},
            "constant/sphProperties:particleShifting": {
                "type": shifting, "correctVelocity": "yes", "correctDensity": "yes",
                "correctMass": "yes"}})))
        assert sel.particleShifting.implements("after_step")
        assert refusals(sel) == []
    sel = selection(Case(tutorial("damBreak", {
        "constant/sphProperties:boundary": {"type": "adami", "noSlip": "no"}})))
    assert refusals(sel) == []
    sel = selection(Case(tutorial("turbulentChannel")))
    assert sel.turbulence.name == "mixingLength" and sel.turbulence.implements("attach")
    assert refusals(sel) == []


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


def test_a_3d_case_is_served_and_a_motion_with_no_3d_form_is_refused_by_name(tutorial,
                                                                           monkeypatch):
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
                                      "table": [(0.0, (0.0, 0.0, 0.0)), (1.0, (0.1, 0, 0))]})
    check_supported(sel, {1: table})                # so has the displacement table
    monkeypatch.setattr(type(table), "dims", (2,))  # a motion written for 2-D only
    with pytest.raises(Unsupported, match="motion 'displacementTable': no 3-D form"):
        check_supported(sel, {1: table})


def test_declared_forms_stand_for_hooks_the_model_implements():
    """A form runs on the device only what the model's own hooks do on the host: every hook
    a declared form stands for is one the model implements (with every correction of the
    shiftings on and off, the mixing length with and without a wall law)."""
    from sphfoam import registry
    from sphfoam.engine.cuda.build import _HOOKS
    from sphfoam.engine.hookforms import device_forms, uncovered

    variants = {"particleShifting": [{}, {"correctVelocity": True},
                                     {"correctDensity": True, "correctMass": True},
                                     {"consistentContinuity": True}],
                "turbulence": [{}, {"wallLaw": "smooth"}]}
    declared = set()
    for family, models in registry.families().items():
        for name, cls in models.items():
            for extra in variants.get(family, [{}]):
                try:
                    m = registry.build(family, {"type": name, **extra})
                except Exception:  # noqa: BLE001  (a model that needs coefficients)
                    continue
                forms = device_forms(m)
                for f in forms:
                    for h in f.hooks:
                        assert m.implements(h), (family, name, extra, f, h)
                if forms:
                    declared.add(name)
                    assert uncovered(m, _HOOKS) == [], (family, name, extra)
    assert {"xsph", "deltaPlusShifting", "lindShifting", "mixingLength", "adami"} <= declared


def test_a_hook_its_device_form_does_not_stand_for_is_refused_by_name(tutorial):
    """A model whose device form leaves out one of its hooks is refused, naming that hook."""
    from types import SimpleNamespace

    from sphfoam.case.case import Case
    from sphfoam.engine.cuda.build import refusals

    bnd = Case(tutorial("solitaryBeach")).models.sph["boundary"]
    sel = SimpleNamespace(dim=2, models=lambda: [bnd])
    assert refusals(sel) == []
    partial = type("PartialMirror", (type(bnd),), {
        "device_hooks": tuple(h for h in type(bnd).device_hooks if h != "after_step")})
    sel = SimpleNamespace(dim=2, models=lambda: [partial(bnd.coeffs)])
    assert refusals(sel) == ["boundary 'mirrorGhosts': its run-time hooks (after_step) run on "
                             "host arrays (no device form)"]
