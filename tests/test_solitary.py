"""A solitary wave set up from theory (P §4) travels ten depths keeping its height and speed.

The wall run-up tutorial at 10 particles per depth (P used 16), the crest 10 depths from the
wall: the ``crestTracker`` function object follows the crest while it travels from x = -60 m
to x = 40 m (ten depths of 10 m) and fits its celerity; the height must stay within 8 % of
A = 3 m (A/H = 0.3) and the celerity within 3 % of the second-order KdV theory P(12) the
wave was set up with.
"""

from __future__ import annotations

import numpy as np
import pytest

from sphfoam import registry
from sphfoam.case.case import Case
from sphfoam.case.times import list_times
from sphfoam.io.fields import read_state
from sphfoam.setup import setup_case
from sphfoam.timeloop import run_case


def test_solitary_wave_from_theory_keeps_height_and_celerity_over_ten_depths(tutorial):
    A, d = 3.0, 10.0
    kdv2 = registry.build("waveTheory", {"type": "kdv2"}).solitary(A, d)
    t_end = 100.0 / kdv2.c + 0.5
    case = tutorial("solitaryWallRunup", {
        "system/particleDict:dx": 1.0,
        "constant/waveProperties:waves.incident.x0": -60.0,
        "system/controlDict:endTime": round(t_end, 2),
        "system/controlDict:writeInterval": round(t_end, 2),
        "system/controlDict:functions": {"crest": {
            "type": "crestTracker", "xMin": -100.0, "xMax": 80.0, "still": d,
            "fitFrom": -50.0, "fitTo": 40.0, "writeControl": "runTime",
            "writeInterval": 0.1}}})
    c = Case(case)
    st = setup_case(c, log=lambda m: None)
    # the set-up: columns up to the theory's surface, velocities from the theory
    f = st.kind == 0
    crest = f & (np.abs(st.x - (-60.0)) < 0.51)        # the two columns either side
    assert st.y[crest].max() + 0.5 * (d + A) / round((d + A) / 1.0) == pytest.approx(d + A,
                                                                                   abs=0.05)
    k = np.flatnonzero(crest)
    np.testing.assert_allclose(st.u[k], kdv2.u(st.x[k], st.y[k], x0=-60.0), rtol=1e-9)
    np.testing.assert_allclose(st.v[k], kdv2.w(st.x[k], st.y[k], x0=-60.0), rtol=1e-9,
                               atol=1e-12)
    run_case(case, progress=False, echo=None)
    rows = np.loadtxt(case / "postProcessing" / "crest" / "0" / "crest.dat", ndmin=2)
    fit = np.loadtxt(case / "postProcessing" / "crest" / "0" / "celerity.dat", ndmin=2)
    x_c, eta_c = rows[:, 1], rows[:, 2]
    assert x_c.max() > 35.0                        # it did travel ten depths
    travelled = x_c > 30.0
    # measured at 10 particles per depth: the crest drops from 3.00 to about 2.78 m within the
    # first 0.5 s (the SPH surface settling from the theory's), then holds: 2.75-2.79 m over
    # the last depth, a mean 7.8 % low. The mean is held to the 8 % bar, each sample to 9 %.
    assert abs(eta_c[travelled].mean() / A - 1) < 0.08, eta_c[travelled]
    assert np.all(np.abs(eta_c[travelled] / A - 1) < 0.09), eta_c[travelled]
    assert fit[0, 0] == pytest.approx(kdv2.c, rel=0.03)
    s = read_state(list_times(case)[-1][1])
    assert (s["type"] == 0).sum() == f.sum()


def test_sample_adds_gauges_after_a_run_and_plot_compares_them_with_theory(tutorial):
    """``sphfoam sample -f NAME`` evaluates a function object added after the run on every
    written time; ``sphfoam plot`` draws the gauges against a theory and tabulates heights."""
    from typer.testing import CliRunner

    from sphfoam.case.edit import set_entry
    from sphfoam.cli import app

    case = tutorial("solitaryWallRunup", {
        "system/particleDict:dx": 2.5,
        "system/controlDict:endTime": 0.4, "system/controlDict:writeInterval": 0.1,
        "system/controlDict:functions": {}})
    run_case(case, progress=False, echo=None)
    times = [t for t, _ in list_times(case)]
    assert len(times) == 5
    set_entry(case, "system/controlDict", "functions",
              {"late": {"type": "waveGauges", "x": [-20.0, 0.0, 20.0], "still": 10.0}})
    runner = CliRunner()
    res = runner.invoke(app, ["sample", str(case), "-f", "late"])
    assert res.exit_code == 0, res.output
    rows = np.loadtxt(case / "postProcessing" / "late" / "0" / "late.dat", ndmin=2)
    np.testing.assert_allclose(rows[:, 0], times)
    # the crest (x0 = 0) reads close to A = 3 m at t = 0 (coarse: 4 particles per depth)
    assert rows[0, 2] == pytest.approx(3.0, abs=0.5 * 2.5)
    assert rows[0, 1] < rows[0, 2] and rows[0, 3] < rows[0, 2]
    res = runner.invoke(app, ["plot", str(case), "--theory", "kdv2"])
    assert res.exit_code == 0, res.output
    assert (case / "postProcessing" / "late" / "0" / "late_kdv2.png").is_file()
    table = np.loadtxt(case / "postProcessing" / "late" / "0" / "late_height.dat", ndmin=2)
    assert table.shape == (3, 5)
    res = runner.invoke(app, ["sample", str(case), "-f", "nope"])
    assert res.exit_code != 0 and "late" in res.output


def test_initial_waves_set_up_beside_wall_particles(tutorial):
    """Initial waves (constant/waveProperties) with a boundary model that has wall particles:
    the wave's velocities reach the fluid columns, the walls get particles (a regression: the
    wall rows once replaced the fluid regions' list the wave fields were set from)."""
    A, d = 3.0, 10.0
    kdv2 = registry.build("waveTheory", {"type": "kdv2"}).solitary(A, d)
    case = tutorial("solitaryWallRunup", {"system/particleDict:dx": 1.0,
                                          "constant/sphProperties:boundary":
                                          {"type": "stationaryGhosts"}})
    st = setup_case(Case(case), log=lambda m: None)
    assert (st.kind != 0).sum() > 0
    f = np.flatnonzero((st.kind == 0) & (np.abs(st.x) < 0.51))   # the crest's columns
    assert f.size > 0
    np.testing.assert_allclose(st.u[f], kdv2.u(st.x[f], st.y[f], x0=0.0), rtol=1e-9)


@pytest.mark.parametrize("boundary", ["mirrorGhosts", "stationaryGhosts"])
def test_initial_wave_columns_keep_their_bottom_particle(tutorial, boundary):
    """Every column of the initial wave holds round((d + eta)/dx) particles from dy/2 above
    the bed up (a regression: where n rounded up, dy < dx put the bottom particle closer than
    dx/2 to the bed and the set-up dropped it, leaving a hole under each such column, 29 %
    of the wave's volume at d/dx = 8, that made the crest breathe by 8 %)."""
    from sphfoam.setup.waves import surface
    d, dx = 10.0, 1.25
    case = tutorial("solitaryWallRunup", {"system/particleDict:dx": dx,
                                          "constant/sphProperties:boundary":
                                          {"type": boundary}})
    c = Case(case)
    st = setup_case(c, log=lambda m: None)
    f = st.kind == 0
    x, y = st.x[f], st.y[f]
    cols = np.unique(np.round(x, 6))
    eta = surface(cols, d, list(c.waves.values()), 9.81)
    n = np.round((d + eta) / dx).astype(int)
    assert (n * dx < d + eta).any(), "no column with dy < dx: the test tests nothing"
    for xc, nc, e in zip(cols, n, eta):
        yc = np.sort(y[np.abs(x - xc) < 1e-6])
        assert yc.size == nc, (xc, yc)
        np.testing.assert_allclose(yc[0], 0.5 * (d + e) / nc, rtol=1e-9)
    # the fluid's volume is the exact wave's (the columns' heights)
    np.testing.assert_allclose((st.m[f] / st.rho[f]).sum(), dx * (d + eta).sum(),
                               rtol=1e-9)


@pytest.mark.parametrize("dx", [0.4166667, 0.41666667])
@pytest.mark.parametrize("boundary", ["mirrorGhosts", "stationaryGhosts"])
def test_a_rounded_dx_fills_the_tank_to_the_far_wall(tutorial, dx, boundary):
    """A dx typed with 7-8 digits (10/24 m as 0.4166667) makes P's 250 m tank 599.99995
    spacings long; the lattice used to floor that to 599 columns and leave a column-wide gap
    at the far wall (x = 100 m) that the water fell into, sloshing at 3 m/s within a second.
    Every column from the near to the far wall is there, dx apart."""
    case = tutorial("solitaryWallRunup", {"system/particleDict:dx": dx,
                                          "constant/sphProperties:boundary":
                                          {"type": boundary}})
    st = setup_case(Case(case), log=lambda m: None)
    f = st.kind == 0
    cols = np.unique(np.round(st.x[f], 5))
    assert cols.size == 600
    assert cols[0] - (-150.0) == pytest.approx(0.5 * dx, rel=1e-3)
    assert 100.0 - cols[-1] == pytest.approx(0.5 * dx, rel=1e-3)
    np.testing.assert_allclose(np.diff(cols), dx, rtol=1e-4)   # cols rounded to 1e-5 m
