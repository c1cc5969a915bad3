"""Reading function-object output: the ``postProcessing/<name>/<startTime>/<file>.dat``
tables (a ``#`` header whose last line names the tab-separated columns)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def read_table(path: Path) -> tuple[list[str], np.ndarray]:
    """(columns, rows) of a function-object file: ``#`` header lines, the last naming the
    tab-separated columns; rows of another length (a line cut short) are skipped."""
    cols: list[str] = []
    rows: list[list[float]] = []
    for line in Path(path).read_text().splitlines():
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            cols = [c.strip() for c in s[1:].strip().split("\t")]
            continue
        try:
            rows.append([float(v) for v in s.split()])
        except ValueError:
            continue
    rows = [r for r in rows if len(r) == len(cols)]
    return cols, np.array(rows, dtype=float).reshape(len(rows), len(cols))


def start_folders(case_path: Path, function: str) -> list[tuple[float, Path]]:
    """(start time, folder) of ``postProcessing/<function>/<startTime>/``, oldest first."""
    root = Path(case_path) / "postProcessing" / function
    out = []
    if root.is_dir():
        for p in root.iterdir():
            try:
                t = float(p.name)
            except ValueError:
                continue
            if p.is_dir():
                out.append((t, p))
    return sorted(out, key=lambda tp: tp[0])


def join_series(folders: list[tuple[float, Path]], filename: str
                ) -> tuple[list[str], np.ndarray]:
    """(columns, rows) of one time series over start-time folders (oldest first), as
    OpenFOAM's post-processing joins a restarted run's: each older folder's rows before the
    next folder's start time, then the newest folder's. The columns are the newest file's;
    an older folder without the file, or with other columns, is left out."""
    cols, last = read_table(folders[-1][1] / filename)
    parts = []
    for (_, folder), (t1, _) in zip(folders[:-1], folders[1:]):
        f = folder / filename
        if not f.is_file():
            continue
        c, d = read_table(f)
        if c == cols:
            parts.append(d[d[:, 0] < t1 - 1e-9 * max(1.0, abs(t1))])
    return cols, (np.vstack(parts + [last]) if parts else last)
