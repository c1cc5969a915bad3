"""Time-directory helpers for OpenFOAM-style case directories.

A case stores its state in directories named after the simulation time
(``0``, ``0.5``, ``1e-05``, ...) next to ``constant/`` and ``system/``.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

__all__ = ["time_name", "list_times", "latest_time"]

# A plain decimal number, optionally signed and with an exponent. Stricter than
# float() on purpose: rejects "nan", "inf" and "1_000" as time names.
_TIME_RE = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$")


def time_name(t: float, precision: int = 6) -> str:
    """Directory name for time ``t``, like C++ ``ostream`` general format.

    >>> time_name(0.1 + 0.2), time_name(1.0), time_name(1e-5)
    ('0.3', '1', '1e-05')
    """
    if t == 0:  # also maps -0.0 to "0"
        return "0"
    return f"{t:.{precision}g}"


def list_times(case_dir: str | Path) -> list[tuple[float, Path]]:
    """All time directories of a case as ``(time, path)``, sorted by time.

    Subdirectories whose names are not numbers (``constant``, ``system``,
    ``VTK``, ...) are ignored.
    """
    out = []
    case_dir = Path(case_dir)
    if not case_dir.is_dir():
        return out
    for p in case_dir.iterdir():
        if p.is_dir() and _TIME_RE.match(p.name):
            t = float(p.name)
            if math.isfinite(t):
                out.append((t, p))
    out.sort(key=lambda tp: (tp[0], tp[1].name))
    return out


def latest_time(case_dir: str | Path) -> tuple[float, Path] | None:
    """The latest ``(time, path)`` of a case, or ``None`` if it has none."""
    times = list_times(case_dir)
    return times[-1] if times else None
