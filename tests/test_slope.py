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
from sphfoam.setup.initial import setup_case
from sphfoam.setup.particles import seam_keep

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"

DX = 0.02
ANGLE = 5.0
TOE = 0.4             # x of the toe of the slope
D = 0.1               # still-water depth over the flat bed
END = 1.6             # x of the end of the beach (the shoreline is at TOE + D / tan 5 = 1.543)

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
        points  ((0.4 0) (1.6 0.1049863962) (1.6 0.1) (0.4 0.1));
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

