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
from sphfoam.setup.waves import continuity_velocity, is_kinematic
from sphfoam.timeloop import run_case


def test_solitary_wave_from_theory_keeps_height_and_celerity_over_ten_depths(tutorial, p_wall):
    """P's set-up (section 4) carries its KdV2 wave ten depths."""
    A, d = 3.0, 10.0
    kdv2 = registry.build("waveTheory", {"type": "kdv2"}).solitary(A, d)
    t_end = 100.0 / kdv2.c + 0.5
    case = tutorial("solitaryWallRunup", {
        **p_wall,
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
    # KdV2's u scaled to the flux c eta, w from continuity (waveProperties velocity continuity)
    u, w = continuity_velocity(kdv2, st.x[k], st.y[k], -60.0)
    np.testing.assert_allclose(st.u[k], u, rtol=1e-9)
    np.testing.assert_allclose(st.v[k], w, rtol=1e-9, atol=1e-12)
    run_case(case, progress=False, echo=None)
    rows = np.loadtxt(case / "postProcessing" / "crest" / "0" / "crest.dat", ndmin=2)
    fit = np.loadtxt(case / "postProcessing" / "crest" / "0" / "celerity.dat", ndmin=2)
    x_c, eta_c = rows[:, 1], rows[:, 2]
    assert x_c.max() > 35.0                        # it did travel ten depths
    travelled = x_c > 30.0
    # measured at 10 particles per depth (particle surface): 2.97-3.01 m over the last depth,
    # a mean 0.25 % low (the quiet start, issue 35; before the set-up's hole at the bed was
    # fixed the crest dropped to about 2.78 m within 0.5 s and held there, 7.8 % low). The
    # bars stay the old ones: the mean within 8 %, each sample within 9 %.
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
                                          {"type": "stationaryGhosts"},
                                          "constant/waveProperties:waves.incident.theory":
                                          "kdv2"})
    st = setup_case(Case(case), log=lambda m: None)
    assert (st.kind != 0).sum() > 0
    f = np.flatnonzero((st.kind == 0) & (np.abs(st.x) < 0.51))   # the crest's columns
    assert f.size > 0
    np.testing.assert_allclose(st.u[f], continuity_velocity(kdv2, st.x[f], st.y[f], 0.0)[0],
                               rtol=1e-9)


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


def _small_wall_case(tutorial, edits, setup=None):
    """The wall tutorial (or it with ``setup``'s edits) cut to a 100 m tank at d/dx = 8 with
    the hydrostatic mirrored bed, 1.5 s, a crestTracker (surface fraction) every 0.01 s."""
    return tutorial("solitaryWallRunup", {
        **(setup or {}),
        "system/particleDict:dx": 1.25,
        "system/particleDict:fluid.water.min": [-50.0, 0.0],
        "system/particleDict:fluid.water.max": [50.0, 10.0],
        "system/particleDict:walls.tank.min": [-50.0, 0.0],
        "system/particleDict:walls.tank.max": [50.0, 30.0],
        "constant/sphProperties:boundary.pressure": "hydrostatic",
        "system/controlDict:threads": 1,
        "system/controlDict:endTime": 1.5,
        "system/controlDict:writeInterval": 1.5,
        "system/controlDict:functions": {"crest": {
            "type": "crestTracker", "still": 10.0, "surface": "fraction",
            "writeControl": "runTime", "writeInterval": 0.01}}, **edits})


def _crest_breathing(case, A):
    """Run ``case`` (:func:`_small_wall_case`): its crest eta_c(t) over the 1.5 s, and the
    breathing, max - min of eta_c about its least-squares line in % of A."""
    run_case(case, progress=False, echo=None)
    rows = np.loadtxt(case / "postProcessing" / "crest" / "0" / "crest.dat", ndmin=2)
    t, eta = rows[:, 0], rows[:, 2]
    assert t[-1] > 1.49 and t.size > 140
    b, a = np.polyfit(t, eta, 1)
    r = eta - (a + b * t)
    return eta, 100.0 * (r.max() - r.min()) / A


def test_exact_wave_starts_quiet(tutorial, p_wall):
    """Issue 35, a quiet start: the crest of the exact (Euler) solitary wave set up at t = 0
    does not breathe. The wall tutorial with P's scheme cut to a 100 m tank at d/dx = 8,
    A/d = 0.3, the hydrostatic mirrored bed; the crest (crestTracker, surface fraction,
    every 0.01 s) over the first 1.5 s. Breathing: max - min of eta_c(t) about its
    least-squares line, in % of A (benchmarks/breathing.py). Measured 0.35 %; with the set-up's old hole at the bed
    under every column where round((d + eta)/dx) rounds up (before the bottom particle kept
    half its own spacing from the bed) 7.6 %, the crest falling to 2.76 m at the column's
    acoustic period 4 (d + A)/c0 = 0.46 s. The bar is the issue's goal, 0.5 % of A."""
    A = 3.0
    case = _small_wall_case(tutorial, {"constant/waveProperties:waves.incident.theory": "euler"},
                            p_wall)
    eta, breathing = _crest_breathing(case, A)
    assert breathing < 0.5, (breathing, eta[::10])
    assert eta.min() > 0.99 * A, eta[::10]


def test_the_wall_tutorial_as_shipped_starts_quiet(tutorial):
    """Issue 35's goal for the tutorial as shipped (the exact wave, the hydrostatic mirrored
    bed, the quartic with delta-SPH and delta+ shifting) in the case of
    :func:`test_exact_wave_starts_quiet`: breathing below 0.5 % of A over 1.5 s (measured
    0.41 %)."""
    A = 3.0
    eta, breathing = _crest_breathing(_small_wall_case(tutorial, {}), A)
    assert breathing < 0.5, (breathing, eta[::10])


def test_kdv2_start_does_not_surge(tutorial, p_wall):
    """Issue 35: KdV2 (the tutorials' theory) set up with ``velocity continuity`` (u scaled
    to the flux c eta, w from continuity) does not surge at the start: in the case of
    :func:`test_exact_wave_starts_quiet` its crest stays below 3.037 m (+1.2 % of A) over
    1.5 s, where KdV2's own, non-solenoidal velocity (``velocity theory``, P's set-up) sends
    it to 3.097 m (+3.2 %) while the crest's trend triples (0.083 against 0.028 m/s)."""
    A = 3.0
    case = _small_wall_case(tutorial, {}, p_wall)
    run_case(case, progress=False, echo=None)
    rows = np.loadtxt(case / "postProcessing" / "crest" / "0" / "crest.dat", ndmin=2)
    assert rows[-1, 0] > 1.49
    assert rows[:, 2].max() < 1.02 * A, rows[::10, 2]


def test_wall_particles_carry_the_waves_pressure(tutorial):
    """Wall particles under an initial wave get the wave's own (non-hydrostatic) pressure,
    continued hydrostatically from the nearest fluid particle: under the crest of the exact
    wave at A/d = 0.3 the bed's pressure is 5.2 kPa below rho0 g (d + A), which the
    hydrostatic rule of the still tank gave them. Beside still water nothing changes."""
    from sphfoam.setup.waves import fields
    d, dx = 10.0, 1.25
    case = tutorial("solitaryWallRunup", {
        "system/particleDict:dx": dx,
        "constant/waveProperties:waves.incident.theory": "euler",
        "constant/sphProperties:boundary": {"type": "stationaryGhosts"}})
    c = Case(case)
    st = setup_case(c, log=lambda m: None)
    eos = c.models.sph["equationOfState"]
    p = eos.pressure(st.rho, c.context)
    w = (st.kind == 1) & (np.abs(st.x) < 2.0) & (st.y < 0)          # the bed under the crest
    assert w.sum() >= 6
    rho0, g = c.context.rho0, 9.81
    _, _, pbed = fields(st.x[w], np.zeros(w.sum()), 0.0, d, list(c.waves.values()), g, rho0)
    np.testing.assert_allclose(p[w], pbed - rho0 * g * st.y[w], rtol=2e-3)
    assert (p[w] < rho0 * g * (d + 3.0 - st.y[w]) - 4000.0).all()
    still = (st.kind == 1) & (st.x > 90.0) & (st.y < 0)                  # far from the wave
    np.testing.assert_allclose(p[still], rho0 * g * (d - st.y[still]), rtol=1e-3)


@pytest.mark.parametrize("theory", ["kdv2", "laitone", "kdv1"])
def test_approximate_theories_start_solenoidal(tutorial, theory):
    """waveProperties ``velocity continuity`` (the default): a theory whose own (u, w) is not
    divergence-free or whose flux is not c eta gets u scaled to the flux c eta per column and
    w from continuity; div u = 0 and the kinematic surface condition w = (u - c) eta_x hold
    (KdV2's own: |div u| up to 12 % of |du/dx|, the surface condition off by 0.12 m/s).
    ``velocity theory`` keeps the theory's own fields (P's set-up)."""
    A, d = 3.0, 10.0
    sw = registry.build("waveTheory", {"type": theory}).solitary(A, d)
    assert not is_kinematic(sw)
    x = np.linspace(-40.0, 40.0, 81)
    eta = sw.eta(x)
    e = 1e-4
    for frac in (0.2, 0.6, 1.0):
        z = frac * (d + eta)
        dudx = (continuity_velocity(sw, x + e, z, 0.0)[0]
                - continuity_velocity(sw, x - e, z, 0.0)[0]) / (2 * e)
        dwdz = (continuity_velocity(sw, x, z + e, 0.0)[1]
                - continuity_velocity(sw, x, z - e, 0.0)[1]) / (2 * e)
        assert np.abs(dudx + dwdz).max() < 1e-5 * np.abs(dudx).max()
    u, w = continuity_velocity(sw, x, d + eta, 0.0)
    slope = (sw.eta(x + e) - sw.eta(x - e)) / (2 * e)
    np.testing.assert_allclose(w, (u - sw.c) * slope, atol=1e-8)
    assert np.abs(continuity_velocity(sw, x, np.zeros_like(x), 0.0)[1]).max() == 0.0
    for exact in ("euler", "mcCowan", "boussinesq"):
        assert is_kinematic(registry.build("waveTheory", {"type": exact}).solitary(A, d))
    # the set-up: continuity by default, the theory's own with velocity theory
    for mode in ("continuity", "theory"):
        case = tutorial("solitaryWallRunup", {
            "system/particleDict:dx": 1.25,
            "constant/waveProperties:waves.incident.theory": theory,
            **({"constant/waveProperties:waves.incident.velocity": mode}
               if mode == "theory" else {})})
        st = setup_case(Case(case), log=lambda m: None)
        f = np.flatnonzero((st.kind == 0) & (np.abs(st.x) < 20.0))
        uu, ww = (continuity_velocity(sw, st.x[f], st.y[f], 0.0) if mode == "continuity" else
                  (sw.u(st.x[f], st.y[f]), sw.w(st.x[f], st.y[f])))
        np.testing.assert_allclose(st.u[f], uu, rtol=1e-9)
        np.testing.assert_allclose(st.v[f], ww, rtol=1e-9, atol=1e-12)


def test_packing_benchmark_reads_a_still_tank(tmp_path):
    """benchmarks/packing.py (issue 35, the flume's packing drift): its still tank, cloned
    from the flume tutorial at d/dx = 10 and run for 0.1 s, reads at t = 0 the set-up's own
    state: the bulk's fluid fraction 1 within 0.1 %, the level 0.5 m by the volumes and by
    the particles, no motion, the bulk density's slope the Tait equation's hydrostatic one
    within 0.5 %; at 0.1 s the water has barely moved (rms speed below 2 cm/s).

    Its budget (``--budget``) at t = 0: the lattice is not shifted (the shift's rate of the
    kernel sums below 1e-5 /s), and Fourtakas et al.'s filter, whose hydrostatic reference is
    linear in the pair's depth difference about p = 0, leaves on the Tait column the
    diffusion of its curvature: D/rho = delta h c0 rho''/rho with rho = rho0 (1 + gamma g
    d / c0^2)^(1/gamma), T(3.27), i.e. rho''/rho = -(gamma - 1) (g/c0^2)^2 (1 + gamma g d /
    c0^2)^-2, within 5 % over the bulk's depths (a wrong sign, factor h or c0, or a reference
    that cancelled the curvature, is off by 100 % or more)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "benchmarks" / "packing.py"
    spec = importlib.util.spec_from_file_location("packing", path)
    packing = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(packing)
    rows = packing.main(["--dx", "0.05", "--end", "0.1", "--write", "0.1",
                         "--keep", str(tmp_path / "tank"), "--json", "--budget"])
    first, last = rows[0], rows[-1]
    assert first["t"] == 0.0 and abs(last["t"] - 0.1) < 1e-9
    assert abs(first["fraction"] - 1.0) < 1e-3, first
    assert abs(first["level_volume"] - 0.5) < 1e-4 and abs(first["level_particles"] - 0.5) < 1e-4
    assert first["u_rms"] == 0.0
    assert abs(first["drho_dz_ratio"] - 1.0) < 5e-3, first
    assert 0.0 < last["u_rms"] < 0.02, last
    case = Case(tmp_path / "tank")
    case.validate()
    ctx, gamma, g = case.context, 7.0, 9.81
    assert case.models.sph["densityFilter"].coeffs.delta == 0.1
    d = np.linspace(0.15, 0.4, 101)                  # the bulk's depths (0.1-0.35 m up)
    curv = -(gamma - 1) * (g / ctx.c0 ** 2) ** 2 / (1 + gamma * g * d / ctx.c0 ** 2) ** 2
    expected = 0.1 * ctx.h * ctx.c0 * curv.mean()
    assert abs(first["shift_rate"]) < 1e-5, first
    assert abs(first["filter_rate"] / expected - 1.0) < 0.05, (first, expected)
