"""Blow-up detection: the per-step checks, the diagnosis, the last good time directory."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.case.schemas import StabilityChecks
from sphfoam.cli import app
from sphfoam.engine.health import (DENSITY, NONFINITE, SPEED, BlowUp, HealthMonitor, offenders,
                                   scan, scan_arrays)
from sphfoam.engine.simulation import Removal
from sphfoam.engine.state import FLUID, GHOST, WALL, ParticleState
from sphfoam.io.fields import read_state
from sphfoam.timeloop import run_case

RHO0, C0 = 1000.0, 20.0


# --- the compiled check on synthetic states ------------------------------------------------
def synthetic(n_fluid=10, n_wall=3, n_ghost=2) -> ParticleState:
    """A row of fluid particles at rest, some walls and ghosts (ids 100, 101, ...)."""
    n = n_fluid + n_wall + n_ghost
    kind = np.array([FLUID] * n_fluid + [WALL] * n_wall + [GHOST] * n_ghost)
    x = np.arange(n, dtype=float) * 0.1
    return ParticleState(x, np.zeros(n), np.zeros(n), np.zeros(n), np.full(n, RHO0),
                         np.ones(n), kind, np.arange(100, 100 + n),
                         {"wallDist": np.linspace(0.0, 1.0, n)})


def run_scan(st, lo=0.5, hi=2.0, vmax=C0):
    x, y, z, u, v, w, three = scan_arrays(st)
    return scan(x, y, z, u, v, w, st.rho, st.m, st.kind, three, lo * RHO0, hi * RHO0,
                vmax ** 2)


def bad(st, what, lo=0.5, hi=2.0, vmax=C0):
    x, y, z, u, v, w, three = scan_arrays(st)
    return offenders(x, y, z, u, v, w, st.rho, st.kind, three, what, lo * RHO0, hi * RHO0,
                     vmax ** 2).tolist()


def test_scan_of_a_healthy_state():
    st = synthetic()
    st.u[:10] = 1.0
    n_bad, n_rho, n_fast, s2max, ke, mass, n_fluid = run_scan(st)
    assert (n_bad, n_rho, n_fast, n_fluid) == (0, 0, 0, 10)
    assert s2max == 1.0 and ke == pytest.approx(5.0) and mass == 10.0


def test_scan_finds_non_finite_values_and_ignores_ghosts():
    st = synthetic()
    st.u[2] = np.nan
    st.rho[4] = np.inf
    st.y[11] = np.nan         # a wall particle: counted (a NaN is never written)
    st.x[13] = np.nan         # a ghost: ignored
    st.rho[14] = -np.inf
    assert run_scan(st)[0] == 3
    assert bad(st, NONFINITE) == [2, 4, 11]


def test_scan_in_3d_flags_exactly_the_non_finite_components():
    """3-D: a NaN or an infinity in z or w is found as in x, y, u, v, rho; the largest finite
    values (whose sum would overflow) are not; scan and offenders agree."""
    st = synthetic()
    n = st.n
    st = ParticleState(st.x, st.y, st.u, st.v, st.rho, st.m, st.kind, st.id, {},
                       z=np.zeros(n), w=np.zeros(n))
    big = np.finfo(float).max
    st.x[0] = st.y[0] = st.z[0] = st.u[0] = big   # finite: not flagged
    st.v[0] = st.w[0] = -big
    st.z[3] = np.inf
    st.w[5] = -np.inf
    st.w[7] = np.nan
    st.z[12] = np.nan         # a wall particle
    st.w[13] = np.inf         # a ghost: ignored
    assert run_scan(st, vmax=math.inf)[0] == 4
    assert bad(st, NONFINITE) == [3, 5, 7, 12]


def test_scan_finds_density_out_of_range():
    st = synthetic()
    st.rho[1] = 0.4 * RHO0
    st.rho[7] = 2.5 * RHO0
    st.rho[10] = 3.0 * RHO0     # wall: not checked
    st.rho[12] = 0.1 * RHO0     # wall
    st.rho[13] = 5.0 * RHO0     # ghost
    assert run_scan(st)[1] == 2
    assert bad(st, DENSITY) == [1, 7]
    assert bad(st, DENSITY, lo=0.3, hi=3.0) == []


def test_scan_finds_fast_particles_and_kinetic_energy():
    st = synthetic()
    st.u[3], st.v[3] = 30.0, 0.0
    st.v[8] = -25.0
    st.u[10] = 100.0            # a wall moves as prescribed: not checked
    st.u[14] = 100.0            # ghost
    n_bad, n_rho, n_fast, s2max, ke, mass, n_fluid = run_scan(st)
    assert n_fast == 2 and s2max == 900.0
    assert ke == pytest.approx(0.5 * (900.0 + 625.0))
    assert bad(st, SPEED) == [3, 8]


# --- the monitor on a stand-in simulation --------------------------------------------------
def fake_sim(st, mirror=True):
    return SimpleNamespace(state=st, removals=[], time=0.0, step_index=0, last_dt=1e-3,
                           h=0.013, mirror=mirror)


def advance(sim, dt=1e-3):
    sim.time += dt
    sim.step_index += 1
    sim.last_dt = dt
    return dt


def monitor(**settings):
    return HealthMonitor(StabilityChecks(**settings), RHO0, C0)


def test_monitor_snapshot_leaves_ghosts_out_and_reuses_its_arrays():
    st = synthetic()
    sim = fake_sim(st)
    mon = monitor()
    mon.start(sim)
    snap = mon.snapshot
    assert snap.n == 13 and GHOST not in snap.arrays["kind"]
    x_buffer = snap.arrays["x"]
    st.x += 1.0
    assert mon.check(sim, advance(sim)) is None
    assert snap.arrays["x"] is x_buffer                    # copied into, not reallocated
    np.testing.assert_array_equal(snap.arrays["x"], st.x[:13])
    assert (snap.time, snap.step) == (sim.time, 1)
    back = snap.state()
    assert back.n == 13 and back.extra["wallDist"].shape == (13,)
    st.x[5] = np.nan
    assert back.to_fields()["positions"].shape == (13, 2) and np.isfinite(snap.arrays["x"]).all()


def test_monitor_reports_nan_with_ids_and_the_last_good_position():
    st = synthetic()
    sim = fake_sim(st)
    mon = monitor()
    mon.start(sim)
    x_good = st.x[6]
    st.x[6] = np.nan
    st.rho[9] = np.nan
    d = mon.check(sim, advance(sim))
    assert d.kind == "nan" and d.ids == [106, 109] and d.count == 2
    assert (d.time, d.step, d.fail_time) == (0.0, 1, 1e-3)
    assert "2 of 13 particles have a non-finite x/rho" in d.message
    # 106 has no position now: it is placed where it was in the last good state
    assert d.where.lo == (x_good, 0.0) and d.where.hi == (st.x[9], 0.0)
    assert mon.snapshot.time == 0.0                        # a failed step is not kept
    assert d.as_row() == {"kind": "nan", "time": 0.0, "message": d.message}
    assert any(line.startswith("particles: ids 106 109") for line in d.lines())


def test_monitor_reports_density_speed_and_energy():
    st = synthetic()
    sim = fake_sim(st)
    mon = monitor()
    mon.start(sim)
    st.rho[2] = 0.3 * RHO0
    d = mon.check(sim, advance(sim))
    assert d.kind == "density" and d.ids == [102]
    assert "densityRatio (0.5 2)" in d.message and "0.3" in d.message
    st.rho[2] = RHO0
    st.u[4] = 1.5 * C0
    d = mon.check(sim, advance(sim))
    assert d.kind == "escape" and d.ids == [104] and "maxSpeed" in d.message
    assert monitor(maxSpeed=2.0, maxKineticEnergy=100.0).check(sim, 1e-3) is None
    # every fluid particle at 3 vmax (vmax = c0/10): KE = 9 x M vmax^2 / 2 > 4 x
    st.u[:10] = 3.0 * C0 / 10
    st.u[7] = 3.5 * C0 / 10
    d = mon.check(sim, advance(sim))
    assert d.kind == "energy" and d.ids[0] == 107 and len(d.ids) == 10
    assert "maxKineticEnergy = 4" in d.message
    assert monitor(maxKineticEnergy=20.0).check(sim, 1e-3) is None


def test_monitor_reports_escaped_particles():
    st = synthetic(n_fluid=40, n_ghost=0)
    sim = fake_sim(st, mirror=False)
    mon = monitor()
    mon.start(sim)
    sim.removals.append(Removal(0.0, 2, np.array([7, 8]), np.array([[9.0, 1.0], [9.0, 3.0]])))
    assert mon.check(sim, advance(sim)) is None            # 2 of 40 = 5 %: allowed
    sim.removals.append(Removal(0.0, 1, np.array([9]), np.array([[10.0, 2.0]])))
    d = mon.check(sim, advance(sim))
    assert d.kind == "escape" and d.ids == [7, 8, 9] and "maxEscaped = 0.05" in d.message
    assert d.where.centroid == pytest.approx((28 / 3, 2.0))


def test_monitor_reports_time_step_collapse():
    st = synthetic()
    st.c[:] = 20.0
    st.c[5] = 1e6                                          # the particle that limits the step
    sim = fake_sim(st)
    mon = monitor()
    mon.start(sim)
    assert mon.check(sim, advance(sim, 1e-3)) is None
    assert mon.check(sim, advance(sim, 2e-6), landed=True) is None   # shortened for a write
    d = mon.check(sim, advance(sim, 5e-7))
    assert d.kind == "deltaT" and d.ids[0] == 105 and "minDeltaT = 0.001" in d.message
    for dt in (0.0, -1.0, math.nan):
        assert monitor().check(sim, dt).kind == "deltaT"
        # a step that is not positive stops the run even with the checks switched off
        assert monitor(enabled=False).check(sim, dt).kind == "deltaT"


def test_switched_off_monitor_passes_anything():
    st = synthetic()
    st.u[1] = np.nan
    st.rho[2] = 0.0
    sim = fake_sim(st)
    mon = monitor(enabled=False)
    mon.start(sim)
    assert mon.check(sim, advance(sim)) is None


# --- settings -------------------------------------------------------------------------------
def test_bad_stability_settings_name_the_file_and_key(tutorial):
    case = tutorial("hydrostaticTank", {"system/controlDict:stability.densityRatio": (2, 0.5)})
    with pytest.raises(CaseError) as e:
        Case(case).validate()
    msg = str(e.value)
    assert "system/controlDict: stability.densityRatio" in msg and "0 < lo < 1 < hi" in msg
    case = tutorial("hydrostaticTank", {"system/controlDict:stability.maxSped": 2})
    with pytest.raises(CaseError) as e:
        Case(case).validate()
    assert "stability.maxSped: unknown key 'maxSped'; did you mean 'maxSpeed'?" in str(e.value)
    assert Case(tutorial("hydrostaticTank")).control.stability == StabilityChecks()


# --- whole runs -----------------------------------------------------------------------------
COARSE = {"system/particleDict:dx": 0.02, "system/controlDict:writeInterval": 0.5}
#: a fixed step 50 times the stable one (h / c0 = 0.026 / 28 s, maxCo 0.2)
ABSURD = {**COARSE, "system/controlDict:adjustTimeStep": "no",
          "system/controlDict:deltaT": 0.01, "system/controlDict:endTime": 1.0}


def test_healthy_run_does_not_fire_and_checks_can_be_switched_off(tutorial):
    case = tutorial("hydrostaticTank", {**COARSE, "system/controlDict:endTime": 0.02})
    rep = run_case(case, progress=False, echo=None)
    assert rep.failure is None and rep.steps > 10
    assert not (case / "postProcessing" / "stability").exists()
    assert "BLOW-UP" not in (case / "log.sphfoam").read_text()
    # the absurd step with the checks off runs on (and writes what it computes)
    off = tutorial("hydrostaticTank", {**ABSURD, "system/controlDict:endTime": 0.03,
                                "system/controlDict:functions": {},
                                "system/controlDict:stability": {"enabled": False}})
    rep = run_case(off, progress=False, echo=None)
    assert rep.failure is None and rep.end_time == pytest.approx(0.03)


def test_forced_blow_up_writes_diagnosis_and_last_good_state(tutorial):
    case = tutorial("hydrostaticTank", ABSURD)
    with pytest.raises(BlowUp) as e:
        run_case(case, progress=False, echo=None)
    d, rep = e.value.diagnosis, e.value.report
    assert d.kind == "density" and "densityRatio (0.5 2)" in d.message
    assert 0 < d.time < d.fail_time < 0.1 and d.step >= 2 and d.ids and d.where is not None
    assert rep.failure is d and rep.end_time == d.time and rep.steps == d.step
    # the last good state: a complete, finite, restartable time directory
    assert d.last_good == "0.02" or float(d.last_good) == pytest.approx(d.time)
    good = case / d.last_good
    fields = read_state(good)
    for k, a in fields.items():
        assert np.isfinite(a).all(), k
    rho = fields["rho"][fields["type"] == FLUID]
    assert (rho > 0.5 * RHO0).all() and (rho < 2 * RHO0).all()
    assert (good / "uniform" / "time").is_file()
    # the diagnosis file and the log
    dat = (case / "postProcessing" / "stability" / "0" / "diagnosis.dat").read_text()
    assert dat.startswith("# ") and "kind        density" in dat
    assert f"lastGood    {d.last_good}" in dat and d.file.endswith("diagnosis.dat")
    log = (case / "log.sphfoam").read_text()
    assert "BLOW-UP: density out of range at step" in log
    assert f"BLOW-UP: last good state: time directory {d.last_good}" in log
    # the CLI restarts from the last good state, blows up again: one screen, exit code 3
    res = CliRunner().invoke(app, ["run", str(case), "--no-progress"])
    assert res.exit_code == 3, res.output
    assert "Traceback" not in res.output and not isinstance(res.exception, BlowUp)
    for word in ("blow-up", "density out of range", "particles: ids", "last good",
                 "diagnosis:", "log:"):
        assert word in res.output, word
    log = (case / "log.sphfoam").read_text()
    assert f"starting from time {d.last_good} " in log
