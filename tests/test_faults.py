"""Fault tests (issue 15): nothing lost, nothing outside the case, no traceback.

* SIGKILL at random instants while time directories are written (and rewritten): never a
  directory a restart would use that is not complete;
* partial or foreign time directories skipped by ``startFrom latestTime``, each with the
  reason;
* a full disk (a small tmpfs, where this machine lets the tests mount one) and a read-only
  case: a clear message, exit 1, the earlier directories intact and restartable;
* two runs on one case: the second refused, naming the first's pid; a stale lock taken over;
* paths a dictionary names that would escape the case or the study: refused;
* Ctrl-C twice: the message says whether the state was written, and it is true.
"""

from __future__ import annotations

import errno
import os
import random
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.check import check_case
from sphfoam.case.errors import CaseError
from sphfoam.case.times import list_times
from sphfoam.cli import app
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import CLOUD_DIR, has_particles, read_state
from sphfoam.io.timedirs import (LOCK_FILE, CaseLocked, case_lock, check_time_dir, recover,
                                 write_time_dir)
from sphfoam.io.timedirs import start_folder, write_time
from sphfoam.setup import setup_case
from sphfoam.timeloop import run_case

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"
KILLS = 16


@pytest.fixture
def tank(tmp_path):
    """hydrostaticTank with its particles set up in 0/ (no pipeline compiled)."""
    case = tmp_path / "tank"
    shutil.copytree(TUTORIALS / "hydrostaticTank", case)
    setup_case(Case(case), log=lambda m: None)
    return case


def _complete(case: Path) -> list[str]:
    """Names of the visible time directories with particles that are not complete."""
    return [p.name for _, p in list_times(case)
            if has_particles(p) and check_time_dir(p)[0] is not None]


# --- atomic writes ----------------------------------------------------------------------------
KILL_SCRIPT = textwrap.dedent("""
    import sys
    from sphfoam.case.case import Case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state
    from sphfoam.io.timedirs import write_time
    case = Case(sys.argv[1])
    state = ParticleState.from_fields(read_state(case.path / "0"))
    print("ready", flush=True)
    i = 0
    while True:
        i += 1
        write_time(case, state, 0.001 * i, i, 1e-4, p=state.rho)
        write_time(case, state, 0.0005, i, 1e-4, p=state.rho, name="0.0005")   # a rewrite
""")


def test_sigkill_during_writes_never_leaves_a_directory_a_restart_would_use(tank):
    script = tank.parent / "writer.py"
    script.write_text(KILL_SCRIPT)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    rng = random.Random(15)
    hidden_seen = 0
    for seed in range(KILLS):
        proc = subprocess.Popen([sys.executable, str(script), str(tank)], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        assert proc.stdout.readline().strip() == b"ready", proc.stderr.read().decode()
        time.sleep(rng.uniform(0.0, 0.25))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        hidden_seen += sum(1 for p in tank.iterdir() if p.name.startswith(".0"))
        assert not _complete(tank), f"kill {seed}: incomplete directories visible"
        recover(tank)
        assert not [p for p in tank.iterdir() if p.name.startswith(".0")], \
            f"kill {seed}: remains of an interrupted write not tidied"
        assert not _complete(tank)
        folder = start_folder(Case(tank))
        assert folder is not None and check_time_dir(folder)[0] is None
    # the restart reads what was written: the particle count and the step index survive
    folder = start_folder(Case(tank))
    d = read_state(folder)
    assert len(d["positions"]) == len(read_state(tank / "0")["positions"])
    assert "origId" in d and "p" in d
    print(f"{KILLS} SIGKILLs, {hidden_seen} left a temporary directory behind (tidied), "
          f"none a visible partial one")


def test_latest_time_skips_partial_and_foreign_directories(tank):
    case = Case(tank)
    state = ParticleState.from_fields(read_state(tank / "0"))
    for i, t in enumerate((0.1, 0.2, 0.3, 0.4, 0.5, 0.6), start=1):
        write_time(case, state, t, i, 1e-4, p=state.rho)
    (tank / "0.6" / CLOUD_DIR / "rho").unlink()                         # a field missing
    (tank / "0.5" / "uniform" / "time").write_bytes(b"")                # 0-byte uniform/time
    f = tank / "0.4" / CLOUD_DIR / "U"
    f.write_bytes(f.read_bytes()[:-100])                                # truncated field
    shutil.rmtree(tank / "0.3" / "uniform")                             # no uniform/time
    (tank / "0.7" / CLOUD_DIR).mkdir(parents=True)                      # a foreign directory
    shutil.copy(tank / "0" / CLOUD_DIR / "positions", tank / "0.7" / CLOUD_DIR / "positions")
    lines = []
    assert start_folder(case, lines.append) == tank / "0.2"
    text = "\n".join(lines)
    for name in ("0.7", "0.6", "0.5", "0.4", "0.3"):
        assert f"skipping time directory {name}:" in text
    assert "missing particle field(s): rho" in text and "uniform/time" in text


def test_no_complete_directory_is_a_case_error(tank):
    (tank / "0" / "uniform" / "time").unlink()
    with pytest.raises(CaseError) as e:
        start_folder(Case(tank))
    assert "no complete time directory" in str(e.value) and "uniform/time" in str(e.value)


def test_rewrite_replaces_whole_and_an_error_leaves_the_old_directory(tank, monkeypatch):
    case = Case(tank)
    state = ParticleState.from_fields(read_state(tank / "0"))
    write_time(case, state, 0.1, 1, 1e-4, p=state.rho)
    before = (tank / "0.1" / "uniform" / "time").read_text()
    import sphfoam.io.timedirs as td

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", "x")

    monkeypatch.setattr(td, "write_state", full)
    with pytest.raises(OSError):
        write_time(case, state, 0.1, 2, 1e-4, p=state.rho)
    assert (tank / "0.1" / "uniform" / "time").read_text() == before
    assert not [p for p in tank.iterdir() if p.name.startswith(".")]


# --- a full disk, a read-only case (a tmpfs mount; skipped where not allowed) -------------------
@pytest.fixture
def small_fs(tmp_path):
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mnt)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({r.stderr.strip() or 'not permitted'}): the "
                    "full-disk and read-only tests need one")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def _copy_case(tank: Path, dst: Path) -> Path:
    shutil.copytree(tank, dst, ignore=shutil.ignore_patterns("log.*"))
    return dst


def test_disk_full_is_a_clear_error_and_earlier_directories_stay_restartable(tank, small_fs):
    case_dir = _copy_case(tank, small_fs / "tank")
    case = Case(case_dir)
    state = ParticleState.from_fields(read_state(case_dir / "0"))
    written = []
    with pytest.raises(OSError) as e:
        for i in range(1, 50):
            written.append(write_time(case, state, 0.1 * i, i, 1e-4, p=state.rho).name)
    assert e.value.errno == errno.ENOSPC
    assert written, "the file system was full before the first write"
    assert not [p for p in case_dir.iterdir() if p.name.startswith(".")]
    assert not _complete(case_dir)
    assert start_folder(case) == case_dir / written[-1]
    # the command line: one screen, exit 1, no traceback
    res = CliRunner().invoke(app, ["setup", str(case_dir), "--force"])
    assert res.exit_code == 1, res.output
    assert "No space left on device" in res.output and "Traceback" not in res.output
    assert check_time_dir(case_dir / "0")[0] is None           # the old 0/ is intact


def test_read_only_case_is_a_clear_error(tank, small_fs):
    case_dir = _copy_case(tank, small_fs / "tank")
    r = subprocess.run(["mount", "-o", "remount,ro", str(small_fs)], capture_output=True,
                       text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot remount read-only: {r.stderr.strip()}")
    for args in (["run", str(case_dir), "--no-progress"], ["setup", str(case_dir), "--force"]):
        res = CliRunner().invoke(app, args)
        assert res.exit_code == 1, res.output
        assert "Read-only file system" in res.output and "Traceback" not in res.output
    assert check_time_dir(case_dir / "0")[0] is None


# --- the lock ---------------------------------------------------------------------------------
def test_second_run_refused_naming_the_first_pid(tank):
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tank / LOCK_FILE).write_text(f"{holder.pid} {os.uname().nodename} run\n")
        with pytest.raises(CaseLocked) as e:
            run_case(tank, progress=False, echo=None)
        assert str(holder.pid) in str(e.value)
        res = CliRunner().invoke(app, ["run", str(tank), "--no-progress"])
        assert res.exit_code == 2 and str(holder.pid) in res.output, res.output
        assert not (tank / "log.sphfoam").exists()        # the second run wrote nothing
    finally:
        holder.kill()
        holder.wait()


def test_stale_lock_of_a_dead_process_is_taken_over(tank):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tank / LOCK_FILE).write_text(f"{dead.pid} {os.uname().nodename} run\n")
    with case_lock(tank) as f:
        assert f.read_text().split()[0] == str(os.getpid())
    assert not (tank / LOCK_FILE).exists()


def test_lock_is_exclusive_between_processes(tank):
    code = ("import sys, time\nfrom sphfoam.io.timedirs import case_lock\n"
            "with case_lock(sys.argv[1]):\n    print('locked', flush=True)\n"
            "    time.sleep(30)\n")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    p = subprocess.Popen([sys.executable, "-c", code, str(tank)], stdout=subprocess.PIPE,
                         env=env)
    try:
        assert p.stdout.readline().strip() == b"locked"
        with pytest.raises(CaseLocked) as e:
            with case_lock(tank):
                pass
        assert f"process {p.pid}" in str(e.value)
    finally:
        p.kill()
        p.wait()


# --- paths ------------------------------------------------------------------------------------
def _edit(case: Path, rel: str, old: str, new: str):
    f = case / rel
    text = f.read_text()
    assert old in text
    f.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize("name", ['"../../escaped"', '"/abs/path"', '".."', '"a/b"'])
def test_function_object_names_cannot_escape(tmp_path, name):
    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "damBreak", case)
    _edit(case, "system/controlDict", "functions\n{", f"functions\n{{\n    {name} {{ type "
          "damBreakFront; wallX 0; }")
    with pytest.raises(CaseError) as e:
        check_case(case)
    assert any(p.file == "system/controlDict" and p.key == "functions" and "plain name" in
               p.message for p in e.value.problems), str(e.value)


def test_study_never_touches_anything_outside_its_folder(tmp_path):
    base = tmp_path / "work" / "solitaryWave"
    shutil.copytree(TUTORIALS / "solitaryWave", base)
    victim = tmp_path / "victim"
    victim.mkdir()
    (victim / "keep").write_text("precious")
    sd = base / "evilDict"
    sd.write_text(textwrap.dedent("""
        directory "evilStudy";
        variants { "../../../victim" { endTime 1; } ok { endTime 1; } }
    """))
    from sphfoam import study as st

    with pytest.raises(CaseError) as e:
        st.load(sd)
    assert any("plain name" in p.message and p.key.startswith("variants.") for p in
               e.value.problems), str(e.value)
    sd.write_text('directory "../../../victim";\nvariants { ok { endTime 1; } }\n')
    with pytest.raises(CaseError) as e:
        st.load(sd)
    assert e.value.problems[0].key == "directory" and "outside" in e.value.problems[0].message
    res = CliRunner().invoke(app, ["study", str(sd), "--dry-run"])
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert (victim / "keep").read_text() == "precious"


def test_displacement_table_must_lie_inside_the_case(tmp_path):
    from sphfoam.models.motion import DisplacementTable

    case = tmp_path / "c"
    case.mkdir()
    (tmp_path / "outside.dat").write_text("0 0 0\n1 0.1 0\n")
    (case / "inside.dat").write_text("0 0 0\n1 0.1 0\n")
    m = DisplacementTable(DisplacementTable.Coeffs(file="inside.dat"))
    m.resolve(case)
    for bad, why in (("../outside.dat", "outside the case"), ("/dev/zero", "regular file"),
                     ("nothere.dat", "no such file")):
        m = DisplacementTable(DisplacementTable.Coeffs(file=bad))
        with pytest.raises(ValueError, match=why):
            m.resolve(case)
    # an absolute path is a deliberate choice (documented key)
    m = DisplacementTable(DisplacementTable.Coeffs(file=str(tmp_path / "outside.dat")))
    m.resolve(case)
    (case / "nan.dat").write_text("0 0 0\n1 nan 0\n")
    with pytest.raises(ValueError, match="non-finite"):
        DisplacementTable(DisplacementTable.Coeffs(file="nan.dat")).resolve(case)


def test_clone_into_the_case_itself_is_refused(tmp_path):
    from sphfoam.case.edit import clone_case

    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "damBreak", case)
    for dst in (case / "copy", case, tmp_path):
        with pytest.raises(ValueError, match="cannot clone"):
            clone_case(case, dst)
    clone_case(case, case / "study" / "run")     # a result folder is left out of the copy
    assert (case / "study" / "run" / "system" / "controlDict").is_file()
    assert not (case / "study" / "run" / "study").exists()


# --- no traceback -----------------------------------------------------------------------------
def test_rich_markup_in_a_value_is_printed_as_written(tmp_path):
    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "damBreak", case)
    f = case / "system" / "controlDict"
    import re

    f.write_text(re.sub(r"^startFrom\s+[^;]*;", 'startFrom "[/bold]";', f.read_text(),
                        flags=re.M) if re.search(r"^startFrom", f.read_text(), re.M)
                 else f.read_text() + '\nstartFrom "[/bold]";\n')
    res = CliRunner().invoke(app, ["check", str(case)])
    assert res.exit_code == 2 and "[/bold]" in res.output and "Traceback" not in res.output


def test_vtk_existing_as_a_file_is_an_os_error(tank):
    (tank / "VTK").write_text("not a folder")
    res = CliRunner().invoke(app, ["export", "vtk", str(tank)])
    assert res.exit_code == 1 and "VTK" in res.output and "Traceback" not in res.output
    res = CliRunner().invoke(app, ["--debug", "export", "vtk", str(tank)])
    assert isinstance(res.exception, OSError)            # --debug keeps the exception


def test_latin1_byte_names_the_file(tmp_path):
    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "damBreak", case)
    f = case / "constant" / "transportProperties"
    f.write_bytes(f.read_bytes() + b"// caf\xe9\n")
    res = CliRunner().invoke(app, ["check", str(case)])
    assert res.exit_code == 2 and "constant/transportProperties" in res.output
    assert "UTF-8" in res.output


@pytest.mark.parametrize("edit,key", [
    ({"system/particleDict:dx": 1e-7}, "dx"),
    ({"system/particleDict:domain": {"min": [0, 0], "max": [0, 0]}}, "domain"),
])
def test_geometry_sanity(tmp_path, edit, key):
    from sphfoam.case.edit import clone_case

    case = clone_case(TUTORIALS / "damBreak", tmp_path / "c", edit)
    with pytest.raises(CaseError) as e:
        check_case(case)
    assert any(p.file == "system/particleDict" and p.key.startswith(key)
               for p in e.value.problems), str(e.value)
    if key == "dx":
        assert "memory" in str(e.value) and "particles" in str(e.value)


def test_fluid_outside_the_tank(tmp_path):
    case = tmp_path / "c"
    shutil.copytree(TUTORIALS / "hydrostaticTank", case)
    text = (case / "system" / "particleDict").read_text()
    import re

    # move the first fluid box 10 m to the right, out of the tank
    m = re.search(r"fluid\s*\{.*?max\s*\(([^)]*)\)", text, re.S)
    x, y = m[1].split()[:2]
    text = text[:m.start(1)] + f"{float(x) + 10:g} {y}" + text[m.end(1):]
    (case / "system" / "particleDict").write_text(text)
    with pytest.raises(CaseError) as e:
        check_case(case)
    assert "outside the tank" in str(e.value)


def test_ctrl_c_twice_tells_the_truth(tutorial):
    """Two SIGINTs at once: either the state was written (and the directory is complete)
    or the message says it was not (and no new directory appeared). On a loaded machine the
    signals may even arrive before the time loop: that, too, must say NOT written."""
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
    time.sleep(0.003)             # two presses at once are one signal to Python
    proc.send_signal(signal.SIGINT)
    out = proc.communicate(timeout=60)[0].decode()
    assert proc.returncode == 130, out
    assert "Traceback" not in out
    later = [p for t, p in list_times(case) if t > 0]
    if "NOT written" in out:
        assert not later
    else:
        assert "was written to" in out and len(later) == 1
        assert check_time_dir(later[0])[0] is None
    assert not (case / LOCK_FILE).exists()


@pytest.mark.parametrize("where", ["mid-step", "during the write"])
def test_second_ctrl_c_is_reported_as_not_written(tutorial, monkeypatch, where):
    """The second Ctrl-C (simulated): mid-step, or while the state is being written. The run
    ends with Interrupted(written=None) and leaves no new time directory behind."""
    import sphfoam.timeloop as runner

    case = tutorial("damBreak", {"system/particleDict:dx": 0.0125,
                                 "system/controlDict:writeInterval": 10.0,
                                 "system/controlDict:endTime": 20.0,
                                 "system/controlDict:functions": {}})

    class Stop(runner._StopRequest):
        checks = 0

        @property
        def requested(self):
            Stop.checks += 1
            return Stop.checks > 5

        @requested.setter
        def requested(self, v):
            pass

    monkeypatch.setattr(runner, "_StopRequest", Stop)
    if where == "mid-step":
        monkeypatch.setattr(Stop, "hard", True, raising=False)
        Stop.__init__ = lambda self: setattr(self, "_previous", None)
    else:
        real = runner.write_time

        def interrupted_write(case, state, t, *a, **k):
            if t > 0:
                raise KeyboardInterrupt
            return real(case, state, t, *a, **k)

        monkeypatch.setattr(runner, "write_time", interrupted_write)
    with pytest.raises(runner.Interrupted) as e:
        run_case(case, progress=False, echo=None)
    assert e.value.written is None and e.value.latest == "0"
    assert [p.name for _, p in list_times(case)] == ["0"]
    assert "NOT written" in (case / "log.sphfoam").read_text()
    assert not (case / LOCK_FILE).exists()


def test_second_ctrl_c_inside_a_finaliser_prints_no_traceback():
    """A KeyboardInterrupt raised by the second Ctrl-C inside a ``__del__`` (numba's compiler
    freeing LLVM objects) is not printed as an "Exception ignored" traceback once a stop is
    requested; other unraisable exceptions still reach the previous hook."""
    import sys

    from sphfoam.timeloop import _StopRequest

    seen = []
    old = sys.unraisablehook
    sys.unraisablehook = seen.append
    try:
        stop = _StopRequest()

        class Finaliser:
            def __init__(self, exc):
                self.exc = exc

            def __del__(self):
                raise self.exc

        stop.requested = stop.hard = True
        Finaliser(KeyboardInterrupt())            # dropped: the loop stops at the next step
        Finaliser(ValueError("real"))             # passed on
        stop.restore()
        assert sys.unraisablehook == seen.append
    finally:
        sys.unraisablehook = old
    assert [type(u.exc_value) for u in seen] == [ValueError]
