"""`sphfoam study`: reading study dictionaries, running variants in parallel (local processes
and a Dask cluster, one code path), the table, CSV and Pareto plot, resuming, blow-ups."""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from sphfoam import study as st
from sphfoam.case.errors import CaseError
from sphfoam.cli import app

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"
HEADER = "FoamFile { version 2.0; format ascii; class dictionary; object studyDict; }\n"


@pytest.fixture()
def flume(tmp_path):
    """A copy of the flume tutorial (with its study dictionaries) in a scratch folder."""
    dst = tmp_path / "solitaryWave"
    shutil.copytree(TUTORIALS / "solitaryWave", dst,
                    ignore=shutil.ignore_patterns("study", "studySmall", "0", "[1-9]*",
                                                  "postProcessing", "log.*"))
    return dst


def write_study(case: Path, body: str, name="studyDict.test") -> Path:
    p = case / name
    p.write_text(HEADER + body)
    return p


# --- reading ----------------------------------------------------------------------------------
def test_thesis_study_lists_the_eleven_cases_of_table_4_1():
    s = st.load(TUTORIALS / "solitaryWave" / "studyDict")
    assert [r.name for r in s.runs] == [f"case{i}" for i in range(1, 12)]
    e = s.edits
    assert e["case1"]["constant/sphProperties:boundary"] == {"type": "repulsiveMonaghanKos"}
    assert e["case2"]["constant/sphProperties:boundary"] == {"type": "stationaryGhosts"}
    assert e["case9"]["system/sphSchemes:integrator"] == {"type": "predictorCorrector"}
    assert e["case10"]["system/particleDict:dx"] == 0.1
    assert e["case11"]["constant/sphProperties:densityFilter"]["type"] == "shepard"
    assert e["case11"]["constant/sphProperties:kernel"]["type"] == "quartic"


def test_axes_make_every_combination_and_resolutions_multiply(flume):
    p = write_study(flume, """
        resolutions (0.1 0.05);
        axes { visc { art { viscosity { type artificial; alpha 0.1; } }
                      lam { viscosity { type laminar; } } }
               filt { none { densityFilter { type none; } } shep { densityFilter.every 20; } } }
        variants { extra { maxCo 0.3; } }""")
    s = st.load(p)
    names = [r.name for r in s.runs]
    assert names == ["art_none_dx0.1", "art_none_dx0.05", "art_shep_dx0.1", "art_shep_dx0.05",
                     "lam_none_dx0.1", "lam_none_dx0.05", "lam_shep_dx0.1", "lam_shep_dx0.05",
                     "extra_dx0.1", "extra_dx0.05"]
    ed = s.edits["lam_shep_dx0.05"]
    assert ed == {"constant/sphProperties:viscosity": {"type": "laminar"},
                  "constant/sphProperties:densityFilter.every": 20,
                  "system/particleDict:dx": 0.05}
    assert s.edits["extra_dx0.1"]["system/controlDict:maxCo"] == 0.3


def test_a_variants_own_resolutions_and_only_one_run(flume):
    p = write_study(flume, """
        resolutions (0.1 0.05);
        variants { a { maxCo 0.3; } b { resolutions (0.1 0.05 0.025); } }""")
    assert [r.name for r in st.load(p).runs] == ["a_dx0.1", "a_dx0.05", "b_dx0.1",
                                                 "b_dx0.05", "b_dx0.025"]
    (fine,) = st.load(p, ["b_dx0.025"]).runs
    assert fine.dx == 0.025 and st.load(p, ["b_dx0.025"]).edits[fine.name] == {
        "system/particleDict:dx": 0.025}
    assert [r.name for r in st.load(p, ["a"]).runs] == ["a_dx0.1", "a_dx0.05"]
    with pytest.raises(CaseError) as e:
        st.load(p, ["a_dx0.025"])
    assert "no such variant or run" in str(e.value.problems[0])


@pytest.mark.parametrize("body, key, words", [
    ("variants { a { viscosty.type laminar; } }", "variants.a.viscosty.type",
     ["not an entry", "viscosity"]),
    ("variants { a { description \"x\"; } } baseline b;", "baseline", ["'b' is not a variant"]),
    ("variants { }", "variants", ["nothing to run"]),
    ("variants { a { \"system/nowhere:x\" 1; } }", "variants.a.system/nowhere:x",
     ["no dictionary"]),
    ("variants { a { } } resolutions (0.1 -1);", "resolutions", ["> 0"]),
    ("variants { a { resolutions (0.1 0); } }", "variants.a.resolutions", ["> 0"]),
    ("variants { a { resolutions (x); } }", "variants.a.resolutions", ["particle spacings"]),
    ("variants { a { } } jobs 0;", "jobs", ["greater than or equal to 1"]),
    ("variants { a { } } colour red;", "colour", ["colour"]),
])
def test_bad_study_dictionaries_name_file_key_and_choices(flume, body, key, words):
    p = write_study(flume, body)
    with pytest.raises(CaseError) as e:
        st.load(p)
    text = "\n".join(str(x) for x in e.value.problems)
    assert "studyDict.test" in text and key in text, text
    for w in words:
        assert w in text, text


def test_a_variant_that_makes_an_invalid_case_is_caught_before_anything_runs(flume, tmp_path):
    p = write_study(flume, f"""directory "{tmp_path / 'out'}";
        variants {{ good {{ }} bad {{ viscosity {{ type laminr; }} }} }}""")
    s = st.load(p)
    with pytest.raises(CaseError) as e:
        st.prepare(s)
    text = "\n".join(str(x) for x in e.value.problems)
    assert "bad/constant/sphProperties" in text and "laminar" in text, text
    assert not (tmp_path / "out" / "good" / "result.json").exists()


def test_a_run_is_cloned_without_the_runs_of_the_base_cases_other_studies(flume, tmp_path):
    """The flume tutorial's low-dissipation study keeps its runs in studyLowDissipation (its
    studyDict.lowDissipation's directory); a run of another study copies the case's
    dictionaries, not those runs."""
    old = flume / "studyLowDissipation" / "someRun"
    (old / "system").mkdir(parents=True, exist_ok=True)
    (old / "result.json").write_text("{}")
    p = write_study(flume, f"""directory "{tmp_path / 'out'}";
        variants {{ a {{ }} }}""")
    st.prepare(st.load(p))
    run = tmp_path / "out" / "a"
    assert (run / "system" / "controlDict").is_file()
    assert (run / "studyDict.lowDissipation").is_file()
    assert not (run / "studyLowDissipation").exists()


def test_the_cli_reports_a_bad_study_without_a_traceback(flume):
    p = write_study(flume, "variants { a { maxCoo 1; } }")
    res = CliRunner().invoke(app, ["study", str(p)])
    assert res.exit_code == 2
    assert "maxCoo" in res.output and "maxCo" in res.output
    assert "Traceback" not in res.output


def test_dry_run_lists_runs_and_overrides(flume):
    res = CliRunner().invoke(app, ["study", str(flume / "studyDict.small"), "--dry-run"])
    assert res.exit_code == 0, res.output
    for name in ("case2_dx0.1", "case4_dx0.1", "case11_dx0.1"):
        assert name in res.output
    assert not (flume / "studySmall").exists()


# --- tables -----------------------------------------------------------------------------------
def test_pareto_front_keeps_only_undominated_points():
    pts = [(10, 5.0), (20, 2.0), (15, 6.0), (30, 2.5), (40, 1.0), (5, 9.0), (20, 2.0)]
    assert sorted(st.pareto_front(pts)) == [0, 1, 4, 5]


def test_relative_runtime_is_per_resolution_against_the_baseline():
    rows = [{"variant": "a", "dx": 0.1, "wallSeconds": 10.0, "outcome": "ok"},
            {"variant": "b", "dx": 0.1, "wallSeconds": 15.0, "outcome": "ok"},
            {"variant": "a", "dx": 0.05, "wallSeconds": 80.0, "outcome": "ok"},
            {"variant": "b", "dx": 0.05, "wallSeconds": 40.0, "outcome": "ok"},
            {"variant": "b", "dx": 0.2, "wallSeconds": 4.0, "outcome": "ok"},
            {"variant": "c", "dx": 0.1, "wallSeconds": 1.0, "outcome": "blowUp:nan"}]
    st.relative_runtimes(rows, "a")
    assert [r["relativeRuntime"] for r in rows] == [1.0, 1.5, 1.0, 0.5, None, None]


# --- running ----------------------------------------------------------------------------------
def test_small_flume_study_runs_in_parallel_and_resumes(flume):
    """tutorials/solitaryWave/studyDict.small: three of T Table 4.1's cases at d/dx = 5."""
    res = CliRunner().invoke(app, ["study", str(flume / "studyDict.small")])
    assert res.exit_code == 0, res.output
    out = flume / "studySmall"
    with open(out / "study.csv") as fh:
        rows = {r["run"]: r for r in csv.DictReader(fh)}
    assert set(rows) == {"case2_dx0.1", "case4_dx0.1", "case11_dx0.1"}
    for r in rows.values():
        assert r["outcome"] == "ok", r
        assert int(r["steps"]) > 100 and int(r["particles"]) > 1000
        assert float(r["wallSeconds"]) > 0 and float(r["compileSeconds"]) >= 0
        assert float(r["particleStepsPerSecond"]) > 0
        # the wave reaches the 4 m gauge: a height near H = 0.15 m (the gauge reads within
        # dx/2 = 0.05 m at d/dx = 5) and a celerity near theory (2 -> 8 m, still forming)
        assert 0.09 < float(r["H4"]) < 0.17, r
        assert abs(float(r["celerity err %"])) < 15, r
    assert float(rows["case2_dx0.1"]["relativeRuntime"]) == 1.0
    md = (out / "study.md").read_text()
    assert "| run | description | dx |" in md and "runtime vs case2" in md
    assert "H4 err %" in md
    assert (out / "pareto.png").stat().st_size > 10_000
    # each run keeps its own result: a second invocation runs nothing and loses nothing
    stamp = (out / "case4_dx0.1" / "result.json").stat().st_mtime_ns
    res = CliRunner().invoke(app, ["study", str(flume / "studyDict.small")])
    assert res.exit_code == 0 and "3 already done, 0 to run" in res.output
    assert (out / "case4_dx0.1" / "result.json").stat().st_mtime_ns == stamp


def test_a_blow_up_is_a_row_with_its_diagnosis(flume, tmp_path):
    p = write_study(flume, f"""directory "{tmp_path / 'blow'}";
        resolutions (0.1);
        set {{ endTime 2; writeInterval 0.5; }}
        variants {{ absurd {{ adjustTimeStep no; deltaT 0.05; }} }}
        metrics {{ H1 {{ type waveHeight; function gauges; x 1; reference 0.15; }} }}""")
    rows = st.run_study(st.load(p), log=lambda m: None)
    (r,) = rows
    assert r["outcome"].startswith("blowUp:"), r
    assert r["diagnosis"] and r["lastGood"]
    assert (tmp_path / "blow" / "absurd_dx0.1" / r["lastGood"]).is_dir()
    md = (tmp_path / "blow" / "study.md").read_text()
    assert "Runs that did not finish" in md and "absurd_dx0.1" in md


def test_a_stopped_run_continues_from_its_last_write(flume, tmp_path):
    """A run whose study was stopped (written times, no result.json) continues from its last
    written time, to the end and metrics of an uninterrupted run; one whose variant has
    changed since is kept aside as <run>.old and starts again."""
    body = f"""directory "{tmp_path / 'res'}";
        resolutions (0.1);
        set {{ endTime 2.5; writeInterval 0.5; }}
        variants {{ one {{ maxCo @; }} }}
        metrics {{ H1 {{ type waveHeight; function gauges; x 1; reference 0.15; }} }}"""
    p = write_study(flume, body.replace("@", "0.25"))
    (whole,) = st.run_study(st.load(p), log=lambda m: None)
    assert whole["outcome"] == "ok" and "resumedFrom" not in whole
    run = tmp_path / "res" / "one_dx0.1"
    # what a stop after the write of t = 1 leaves: no result, the times after it gone
    (run / "result.json").unlink()
    for t in ("1.5", "2", "2.5"):
        shutil.rmtree(run / t)
    # what lies beside the dictionaries (notes, logs, other study dictionaries) is no change
    (flume / "notes.txt").write_text("started the study again\n")
    said = []
    (part,) = st.run_study(st.load(p), log=said.append)
    assert "1 to run" in said[0]
    assert part["outcome"] == "ok" and part["resumedFrom"] == 1.0, part
    assert (run / "0.5").is_dir() and (run / "2.5").is_dir()
    assert 0 < part["steps"] < whole["steps"]
    # the step that writes t = 1 is where the restart takes over (monaghan2007 restarts bit
    # for bit): the same end, the same metric
    assert part["H1"] == pytest.approx(whole["H1"], rel=1e-9)
    assert part["endTime"] == whole["endTime"]
    md = (tmp_path / "res" / "study.md").read_text()
    assert "## Runs continued after a stop" in md and "**one_dx0.1**: from t = 1 s" in md
    # changed since: the old run is kept, the new one starts from 0
    (run / "result.json").unlink()
    shutil.rmtree(run / "2.5")
    p = write_study(flume, body.replace("@", "0.2"))
    (again,) = st.run_study(st.load(p), log=said.append)
    assert "resumedFrom" not in again and again["outcome"] == "ok"
    old = tmp_path / "res" / "one_dx0.1.old"
    assert (old / "2").is_dir() and not (old / "2.5").exists()
    assert any("kept in" in m and "one_dx0.1.old" in m for m in said)


def test_dask_cluster_runs_the_same_code_path(flume, tmp_path):
    distributed = pytest.importorskip("distributed")
    p = write_study(flume, f"""directory "{tmp_path / 'dask'}";
        resolutions (0.1);
        set {{ endTime 3; writeInterval 1;
               kernel {{ type cubicSpline; hdx 1.3; }} viscosity {{ type laminar; }}
               densityFilter {{ type none; }} }}
        variants {{ one {{ }} }}
        metrics {{ H1 {{ type waveHeight; function gauges; x 1; reference 0.15; }} }}""")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        res = CliRunner().invoke(app, ["study", str(p), "--scheduler",
                                       cluster.scheduler_address])
    assert res.exit_code == 0, res.output
    assert "Dask" in res.output
    row = json.loads((tmp_path / "dask" / "one_dx0.1" / "result.json").read_text())
    assert row["outcome"] == "ok" and row["steps"] > 0
    assert math.isfinite(row["H1"])


def _orphan_sleeper(folder):
    """A stand-in for a run: sleeps until Ctrl-C (SIGINT), then records that it stopped."""
    import os
    import time
    Path(folder, "worker.pid").write_text(str(os.getpid()))
    try:
        time.sleep(120)
    except KeyboardInterrupt:
        Path(folder, "stopped").write_text("interrupted")


def _orphaned_study(folder):
    """A stand-in for `sphfoam study`: the same pool as study.executor, one long run."""
    import multiprocessing as mp
    import os
    import signal
    import time
    from concurrent.futures import ProcessPoolExecutor

    from sphfoam.study import follow_parent
    # as started in the background (nohup, `&`): SIGINT ignored, inherited by the workers
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    ex = ProcessPoolExecutor(1, mp_context=mp.get_context("spawn"), initializer=follow_parent,
                             initargs=(os.getpid(), 0.1, 10.0))
    ex.submit(_orphan_sleeper, folder)
    time.sleep(120)


def test_a_killed_study_stops_its_runs(tmp_path):
    """Killing the study process (SIGKILL: no handler runs) stops its workers' runs as Ctrl-C
    does, within a second; before, they went on computing, orphaned, to their end time. It
    holds for a study started in the background (SIGINT inherited as ignored), as the
    stand-in study here is."""
    import multiprocessing as mp
    import os
    import signal
    import time

    parent = mp.get_context("spawn").Process(target=_orphaned_study, args=(str(tmp_path),))
    parent.start()
    pid_file = tmp_path / "worker.pid"
    t0 = time.time()
    while not pid_file.is_file() and time.time() - t0 < 60:
        time.sleep(0.05)
    assert pid_file.is_file(), "the worker never started"
    worker = int(pid_file.read_text())
    os.kill(parent.pid, signal.SIGKILL)
    parent.join()
    t0 = time.time()
    while not (tmp_path / "stopped").is_file() and time.time() - t0 < 10:
        time.sleep(0.05)
    assert (tmp_path / "stopped").read_text() == "interrupted"

    def running():
        # a quit worker may linger as a zombie (no one reaps an orphan in a container):
        # where /proc tells, a zombie has quit; elsewhere orphans are reaped (launchd)
        try:
            status = Path(f"/proc/{worker}/status").read_text()
        except FileNotFoundError:
            if Path("/proc/self/status").is_file():
                return False            # /proc exists and the worker is gone
            try:
                os.kill(worker, 0)
            except ProcessLookupError:
                return False
            return True
        return "\nState:\tZ" not in status

    t0 = time.time()
    while running() and time.time() - t0 < 20:
        time.sleep(0.05)
    if running():
        os.kill(worker, signal.SIGKILL)
        raise AssertionError("the orphaned worker did not quit")
