"""Particles above a slope (T §5.3.4, Fig 5.2): the usual grid over the flat bed, a grid
rotated parallel to a 5 degree slope above it, the seam between them thinned, the bed's wall
rows parallel to the slope; and the errors of a bad ``grid``."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.cli import app
from sphfoam.setup.settling import setup_case
from sphfoam.setup.particles import seam_keep

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"

DX = 0.02
ANGLE = 5.0
TOE = 0.4             # x of the toe of the slope
D = 0.1               # still-water depth over the flat bed
END = 1.6             # x of the end of the beach (the shoreline is at TOE + D / tan 5 = 1.543)
SHORE = 1.5430052

#: a tiny flume with a 5 degree beach: the syntax tutorials/solitaryBeach copies
SLOPE_PARTICLE_DICT = """\
FoamFile { version 2.0; format ascii; class dictionary; location "system"; object particleDict; }

dx          0.02;
minSpacing  0.5;                // seam: fluid particles of two regions closer than 0.5 dx go

fluid
{
    flat                        // over the flat bed: the usual grid
    {
        type    box;
        min     (0 0);
        max     (0.4 0.1);      // top = still water level
    }
    beach                       // over the slope: rows parallel to it, the first dx/2 above
    {
        type    polygon;
        points  ((0.4 0) (1.5430052 0.1) (0.4 0.1));    // up to the shoreline
        grid    { origin (0.4 0); angle 5; }
    }
}

walls
{
    bed                         // paddle side, flat bed, toe, 5 degree beach, far wall
    {
        type    polyline;
        points  ((0 0.3) (0 0) (0.4 0) (1.6 0.1049863962) (1.6 0.3));
        side    right;          // the solid lies to the right of the direction of travel
        layers  3;
    }
}
"""

WALL_MODELS = ("stationaryGhosts", "repulsiveMonaghanKos", "hybrid", "adami")


def slope_case(tmp_path: Path, particle_dict: str = SLOPE_PARTICLE_DICT,
               boundary: str = "stationaryGhosts") -> Path:
    """The hydrostatic tank tutorial with the sloping flume above."""
    case = tmp_path / f"slope-{boundary}"
    shutil.copytree(TUTORIALS / "hydrostaticTank", case)
    (case / "system" / "particleDict").write_text(particle_dict)
    sp = case / "constant" / "sphProperties"
    sp.write_text(sp.read_text().replace("type            stationaryGhosts;",
                                         f"type            {boundary};"))
    return case


def _rotated(x, y):
    """Coordinates along and normal to the slope, from the toe, in units of dx."""
    a = math.radians(ANGLE)
    s = ((x - TOE) * math.cos(a) + y * math.sin(a)) / DX
    n = (-(x - TOE) * math.sin(a) + y * math.cos(a)) / DX
    return s, n


def _on_centres(q) -> bool:
    """Whether every q (in units of dx) is a cell centre k + 1/2."""
    return bool(np.allclose(q - 0.5, np.round(q - 0.5), atol=1e-9, rtol=0))


def test_example_is_a_5_degree_beach():
    assert math.isclose((END - TOE) * math.tan(math.radians(ANGLE)), 0.1049863962, rel_tol=1e-7)


@pytest.mark.parametrize("boundary", WALL_MODELS)
def test_slope_layout(tmp_path, boundary):
    case = Case(slope_case(tmp_path, boundary=boundary))
    state = setup_case(case, log=lambda m: None)
    f = state.kind == 0
    P = np.column_stack([state.x, state.y])
    # no two particles closer than minSpacing dx (fluid-fluid), dx/2 (anything)
    d_ff = cKDTree(P[f]).query(P[f], k=2)[0][:, 1]
    assert d_ff.min() >= 0.5 * DX * (1 - 1e-9)
    d_all = cKDTree(P).query(P, k=2)[0][:, 1]
    assert d_all.min() >= 0.5 * DX * (1 - 1e-9)
    # over the flat bed: the usual grid, cell centred from (0, 0)
    flat = f & (state.x < TOE)
    assert _on_centres(state.x[flat] / DX) and _on_centres(state.y[flat] / DX)
    assert flat.sum() == round(TOE / DX) * round(D / DX)
    # over the slope: the lattice rotated by 5 degrees about the toe, spacing dx both ways,
    # the first row dx/2 above the slope
    beach = f & (state.x > TOE)
    s, n = _rotated(state.x[beach], state.y[beach])
    assert _on_centres(s) and _on_centres(n)
    assert n.min() == pytest.approx(0.5)
    # nearest neighbours in the rotated rows are dx apart along 5 degrees (or 95)
    Pb = P[beach]
    d, j = cKDTree(Pb).query(Pb, k=2)
    assert np.allclose(d[:, 1], DX)
    ang = np.degrees(np.arctan2(*(Pb[j[:, 1]] - Pb)[:, ::-1].T)) % 90.0
    np.testing.assert_allclose(ang, ANGLE, atol=1e-6)
    # the beach region holds about its area / dx^2 (its area is a triangle up to the shoreline)
    shore = TOE + D / math.tan(math.radians(ANGLE))
    area = 0.5 * (shore - TOE) * D
    assert abs(beach.sum() - area / DX ** 2) < 0.1 * area / DX ** 2
    # wall rows under the slope: parallel to it, (k + 1/2) dx behind it, about dx apart
    w = ~f
    layers = 1 if boundary.startswith("repulsive") else 3
    under = w & (state.x > TOE + 3 * DX) & (state.x < END - 3 * DX)
    s, n = _rotated(state.x[under], state.y[under])
    rows = -np.round(n + 0.5)
    np.testing.assert_allclose(n, -(rows + 0.5), atol=1e-9)
    assert sorted(set(rows.astype(int))) == list(range(layers))
    for k in range(layers):
        gaps = np.diff(np.sort(s[rows == k]))
        np.testing.assert_allclose(gaps, gaps[0], rtol=1e-9)
        assert abs(gaps[0] - 1.0) < 0.02
    # at the toe's kink: no gap in the wall rows (every wall particle's nearest wall
    # neighbour within dx), and none closer than dx/2 (checked above)
    Pw = P[w]
    d_ww = cKDTree(Pw).query(Pw, k=2)[0][:, 1]
    assert d_ww.max() <= 1.01 * DX
    near_toe = np.hypot(Pw[:, 0] - TOE, Pw[:, 1]) < 3.5 * DX
    assert near_toe.sum() >= 3 * layers
    # the first fluid row over the slope and over the flat bed: dx from the first wall row
    d_fw = cKDTree(Pw).query(P[f])[0]
    assert d_fw.min() >= 0.95 * DX
    # hydrostatic start: p = rho0 g (surface - y), the local surface dx/2 above the top
    # particle of its column (the rotated rows' tops lie anywhere in the last dx: within dx/2)
    p = case.models.sph["equationOfState"].pressure(state.rho[f], case.context)
    assert np.max(np.abs(p - 1000 * 9.81 * (D - state.y[f]))) <= 1000 * 9.81 * 0.5 * DX * 1.01


def test_a_box_clipped_to_the_walls_fills_the_beach_as_the_polygon(tmp_path):
    """clipToWalls: a box over the whole beach, on the rotated grid, keeps only the particles
    above the slope: the same as the polygon up to the shoreline."""
    poly = setup_case(Case(slope_case(tmp_path / "a")), log=lambda m: None)
    text = SLOPE_PARTICLE_DICT.replace(
        "type    polygon;\n        points  ((0.4 0) (1.5430052 0.1) (0.4 0.1));    // up to the "
        "shoreline", "type    box;\n        min     (0.4 0);\n        max     (1.6 0.1);\n"
        "        clipToWalls yes;")
    assert "clipToWalls" in text
    box = setup_case(Case(slope_case(tmp_path / "b", text)), log=lambda m: None)
    a = np.unique(np.round(np.column_stack([poly.x, poly.y])[poly.kind == 0] / DX, 6), axis=0)
    b = np.unique(np.round(np.column_stack([box.x, box.y])[box.kind == 0] / DX, 6), axis=0)
    assert len(a) == np.count_nonzero(poly.kind == 0)
    np.testing.assert_array_equal(a, b)
    # without clipping the box fills the solid under the slope too
    unclipped = setup_case(Case(slope_case(tmp_path / "c", text.replace(
        "clipToWalls yes;", "clipToWalls no;"))), log=lambda m: None)
    uf = unclipped.kind == 0
    assert np.count_nonzero(_rotated(unclipped.x[uf], unclipped.y[uf])[1] < 0) > 10
    assert np.all(_rotated(box.x[box.kind == 0], box.y[box.kind == 0])[1] > 0)


def test_seam_thinning(tmp_path):
    """Raising minSpacing above the smallest gap at the seam (0.606 dx here, T Fig 5.2)
    removes particles of the later region only, and leaves none closer than it."""
    base = setup_case(Case(slope_case(tmp_path / "a")), log=lambda m: None)
    thin = setup_case(Case(slope_case(tmp_path / "b", SLOPE_PARTICLE_DICT.replace(
        "minSpacing  0.5;", "minSpacing  0.8;"))), log=lambda m: None)
    fb, ft = base.kind == 0, thin.kind == 0
    assert np.count_nonzero(fb & (base.x < TOE)) == np.count_nonzero(ft & (thin.x < TOE))
    removed = fb.sum() - ft.sum()
    assert 1 <= removed <= round(D / DX) + 1          # at most one per row of the seam
    Pt = np.column_stack([thin.x[ft], thin.y[ft]])
    assert cKDTree(Pt).query(Pt, k=2)[0][:, 1].min() >= 0.8 * DX * (1 - 1e-9)
    # and the removed ones were next to the seam
    Pb = np.column_stack([base.x[fb], base.y[fb]])
    gone = cKDTree(Pt).query(Pb)[0] > 1e-12
    assert np.all(np.abs(Pb[gone, 0] - TOE) < DX)


def test_seam_keep_drops_the_later_region():
    x = np.array([0.0, 0.3, 1.0, 0.0, 5.0])
    y = np.zeros(5)
    reg = np.array([0, 1, 1, 2, 2])
    keep = seam_keep(x, y, reg, 0.5)
    # 0-1 (0.3 apart, regions 0 and 1): 1 goes; 0-3 (same point, 0 and 2): 3 goes
    assert keep.tolist() == [True, False, True, False, True]


def _check(case: Path):
    res = CliRunner().invoke(app, ["check", str(case)], env={"COLUMNS": "250"})
    return res.exit_code, res.output


def test_check_reports_the_slope_case(tmp_path):
    code, out = _check(slope_case(tmp_path))
    assert code == 0, out
    flat = " ".join(out.split())
    assert "beach (polygon)" in flat and "grid at 5 deg from (0.4, 0.0)" in flat, out


@pytest.mark.parametrize("edit, key, words", [
    ("grid    { origin (0.4 0); angle 5; }", "fluid.beach.grid.origin", "missing"),
    ("grid    { origin (0.4 0); angle 5; }", "fluid.beach.grid.angle", "out of range"),
    ("grid    { origin (0.4 0); angle 5; }", "fluid.beach.grid.spacing", "unknown key"),
    ("minSpacing  0.5;", "minSpacing", "less than or equal to 1"),
])
def test_bad_grid_names_file_and_key(tmp_path, edit, key, words):
    replacement = {"fluid.beach.grid.origin": "grid    { angle 5; }",
                   "fluid.beach.grid.angle": "grid    { origin (0.4 0); angle 60; }",
                   "fluid.beach.grid.spacing": "grid    { origin (0.4 0); angle 5; spacing 1; }",
                   "minSpacing": "minSpacing  1.5;"}[key]
    text = SLOPE_PARTICLE_DICT.replace(edit, replacement)
    assert text != SLOPE_PARTICLE_DICT
    code, out = _check(slope_case(tmp_path, text))
    assert code != 0
    flat = " ".join(out.split())
    # (a discriminated entry's key names its type too: fluid.beach.polygon.grid.origin)
    assert "system/particleDict" in flat, out
    assert key in flat.replace(".polygon.", "."), out
    assert words.lower() in flat.lower(), out
    assert "Traceback" not in out


def test_overlapping_regions_are_reported(tmp_path):
    text = SLOPE_PARTICLE_DICT.replace("max     (0.4 0.1);", "max     (0.8 0.1);")
    code, out = _check(slope_case(tmp_path, text))
    flat = " ".join(out.split())
    assert code != 0 and "fluid.beach" in flat and "overlaps fluid.flat" in flat, out


# --- settling (T §5.3.4) ----------------------------------------------------------------------
SETTLE = 0.3           # s: about 2.5 crossings of the tank by sound (c0 = 14 m/s, 1.6 m)

#: the flume above with its left wall a paddle that a displacement table would push 5 cm in
#: 0.05 s: it must not move while the particles settle
PADDLE_PARTICLE_DICT = SLOPE_PARTICLE_DICT.replace(
    "points  ((0 0.3) (0 0) (0.4 0) (1.6 0.1049863962) (1.6 0.3));",
    "points  ((-0.06 0) (0.4 0) (1.6 0.1049863962) (1.6 0.3));").replace(
    "walls\n{\n", """walls
{
    paddle
    {
        type    polyline;
        points  ((0 0.3) (0 0));
        side    right;
        layers  3;
        motion  { type displacementTable; table ((0 (0 0)) (0.05 (0.05 0))); }
    }
""")


def settling_case(tmp_path: Path, endTime: float = SETTLE) -> Path:
    case = slope_case(tmp_path, PADDLE_PARTICLE_DICT)
    cd = case / "system" / "controlDict"
    cd.write_text(cd.read_text() + f"\nsettling {{ endTime {endTime:g}; }}\n")
    return case


def _fields(folder: Path):
    from sphfoam.io.fields import read_state

    f = read_state(folder)
    order = np.argsort(f["origId"])
    return {k: np.asarray(a)[order] for k, a in f.items()}


def test_settling_writes_0_and_keeps_the_unsettled_layout(tmp_path):
    from sphfoam.io.timedirs import read_time_dict

    case = settling_case(tmp_path)
    code, out = _check(case)
    assert code == 0 and "0.3 s before t = 0, walls still" in " ".join(out.split()), out
    res = CliRunner().invoke(app, ["setup", str(case)])
    assert res.exit_code == 0, res.output
    assert "settled in" in res.output
    raw, settled = _fields(case / "0.unsettled"), _fields(case / "0")
    # the unsettled layout is exactly what the set-up without settling writes
    plain = setup_case(Case(slope_case(tmp_path / "plain", PADDLE_PARTICLE_DICT)),
                       log=lambda m: None)
    po = np.argsort(plain.id)
    np.testing.assert_array_equal(raw["positions"][:, 0], plain.x[po])
    np.testing.assert_array_equal(raw["origId"], settled["origId"])
    # 0/ is the start: time 0, step 0, fluid at rest, the particles moved
    d = read_time_dict(case / "0")
    assert float(d["value"]) == 0.0 and int(d["index"]) == 0
    f = settled["type"] == 0
    assert np.all(settled["U"][f] == 0.0)
    moved = np.hypot(*(settled["positions"][f] - raw["positions"][f]).T) / DX
    assert moved.max() > 0.05                       # the seam evens out (about 0.9 dx here)
    assert moved.max() < 1.5 and np.median(moved) < 0.5     # settling, not flowing
    # every wall still, the paddle included (its table would have moved it 5 cm)
    w = ~f
    np.testing.assert_array_equal(settled["positions"][w], raw["positions"][w])
    # hydrostatic after settling, below the top two rows (five rows deep: the acoustic noise
    # of weak compressibility is still there after 0.3 s): the fitted p(y) has the gradient
    # rho0 g within 15 % and the bed pressure rho0 g d within 10 %; RMS deviation from
    # rho0 g (d - y) under 12 % of rho0 g d
    y, p = settled["positions"][f, 1], settled["p"][f]
    deep = y < D - 2 * DX
    slope, p_bed = np.polyfit(y[deep], p[deep], 1)
    assert abs(-slope / (1000 * 9.81) - 1) < 0.15
    assert abs(p_bed / (1000 * 9.81 * D) - 1) < 0.10
    rms = np.sqrt(np.mean((p[deep] - 1000 * 9.81 * (D - y[deep])) ** 2))
    assert rms < 0.12 * 1000 * 9.81 * D
    # re-running setup does not overwrite the settled start
    res = CliRunner().invoke(app, ["setup", str(case)])
    assert res.exit_code != 0 and "--force" in res.output
    # the unsettled layout is exported for ParaView beside the time series
    res = CliRunner().invoke(app, ["export", "vtk", str(case)])
    assert res.exit_code == 0, res.output
    assert (case / "VTK" / f"{case.name}_0.unsettled.vtm").is_file()
    assert "unsettled" not in (case / "VTK" / f"{case.name}.pvd").read_text()


def test_run_without_0_settles_first_then_the_paddle_moves(tmp_path):
    from sphfoam.timeloop import run_case

    case = settling_case(tmp_path, endTime=0.02)
    run_case(case, progress=False, echo=None, end_time=0.01)
    log = (case / "log.sphfoam").read_text()
    assert "settling for 0.02 s" in log and "settled in" in log
    assert log.count("settling: time ") == 10 and "settling: time 0.02 of 0.02 s" in log
    raw, start = _fields(case / "0.unsettled"), _fields(case / "0")
    end = _fields(case / "0.01")
    paddle = (raw["type"] != 0) & (raw["positions"][:, 0] < 0) & (raw["positions"][:, 1] > 0)
    assert paddle.sum() == 3 * round(0.3 / DX)
    np.testing.assert_array_equal(start["positions"][paddle], raw["positions"][paddle])
    # after t = 0 the table moves it: 0.05 m in 0.05 s, so 0.01 m at t = 0.01
    np.testing.assert_allclose(end["positions"][paddle, 0] - raw["positions"][paddle, 0],
                               0.01, rtol=1e-6)


@pytest.mark.parametrize("entry, words", [
    ("settling { }", "settling.endTime: required key is missing"),
    ("settling { endTime -1; }", "settling.endTime: Input should be greater than 0"),
    ("settling { endTime 0.5; writeInterval 0.1; }", "settling.writeInterval: unknown key"),
])
def test_bad_settling_names_file_and_key(tmp_path, entry, words):
    case = slope_case(tmp_path)
    cd = case / "system" / "controlDict"
    cd.write_text(cd.read_text() + f"\n{entry}\n")
    code, out = _check(case)
    flat = " ".join(out.split())
    assert code != 0 and "system/controlDict" in flat and words in flat, out
    assert "Traceback" not in out


def test_settling_refuses_initial_waves(tutorial):
    from sphfoam.case.errors import CaseError

    case = tutorial("solitaryCollision")
    cd = case / "system" / "controlDict"
    cd.write_text(cd.read_text() + "\nsettling { endTime 0.1; }\n")
    with pytest.raises(CaseError, match="settling: the initial waves"):
        setup_case(Case(case), log=lambda m: None)
    assert not (case / "0.unsettled").exists()
    code, out = _check(case)
    flat = " ".join(out.split())
    assert code != 0 and "system/controlDict: settling: the initial waves" in flat, out
