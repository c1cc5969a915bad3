"""Paths a dictionary names, kept inside the case (or study) directory.

* A *name* that becomes a folder or file name (a function object's, a study variant's or a
  run's) is one plain path component: letters, digits and ``_ . + - @ ,``, not starting
  with a dot (so never ``..``, ``/abs`` or ``a/b``).
* A *relative file* (a displacement table) is resolved against the case, symlinks followed,
  and must stay inside it; an absolute path is only accepted where a key's documentation
  says so (``absolute=True``), and must then be a regular file too (``/dev/zero``,
  ``/dev/stdin``, fifos and directories are refused).
"""

from __future__ import annotations

import re
import stat
from pathlib import Path

__all__ = ["check_name", "NAME_RULE", "inside", "resolve_file"]

_NAME = re.compile(r"[A-Za-z0-9_+@,-][A-Za-z0-9_.+@,-]*")
NAME_RULE = ("a plain name: letters, digits and _ . + - @ , (not starting with a dot, no "
             "'/' or '..')")


def check_name(name) -> str:
    """``name`` if it is a safe single path component, else ValueError saying why."""
    s = str(name)
    if not _NAME.fullmatch(s) or len(s) > 200:
        raise ValueError(f"{s!r} is not {NAME_RULE}")
    return s


def inside(path: Path, root: Path) -> bool:
    """True when ``path`` (resolved, symlinks followed) is ``root`` or lies below it."""
    p, r = Path(path).resolve(), Path(root).resolve()
    return p == r or r in p.parents


def resolve_file(case_path: Path, name: str, absolute: bool = False) -> Path:
    """The regular file ``name`` names (relative to ``case_path``); ValueError saying why
    not (outside the case, a special file, missing)."""
    p = Path(str(name)).expanduser() if absolute else Path(str(name))
    if p.is_absolute():
        if not absolute:
            raise ValueError(f"{name}: an absolute path is not accepted here; name a file "
                             "inside the case, relative to it")
        f = p.resolve()
    else:
        f = (Path(case_path) / p).resolve()
        if not inside(f, case_path):
            raise ValueError(f"{name}: lies outside the case {Path(case_path).resolve()}"
                             + ("; give an absolute path to use a file elsewhere on purpose"
                                if absolute else ""))
    try:
        mode = f.stat().st_mode
    except OSError:
        raise ValueError(f"{name}: no such file") from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"{name}: not a regular file (a directory, device or pipe is not "
                         "read)")
    return f
