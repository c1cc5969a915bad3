"""RMS height errors of two gauge series against SPHERIC Test 2's measurement, by window.

    python rms_windows.py h30_to1.5s_heights.dat h30_to1.5s_heightsWire.dat \
        ../../../../tutorials/damBreak3D/validation/test_case_2_exp_data.dat
    python rms_windows.py ../H30-6s/heights.dat ../H30-6s/heightsWire.dat \
        ../../../../tutorials/damBreak3D/validation/test_case_2_exp_data.dat

A dry gauge (NaN) reads 0, as the tutorial's metrics (missing zero). The measurement's
columns for H1-H4 are 11, 10, 9 and 12 (its README: the labels are the wrong way round).
"""

import sys

import numpy as np

COLUMNS = {1: 11, 2: 10, 3: 9, 4: 12}


def series(path):
    return np.loadtxt(path, comments="#", ndmin=2)


def measured(path):
    rows = [line.split() for line in open(path)
            if line.strip() and not line.lstrip()[0].isalpha() and not line.startswith("#")]
    return np.array([[float(v) for v in r] for r in rows])


def main(a, b, meas):
    sa, sb, m = series(a), series(b), measured(meas)
    end = min(sa[-1, 0], sb[-1, 0])
    windows = [(0.0, end)] + [(lo, min(hi, end)) for lo, hi in
                              ((0.0, 0.6), (0.6, 1.3), (1.3, 2.2), (2.2, 3.2), (3.2, 6.0))
                              if lo < end]
    for lo, hi in windows:
        out = []
        for g, col in COLUMNS.items():
            for name, s in ((a, sa), (b, sb)):
                sel = (s[:, 0] >= lo) & (s[:, 0] <= hi)
                err = np.nan_to_num(s[sel, g]) - np.interp(s[sel, 0], m[:, 0], m[:, col])
                out.append(f"H{g} {name}: {np.sqrt(np.mean(err ** 2)):.3f}")
        print(f"{lo:g}-{hi:g} s | " + " | ".join(out))


if __name__ == "__main__":
    main(*sys.argv[1:4])
