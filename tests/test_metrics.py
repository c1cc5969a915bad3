"""Error metrics (``metric`` family, system/metricsDict) read from synthetic function-object
output written by the sampling modules' own writers; no simulation."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from sphfoam import registry
from sphfoam.case import foamdict
from sphfoam.case.errors import CaseError
from sphfoam.cli import app
from sphfoam.engine.state import FLUID
from sphfoam.case.metrics_dict import MetricValue, evaluate_metrics, load_metrics, relative_error
from sphfoam.reference import channel_theory as ct

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"

GAUGES = {"type": "waveGauges", "x": [1, 2, 18], "still": 0.5}
CREST = {"type": "crestTracker", "xMin": 0.5, "still": 0.5, "fitFrom": 2, "fitTo": 18}
RUNUP = {"type": "runUp", "mode": "wall", "x": 100, "still": 10}
PROFILE = {"type": "velocityProfile", "l": 0.01, "theory": "poiseuille", "times": [2],
           "plot": False}
FRONT = {"type": "damBreakFront", "wallX": 0, "H0": 0.25, "plot": False}
F, NU, L = 8e-6, 1e-6, 0.01


def write_control(case: Path, functions: dict) -> None:
    foamdict.write(case / "system" / "controlDict",
                   {"endTime": 10, "deltaT": 1e-4, "writeInterval": 1, "functions": functions},
                   header={"location": "system", "object": "controlDict"})


def write_metrics(case: Path, metrics: dict, pareto: str | None = None) -> None:
    d = {"metrics": metrics} | ({"pareto": pareto} if pareto else {})
    foamdict.write(case / "system" / "metricsDict", d,
                   header={"location": "system", "object": "metricsDict"})


def function_object(case: Path, name: str, spec: dict, start: str = "0", **ctx):
    """A function object of ``spec`` started in ``case`` as a run would start it."""
    fo = registry.build("functionObject", spec)
    fo.object_name = name
    context = SimpleNamespace(**{"dx": 0.05, "g": (0.0, -9.81), "nu": NU, **ctx})
    fo.start(SimpleNamespace(path=case, control=SimpleNamespace(endTime=10.0)), context, start)
    return fo


def gauge_rows(t):
    """eta at x = 1, 2, 18: pulses of 0.15, 0.149 and 0.14 m peaking at t = 1, 2, 5 s."""
    return np.column_stack([t, 0.15 * np.exp(-(t - 1) ** 2), 0.149 * np.exp(-(t - 2) ** 2),
                            0.14 * np.exp(-(t - 5) ** 2)])


def write_gauges(case: Path, t_end: float = 10.0, name: str = "gauges") -> None:
    fo = function_object(case, name, GAUGES)
    for row in gauge_rows(np.round(np.arange(0.0, t_end + 1e-9, 0.01), 2)):
        fo.write_row(row)
    fo.end()


def crest_samples(t):
    return np.column_stack([t, 1.0 + 2.4 * t + 0.01 * t * t, 0.15 + 0.02 * np.exp(-(t - 3) ** 2)])


def write_crest(case: Path, samples, start: str = "0") -> None:
    fo = function_object(case, "crest", CREST, start)
    fo.samples = [tuple(s) for s in samples]
    fo.end()                                   # crest.dat rows and celerity.dat, as a run ends


@pytest.fixture
def flume(tmp_path):
    """A case with gauge and crest output and a controlDict declaring both objects."""
    case = tmp_path / "flume"
    write_control(case, {"gauges": GAUGES, "crest": CREST})
    write_gauges(case)
    write_crest(case, crest_samples(np.round(np.arange(0.0, 7.0 + 1e-9, 0.05), 2)))
    return case


# --- values -----------------------------------------------------------------------------------
def test_relative_error_is_signed_and_nan_safe():
    assert relative_error(0.14, 0.15) == pytest.approx(-100 / 15)
    assert relative_error(1.0, None) is None
    assert math.isnan(relative_error(float("nan"), 1.0))
    assert math.isnan(relative_error(1.0, 0.0))


def test_wave_height_and_arrival_time(flume):
    vals = evaluate_metrics(flume, {
        "H18": {"type": "waveHeight", "x": 18, "reference": 0.15},
        "H2": {"type": "waveHeight", "function": "gauges", "x": 2},
        "t18": {"type": "arrivalTime", "x": 18, "reference": 4.9}})
    assert vals["H18"] == MetricValue(pytest.approx(0.14, rel=1e-12), 0.15,
                                      pytest.approx(-100 / 15, rel=1e-9), "m")
    assert vals["H2"].value == pytest.approx(0.149, rel=1e-12) and vals["H2"].error is None
    assert vals["t18"].value == pytest.approx(5.0, rel=1e-12)
    assert vals["t18"].error == pytest.approx(100 * 0.1 / 4.9, rel=1e-9)
    assert vals["t18"].unit == "s"


def test_celerity_against_theory_and_given_value(flume):
    t = np.round(np.arange(0.0, 7.0 + 1e-9, 0.05), 2)
    s = crest_samples(t)
    sel = (s[:, 1] >= 2) & (s[:, 1] <= 18)
    c_fit = np.polyfit(s[sel, 0], s[sel, 1], 1)[0]
    c_theory = math.sqrt(9.81 * 0.65)                            # Boussinesq, T(4.4)
    vals = evaluate_metrics(flume, {
        "c": {"type": "celerity", "theory": "boussinesq", "height": 0.15, "depth": 0.5},
        "c2": {"type": "celerity", "function": "crest", "reference": 2.5}})
    assert vals["c"].value == pytest.approx(c_fit, rel=1e-8)
    assert vals["c"].reference == pytest.approx(c_theory, rel=1e-12)
    assert vals["c"].error == pytest.approx(100 * (c_fit - c_theory) / c_theory, rel=1e-6)
    assert vals["c2"].error == pytest.approx(100 * (c_fit - 2.5) / 2.5, rel=1e-6)


def test_restarted_run_joins_series_and_refits_celerity(tmp_path):
    """Folders 0/ and 4/: rows of 0/ from t = 4 on are superseded by the restart."""
    case = tmp_path / "restart"
    write_control(case, {"crest": CREST, "gauges": GAUGES})
    t = np.round(np.arange(0.0, 7.0 + 1e-9, 0.05), 2)
    s = crest_samples(t)
    old = s[t <= 4.5].copy()
    old[old[:, 0] >= 4, 1:] = (100.0, 9.0)                       # superseded: must be dropped
    write_crest(case, old, "0")
    write_crest(case, s[t >= 4], "4")
    sel = (s[:, 1] >= 2) & (s[:, 1] <= 18)
    c_all = np.polyfit(s[sel, 0], s[sel, 1], 1)[0]
    seg = np.loadtxt(case / "postProcessing/crest/4/celerity.dat")[0]
    assert abs(seg - c_all) > 1e-3                               # the restart's own fit differs
    vals = evaluate_metrics(case, {"c": {"type": "celerity", "reference": 2.5},
                                   "peak": {"type": "peakElevation"}})
    assert vals["c"].value == pytest.approx(c_all, rel=1e-8)
    assert vals["peak"].value == pytest.approx(0.17, rel=1e-9)  # not the dropped 9.0
    # the wave passed x = 18 before the restart: the joined series still holds its height
    write_gauges(case, t_end=6.0)
    fo = function_object(case, "gauges", GAUGES, "6")
    for row in gauge_rows(np.round(np.arange(6.0, 8.0, 0.01), 2)):
        fo.write_row(row)
    fo.end()
    assert evaluate_metrics(case, {"H": {"type": "waveHeight", "x": 18}})["H"].value == \
        pytest.approx(0.14, rel=1e-12)


def test_peak_elevation_and_run_up(tmp_path):
    case = tmp_path / "wall"
    write_control(case, {"crest": CREST, "runUp": RUNUP})
    t = np.round(np.arange(0.0, 20.0, 0.05), 2)
    eta = 3.0 + 2.3 * np.exp(-(t - 10) ** 2)                     # collision peak 5.3 m
    write_crest(case, np.column_stack([t, -50 + 5 * t, eta]))
    fo = function_object(case, "runUp", RUNUP)
    r = np.where(t < 2, np.nan, 6.5 * np.exp(-(t - 12) ** 2))    # NaN before water touches
    for ti, ri in zip(t, r):
        fo.write_row((ti, ri, ri))
    fo.end()
    vals = evaluate_metrics(case, {"peak": {"type": "peakElevation", "reference": 5},
                                   "R": {"type": "runUp", "depth": 10, "reference": 0.665},
                                   "Rm": {"type": "runUp"}})
    assert vals["peak"].value == pytest.approx(5.3, rel=1e-12)
    assert vals["peak"].error == pytest.approx(6.0, rel=1e-9)
    assert vals["R"] == MetricValue(pytest.approx(0.65, rel=1e-12), 0.665,
                                    pytest.approx(100 * (0.65 - 0.665) / 0.665, rel=1e-9), "-")
    assert vals["Rm"].value == pytest.approx(6.5, rel=1e-12) and vals["Rm"].unit == "m"


def test_mean_crest_over_a_stretch(tmp_path):
    """meanCrest: the mean of the crest samples between xFrom and xTo that are at least
    minHeight high (a ripple ahead of the wave is left out), against the reference."""
    case = tmp_path / "flume"
    write_control(case, {"crest": CREST})
    t = np.round(np.arange(0.0, 8.0, 0.05), 2)
    x = 0.5 + 2.5 * t
    eta = np.where(t < 1.0, 0.001, 0.15 + 0.01 * np.sin(t))      # a ripple first
    write_crest(case, np.column_stack([t, x, eta]))
    sel = (x >= 2) & (x <= 18) & (eta >= 0.05)
    want = eta[sel].mean()
    assert abs(want - eta[(x >= 2) & (x <= 18)].mean()) > 1e-3    # the ripple matters
    vals = evaluate_metrics(case, {"m": {"type": "meanCrest", "xFrom": 2, "xTo": 18,
                                         "minHeight": 0.05, "reference": 0.15}})
    assert vals["m"].value == pytest.approx(want, rel=1e-8)      # crest.dat to 10 digits
    assert vals["m"].error == pytest.approx(100 * (vals["m"].value - 0.15) / 0.15, rel=1e-12)
    with pytest.raises(CaseError, match="no crest sample"):
        evaluate_metrics(case, {"m": {"type": "meanCrest", "xFrom": 30, "xTo": 40}})
    with pytest.raises(CaseError, match="xTo"):
        evaluate_metrics(case, {"m": {"type": "meanCrest", "xFrom": 18, "xTo": 2}})


def channel_profile(case: Path, times=(2.0, 120.0), factor=0.98):
    """velocityProfile output of rows at (k + 1/2) dx moving at factor x T(3.42)."""
    fo = function_object(case, "profile", PROFILE, dx=L / 40, g=(F, 0.0))
    y = np.repeat((np.arange(40) + 0.5) * L / 40, 5)
    for t in times:
        state = SimpleNamespace(kind=np.full(y.size, FLUID), y=y,
                                u=factor * ct.poiseuille(y, t, F, NU, L))
        fo.sample(SimpleNamespace(time=t, state=state), t)
        fo.write()
    return fo.samples


def test_channel_max_velocity_against_start_up_series(tmp_path):
    case = tmp_path / "poiseuille"
    write_control(case, {"profile": PROFILE})
    samples = channel_profile(case)
    vals = evaluate_metrics(case, {
        "uMax": {"type": "channelMaxVelocity"},
        "u2": {"type": "channelMaxVelocity", "time": 1.5},
        "bin": {"type": "channelMaxVelocity", "quantity": "maxBin"},
        "given": {"type": "channelMaxVelocity", "reference": 1e-4}})
    last = samples[-1]
    steady = ct.poiseuille([L / 2], 120.0, F, NU, L)[0]          # the series at t = 120 s
    assert vals["uMax"].value == pytest.approx(last["uCentre"], rel=1e-8)
    assert vals["uMax"].reference == pytest.approx(steady, rel=1e-8)
    assert vals["uMax"].error == pytest.approx(last["centreError"], rel=1e-6)
    assert vals["uMax"].error == pytest.approx(-2.0, abs=1e-3)
    assert vals["u2"].value == pytest.approx(samples[0]["uCentre"], rel=1e-8)
    assert vals["u2"].reference == pytest.approx(ct.poiseuille([L / 2], 2.0, F, NU, L)[0],
                                                 rel=1e-8)
    assert vals["bin"].value == pytest.approx(last["uMaxBins"], rel=1e-8)
    assert vals["bin"].error == pytest.approx(last["maxError"], rel=1e-6)
    assert vals["given"].reference == 1e-4 and vals["given"].unit == "m/s"


def test_dam_break_front_against_martin_moyce(tmp_path):
    case = tmp_path / "damBreak"
    write_control(case, {"front": FRONT})
    fo = function_object(case, "front", FRONT)
    for T in np.arange(0.0, 3.2, 0.01):
        t = T / math.sqrt(9.81 / 0.25)
        fo.write_row((t, T, 0.25 * (1 + T), 1 + T, 0.2, 0.8, 0, 0.5))   # Z = 1 + T
    fo.end()
    mv = evaluate_metrics(case, {"front": {"type": "damBreakFront"}})["front"]
    z = np.array([2.0, 3.0, 4.0])
    zm = np.array([1.67 + 0.22 * 3 / 17, 3.11, 4.33 + 0.23 * 13 / 17])  # M&M, interpolated
    assert mv.value == pytest.approx(3.0, rel=1e-9)
    assert mv.reference == pytest.approx(zm.mean(), rel=1e-12)
    assert mv.error == pytest.approx(np.mean(100 * (z - zm) / zm), rel=1e-9)
    one = evaluate_metrics(case, {"f": {"type": "damBreakFront", "times": 2}})["f"]
    assert one.value == pytest.approx(3.0) and one.error == pytest.approx(100 * (3 - 3.11) / 3.11)
    with pytest.raises(CaseError, match=r"metrics\.f\.times: T = 3\.3 not sampled"):
        evaluate_metrics(case, {"f": {"type": "damBreakFront", "times": [1, 3.3]}})
    with pytest.raises(CaseError, match=r"metrics\.f\.times: .*outside the Martin & Moyce"):
        evaluate_metrics(case, {"f": {"type": "damBreakFront", "times": [4]}})


def test_measured_rms_and_peak_against_a_measured_series(tmp_path):
    """measuredRMS and measuredPeak read a function object's column against a series file
    of the case (a header line, time first): a simulated pulse 0.01 high and 0.02 s late
    against the measured one gives the RMS of their difference and the peak's value and
    time errors; a dry (NaN) sample reads as 0 with `missing zero`."""
    case = tmp_path / "marin"
    write_control(case, {"gauges": GAUGES})
    t = np.round(np.arange(0.0, 10.0 + 1e-9, 0.01), 2)
    sim = 0.16 * np.exp(-(t - 1.02) ** 2 / 0.01)
    meas = 0.15 * np.exp(-(t - 1.0) ** 2 / 0.01)
    fo = function_object(case, "gauges", GAUGES)
    for k, row in enumerate(np.column_stack([t, sim, sim, np.where(t < 0.5, np.nan, sim)])):
        fo.write_row(row)
    fo.end()
    tm = np.arange(0.0, 10.0, 0.001)
    (case / "series.dat").write_text("Time (s) H (m)\n" + "\n".join(
        f"{a:.6f} {0.15 * np.exp(-(a - 1.0) ** 2 / 0.01):.9f}" for a in tm))
    base = {"function": "gauges", "file": "series.dat", "fileColumn": 1, "window": [0, 3]}
    got = evaluate_metrics(case, {
        "rms": {"type": "measuredRMS", "column": "eta(1)", **base},
        "dry": {"type": "measuredRMS", "column": "eta(18)", "missing": "zero", **base},
        "peak": {"type": "measuredPeak", "column": "eta(1)", **base},
        "when": {"type": "measuredPeak", "column": "eta(1)", "quantity": "time", **base}})
    keep = t <= 3
    want = np.sqrt(np.mean((sim[keep] - np.interp(t[keep], tm, 0.15 * np.exp(
        -(tm - 1.0) ** 2 / 0.01))) ** 2))
    assert got["rms"].value == pytest.approx(want, rel=1e-6)
    assert got["rms"].reference is None and got["rms"].error is None
    assert got["dry"].value == pytest.approx(got["rms"].value, rel=1e-6)   # dry reads 0 ~ sim
    assert got["peak"].value == pytest.approx(0.16) and got["peak"].reference == \
        pytest.approx(0.15)
    assert got["peak"].error == pytest.approx(100 * (0.16 / 0.15 - 1))
    assert got["when"].value == pytest.approx(1.02) and got["when"].reference == \
        pytest.approx(1.0)
    with pytest.raises(CaseError, match=r"metrics\.bad\.fileColumn: series.dat has 2 columns"):
        evaluate_metrics(case, {"bad": {"type": "measuredRMS", "column": "eta(1)",
                                        **{**base, "fileColumn": 5}}})
    with pytest.raises(CaseError, match=r"metrics\.short\.window: the run's eta\(1\) ends at"):
        evaluate_metrics(case, {"short": {"type": "measuredRMS", "column": "eta(1)",
                                          **{**base, "window": [0, 20]}}})


def test_every_registered_metric_is_exercised_here():
    covered = {"waveHeight", "arrivalTime", "celerity", "peakElevation", "runUp", "meanCrest",
               "channelMaxVelocity", "damBreakFront",
               "breakingTime", "runUpPosition",       # these two: tests/test_beach.py
               "measuredRMS", "measuredPeak"}
    assert set(registry.names("metric")) == covered
    assert "metric" in registry.FAMILIES


# --- metricsDict, errors ----------------------------------------------------------------------
def test_metrics_dict_file_and_pareto(flume):
    write_metrics(flume, {"H18": {"type": "waveHeight", "function": "gauges", "x": 18,
                                  "reference": 0.15},
                          "celerity": {"type": "celerity", "function": "crest",
                                       "theory": "boussinesq", "height": 0.15, "depth": 0.5}},
                  pareto="H18")
    mset = load_metrics(flume)
    assert mset.pareto == "H18" and list(mset.metrics) == ["H18", "celerity"]
    vals = evaluate_metrics(flume)
    assert vals["H18"].value == pytest.approx(0.14)
    # a spec given in full (as a metricsDict) overrides the file
    vals = evaluate_metrics(flume, {"metrics": {"t": {"type": "arrivalTime", "x": 2}}})
    assert list(vals) == ["t"]


def problems(case, spec=None, **kw) -> str:
    with pytest.raises(CaseError) as e:
        evaluate_metrics(case, spec, **kw)
    return str(e.value)


def file_problems(case, metrics: dict) -> str:
    """The errors of ``metrics`` written to the case's system/metricsDict."""
    write_metrics(case, metrics)
    return problems(case)


def test_unknown_type_and_key_name_the_file_key_and_choices(flume):
    write_metrics(flume, {"H18": {"type": "waveHight", "x": 18},
                          "c": {"type": "celerity", "refrence": 2.5}}, pareto="H81")
    msg = problems(flume)
    assert "system/metricsDict: metrics.H18.type: 'waveHight' is not a registered metric; " \
           "did you mean 'waveHeight'?" in msg
    assert "damBreakFront" in msg                                # the registered choices
    assert "system/metricsDict: pareto: " in msg and "did you mean 'H18'?" in msg
    write_metrics(flume, {"c": {"type": "celerity", "refrence": 2.5}})
    msg = problems(flume)
    assert "metrics.c.refrence: unknown key 'refrence'; did you mean 'reference'?" in msg
    msg = problems(flume, {"c": {"type": "celerity", "theory": "boussinesk", "height": 1,
                                 "depth": 2}}, source="studyDict")
    assert "studyDict: metrics.c.theory" in msg and "did you mean 'boussinesq'?" in msg
    msg = problems(flume, {"c": {"type": "celerity", "reference": 2.5, "theory": "kdv2",
                                 "height": 1, "depth": 2}})
    assert "exactly one of reference" in msg
    assert "expected a sub-dictionary with a 'type' entry" in problems(flume, {"c": {"x": 1}})


def test_missing_gauge_function_and_output(flume, tmp_path):
    msg = file_problems(flume, {"H17": {"type": "waveHeight", "x": 17}})
    assert "system/metricsDict: metrics.H17.x: no gauge at x = 17 in function object " \
           "'gauges' of system/controlDict; gauges at x = 1, 2, 18" in msg
    msg = file_problems(flume, {"H": {"type": "waveHeight", "function": "gauge", "x": 18}})
    assert "metrics.H.function: no function object 'gauge' in system/controlDict; " \
           "did you mean 'gauges'?" in msg
    msg = file_problems(flume, {"H": {"type": "waveHeight", "function": "crest", "x": 18}})
    assert "function object 'crest' of system/controlDict is a crestTracker, not a " \
           "waveGauges" in msg
    # declared but never run
    write_control(flume, {"gauges": GAUGES, "crest": CREST, "runUp": RUNUP})
    msg = file_problems(flume, {"R": {"type": "runUp"}})
    assert "system/metricsDict: metrics.R.function: no output in postProcessing/runUp/" in msg
    # without a controlDict the output file itself is checked
    bare = tmp_path / "bare"
    write_gauges(bare)
    msg = file_problems(bare, {"H17": {"type": "waveHeight", "x": 17}})
    assert "metrics.H17.x: no gauge at x = 17 in postProcessing/gauges/0/gauges.dat" in msg
    # an unfinished run: crest rows but no celerity.dat yet
    (flume / "postProcessing/crest/0/celerity.dat").unlink()
    msg = file_problems(flume, {"c": {"type": "celerity", "reference": 2.5}})
    assert "postProcessing/crest/0/celerity.dat not found" in msg
    # no metricsDict at all; a spec given by a study names its source
    (bare / "system/metricsDict").unlink()
    assert "system/metricsDict: file not found" in problems(bare)
    assert "studyDict: metrics.H17.x: no gauge" in \
        problems(bare, {"H17": {"type": "waveHeight", "x": 17}}, source="studyDict")


def test_wave_not_arrived_and_lenient_evaluation(tmp_path):
    case = tmp_path / "short"
    write_control(case, {"gauges": GAUGES})
    write_gauges(case, t_end=4.0)                                # the crest reaches 18 m at 5 s
    spec = {"H18": {"type": "waveHeight", "x": 18, "reference": 0.15},
            "H2": {"type": "waveHeight", "x": 2, "reference": 0.15},
            "R": {"type": "runUp"}}
    msg = problems(case, spec)
    assert "metrics.H18.x: eta at x = 18 is still rising at the last sample (t = 4 s) of " \
           "postProcessing/gauges/0/gauges.dat: its maximum is not reached" in msg
    assert "metrics.R.function: no function object 'runUp'" in msg
    vals = evaluate_metrics(case, spec, strict=False)
    assert math.isnan(vals["H18"].value) and math.isnan(vals["H18"].error)
    assert vals["H18"].reference == 0.15 and "not reached" in vals["H18"].problem
    assert vals["H2"].value == pytest.approx(0.149) and vals["H2"].problem is None
    assert math.isnan(vals["R"].value) and vals["R"].error is None


# --- tutorials and CLI --------------------------------------------------------------------------
def test_every_tutorial_metrics_dict_names_registered_types_and_existing_objects():
    cases = sorted(p.parents[1].name for p in TUTORIALS.glob("*/system/metricsDict"))
    assert {"solitaryWave", "poiseuille", "damBreak", "solitaryWallRunup",
            "solitaryCollision"} <= set(cases)
    for name in cases:
        mset = load_metrics(TUTORIALS / name)
        mset.check(TUTORIALS / name)                             # objects, types, gauge x
        assert mset.pareto in mset.metrics, name
        assert all(m.name in registry.names("metric") for m in mset.metrics.values())
    flume = load_metrics(TUTORIALS / "solitaryWave")
    assert flume.metrics["celerity"].known_reference() == pytest.approx(2.525, abs=5e-4)


def test_cli_prints_the_table(flume):
    write_metrics(flume, {"H18": {"type": "waveHeight", "x": 18, "reference": 0.15},
                          "t18": {"type": "arrivalTime", "x": 18}}, pareto="H18")
    runner = CliRunner()
    res = runner.invoke(app, ["metrics", str(flume)])
    assert res.exit_code == 0, res.output
    for s in ("H18 (pareto)", "waveHeight", "0.14", "0.15", "-6.667", "arrivalTime", "5"):
        assert s in res.output, s
    write_metrics(flume, {"H17": {"type": "waveHeight", "x": 17}})
    res = runner.invoke(app, ["metrics", str(flume)])
    assert res.exit_code == 2 and "system/metricsDict" in res.output
    assert "--keep-going" in res.output                         # the hint at -k
    res = runner.invoke(app, ["metrics", "-k", str(flume)])
    assert res.exit_code == 0 and "nan" in res.output


def test_wave_height_defaults_to_the_case_wave(tmp_path):
    """Without a reference, waveHeight compares with the case's own wave: the Goring
    paddle's H in the flume, the initial wave's A in the wall case."""
    from sphfoam.case.edit import clone_case

    flume = clone_case(TUTORIALS / "solitaryWave", tmp_path / "flume")
    write_gauges(flume)
    (v,) = evaluate_metrics(flume, {"H": {"type": "waveHeight", "x": 18}}).values()
    assert v.reference == 0.15
    assert v.error == pytest.approx(100 * (v.value - 0.15) / 0.15)
    wall = clone_case(TUTORIALS / "solitaryWallRunup", tmp_path / "wall",
                      {"constant/waveProperties:waves.incident.height": 4.5,
                       "system/controlDict:functions.gauges.x": [1, 2, 18]})
    write_gauges(wall)
    (v,) = evaluate_metrics(wall, {"H": {"type": "waveHeight", "x": 18}}).values()
    assert v.reference == 4.5
