"""The low-dissipation studies of issue 13 (docs/low-dissipation.md): every run of
tutorials/solitaryWave/studyDict.lowDissipation(.Screen) and
tutorials/solitaryWallRunup/studyDict.lowDissipation clones into a valid case whose metrics
can be read, measured against the exact (Euler) wave with the sub-particle gauges."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from sphfoam import study as st
from sphfoam.case import foamdict

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"
SKIP = shutil.ignore_patterns("study*", "runUp", "0", "[1-9]*", "postProcessing", "log.*",
                              "VTK", "*.png")


def _copy(tmp_path: Path, name: str) -> Path:
    dst = tmp_path / name
    shutil.copytree(TUTORIALS / name, dst, ignore=SKIP)
    for f in (TUTORIALS / name).glob("studyDict*"):
        shutil.copy(f, dst / f.name)
    return dst


@pytest.mark.parametrize("case, dict_name, first", [
    ("solitaryWave", "studyDict.lowDissipation", "case11_d10"),
    ("solitaryWave", "studyDict.lowDissipationScreen", "fourtakasShift"),
    ("solitaryWallRunup", "studyDict.lowDissipation", "P_a03"),
])
def test_every_run_clones_into_a_valid_case(tmp_path, case, dict_name, first):
    base = _copy(tmp_path, case)
    s = st.load(base / dict_name)
    assert s.runs[0].name == first
    todo = st.prepare(s)                    # clones and validates every run, or raises
    assert [r.name for r in todo] == [r.name for r in s.runs]
    for run in s.runs:
        ctl = foamdict.read(Path(run.path) / "system" / "controlDict")["functions"]
        # every gauge of these studies reads a sub-particle surface: the flume study's by
        # the column's water volume, with the fluid fraction 1/2 recorded beside it, the
        # others' by the fluid fraction (the wall study's runUpParticle keeps the thesis's
        # reading, for comparison)
        volume = dict_name == "studyDict.lowDissipation" and case == "solitaryWave"
        for name, fo in ctl.items():
            want = ("particle" if name == "runUpParticle" else
                    "volume" if volume and name in ("gauges", "crest") else "fraction")
            assert fo.get("surface", "particle") == want, (run.name, name)


def test_flume_study_measures_against_the_exact_wave():
    s = st.load(TUTORIALS / "solitaryWave" / "studyDict.lowDissipation")
    m = s.spec.metrics
    assert [k for k in m if k.startswith("H")] == [f"H{x}" for x in range(2, 19, 2)]
    assert {m[f"H{x}"]["function"] for x in range(2, 19, 2)} == {"gauges"}
    assert m["F18"]["function"] == "gaugesFraction" and m["celerity"]["function"] == "crest"
    assert all(m[f"H{x}"]["reference"] == 0.15 for x in range(2, 19, 2))
    assert m["celerity"]["theory"] == "euler"
    dx = {r.name: s.edits[r.name].get("system/particleDict:dx", 0.05) for r in s.runs}
    assert {n: 0.5 / v for n, v in dx.items() if n.startswith("case11_")} == {
        "case11_d10": 10.0, "case11_d20": 20.0, "case11_d40": 40.0}
    assert all(math.isclose(0.5 / v, int(n.rsplit("_d", 1)[1])) for n, v in dx.items())


def test_wall_study_references_are_the_best_theory(tmp_path):
    """R/d of the fully nonlinear potential flow (sphfoam.reference.wall_reflection) where it
    converges, a = A/d <= 0.4, else Su & Mirie's (1980) third order 2a + a^2/2 + 3a^3/4."""
    from sphfoam.reference import wall_reflection as wr

    base = _copy(tmp_path, "solitaryWallRunup")
    s = st.load(base / "studyDict.lowDissipation")
    st.prepare(s)
    for run in s.runs:
        a = float(run.name.rsplit("_a", 1)[1]) / 10.0
        wave = foamdict.read(Path(run.path) / "constant" / "waveProperties")["waves"]
        assert float(wave["incident"]["height"]) == pytest.approx(10.0 * a)
        md = foamdict.read(Path(run.path) / "system" / "metricsDict")["metrics"]
        ref = wr.wall_reflection(a).run_up if a <= wr.MAX_EPS else wr.su_mirie(a)
        assert float(md["runUp"]["reference"]) == pytest.approx(ref, abs=5e-5)
        assert float(md["runUpParticle"]["reference"]) == pytest.approx(ref, abs=5e-5)
        assert float(md["celerity"]["height"]) == pytest.approx(10.0 * a)
        assert md["celerity"]["theory"] == "euler"


def test_collision_study_clones_into_valid_cases(tmp_path):
    """tutorials/solitaryCollision/studyDict.lowDissipation: P's set-up and the
    low-dissipation combinations, all measured against the exact wave's celerity."""
    base = _copy(tmp_path, "solitaryCollision")
    s = st.load(base / "studyDict.lowDissipation")
    assert [r.name for r in s.runs] == ["P", "fourtakas", "fourtakasR0", "fourtakasR005",
                                         "fourtakasQ", "fourtakasQRs"]
    st.prepare(s)
    for run in s.runs:
        m = foamdict.read(Path(run.path) / "system" / "metricsDict")["metrics"]
        assert m["celerity"]["theory"] == "euler" and m["peak"]["reference"] == 5.377
    for run in s.runs[1:]:
        waves = foamdict.read(Path(run.path) / "constant" / "waveProperties")["waves"]
        assert {w["theory"] for w in waves.values()} == {"euler"}


def test_collision_convergence_study_clones_into_valid_cases(tmp_path):
    """tutorials/solitaryCollision/studyDict.convergence: every run clones into a valid case
    measured against the potential flow's peak; the kernel-and-filter variants change only
    the kernel and the density filter, the XSPH variant only XSPH, the density-diffusion
    variants only the filter (and the C-SPH variants add the kernel correction, the shifting
    ones delta+ shifting in XSPH's place)."""
    base = _copy(tmp_path, "solitaryCollision")
    s = st.load(base / "studyDict.convergence")
    st.prepare(s)
    for run in s.runs:
        m = foamdict.read(Path(run.path) / "system" / "metricsDict")["metrics"]
        assert m["peak"]["reference"] == 5.377
        # every run reads its peak by the fluid fraction too
        assert m["peakFraction"] == {"type": "peakElevation", "function": "crestFraction",
                                     "reference": 5.377}
        fo = foamdict.read(Path(run.path) / "system" / "controlDict")["functions"]
        assert fo["crestFraction"]["surface"] == "fraction"
    props = {r.variant: foamdict.read(Path(r.path) / "constant" / "sphProperties")
             for r in s.runs}
    kernel = {v: p["kernel"]["type"] for v, p in props.items()}
    filt = {v: p["densityFilter"]["type"] for v, p in props.items()}
    assert (kernel["default"], filt["default"]) == ("gaussian", "mlsReinitialisation")
    assert (kernel["defaultQ"], filt["defaultQ"]) == ("quartic", "mlsReinitialisation")
    assert (kernel["defaultNoMLS"], filt["defaultNoMLS"]) == ("gaussian", "none")
    assert (kernel["defaultQNoMLS"], filt["defaultQNoMLS"]) == ("quartic", "none")
    xsph = {v: p.get("velocityCorrection", {}).get("type") for v, p in props.items()}
    assert xsph["default"] == "xsph" and xsph["defaultNoXSPH"] == "none"
    assert (kernel["defaultNoXSPH"], filt["defaultNoXSPH"]) == ("gaussian", "mlsReinitialisation")
    # the density-diffusion variants replace the filter and nothing else; the stiffer
    # filter-free one also doubles vmax
    assert filt["defaultDelta"] == "fourtakasDeltaSPH" and filt["defaultAntuono"] == "antuonoDeltaSPH"
    assert filt["defaultNoMLSC2"] == "none"
    assert props["defaultNoMLSC2"]["equationOfState"]["vmax"] == 2 * props["default"]["equationOfState"]["vmax"]
    delta = {v: p["densityFilter"].get("delta") for v, p in props.items()}
    assert (delta["defaultDelta"], delta["defaultDelta007"], delta["defaultDelta005"]) == (0.1, 0.07, 0.05)
    # the C-SPH variants add P's kernel correction, one to the default, one to defaultDelta
    assert props["defaultCsph"]["kernelCorrection"]["type"] == "csph"
    assert props["defaultDeltaCsph"]["densityFilter"] == props["defaultDelta"]["densityFilter"]
    assert (kernel["defaultQDelta"], filt["defaultQDelta"]) == ("quartic", "fourtakasDeltaSPH")
    for variant, changed in (("defaultDelta", {"densityFilter"}),
                             ("defaultDelta007", {"densityFilter"}),
                             ("defaultDelta005", {"densityFilter"}),
                             ("defaultAntuono", {"densityFilter"}),
                             ("defaultNoMLSC2", {"densityFilter", "equationOfState"}),
                             ("defaultCsph", {"kernelCorrection"}),
                             ("defaultDeltaCsph", {"densityFilter", "kernelCorrection"}),
                             ("defaultQDelta", {"densityFilter", "kernel"}),
                             ("defaultDeltaShift", {"densityFilter", "particleShifting",
                                                    "velocityCorrection"})):
        differ = {k for k in props["default"].keys() | props[variant].keys()
                  if props["default"].get(k) != props[variant].get(k)}
        assert differ == changed, (variant, differ)


@pytest.mark.parametrize("case, dict_name", [
    ("solitaryWave", "studyDict.lowDissipation"),
    ("solitaryWave", "studyDict.lowDissipationScreen"),
    ("solitaryWallRunup", "studyDict.lowDissipation"),
    ("solitaryCollision", "studyDict.convergence"),
])
def test_the_commands_in_a_study_dictionarys_comments_name_its_runs(case, dict_name):
    """Every ``--only NAME`` that a study dictionary's comments show names one of its runs
    or variants (a variant selects all its resolutions)."""
    import re

    path = TUTORIALS / case / dict_name
    runs = st.load(path).runs
    names = {r.name for r in runs} | {r.variant for r in runs}
    shown = re.findall(r"--only\s+(\S+)", path.read_text())
    assert set(shown) <= names, set(shown) - names
