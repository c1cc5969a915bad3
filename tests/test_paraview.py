"""A case opens in ParaView's built-in OpenFOAM reader (``paraview CASE/CASE.foam``).

The format tests always run: positions in OpenFOAM's ``Cloud<passiveParticle>`` layout
``(x y 0) celli``, 2-vectors as 3-component ``vectorField`` files with z = 0, a valid
one-cell ``constant/polyMesh`` and ``CASE.foam`` from ``sphfoam setup``, bit-exact
reading back, older (``vector2DField``) cases still read. The ParaView test runs where
``pvpython`` is installed (Debian: ``apt-get install paraview xvfb``) and opens a case
with the reader itself.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from sphfoam.case.case import Case
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import read_field, read_state, write_field, write_state
from sphfoam.io.vtk import export_case
from sphfoam.io.timedirs import write_time
from sphfoam.setup import setup_case

READ_CASE = Path(__file__).parent / "paraview" / "read_case.py"
READ_VTK = Path(__file__).parent / "paraview" / "read_vtk.py"


def _fields(n, seed):
    rng = np.random.default_rng(seed)
    return {
        "positions": rng.normal(size=(n, 2)) * 10.0 ** rng.integers(-3, 3, size=(n, 2)),
        "U": rng.normal(size=(n, 2)),
        "rho": 1000 + rng.random(n),
        "mass": np.full(n, 0.01),
        "type": rng.integers(0, 2, n),
        "origId": rng.permutation(n).astype(np.int64),
        "x0": rng.random(n),
    }


def _cloud(td):
    return Path(td) / "lagrangian" / "particles"


def test_positions_are_an_openfoam_cloud_ascii(tmp_path):
    s = {"positions": np.array([[1.5, -2.0], [0.25, 3.0]]), "U": np.array([[1.0, 2.0], [3.0, 4.5]])}
    write_state(tmp_path / "0.5", s, fmt="ascii", precision=17)
    text = (_cloud(tmp_path / "0.5") / "positions").read_text()
    assert "class       Cloud<passiveParticle>;" in text and "object      positions;" in text
    assert "\n2\n(\n(1.5 -2 0) 0\n(0.25 3 0) 0\n)\n" in text
    u = (_cloud(tmp_path / "0.5") / "U").read_text()
    assert "class       vectorField;" in u and "\n2\n(\n(1 2 0)\n(3 4.5 0)\n)\n" in u
    np.testing.assert_array_equal(read_field(_cloud(tmp_path / "0.5") / "positions"),
                                  [[1.5, -2.0, 0.0], [0.25, 3.0, 0.0]])


def test_positions_binary_layout(tmp_path):
    xy = np.array([[1.5, -2.0], [0.25, 3.0], [7.0, 8.0]])
    write_state(tmp_path / "1", {"positions": xy})
    raw = (_cloud(tmp_path / "1") / "positions").read_bytes()
    assert b'arch        "LSB;label=64;scalar=64";' in raw
    assert b"class       Cloud<passiveParticle>;" in raw
    # OpenFOAM writes a particle's raw bytes, x y z and the cell index, as '(' bytes ')'
    body = b"".join(b"(" + np.array([x, y, 0.0]).tobytes() + np.int64(0).tobytes() + b")\n"
                    for x, y in xy)
    assert raw.endswith(b"3\n(\n" + body + b")\n;\n")


@pytest.mark.parametrize("fmt, precision", [("binary", 6), ("ascii", 17)])
def test_state_bit_exact_through_the_cloud_format(tmp_path, fmt, precision):
    s = _fields(37, 3)
    write_state(tmp_path / "2", s, fmt=fmt, precision=precision)
    r = read_state(tmp_path / "2")
    assert set(r) == set(s)
    for k, a in s.items():
        assert r[k].dtype == a.dtype and r[k].shape == a.shape, k
        assert r[k].tobytes() == a.tobytes(), k
    # and a restart's state: x, y, u, v, rho, m, kind, id and extra fields bit for bit
    back = ParticleState.from_fields(r)
    for name, col in (("x", s["positions"][:, 0]), ("y", s["positions"][:, 1]),
                      ("u", s["U"][:, 0]), ("v", s["U"][:, 1]), ("rho", s["rho"])):
        assert getattr(back, name).tobytes() == np.ascontiguousarray(col).tobytes(), name
    assert back.extra["x0"].tobytes() == s["x0"].tobytes()


def test_older_two_component_cases_still_read(tmp_path):
    """Time directories written before the cloud format (vector2DField positions/U)."""
    s = _fields(11, 4)
    cloud = _cloud(tmp_path / "0.1")
    cloud.mkdir(parents=True)
    for name, a in s.items():
        write_field(cloud / name, a)
    assert "vector2DField" in (cloud / "positions").read_bytes().decode("latin-1")
    r = read_state(tmp_path / "0.1")
    for k, a in s.items():
        assert r[k].shape == a.shape and r[k].tobytes() == a.tobytes(), k


def test_empty_and_malformed_positions(tmp_path):
    for fmt in ("binary", "ascii"):
        write_state(tmp_path / fmt, {"positions": np.zeros((0, 2))}, fmt=fmt)
        assert read_state(tmp_path / fmt)["positions"].shape == (0, 2)
    p = _cloud(tmp_path / "binary") / "positions"
    write_state(tmp_path / "binary", {"positions": np.ones((4, 2))})
    raw = p.read_bytes()
    p.write_bytes(raw.replace(b")\n(", b"))(", 1))
    with pytest.raises(ValueError, match="positions"):
        read_field(p)
    p.write_bytes(raw[:-60])
    with pytest.raises(ValueError, match="truncated"):
        read_field(p)


def _setup(tutorial, dx=0.05):
    case = Case(tutorial("hydrostaticTank", {"system/particleDict:dx": dx}))
    state = setup_case(case, log=lambda m: None)
    return case, state


def test_setup_writes_a_valid_one_cell_mesh_and_foam_file(tutorial):
    case, state = _setup(tutorial)
    assert (case.path / "hydrostaticTank.foam").is_file()
    mesh = case.path / "constant" / "polyMesh"
    pts = read_field(mesh / "points")
    assert pts.shape == (8, 3)
    text = (mesh / "faces").read_text()
    body = text[text.index("6\n(") + 3:]
    faces = [tuple(int(v) for v in f.split(")")[0].split()) for f in body.split("4(")[1:]]
    assert len(faces) == 6 and sorted(v for f in faces for v in f) == sorted(list(range(8)) * 3)
    centre = pts.mean(axis=0)
    area = np.zeros(3)
    for f in faces:
        q = pts[list(f)]
        n = 0.5 * np.cross(q[2] - q[0], q[3] - q[1])          # face area vector
        assert np.dot(n, q.mean(axis=0) - centre) > 0         # points out of the owner cell
        area += n
    np.testing.assert_allclose(area, 0.0, atol=1e-12)       # the cell is closed
    # every particle lies inside the cell (z = 0 is mid-thickness)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    assert lo[2] < 0 < hi[2]
    assert (state.x > lo[0]).all() and (state.x < hi[0]).all()
    assert (state.y > lo[1]).all() and (state.y < hi[1]).all()
    bnd = (mesh / "boundary").read_text()
    assert "sides" in bnd and "frontAndBack" in bnd and "empty;" in bnd
    assert "nCells:1" in (mesh / "owner").read_text()
    s0 = read_state(case.path / "0")
    assert s0["positions"].shape == (state.n, 2)
    assert s0["positions"][:, 0].tobytes() == state.x.tobytes()


def test_export_foam_upgrades_an_older_case(tutorial):
    """``sphfoam export foam``: mesh, .foam and older time directories in the new layout."""
    import shutil as sh

    from typer.testing import CliRunner

    from sphfoam.cli import app

    case, state = _setup(tutorial)
    sh.rmtree(case.path / "constant" / "polyMesh")
    (case.path / "hydrostaticTank.foam").unlink()
    s = read_state(case.path / "0")
    for name, fmt in (("0", "binary"), ("0.5", "ascii")):       # as earlier versions wrote
        cloud = _cloud(case.path / name)
        cloud.mkdir(parents=True, exist_ok=True)
        for k, a in s.items():
            write_field(cloud / k, a, fmt=fmt, precision=17)
    res = CliRunner().invoke(app, ["export", "foam", str(case.path)])
    assert res.exit_code == 0, res.output
    assert "rewrote 2 time directories" in res.output and "0, 0.5" in res.output
    assert (case.path / "hydrostaticTank.foam").is_file()
    assert (case.path / "constant" / "polyMesh" / "faces").is_file()
    for name, fmt in (("0", "binary"), ("0.5", "ascii")):
        cloud = _cloud(case.path / name)
        head = (cloud / "positions").read_bytes()[:400].decode("latin-1")
        assert "Cloud<passiveParticle>" in head and f"format      {fmt};" in head
        assert "vectorField" in (cloud / "U").read_bytes()[:400].decode("latin-1")
        r = read_state(case.path / name)
        for k, a in s.items():
            assert r[k].tobytes() == a.tobytes(), (name, k)
    res = CliRunner().invoke(app, ["export", "foam", str(case.path)])
    assert res.exit_code == 0 and "rewrote" not in res.output


# ----------------------------------------------------------------------------- ParaView
def _pvpython() -> list[str] | None:
    pv = shutil.which("pvpython")
    if pv is None:
        return None
    xvfb = shutil.which("xvfb-run")
    return [xvfb, "-a", pv] if xvfb else [pv]


needs_paraview = pytest.mark.skipif(
    _pvpython() is None,
    reason="ParaView's pvpython is not installed (Debian: apt-get install paraview xvfb); "
           "the format tests above still check the layout")


@needs_paraview
def test_paraview_opens_the_case(tutorial, tmp_path):
    """ParaView's own OpenFOAM reader lists the cloud, every field and every time."""
    case, state = _setup(tutorial)
    rng = np.random.default_rng(5)
    written = {"0": read_state(case.path / "0")}
    for t, fmt in ((0.1, "binary"), (0.2, "ascii")):
        state.x = state.x + 0.01 * rng.random(state.n)
        state.u = rng.normal(size=state.n)
        state.v = rng.normal(size=state.n)
        case.control.writeFormat, case.control.writePrecision = fmt, 17
        folder = write_time(case, state, t, int(t * 100), 1e-4, p=rng.normal(size=state.n))
        assert f"format      {fmt};" in (_cloud(folder) / "positions").read_bytes()[:400].decode("latin-1")
        written[folder.name] = read_state(folder)

    out = tmp_path / "pv.json"
    cmd = _pvpython() + [str(READ_CASE), str(case.path / "hydrostaticTank.foam"), str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    rep = json.loads(out.read_text())
    assert rep["times"] == [0.0, 0.1, 0.2]
    assert "lagrangian/particles" in rep["regions"] and "internalMesh" in rep["regions"]
    fields = set(written["0"]) - {"positions"}
    assert set(rep["lagrangian_arrays"]) == fields
    for (name, ours), t in zip(written.items(), rep["times"]):
        got = rep["data"][repr(t)]
        assert got["n_cells"] == state.n
        pts = np.array(got["points"])
        # ParaView's reader keeps float32: equal to our float64 values to float32 rounding
        np.testing.assert_allclose(pts[:, :2], ours["positions"], rtol=2e-7, atol=1e-7)
        np.testing.assert_array_equal(pts[:, 2], 0.0)
        assert set(got["arrays"]) == fields
        for k in fields:
            a = np.array(got["arrays"][k]["values"])
            if ours[k].ndim == 2:
                assert got["arrays"][k]["components"] == 3, k
                np.testing.assert_allclose(a[:, :2], ours[k], rtol=2e-7, atol=1e-7)
                np.testing.assert_array_equal(a[:, 2], 0.0)
            else:
                np.testing.assert_allclose(a, ours[k], rtol=2e-7, atol=1e-7, err_msg=k)


@needs_paraview
def test_paraview_opens_the_vtk_export(tutorial, tmp_path):
    """ParaView reads the .pvd (multiblock fluid/walls per time) and a block's .vtp.series."""
    case, state = _setup(tutorial)
    state.x = state.x + 0.001
    write_time(case, state, 0.25, 10, 1e-4)
    export_case(case.path)
    vtk_dir = case.path / "VTK"
    out = tmp_path / "vtk.json"
    cmd = _pvpython() + [str(READ_VTK), str(vtk_dir / "hydrostaticTank.pvd"),
                         str(vtk_dir / "hydrostaticTank_fluid.vtp.series"), str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stdout + res.stderr
    rep = json.loads(out.read_text())
    assert rep["pvd_times"] == rep["series_times"] == [0.0, 0.25]
    n_fluid = int((state.kind == 0).sum())
    for t in ("0.0", "0.25"):
        assert rep["pvd"][t] == {"fluid": n_fluid, "walls": state.n - n_fluid}
        assert rep["series"][t]["points"] == n_fluid
        assert rep["series"][t]["TimeValue"] == float(t)
        assert rep["series"][t]["U_components"] == 3
