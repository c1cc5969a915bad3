"""When the water reaches the box in damBreak3D runs: the first time the force on it exceeds
1 N, the first time P1 exceeds 2 kPa, and P1's largest reading before 0.7 s (value, time).

    python onset.py RUN ...     (a folder holding force.dat[.gz] and sensors.dat[.gz], or a
                                 case with its postProcessing)
"""
import sys
from pathlib import Path

import numpy as np


def series(folder: Path, name: str, function: str) -> np.ndarray:
    """The folder's ``name``.dat[.gz], or its case's postProcessing/``function``/0/``name``.dat."""
    path = next(iter(sorted(folder.glob(f"{name}.dat*"))
                     + [folder / "postProcessing" / function / "0" / f"{name}.dat"]))
    return np.loadtxt(path)          # reads .gz and the sensors' nan as they are


for arg in sys.argv[1:]:
    d = Path(arg)
    F, S = series(d, "force", "boxForce"), series(d, "sensors", "sensors")
    t, ts, p1 = F[:, 0], S[:, 0], S[:, 1]
    i = np.flatnonzero(np.abs(F[:, 1]) > 1.0)
    j = np.flatnonzero(np.nan_to_num(p1) > 2000)
    early = np.where(ts < 0.7, p1, np.nan)
    force = f"{t[i[0]]:.3f} s" if i.size else "never"
    onset = f"{ts[j[0]]:.3f} s" if j.size else "never"
    if np.isfinite(early).any():
        k = np.nanargmax(early)
        peak = f"{p1[k] / 1000:.1f} kPa at {ts[k]:.3f} s"
    else:
        peak = "no reading"
    print(f"{arg:<40} force > 1 N at {force}, P1 > 2 kPa at {onset}, "
          f"P1's largest before 0.7 s {peak}")
