"""``sphfoam render``: PNG frames of the right size, one colour range over all frames, grey
walls, a GIF with one frame per time; clear errors for a bad field or no results."""

from __future__ import annotations

import re

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.cli import app
from sphfoam.render import ffmpeg_available, render_case
from sphfoam.io.timedirs import write_time
from sphfoam.setup import setup_case

VIRIDIS_LOW, VIRIDIS_HIGH = (68, 1, 84), (253, 231, 37)
GREY = (154, 154, 154)


@pytest.fixture
def three_times(tutorial):
    """damBreak at dx = 0.05 (25 fluid particles): t = 0 at rest, t = 0.1 with every fluid
    particle at |U| = 2 m/s, t = 0.2 with |U| = 1 m/s and the column shifted right."""
    path = tutorial("damBreak", {"system/particleDict:dx": 0.05})
    case = Case(path)
    st = setup_case(case, log=lambda m: None)
    fl = st.kind == 0
    st.u[fl] = 2.0
    p = 1000 * 9.81 * (0.25 - st.y)
    write_time(case, st, 0.1, 10, 1e-3, p=p)
    st.u[fl], st.v[fl] = 0.6, 0.8
    st.x[fl] += 0.5
    write_time(case, st, 0.2, 20, 1e-3, p=p)
    return path


def colours(png) -> set:
    """The colours of a frame left of the colour bar (the right 110 px)."""
    a = np.asarray(Image.open(png).convert("RGB"), dtype=int)[:, :-110]
    return {tuple(c) for c in a.reshape(-1, 3)}


def near(cols, rgb, tol=6) -> bool:
    return any(max(abs(a - b) for a, b in zip(c, rgb)) <= tol for c in cols)


def test_frames_size_fixed_range_grey_walls_and_gif(three_times):
    r = render_case(three_times, movie="gif", width=640, log=lambda m: None)
    assert [p.name for p in r.frames] == ["0.png", "0.1.png", "0.2.png"]
    assert all(p.parent == three_times / "postProcessing/render/U" for p in r.frames)
    sizes = {Image.open(p).size for p in r.frames}
    assert len(sizes) == 1
    (w, h), = sizes
    assert w == 640 and 100 < h < 640                 # a wide tank: landscape frames
    assert (r.vmin, r.vmax) == (0.0, 2.0)             # min..max over all frames
    c0, c1, c2 = (colours(p) for p in r.frames)
    assert near(c0, GREY) and near(c1, GREY)          # the tank's walls
    assert near(c0, VIRIDIS_LOW) and not near(c0, VIRIDIS_HIGH)   # at rest: the low end
    assert near(c1, VIRIDIS_HIGH) and not near(c1, VIRIDIS_LOW)   # 2 m/s: the high end
    assert not near(c2, VIRIDIS_HIGH) and not near(c2, VIRIDIS_LOW)  # 1 m/s: in between
    gif = Image.open(r.movie)
    assert r.movie == three_times / "postProcessing/render/U.gif"
    assert gif.n_frames == 3 and gif.size == (w, h)


def test_field_range_times_and_no_movie(three_times):
    r = render_case(three_times, "Ux", times=[0.1, 0.2], movie="none",
                    value_range=(-1.0, 1.0), log=lambda m: None)
    assert [p.name for p in r.frames] == ["0.1.png", "0.2.png"] and r.movie is None
    assert (r.vmin, r.vmax) == (-1.0, 1.0)
    assert near(colours(r.frames[0]), VIRIDIS_HIGH)   # Ux = 2 clipped to the top of the range


def test_box_sets_the_view_and_the_colour_range(three_times):
    """Only y < 0.1 (the two lowest rows of fluid, y = 0.025 and 0.075): the range of p =
    rho0 g (0.25 - y) comes from them alone; the axes keep the box's aspect."""
    r = render_case(three_times, "p", box=(-0.1, -0.1, 0.9, 0.1), movie="none", width=500,
                    log=lambda m: None)
    assert r.vmin == pytest.approx(9810 * 0.175) and r.vmax == pytest.approx(9810 * 0.225)
    w, h = Image.open(r.frames[0]).size
    assert w == 500 and h == round((500 - 180) * 0.2) + 90
    full = render_case(three_times, "p", movie="none", log=lambda m: None)
    assert full.vmin == pytest.approx(9810 * 0.025)
    with pytest.raises(CaseError, match="x1 > x0"):
        render_case(three_times, box=(1, 0, 0, 1), movie="none", log=lambda m: None)


def test_bad_field_and_no_results_are_clear_errors(three_times, tutorial):
    with pytest.raises(CaseError) as e:
        render_case(three_times, "speed", movie="none", log=lambda m: None)
    assert "'speed' is not a field" in str(e.value) and "Ux" in str(e.value) \
        and "rho" in str(e.value)
    with pytest.raises(CaseError) as e:
        render_case(tutorial("hydrostaticTank"), movie="none", log=lambda m: None)
    assert "no time directory with particles" in str(e.value)


def test_mp4_with_ffmpeg_or_a_clear_error(three_times):
    if ffmpeg_available():
        r = render_case(three_times, movie="mp4", log=lambda m: None)
        assert r.movie.suffix == ".mp4" and r.movie.stat().st_size > 0
    else:
        with pytest.raises(CaseError, match="mp4 needs ffmpeg"):
            render_case(three_times, movie="mp4", log=lambda m: None)


def test_cli_render(three_times):
    r = CliRunner().invoke(app, ["render", str(three_times), "-f", "p", "--movie", "gif",
                                 "--width", "400"])
    assert r.exit_code == 0, r.output
    assert "3 frame(s) of p (Pa)" in r.output      # 0/ was written with p by setup
    assert Image.open(three_times / "postProcessing/render/p/0.png").size[0] == 400
    r = CliRunner().invoke(app, ["render", str(three_times), "-f", "nope"])
    assert r.exit_code != 0 and "Traceback" not in r.output and "'nope'" in r.output
    r = CliRunner().invoke(app, ["render", str(three_times), "--movie", "avi"])
    text = re.sub(r"[│╭╮╰╯─\s]+", " ", r.output)           # the error panel, unwrapped
    assert r.exit_code == 2 and "'avi' is not one of 'auto', 'gif', 'mp4', 'none'" in text
