"""Particle generation, writing control, purgeWrite and the export utility."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.schemas import ParticleDict
from sphfoam.case.times import list_times
from sphfoam.cli import app
from sphfoam.io.fields import read_state
from sphfoam.setup import setup_case
from sphfoam.timeloop import run_case
from sphfoam.setup.particles import local_surface, polyline_points, wall_points


def test_box_fluid_and_tank_walls_are_on_the_lattice(tutorial):
    case = Case(tutorial("hydrostaticTank"))
    state = setup_case(case, log=lambda m: None)
    f = state.kind == 0
    assert f.sum() == 50 * 40                          # 0.5 x 0.4 at dx = 0.01
    assert state.x[f].min() == pytest.approx(0.005) and state.y[f].max() == pytest.approx(0.395)
    w = ~f
    # 3 rows under the bed and beside both walls, open top: (50 + 6) * 3 + 2 * 3 * 60
    assert w.sum() == 56 * 3 + 2 * 3 * 60
    # hydrostatic start: p = rho g (H - y) in the fluid, masses rho dx^2
    p = 1000 * 9.81 * (0.4 - state.y[f])
    B = case.models.sph["equationOfState"].B(case.context)
    np.testing.assert_allclose(B * ((state.rho[f] / 1000) ** 7 - 1), p, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(state.m, state.rho * 0.01 ** 2)
    assert (case.path / "0" / "lagrangian" / "particles" / "positions").is_file()


def test_polygon_fluid_and_polyline_walls():
    pd = ParticleDict.model_validate({
        "dx": 0.1,
        "fluid": {"wedge": {"type": "polygon", "points": [(0, 0), (2, 0), (0, 1)]}},
        "walls": {"bed": {"type": "polyline", "points": [(0, 0), (2, 0), (2, 1)],
                          "layers": 2, "side": "right"}},
    })
    x, y = polyline_points(np.array([(0, 0), (2, 0), (2, 1)], float), 0.1, 2, "right")
    # bed: 20 per row; vertical wall: 10 per row; solid on the right of travel = below/right
    assert x.size == 2 * 20 + 2 * 10
    assert np.all((y < 0) | (x > 2))
    wx, _ = wall_points(pd.walls["bed"], 0.1)
    assert wx.size == x.size
    xs = np.array([0.05, 0.05, 0.15])
    ys = np.array([0.05, 0.15, 0.05])
    np.testing.assert_allclose(local_surface(xs, ys, 0.1), [0.2, 0.2, 0.1])


def test_time_step_write_control_and_purge_write(tutorial):
    case = tutorial("damBreak", {"system/particleDict:dx": 0.0125,
                                 "system/controlDict:writeControl": "timeStep",
                                 "system/controlDict:writeInterval": 10,
                                 "system/controlDict:purgeWrite": 2,
                                 "system/controlDict:functions": {}})
    rep = run_case(case, progress=False, echo=None, end_time=0.01)
    times = [p.name for _, p in list_times(case)]
    assert times[0] == "0" and len(times) == 3          # 0 plus the last two writes kept
    assert rep.steps > 20
    log = (case / "log.sphfoam").read_text()
    assert "compile:" in log and "particle-steps/s" in log


def test_export_vtk_via_cli(tutorial):
    case = tutorial("damBreak", {"system/particleDict:dx": 0.0125,
                                 "system/controlDict:writeInterval": 0.005,
                                 "system/controlDict:functions": {}})
    runner = CliRunner()
    res = runner.invoke(app, ["run", str(case), "--end-time", "0.01", "--no-progress"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["export", "vtk", str(case)])
    assert res.exit_code == 0, res.output
    import vtk

    pvd = case / "VTK" / "damBreak.pvd"
    assert pvd.is_file()
    # one multiblock (fluid, walls) per time, named by the time (issue 16)
    files = sorted((case / "VTK").glob("*.vtm"))
    assert len(files) == 3
    state = read_state(case / "0.01")
    n = 0
    for block in ("fluid", "walls"):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(str(case / "VTK" / "damBreak_0.01" / f"{block}.vtp"))
        r.Update()
        out = r.GetOutput()
        n += out.GetNumberOfPoints()
        assert out.GetPointData().GetArray("U").GetNumberOfComponents() == 3
        for name in ("rho", "p", "mass", "type", "origId"):
            assert out.GetPointData().GetArray(name) is not None, name
    assert n == len(state["rho"])


def test_setup_refuses_to_overwrite_without_force(tutorial):
    case = tutorial("hydrostaticTank")
    runner = CliRunner()
    assert runner.invoke(app, ["setup", str(case)]).exit_code == 0
    res = runner.invoke(app, ["setup", str(case)])
    assert res.exit_code == 2 and "--force" in res.output
    assert runner.invoke(app, ["setup", str(case), "--force"]).exit_code == 0


def test_ctrl_c_writes_a_whole_step_and_the_run_resumes(tutorial):
    """SIGINT mid-run: the current state is written (never lost) and `run` continues from it."""
    import signal
    import subprocess
    import sys
    import time

    case = tutorial("damBreak", {"system/particleDict:dx": 0.0125,
                                 "system/controlDict:writeInterval": 10.0,
                                 "system/controlDict:endTime": 20.0,
                                 "system/controlDict:functions": {}})
    proc = subprocess.Popen([sys.executable, "-m", "sphfoam.cli", "run", str(case),
                             "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    log = case / "log.sphfoam"
    deadline = time.time() + 120
    while time.time() < deadline and "compile:" not in (log.read_text() if log.exists() else ""):
        time.sleep(0.2)
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out = proc.communicate(timeout=60)[0].decode()
    assert proc.returncode == 130, out
    assert "Traceback" not in out
    times = [(t, p) for t, p in list_times(case) if t > 0]
    assert len(times) == 1 and (times[0][1] / "uniform" / "time").is_file()
    assert "interrupted at time" in log.read_text()
    rep = run_case(case, progress=False, echo=None, end_time=times[0][0] + 0.002)
    assert rep.start_time == pytest.approx(times[0][0], abs=1e-6) and rep.steps > 0
