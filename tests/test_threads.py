"""The thread count of a run (sphfoam.engine.threads, controlDict ``threads``).

The adaptive controller is tested on synthetic step times (no clock is read); the choice of
the count must not change results, which a run at 1 thread, at 2 threads and an adaptive run
that keeps switching between them check bit for bit, in a fresh Python with a pool of 2
threads (this suite may run with NUMBA_NUM_THREADS=1).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.cli import app
from sphfoam.engine.threads import AdaptiveThreads, check_setting

REPO = Path(__file__).resolve().parents[1]


def drive(ctl: AdaptiveThreads, cost, steps: int) -> list[int]:
    """Feed ``ctl`` the step times ``cost(step, threads)``; the count of every step."""
    used = []
    for k in range(steps):
        used.append(ctl.current)
        ctl.record(cost(k, ctl.current))
    return used


# -- the controller on synthetic times -----------------------------------------------------
IDLE = {1: 18e-3, 2: 10e-3}            # ms/step measured at 89 000 particles, idle 2 cores
CONTENDED = {1: 18.5e-3, 2: 26e-3}     # the same beside a process spinning on one core


def test_idle_machine_keeps_two_threads_and_probes_ever_more_rarely():
    ctl = AdaptiveThreads(2)
    used = drive(ctl, lambda k, n: IDLE[n], 20000)
    assert not ctl.changes and ctl.n == 2
    assert used[-1] == 2
    # probes back off to one every MAX_GAP + 2 windows: steps at 1 thread stay rare
    assert used.count(1) / len(used) < 0.07
    assert ctl.steps[1] == used.count(1) and ctl.steps[2] == used.count(2)
    late = used[10000:]
    assert 0 < late.count(1) / len(late) < 1 / (ctl.max_gap + 1)


def test_a_competing_process_moves_to_one_thread_and_its_end_moves_back():
    ctl = AdaptiveThreads(2)
    stop = 6000                          # the other process stops at this step

    def cost(k, n):
        return (CONTENDED if k < stop else IDLE)[n]

    used = drive(ctl, cost, 12000)
    first = ctl.changes[0]
    assert (first.new, first.old) == (1, 2)
    assert first.t_new == pytest.approx(18.5e-3) and first.t_old == pytest.approx(26e-3)
    # the move comes after warm-up, one window at 2, one probe at 1 and one window at 2
    assert first.step <= ctl.warmup + 3 * max(ctl.min_steps, 27) + 2 * ctl.warmup + 3
    assert used[first.step:stop].count(1) / (stop - first.step) > 0.93
    back = [c for c in ctl.changes if c.step > stop]
    assert back and (back[0].new, back[0].old) == (2, 1)
    # back within MAX_GAP base windows + the probe's windows (windows of 0.5 s at 18.5 ms)
    window = int(0.5 / 18.5e-3) + 1 + ctl.warmup
    assert back[0].step - stop <= (ctl.max_gap + 3) * window
    assert len(ctl.changes) == 2 and used[-1] == 2


def test_a_difference_within_the_margin_never_changes_the_count():
    ctl = AdaptiveThreads(2)
    drive(ctl, lambda k, n: {1: 10.3e-3, 2: 10e-3}[n] if k % 2 else {1: 9.9e-3, 2: 10.1e-3}[n],
          20000)
    assert not ctl.changes and ctl.n == 2


def test_a_drifting_step_cost_is_cancelled_by_the_bracketing_windows():
    # the same cost at both counts, falling 40 % over the run (a probe, later than the base
    # window before it, would look faster if compared with that window alone)
    ctl = AdaptiveThreads(2, margin=0.01)
    drive(ctl, lambda k, n: 20e-3 * (1 - 0.4 * k / 20000), 20000)
    assert not ctl.changes


def test_more_cores_climb_to_the_fastest_count():
    cost = {1: 40e-3, 2: 22e-3, 3: 15e-3, 4: 19e-3}    # e.g. one of 4 cores is busy
    ctl = AdaptiveThreads(4)
    used = drive(ctl, lambda k, n: cost[n], 20000)
    assert ctl.n == 3 and [(c.old, c.new) for c in ctl.changes] == [(4, 3)]
    assert used[-1] == 3 and set(used) == {2, 3, 4}    # probes on both sides of 3


def test_one_thread_pool_never_probes():
    ctl = AdaptiveThreads(1)
    assert drive(ctl, lambda k, n: 1e-3, 1000) == [1] * 1000
    assert ctl.tries == 0 and "1000 at 1" in ctl.summary()


def test_setting_values():
    assert check_setting("auto", "threads") == "auto" and check_setting(3, "threads") == 3
    for bad in (0, -1, 2.5, True, "many"):
        with pytest.raises(ValueError, match="threads: expected auto or a whole number"):
            check_setting(bad, "threads")


# -- controlDict and the command line --------------------------------------------------------
@pytest.mark.parametrize("value", [0, -2, 2.5, "yes", "many"])
def test_bad_threads_in_control_dict_names_file_key_and_choices(tutorial, value):
    case = tutorial("damBreak", {"system/controlDict:threads": value})
    with pytest.raises(CaseError) as e:
        Case(case).validate()
    msg = str(e.value)
    assert "system/controlDict: threads" in msg
    assert "expected auto or a whole number of threads >= 1" in msg


@pytest.mark.parametrize("value", ["auto", 1, 4])
def test_good_threads_in_control_dict(tutorial, value):
    case = Case(tutorial("damBreak", {"system/controlDict:threads": value}))
    case.validate()
    assert case.control.threads == value


def test_default_is_auto(tutorial):
    assert Case(tutorial("damBreak")).control.threads == "auto"


@pytest.mark.parametrize("value", ["0", "two"])
def test_bad_threads_option_is_one_usage_error(tutorial, value):
    res = CliRunner().invoke(app, ["run", str(tutorial("damBreak")), "-j", value])
    assert res.exit_code == 2
    text = " ".join(res.output.replace("\u2502", " ").split())     # rich's box drawn round it
    assert "expected auto or a whole number of threads >= 1" in text
    assert "Traceback" not in text


# -- the count does not change the results ----------------------------------------------------
CHILD = textwrap.dedent("""
    import hashlib, json, sys
    from pathlib import Path
    import numba
    import sphfoam.engine.threads as th
    from sphfoam.case.edit import clone_case
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import read_state
    from sphfoam.timeloop import run_case

    assert numba.config.NUMBA_NUM_THREADS == 2
    # windows of 2 steps, a probe every third window: an auto run that keeps switching
    th.WINDOW_SECONDS, th.MIN_WINDOW_STEPS, th.WARMUP_STEPS, th.MAX_GAP = 0.0, 2, 0, 1
    out = {}
    for label, threads in (("one", 1), ("two", 2), ("auto", None)):
        edits = {"system/controlDict:functions": {}, "system/particleDict:dx": 0.02}
        if threads is not None:
            edits["system/controlDict:threads"] = threads
        case = clone_case(Path(sys.argv[1]) / "tutorials" / "damBreak",
                          Path(sys.argv[2]) / label, edits)
        lines = []
        rep = run_case(case, progress=False, echo=lines.append, end_time=0.04)
        s = read_state(list_times(case)[-1][1])
        out[label] = {"steps": rep.steps, "log": [l for l in lines if "threads" in l],
                      "fields": {k: hashlib.sha256(v.tobytes()).hexdigest()
                                 for k, v in s.items()}}
    print("JSON:" + json.dumps(out))
""")


def test_one_two_and_adaptive_threads_give_bit_identical_results(tmp_path):
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    env = {**os.environ, "NUMBA_NUM_THREADS": "2", "PYTHONPATH": str(REPO)}
    cp = subprocess.run([sys.executable, str(script), str(REPO), str(tmp_path)], env=env,
                        capture_output=True, text=True, timeout=600)
    assert cp.returncode == 0, cp.stderr[-3000:]
    out = json.loads([ln for ln in cp.stdout.splitlines() if ln.startswith("JSON:")][-1][5:])
    one, two, auto = out["one"], out["two"], out["auto"]
    assert "threads: 1 (system/controlDict threads 1)" in one["log"]
    assert "threads: 2 (system/controlDict threads 2)" in two["log"]
    summary = [ln for ln in auto["log"] if ln.startswith("threads auto: steps")]
    assert summary, auto["log"]
    # the adaptive run did run steps at both counts
    counts = dict(reversed(p.split(" at ")) for p in
                  summary[0].split("steps ", 1)[1].split(";")[0].split(", "))
    assert int(counts.get("1", 0)) > 0 and int(counts.get("2", 0)) > 0, summary
    assert one["steps"] == two["steps"] == auto["steps"]
    for other in (two, auto):
        differ = [k for k in one["fields"] if one["fields"][k] != other["fields"][k]]
        assert not differ, f"fields differing from the 1-thread run: {differ}"


def test_pinned_count_beyond_the_pool_is_capped_and_said(tutorial):
    import numba

    from sphfoam.engine.threads import RunThreads, pool_size

    before = numba.get_num_threads()
    lines: list[str] = []
    rt = RunThreads(64, "system/controlDict threads 64", lines.append)
    assert numba.get_num_threads() == pool_size() and rt.adaptive is None
    assert lines[0] == (f"threads: {pool_size()} (system/controlDict threads 64; numba's pool "
                        f"has only {pool_size()} (NUMBA_NUM_THREADS))")
    assert lines[1].startswith("threads: threading layer ")
    rt.end()
    assert numba.get_num_threads() == before


def test_threads_option_auto_and_numbers():
    from sphfoam.cli import _threads

    assert _threads(None) is None and _threads("auto") == "auto" and _threads("3") == 3


@pytest.mark.parametrize("env, expected", [({}, "omp tbb workqueue"),
                                           ({"NUMBA_THREADING_LAYER": "workqueue"}, None),
                                           ({"NUMBA_THREADING_LAYER_PRIORITY":
                                             "workqueue omp tbb"}, "workqueue omp tbb")])
def test_import_asks_for_omp_first_unless_the_user_chose(env, expected):
    base = {k: v for k, v in os.environ.items()
            if k not in ("NUMBA_THREADING_LAYER", "NUMBA_THREADING_LAYER_PRIORITY")}
    code = ("import os, sphfoam, numba; print(os.environ.get('NUMBA_THREADING_LAYER_PRIORITY'), "
            "' '.join(numba.config.THREADING_LAYER_PRIORITY), sep='|')")
    cp = subprocess.run([sys.executable, "-c", code], env={**base, **env, "PYTHONPATH": str(REPO)},
                        capture_output=True, text=True, timeout=120)
    assert cp.returncode == 0, cp.stderr
    got_env, _, got_cfg = cp.stdout.strip().partition("|")
    assert got_env == str(expected)
    assert got_cfg == (expected or "tbb omp workqueue")
