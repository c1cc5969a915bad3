"""Time directories that are never half-written, and a lock on a running case.

A time directory is written whole under a hidden temporary name beside its final place
(``<case>/.<name>.writing-<pid>``: no time name, so no reader ever takes it for a time) and
renamed into place only once every particle field and ``uniform/time`` are on disk. A kill,
a full disk or a read-only case therefore leaves either the complete directory or none.
``uniform/time`` lists the fields written with it (``fields``) and the particle count
(``particles``): a restart checks a directory against that list before using it, so a
directory written by hand, by an older sphfoam or by another tool is only used when it is
complete (:func:`check_time_dir`).

The lock (``<case>/.sphfoam.lock``, holding the pid and host of the run) makes a second
``sphfoam run`` on the same case refuse to start; a lock left by a process that no longer
exists is taken over.
"""

from __future__ import annotations

import errno
import os
import shutil
import socket
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sphfoam.case import foamdict
from sphfoam.case.errors import CaseError
from sphfoam.case.times import list_times, time_name
from sphfoam.io.fields import CLOUD_DIR, has_particles, read_state, write_state

if TYPE_CHECKING:
    from sphfoam.case.case import Case
    from sphfoam.engine.state import ParticleState

__all__ = ["write_time_dir", "check_time_dir", "recover", "case_lock", "CaseLocked", "REQUIRED_FIELDS",
           "LOCK_FILE"]

#: fields every time directory must hold (ParticleState.to_fields writes them all)
REQUIRED_FIELDS = ("positions", "U", "rho", "mass", "type", "origId")
LOCK_FILE = ".sphfoam.lock"
#: the layout before settling (sphfoam.setup.settling): no time name, so no reader of time
#: directories (restarts, sampling, ParaView's time series) takes it for a time
UNSETTLED = "0.unsettled"


def _fsync_tree(root: Path) -> None:
    """Flush every file and directory of ``root`` to disk (a power cut after the rename must
    not leave a renamed directory of empty files)."""
    for dirpath, _dirs, files in os.walk(root):
        for name in files:
            fd = os.open(os.path.join(dirpath, name), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        _fsync_dir(Path(dirpath))


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:         # some file systems cannot fsync a directory: nothing to do
        pass
    finally:
        os.close(fd)


def write_time_dir(case_path: Path, name: str, fields: dict[str, np.ndarray],
                   time: dict, *, fmt: str = "binary", precision: int = 6) -> Path:
    """Write the time directory ``case_path/name`` atomically: the fields and
    ``uniform/time`` (``time``: value, index, deltaT) go to a temporary directory beside it,
    which is then renamed into place. An existing directory of that name is replaced whole.
    On any error (or a Ctrl-C) the temporary directory is removed and the error raised; the
    case is as it was."""
    case_path = Path(case_path)
    final = case_path / name
    tmp = case_path / f".{name}.writing-{os.getpid()}"
    old = case_path / f".{name}.replaced-{os.getpid()}"
    try:
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir()
        write_state(tmp, fields, fmt=fmt, precision=precision)
        n = len(next(iter(fields.values()))) if fields else 0
        entries = {**time, "name": foamdict.QuotedString(name), "particles": int(n),
                   "fields": [foamdict.QuotedString(k) for k in sorted(fields)]}
        foamdict.write(tmp / "uniform" / "time", entries,
                       header={"class": "dictionary", "location": f"{name}/uniform",
                               "object": "time"})
        _fsync_tree(tmp)
        if final.exists() or final.is_symlink():
            if not final.is_dir() or final.is_symlink():
                raise FileExistsError(errno.EEXIST, "exists and is not a time directory",
                                      str(final))
            os.rename(final, old)
        os.rename(tmp, final)
        _fsync_dir(case_path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old.exists() and not final.exists():
            os.rename(old, final)           # put the replaced directory back
        raise
    shutil.rmtree(old, ignore_errors=True)
    return final


def read_time_dict(folder: Path) -> dict:
    """``uniform/time`` of a time directory; ValueError (with the reason) when it is missing
    or unreadable."""
    f = Path(folder) / "uniform" / "time"
    if not f.is_file():
        raise ValueError("uniform/time is missing")
    try:
        d = foamdict.read(f)
    except (ValueError, OSError) as e:      # FoamDictError and UnicodeDecodeError included
        raise ValueError(f"uniform/time is unreadable ({type(e).__name__})") from None
    try:
        float(d["value"])
        int(d.get("index", 0))
    except (KeyError, TypeError, ValueError):
        raise ValueError("uniform/time has no valid 'value'/'index'") from None
    return d


def check_time_dir(folder: Path, read: bool = True):
    """Why ``folder`` cannot be restarted from, or None when it is complete.

    Complete: ``uniform/time`` parses with a time value and step index, every field it lists
    (at least :data:`REQUIRED_FIELDS`) is present and readable, and all fields have the same
    particle count (the one ``uniform/time`` records). Returns ``(reason, fields)``; fields
    is the ``{name: array}`` read, or None.
    """
    folder = Path(folder)
    try:
        d = read_time_dict(folder)
    except ValueError as e:
        return str(e), None
    if not (folder / CLOUD_DIR).is_dir():
        return f"{CLOUD_DIR.as_posix()} is missing", None
    listed = [str(k) for k in d.get("fields", [])] if isinstance(d.get("fields"), list) else []
    want = list(dict.fromkeys([*REQUIRED_FIELDS, *listed]))
    have = {p.name for p in (folder / CLOUD_DIR).iterdir()}
    missing = [k for k in want if k not in have]
    if missing:
        return f"missing particle field(s): {', '.join(missing)}", None
    if not read:
        return None, None
    try:
        fields = read_state(folder)
    except (ValueError, OSError) as e:
        return f"unreadable field: {e}", None
    counts = {k: len(a) for k, a in fields.items()}
    n = d.get("particles", counts["positions"])
    bad = [k for k, c in counts.items() if c != n]
    if bad:
        return (f"field(s) {', '.join(bad)} do not hold {n} particles (a partial write?)",
                None)
    return None, fields


# --- the lock ---------------------------------------------------------------------------------
class CaseLocked(CaseError):
    """Another live process runs the case."""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:             # exists, owned by someone else
        return True
    return True


def _read_lock(f: Path) -> tuple[int | None, str]:
    try:
        words = f.read_text().split()
        return int(words[0]), (words[1] if len(words) > 1 else "")
    except (OSError, ValueError, IndexError):
        return None, ""


@contextmanager
def case_lock(case_path: Path, what: str = "run"):
    """Hold ``<case>/.sphfoam.lock`` for the duration; refuse (:class:`CaseLocked`) when a
    live process holds it, take it over from a dead one."""
    f = Path(case_path) / LOCK_FILE
    if _read_lock(f)[0] == os.getpid():     # this process holds it already (setup, then run)
        yield f
        return
    host = socket.gethostname()
    me = f"{os.getpid()} {host} {what}\n"
    for _attempt in range(3):
        try:
            fd = os.open(f, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            pid, lock_host = _read_lock(f)
            if pid is not None and (lock_host not in ("", host)
                                                           or _alive(pid)):
                raise CaseLocked.single(
                    LOCK_FILE, "", f"the case {case_path} is in use by process {pid}"
                    f"{' on ' + lock_host if lock_host and lock_host != host else ''}; wait "
                    f"for it to end (or, if no such process runs, delete {f})") from None
            if pid is None:
                # written this instant by another starting run, or garbage: look again once
                import time

                time.sleep(0.05)
                pid, _ = _read_lock(f)
                if pid is not None and _alive(pid):
                    continue
            f.unlink(missing_ok=True)       # stale: its process is gone
            continue
        with os.fdopen(fd, "w") as fh:
            fh.write(me)
        break
    else:
        raise CaseLocked.single(LOCK_FILE, "", f"could not take the lock {f}")
    try:
        yield f
    finally:
        pid, _ = _read_lock(f)
        if pid == os.getpid():
            f.unlink(missing_ok=True)


def recover(case_path: Path, log=None) -> None:
    """Tidy what a killed writer left (call with the lock held): a temporary
    ``.<name>.writing-<pid>`` is removed; a ``.<name>.replaced-<pid>`` (the old directory of a
    rewrite, moved aside the instant before the new one took its name) is put back when the
    new one never arrived, removed otherwise."""
    case_path = Path(case_path)
    try:
        entries = list(case_path.iterdir())
    except OSError:
        return
    for p in entries:
        name = p.name
        if not (name.startswith(".") and p.is_dir() and not p.is_symlink()):
            continue
        for tag in (".writing-", ".replaced-"):
            if tag in name and name[name.rindex(tag) + len(tag):].isdigit():
                pid = int(name[name.rindex(tag) + len(tag):])
                if _alive(pid) and pid != os.getpid():
                    break                   # another live writer's: not ours to touch
                target = case_path / name[1:name.rindex(tag)]
                if tag == ".replaced-" and not target.exists():
                    os.rename(p, target)
                    if log:
                        log(f"restored time directory {target.name} (a rewrite of it was "
                            f"interrupted)")
                else:
                    shutil.rmtree(p, ignore_errors=True)
                    if log:
                        log(f"removed {name}: the remains of an interrupted write")
                break


# --- a case's time directories ------------------------------------------------------------
def write_time(case: Case, state: ParticleState, t: float, index: int, dt: float, p=None,
               name: str | None = None) -> Path:
    """Write a time directory atomically (sphfoam.io.timedirs): complete or not at all."""
    c = case.control
    return write_time_dir(case.path, name or time_name(t, c.timePrecision), state.to_fields(p),
                          {"value": float(t), "index": int(index), "deltaT": float(dt)},
                          fmt=c.writeFormat, precision=c.writePrecision)


def read_time_value(folder: Path) -> tuple[float, int]:
    f = folder / "uniform" / "time"
    if f.is_file():
        d = read_time_dict(folder)
        return float(d["value"]), int(d.get("index", 0))
    return float(folder.name), 0


def start_folder(case: Case, log=None) -> Path | None:
    """The time directory to start from: the latest (startFrom latestTime) or startTime's,
    complete (sphfoam.io.timedirs.check_time_dir). Incomplete directories are skipped, each
    with a log line saying why; None when no directory has particles at all."""
    times = [(t, p) for t, p in list_times(case.path) if has_particles(p)]
    if not times:
        return None
    skipped = []
    if case.control.startFrom == "latestTime":
        for t, p in reversed(times):
            why, _ = check_time_dir(p)
            if why is None:
                break
            skipped.append((p, why))
            if log:
                log(f"skipping time directory {p.name}: {why}")
        else:
            raise CaseError.single(
                "system/controlDict", "startFrom", "no complete time directory to start from: "
                + "; ".join(f"{p.name}: {why}" for p, why in skipped)
                + " (run 'sphfoam setup --force' to start again from 0)")
        return p
    want = case.control.startTime
    for t, p in times:
        if abs(t - want) <= 1e-9 * max(1.0, abs(want)):
            why, _ = check_time_dir(p)
            if why is not None:
                raise CaseError.single("system/controlDict", "startTime",
                                       f"time directory {p.name} is incomplete: {why}")
            return p
    raise CaseError.single("system/controlDict", "startTime",
                           f"no time directory with particles at {want:g}; have: "
                           + ", ".join(p.name for _, p in times))
