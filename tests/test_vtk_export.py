"""Tests for the VTK/ParaView export of particle states."""

import xml.etree.ElementTree as ET

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

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


def test_export_case(tmp_path):
    case = tmp_path / "damBreak"
    (case / "constant").mkdir(parents=True)
    (case / "system").mkdir()
    (case / "0.25").mkdir()  # a time dir without particles is skipped
    states = {"0": _state(10, 1), "0.5": _state(10, 2), "1e-05": _state(12, 3)}
    for t, s in states.items():
        write_state(case / t, s, fmt="binary" if t != "0.5" else "ascii", precision=17)

    pvd = export_case(case)
    assert pvd == case / "VTK" / "damBreak.pvd"
    ds = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    assert [float(d.get("timestep")) for d in ds] == [0.0, 1e-05, 0.5]
    assert [d.get("file") for d in ds] == ["damBreak_0.vtp", "damBreak_1.vtp", "damBreak_2.vtp"]
    assert ET.parse(pvd).getroot().get("type") == "Collection"
    for d, t in zip(ds, ["0", "1e-05", "0.5"]):
        _check(_read(pvd.parent / d.get("file")), states[t])


def test_export_selected_times(tmp_path):
    case = tmp_path / "c"
    for t, seed in (("0", 1), ("0.5", 2), ("1", 3)):
        write_state(case / t, _state(5, seed))
    pvd = export_case(case, times=[0.5, 1.0], out_dir_name="post")
    ds = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    assert [(d.get("timestep"), d.get("file")) for d in ds] == [("0.5", "c_0.vtp"), ("1.0", "c_1.vtp")]
    _check(_read(case / "post" / "c_0.vtp"), _state(5, 2))
