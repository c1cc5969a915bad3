"""Output of a 3-D case: `sphfoam export vtk` keeps every z (points and vectors),
ParaView's own OpenFOAM reader sees the 3-D cloud (where pvpython is installed), and
`sphfoam render` draws a 3-D view and a slice to PNG."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.cli import app
from sphfoam.io.fields import read_state
from sphfoam.io.timedirs import write_time
from sphfoam.io.vtk import export_case
from sphfoam.render import render_case
from sphfoam.setup import setup_case
from test_paraview import READ_CASE, _pvpython, needs_paraview


@pytest.fixture
def tank3d(tutorial):
    """hydrostaticTank3D at dx = 0.04 (1000 fluid particles): t = 0 from the set-up, and
    t = 0.1 with a 3-D velocity field (w = -z, u = x, v = 2 y) and the fluid lifted 1 cm."""
    path = tutorial("hydrostaticTank3D", {"system/particleDict:dx": 0.04})
    case = Case(path)
    st = setup_case(case, log=lambda m: None)
    fl = st.kind == 0
    st.u[fl], st.v[fl], st.w[fl] = st.x[fl], 2 * st.y[fl], -st.z[fl]
    st.z[fl] += 0.01
    write_time(case, st, 0.1, 10, 1e-3)
    return path, st


def _read(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    return r.GetOutput()


def test_vtk_export_of_a_3d_case_keeps_z(tank3d):
    path, st = tank3d
    export_case(path)
    fl = st.kind == 0
    for block, sel in (("fluid", fl), ("walls", ~fl)):
        poly = _read(path / "VTK" / f"{path.name}_0.1" / f"{block}.vtp")
        pts = vtk_to_numpy(poly.GetPoints().GetData())
        np.testing.assert_array_equal(pts, np.column_stack([st.x, st.y, st.z])[sel])
        U = vtk_to_numpy(poly.GetPointData().GetArray("U"))
        np.testing.assert_array_equal(U, np.column_stack([st.u, st.v, st.w])[sel])
    assert np.ptp(pts[:, 2]) > 0.3                  # the tank's height, not a plane
    fields = read_state(path / "0.1", dim=3)
    poly = _read(path / "VTK" / f"{path.name}_0.1" / "fluid.vtp")
    arrays = {poly.GetPointData().GetArrayName(k)
              for k in range(poly.GetPointData().GetNumberOfArrays())}
    # a 3-D case's component fields are one 3-vector each, z included
    for vec, comps in (("U_0", ("Ux_0", "Uy_0", "Uz_0")), ("n", ("nx", "ny", "nz"))):
        if all(c in fields for c in comps):
            assert vec in arrays and not set(comps) & arrays
            got = vtk_to_numpy(poly.GetPointData().GetArray(vec))
            np.testing.assert_array_equal(got, np.column_stack([fields[c] for c in comps])[fl])


def test_export_vtk_cli_on_a_3d_case(tank3d):
    path, st = tank3d
    res = CliRunner().invoke(app, ["export", "vtk", str(path)])
    assert res.exit_code == 0, res.output
    poly = _read(path / "VTK" / f"{path.name}_0" / "fluid.vtp")
    assert vtk_to_numpy(poly.GetPoints().GetData())[:, 2].max() > 0.3


@needs_paraview
def test_paraview_opens_a_3d_case(tank3d, tmp_path):
    """ParaView's OpenFOAM reader: the cloud's points and U with their z components."""
    path, st = tank3d
    out = tmp_path / "pv.json"
    cmd = _pvpython() + [str(READ_CASE), str(path / f"{path.name}.foam"), str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    rep = json.loads(out.read_text())
    assert rep["times"] == [0.0, 0.1]
    got = rep["data"][repr(0.1)]
    assert got["n_cells"] == st.n
    pts = np.array(got["points"])
    np.testing.assert_allclose(pts, np.column_stack([st.x, st.y, st.z]), rtol=2e-7,
                               atol=1e-7)
    U = np.array(got["arrays"]["U"]["values"])
    assert got["arrays"]["U"]["components"] == 3
    np.testing.assert_allclose(U, np.column_stack([st.u, st.v, st.w]), rtol=2e-7, atol=1e-7)


def test_render_draws_a_3d_view_and_a_slice(tank3d):
    path, st = tank3d
    r = render_case(path, "Uz", movie="gif", width=900, log=lambda m: None)
    assert [p.name for p in r.frames] == ["0.png", "0.1.png"]
    assert r.movie.name == "Uz.gif" and r.movie.is_file()
    fl = st.kind == 0
    assert (r.vmin, r.vmax) == pytest.approx((st.w[fl].min(), 0.0))    # t = 0 at rest
    a, b = (np.asarray(Image.open(p).convert("RGB")).astype(int) for p in r.frames)
    assert a.shape == b.shape and a.shape[1] == 900 and a.shape[0] > 300
    assert (a != 255).any(axis=2).mean() > 0.1          # drawn on, not a blank figure
    assert np.abs(a - b).sum(axis=2).astype(bool).mean() > 0.01   # the frames differ
    # the slice: the right half holds viridis colours (the field) and wall grey
    right = b[:, 900 // 2:]
    viridis = (right[:, :, 2] > right[:, :, 1] + 20) & (right[:, :, 0] < 120)  # blue-violet
    assert viridis.sum() > 500
    assert (np.abs(right - (154, 154, 154)).sum(axis=2) < 6).sum() > 100


def test_render_3d_slice_options_and_errors(tank3d):
    path, st = tank3d
    # the colour range of the particles in the slab x = 0.2 +- 0.02 and the box y, z < 0.1
    r = render_case(path, "Uy", times=[0.1], movie="none", slice_at="x=0.22", slab=0.04,
                    box=(0, 0, 0.1, 0.1), log=lambda m: None)
    assert len(r.frames) == 1 and r.movie is None
    near = (st.kind == 0) & (np.abs(st.x - 0.22) <= 0.02) & (st.y <= 0.1) & (st.z <= 0.1)
    assert near.sum() > 0 and np.unique(st.x[near]).size == 1     # one layer of the lattice
    assert (r.vmin, r.vmax) == pytest.approx((st.v[near].min(), st.v[near].max()))
    assert r.vmax < st.v.max() / 2
    with pytest.raises(CaseError, match="--slice.*give AXIS=VALUE"):
        render_case(path, movie="none", slice_at="w=1", log=lambda m: None)
    with pytest.raises(CaseError, match="--field.*choose from: U, Ux, Uy, Uz"):
        render_case(path, "nope", movie="none", log=lambda m: None)
    res = CliRunner().invoke(app, ["render", str(path), "-t", "0", "--movie", "none",
                                   "--slice", "z=0.1", "--width", "600"])
    assert res.exit_code == 0, res.output
    assert "slice z = 0.1 m" in res.output


def test_a_2d_case_refuses_the_3d_slice_options(tutorial):
    path = tutorial("damBreak", {"system/particleDict:dx": 0.05})
    setup_case(Case(path), log=lambda m: None)
    with pytest.raises(CaseError, match="--slice.*2-D case"):
        render_case(path, movie="none", slice_at="y=0.1", log=lambda m: None)
    with pytest.raises(CaseError, match="--slab.*2-D case"):
        render_case(path, movie="none", slab=0.1, log=lambda m: None)
