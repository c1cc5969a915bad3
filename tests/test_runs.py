"""Whole runs of the tutorials at coarse resolution: physics and restart continuity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sphfoam.case.case import Case
from sphfoam.case.times import list_times
from sphfoam.io.fields import read_state
from sphfoam.timeloop import run_case
from sphfoam.sampling.damBreak import martin_moyce

RHO0, G = 1000.0, 9.81


def test_restart_equals_uninterrupted_run(tutorial):
    """Run to T, stop, resume with startFrom latestTime to 2T == a straight run to 2T."""
    edits = {"system/particleDict:dx": 0.0125, "system/controlDict:writeInterval": 0.02,
             "system/controlDict:functions": {}}
    straight = tutorial("damBreak", edits)
    run_case(straight, progress=False, echo=None, end_time=0.04)
    split = straight.parent / "split"
    import shutil

    shutil.copytree(straight, split, ignore=shutil.ignore_patterns("0.*", "log.*"))
    run_case(split, progress=False, echo=None, end_time=0.02)
    assert [p.name for _, p in list_times(split)] == ["0", "0.02"]
    run_case(split, progress=False, echo=None, end_time=0.04)   # latestTime: continues
    a = read_state(straight / "0.04")
    b = read_state(split / "0.04")
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=f"field {k} differs after restart")
    assert (split / "0.04" / "uniform" / "time").read_text() == \
        (straight / "0.04" / "uniform" / "time").read_text()


def test_hydrostatic_tank_stays_at_rest(tutorial):
    """H/dx = 40: bed pressure within 2 % of rho g H, nobody crosses a wall, KE decays."""
    case = tutorial("hydrostaticTank", {"system/controlDict:endTime": 1.5,
                                        "system/controlDict:writeInterval": 0.25})
    run_case(case, progress=False, echo=None)
    H, W = 0.4, 0.5
    kes = []
    for t, folder in list_times(case)[1:]:
        s = read_state(folder)
        f = s["type"] == 0
        x, y = s["positions"][f].T
        # no particle through a wall (walls' inner faces at x = 0, x = W, y = 0)
        assert x.min() > 0 and x.max() < W and y.min() > 0, f"particle in a wall at t={t}"
        u = s["U"][f]
        kes.append(0.5 * np.sum(s["mass"][f] * (u ** 2).sum(axis=1)))
    assert len(kes) == 6
    # bed pressure: what the bed carries, the mean pressure of the first wall row under the
    # fluid (y = -dx/2, 0 < x < W), against rho g H
    s = read_state(list_times(case)[-1][1])
    x, y = s["positions"].T
    first_row = (s["type"] == 1) & (y > -0.01) & (y < 0) & (x > 0) & (x < W)
    assert s["p"][first_row].mean() == pytest.approx(RHO0 * G * H, rel=0.02)
    # inside the fluid: the bottom row (measured +1.3 % at 1.5 s with the quartic kernel;
    # Wendland C2 at h = 1.3 dx, whose lattice gradient is 2.6 % low, gives +3 to +4 %)
    f = s["type"] == 0
    bottom = f & (y < 0.01)
    assert s["p"][bottom].mean() == pytest.approx(RHO0 * G * (H - 0.005), rel=0.03)
    # the lattice settles into its SPH equilibrium (KE peaks near 0.75 s), then KE decays
    peak = int(np.argmax(kes))
    assert peak < len(kes) - 1 and kes[-1] < 0.5 * kes[peak]
    m_total = s["mass"][f].sum()
    assert math.sqrt(2 * kes[-1] / m_total) < 0.01 * math.sqrt(G * H)


def test_dam_break_follows_martin_moyce(tutorial):
    """Coarse (H0/dx = 25) collapse: front and residual height against Martin & Moyce."""
    case = tutorial("damBreak", {"system/particleDict:dx": 0.01,
                                 "system/controlDict:endTime": 0.35,
                                 "system/controlDict:writeInterval": 0.35,
                                 "system/controlDict:functions.front.plot": "no",
                                 "system/controlDict:functions.front.heightBand": [0.03, 0.05]})
    run_case(case, progress=False, echo=None)
    dat = case / "postProcessing" / "front" / "0" / "front.dat"
    rows = np.loadtxt(dat)
    assert rows.shape[1] == 8 and rows[0, 0] == 0.0      # time T z Z h H stuck gap
    T, Z, Hn = rows[:, 1], rows[:, 3], rows[:, 5]
    assert np.all(np.diff(Z) >= -1e-9), "front moved backwards"
    front, height = martin_moyce()
    sel = (T > 0.8) & (T < 2.2)
    # measured at H0/dx = 40: front within 5 %, height within 7 % over 0.5 < T < 2.5;
    # at this test's H0/dx = 25: front 8 %, height 11.6 %. The release time of the
    # experiment is itself uncertain by ~0.1 in T.
    zf = np.interp(T[sel], front[:, 0], front[:, 1])
    assert np.max(np.abs(Z[sel] - zf) / zf) < 0.10
    hh = np.interp(T[sel], height[:, 0], height[:, 1])
    assert np.max(np.abs(Hn[sel] - hh) / hh) < 0.15
