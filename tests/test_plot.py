"""``sphfoam plot``: one figure per function object (gauges, probes, lines, run-up, crest,
dam-break front, velocity profile), each against its reference; the references themselves
against their formulas. The function objects are evaluated with ``sphfoam sample`` on time
directories written by hand (a translated wave, a spreading column), so no solver runs."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.edit import set_entry
from sphfoam.case.errors import CaseError
from sphfoam.cli import app
from sphfoam.postprocess import plot_case, run_up_reference, sample
from sphfoam.io.timedirs import write_time
from sphfoam.setup import setup_case

quiet = dict(log=lambda m: None)


def _times(case_dir, shift, times):
    """Write ``times`` with the fluid of 0/ moved by shift(t) in x (walls stay)."""
    case = Case(case_dir)
    st = setup_case(case, **quiet)
    x0 = st.x.copy()
    fl = st.kind == 0
    for i, t in enumerate(times, start=1):
        st.x[fl] = x0[fl] + shift(t)
        write_time(case, st, t, 10 * i, 1e-3, p=1000 * 9.81 * (10 - st.y))
    return case


WAVE_FUNCTIONS = {
    "gauges": {"type": "waveGauges", "x": [-20.0, 0.0, 20.0], "still": 10.0},
    "probe": {"type": "probes", "points": [[0.0, 5.0], [10.0, 5.0]]},
    "crestLine": {"type": "lines", "follow": "crest", "nPoints": 5},
    "fixedLines": {"type": "lines", "x": [0.0, 10.0], "nPoints": 5},
    "runUp": {"type": "runUp", "mode": "wall", "x": 100.0, "still": 10.0},
    "crest": {"type": "crestTracker", "still": 10.0, "xMin": -60.0, "xMax": 60.0},
}


def test_one_figure_per_function_object_of_a_wave_case(tutorial):
    path = tutorial("solitaryWallRunup", {"system/particleDict:dx": 2.5,
                                          "system/controlDict:functions": WAVE_FUNCTIONS})
    c = 9.81 ** 0.5 * 13 ** 0.5                              # about the crest speed
    _times(path, lambda t: c * t, [0.5, 1.0, 1.5])
    sample(path, **quiet)
    lines = []
    pngs = plot_case(path, theory="kdv2", log=lines.append)
    names = sorted(p.name for p in pngs)
    assert names == sorted(["gauges_kdv2.png", "probe.png", "crestLine.png", "fixedLines.png",
                            "runUp.png", "crest.png"])
    for p in pngs:
        assert p.parent.parent.parent == path / "postProcessing" or \
            p.parent.parent.parent.parent == path / "postProcessing"
        w, h = Image.open(p).size
        assert w > 400 and h > 200
    # only the objects asked for
    assert [p.name for p in plot_case(path, ["runUp"], **quiet)] == ["runUp.png"]
    with pytest.raises(CaseError, match="no such function object; defined: gauges"):
        plot_case(path, ["nope"], **quiet)


def test_dam_break_front_profile_and_missing_output(tutorial):
    path = tutorial("damBreak", {"system/particleDict:dx": 0.05,
                                 "system/controlDict:functions.front.plot": "no"})
    _times(path, lambda t: 2.0 * t, [0.05, 0.1])
    with pytest.raises(CaseError, match="no output of front"):
        plot_case(path, **quiet)
    sample(path, **quiet)
    (png,) = plot_case(path, **quiet)
    assert png == path / "postProcessing/front/0/front.png"
    # gauges in a case without a wave: the others are drawn, the gauges reported
    set_entry(path, "system/controlDict", "functions.gauges",
              {"type": "waveGauges", "x": [0.1, 0.5]})
    sample(path, ["gauges"], **quiet)
    said = []
    assert [p.name for p in plot_case(path, log=said.append)] == ["front.png"]
    assert any(m.startswith("not plotted:") and "no wave height" in m for m in said), said
    with pytest.raises(CaseError, match="no wave height"):
        plot_case(path, ["gauges"], **quiet)

    pois = tutorial("poiseuille")
    Case(pois).validate()
    st = setup_case(Case(pois), **quiet)
    st.u[:] = np.where(st.kind == 0, 4.0 * st.y * (0.01 - st.y) / 0.01 ** 2 * 1e-4, 0.0)
    write_time(Case(pois), st, 1.0, 10, 1e-4, p=np.zeros(st.n))
    sample(pois, **quiet)
    (png,) = plot_case(pois, **quiet)
    assert png.name == "profile.png"


def test_references():
    """Run-up: 2A, Su & Mirie's third order and the fully nonlinear potential flow on a wall
    (A/d = 0.3: 0.66525 d and 0.66020 d); Synolakis's law on a beach."""
    ref = dict(run_up_reference("wall", 3.0, 10.0))
    assert ref["linear theory, 2A"] == 6.0
    assert ref["Su & Mirie (1980), third order"] == pytest.approx(6.6525)
    assert ref["potential flow, fully nonlinear (HOS)"] == pytest.approx(6.6020, abs=1e-3)
    assert len(run_up_reference("wall", 6.0, 10.0)) == 2      # beyond the methods' range
    ((_, R),) = run_up_reference("beach", 0.1, 1.0, angle=math.degrees(math.atan(1 / 19.85)))
    assert R == pytest.approx(2.831 * math.sqrt(19.85) * 0.1 ** 1.25, rel=1e-9)


def test_cli_plot_all_and_one(tutorial):
    path = tutorial("damBreak", {"system/particleDict:dx": 0.05,
                                 "system/controlDict:functions.front.plot": "no"})
    _times(path, lambda t: 2.0 * t, [0.05])
    r = CliRunner().invoke(app, ["plot", str(path)])
    text = re.sub(r"[│╭╮╰╯─\s]+", " ", r.output)          # the error panel, unwrapped
    assert r.exit_code != 0 and "no output of front" in text and "Traceback" not in text
    sample(path, **quiet)
    r = CliRunner().invoke(app, ["plot", str(path), "-f", "front"])
    assert r.exit_code == 0, r.output
    assert "front: postProcessing/front/0/front.png" in r.output
