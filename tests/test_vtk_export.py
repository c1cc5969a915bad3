"""Tests for the VTK/ParaView export of particle states."""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from typer.testing import CliRunner
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader, vtkXMLPolyDataReader

from sphfoam.cli import app
from sphfoam.io.fields import write_state
from sphfoam.io.vtk import export_case, write_vtp


def _state(n, seed):
    rng = np.random.default_rng(seed)
    return {
        "positions": rng.random((n, 2)),
        "U": rng.normal(size=(n, 2)),
        "rho": 1000 + rng.random(n),
        "p": rng.normal(size=n),
        "mass": np.full(n, 0.01),
        "type": rng.integers(0, 3, n),
    }


def _read(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(str(path))
    r.Update()
    return r.GetOutput()


def _check(poly, s):
    n = len(s["positions"])
    assert poly.GetNumberOfPoints() == n
    assert poly.GetNumberOfVerts() == n
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    np.testing.assert_array_equal(pts[:, :2], s["positions"])
    np.testing.assert_array_equal(pts[:, 2], 0.0)
    pd = poly.GetPointData()
    u = pd.GetArray("U")
    assert u.GetNumberOfComponents() == 3
    u = vtk_to_numpy(u)
    np.testing.assert_array_equal(u[:, :2], s["U"])
    np.testing.assert_array_equal(u[:, 2], 0.0)
    for k in ("rho", "p", "mass"):
        np.testing.assert_array_equal(vtk_to_numpy(pd.GetArray(k)), s[k])
    t = vtk_to_numpy(pd.GetArray("type"))
    assert t.dtype.kind == "i" and t.dtype.itemsize == 8
    np.testing.assert_array_equal(t, s["type"])


def test_write_vtp(tmp_path):
    s = _state(25, 0)
    write_vtp(tmp_path / "a.vtp", s)
    _check(_read(tmp_path / "a.vtp"), s)


def _sub(s, mask):
    return {k: a[mask] for k, a in s.items()}


def _time_value(poly):
    tv = poly.GetFieldData().GetArray("TimeValue")
    assert tv is not None and tv.GetNumberOfTuples() == 1
    return tv.GetValue(0)


def _case(tmp_path, name="damBreak"):
    case = tmp_path / name
    (case / "constant").mkdir(parents=True)
    (case / "system").mkdir()
    (case / "0.25").mkdir()  # a time dir without particles is skipped
    states = {"0": _state(10, 1), "0.5": _state(10, 2), "1e-05": _state(12, 3)}
    for t, s in states.items():
        write_state(case / t, s, fmt="binary" if t != "0.5" else "ascii", precision=17)
    return case, states


def test_write_vtp_time_value(tmp_path):
    s = _state(5, 0)
    write_vtp(tmp_path / "a.vtp", s, time=0.125)
    assert _time_value(_read(tmp_path / "a.vtp")) == 0.125


def test_export_case(tmp_path):
    case, states = _case(tmp_path)
    pvd = export_case(case)
    assert pvd == case / "VTK" / "damBreak.pvd"
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    ds = root.find("Collection").findall("DataSet")
    assert [float(d.get("timestep")) for d in ds] == [0.0, 1e-05, 0.5]
    # file names carry the time directory's name
    assert [d.get("file") for d in ds] == ["damBreak_0.vtm", "damBreak_1e-05.vtm", "damBreak_0.5.vtm"]
    for d, t in zip(ds, ["0", "1e-05", "0.5"]):
        s = states[t]
        r = vtkXMLMultiBlockDataReader()
        r.SetFileName(str(pvd.parent / d.get("file")))
        r.Update()
        mb = r.GetOutput()
        assert mb.GetNumberOfBlocks() == 2
        names = [mb.GetMetaData(i).Get(mb.NAME()) for i in range(2)]
        assert names == ["fluid", "walls"]
        fluid, walls = mb.GetBlock(0), mb.GetBlock(1)
        _check(fluid, _sub(s, s["type"] == 0))
        _check(walls, _sub(s, s["type"] != 0))
        assert fluid.GetNumberOfPoints() + walls.GetNumberOfPoints() == len(s["rho"])
        for block in (fluid, walls):
            assert _time_value(block) == float(d.get("timestep"))
    # one time series per block, for ParaView's .series reader
    for block in ("fluid", "walls"):
        series = json.loads((case / "VTK" / f"damBreak_{block}.vtp.series").read_text())
        assert series["file-series-version"] == "1.0"
        assert [(f["name"], f["time"]) for f in series["files"]] == [
            (f"damBreak_{t}/{block}.vtp", float(t)) for t in ("0", "1e-05", "0.5")]


def test_pairs_are_exported_as_vectors(tmp_path):
    case = tmp_path / "c"
    s = _state(6, 7)
    s["x0"], s["y0"] = np.arange(6.0), -np.arange(6.0)
    s["type"][:] = 1
    write_state(case / "0", s)
    export_case(case)
    walls = _read(case / "VTK" / "c_0" / "walls.vtp")
    pd = walls.GetPointData()
    assert pd.GetArray("x0") is None and pd.GetArray("y0") is None
    x0 = vtk_to_numpy(pd.GetArray("X0"))
    assert x0.shape == (6, 3)
    np.testing.assert_array_equal(x0, np.column_stack([s["x0"], s["y0"], np.zeros(6)]))
    assert _read(case / "VTK" / "c_0" / "fluid.vtp").GetNumberOfPoints() == 0


def test_export_selected_times_leaves_no_stale_files(tmp_path):
    case = tmp_path / "c"
    for t, seed in (("0", 1), ("0.5", 2), ("1", 3)):
        write_state(case / t, _state(5, seed))
    export_case(case, out_dir_name="post")
    assert (case / "post" / "c_0.vtm").is_file() and (case / "post" / "c_1").is_dir()
    (case / "post" / "c_3.vtp").write_text("from an older sphfoam export, numbered by index")
    (case / "post" / "notes.txt").write_text("not ours: kept")
    pvd = export_case(case, times=[0.5, 1.0], out_dir_name="post")
    ds = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    assert [(d.get("timestep"), d.get("file")) for d in ds] == [("0.5", "c_0.5.vtm"), ("1.0", "c_1.vtm")]
    left = sorted(p.name for p in (case / "post").iterdir())
    assert left == ["c.pvd", "c_0.5", "c_0.5.vtm", "c_1", "c_1.vtm", "c_fluid.vtp.series",
                    "c_walls.vtp.series", "notes.txt"]
    s = _state(5, 2)
    _check(_read(case / "post" / "c_0.5" / "fluid.vtp"), _sub(s, s["type"] == 0))


def test_nothing_to_export_is_an_error(tmp_path):
    case = tmp_path / "empty"
    (case / "constant").mkdir(parents=True)
    (case / "system").mkdir()
    (case / "0").mkdir()
    with pytest.raises(FileNotFoundError, match="nothing to export"):
        export_case(case)
    assert not (case / "VTK").exists()
    write_state(case / "0", _state(4, 1))
    with pytest.raises(FileNotFoundError, match="at 10; have: 0"):
        export_case(case, times=[10.0])
    res = CliRunner().invoke(app, ["export", "vtk", str(case), "-t", "10"])
    assert res.exit_code != 0 and "at 10" in res.output
    res = CliRunner().invoke(app, ["export", "vtk", str(case)])
    assert res.exit_code == 0 and (case / "VTK" / "empty_0.vtm").is_file()
