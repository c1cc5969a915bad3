"""The Python API (sphfoam.Case, run, times, read_time, ...), python -m sphfoam, py.typed,
and machine-readable metrics (sphfoam metrics --json)."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import sphfoam
from sphfoam.cli import app
from sphfoam.io.fields import write_state

ROOT = Path(__file__).resolve().parents[1]


def test_import_is_cheap_and_names_load_lazily():
    code = ("import sys, sphfoam; heavy = [m for m in ('numba', 'pydantic', 'vtkmodules', "
            "'sphfoam.timeloop') if m in sys.modules]; print(heavy); "
            "print(sphfoam.Case.__name__, sphfoam.read_time.__name__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split("\n")
    assert out[0] == "[]"
    assert out[1] == "Case read_time"
    for name in sphfoam.__all__:
        assert getattr(sphfoam, name) is not None, name
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        sphfoam.nope  # noqa: B018


def test_python_m_sphfoam():
    res = subprocess.run([sys.executable, "-m", "sphfoam", "--version"], capture_output=True,
                         text=True)
    assert res.returncode == 0 and res.stdout.strip() == f"sphfoam {sphfoam.__version__}"


def test_py_typed_is_shipped():
    assert (ROOT / "sphfoam" / "py.typed").is_file()
    assert re.search(r'\[tool\.setuptools\.package-data\]\s*sphfoam = \["py\.typed"\]',
                     (ROOT / "pyproject.toml").read_text())


def test_times_and_read_time(tmp_path):
    case = tmp_path / "c"
    (case / "constant").mkdir(parents=True)
    rng = np.random.default_rng(0)
    states = {}
    for name in ("0", "0.05", "0.1"):
        states[name] = {"positions": rng.random((4, 2)), "U": rng.random((4, 2)),
                        "rho": rng.random(4), "type": np.array([0, 0, 1, 1])}
        write_state(case / name, states[name])
    (case / "0.2").mkdir()                          # no particles: not a result time
    assert sphfoam.times(case) == [0.0, 0.05, 0.1]
    last = sphfoam.read_time(case)
    assert last["positions"].tobytes() == states["0.1"]["positions"].tobytes()
    assert sphfoam.read_time(case, "latestTime")["rho"].tobytes() == states["0.1"]["rho"].tobytes()
    assert sphfoam.read_time(case, 0.05)["U"].tobytes() == states["0.05"]["U"].tobytes()
    assert sphfoam.read_time(case, "0")["type"].tolist() == [0, 0, 1, 1]
    assert sphfoam.read_time(case, 0.05 + 1e-12)["rho"].tobytes() == states["0.05"]["rho"].tobytes()
    with pytest.raises(FileNotFoundError, match="at 0.3; have: 0, 0.05, 0.1"):
        sphfoam.read_time(case, 0.3)
    with pytest.raises(FileNotFoundError, match="no time directory holds particles"):
        sphfoam.read_time(tmp_path / "empty")


def _guide_example() -> str:
    guide = (ROOT / "docs" / "user-guide.md").read_text()
    section = guide[guide.index("## Python API"):]
    return re.search(r"```python\n(.*?)```", section, re.S)[1]


def test_the_user_guide_example_runs(tmp_path, monkeypatch):
    """The example of docs/user-guide.md "Python API", executed as written."""
    code = _guide_example()
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr("tempfile.mkdtemp", lambda *a, **k: str(tmp_path))
    ns: dict = {}
    exec(compile(code, "user-guide.md", "exec"), ns)
    case, report = ns["case"], ns["report"]
    assert Path(case.path).parent == tmp_path
    assert report.steps > 0 and report.failure is None
    assert sphfoam.times(case) == [0.0, 0.05, 0.1]
    f, f0 = sphfoam.read_time(case, 0.1), sphfoam.read_time(case, 0)
    fluid = f["type"] == 0
    assert ns["x"].max() == f["positions"][fluid, 0].max()
    # the column collapses: by T = t sqrt(g/H0) = 0.63 the front has moved out by
    # Z/H0 - 1 ~ 0.2 (Martin & Moyce 1952); here at least 1.5 dx beyond its start
    assert ns["x"].max() > f0["positions"][f0["type"] == 0, 0].max() + 0.03
    assert (case.path / "VTK" / "damBreak.pvd").is_file()


# ----------------------------------------------------------------------------- metrics
def test_metrics_json(tmp_path):
    from test_metrics import GAUGES, write_control, write_gauges, write_metrics

    case = tmp_path / "flume"
    write_control(case, {"gauges": GAUGES})
    write_gauges(case)
    write_metrics(case, {"H18": {"type": "waveHeight", "x": 18, "reference": 0.15},
                         "t18": {"type": "arrivalTime", "x": 18},
                         "R": {"type": "runUp"}}, pareto="H18")
    runner = CliRunner()
    res = runner.invoke(app, ["metrics", "--json", "-k", str(case)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["pareto"] == "H18" and set(doc["metrics"]) == {"H18", "t18", "R"}
    h = doc["metrics"]["H18"]
    assert h["type"] == "waveHeight" and h["reference"] == 0.15 and h["unit"] == "m"
    assert h["error_percent"] == pytest.approx(100 * (h["value"] - 0.15) / 0.15)
    assert doc["metrics"]["t18"]["reference"] is None
    # a metric that cannot be evaluated: null value (JSON has no NaN) and the reason
    r = doc["metrics"]["R"]
    assert r["value"] is None and "runUp" in r["problem"]
    # the table and the JSON agree
    table = runner.invoke(app, ["metrics", "-k", str(case)]).output
    assert f"{h['value']:.6g}" in table
    assert not any(isinstance(v, float) and math.isnan(v)
                   for m in doc["metrics"].values() for v in m.values())
