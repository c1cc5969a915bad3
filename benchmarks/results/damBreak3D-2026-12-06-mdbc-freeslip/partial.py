"""The wire gauges' RMS error over 0-T s of damBreak3D runs (a stopped run, or others over the
same window as one):

    python partial.py T heightsWire.dat ...
"""
import sys
from pathlib import Path

import numpy as np

MEASURED = Path(__file__).resolve().parents[3] / \
    "tutorials/damBreak3D/validation/test_case_2_exp_data.dat"

e = np.loadtxt(MEASURED, skiprows=1)
te = e[:, 0]
meas = [e[:, 11], e[:, 10], e[:, 9], e[:, 12]]          # H1, H2, H3, H4 (labels swapped)
T = float(sys.argv[1])
keep = te <= T
for f in sys.argv[2:]:
    d = np.loadtxt(f)
    rms = [np.sqrt(np.mean((np.interp(te[keep], d[:, 0], np.nan_to_num(d[:, g + 1]))
                            - meas[g][keep]) ** 2)) for g in range(4)]
    print(f"{f:<60}", " ".join(f"{v:.3f}" for v in rms))
