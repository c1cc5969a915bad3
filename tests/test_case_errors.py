"""Bad input gives one screen naming file, key, bad value, valid choices; no traceback."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.cli import app

runner = CliRunner()


def problems(case_dir) -> str:
    with pytest.raises(CaseError) as e:
        Case(case_dir).validate()
    return str(e.value)


def test_tutorials_are_valid(tutorial):
    for name in ("damBreak", "hydrostaticTank"):
        Case(tutorial(name)).validate()


def test_misspelt_kernel_names_file_key_choices_and_suggestion(tutorial):
    case = tutorial("damBreak", {"constant/sphProperties:kernel.type": "quartc"})
    msg = problems(case)
    assert "constant/sphProperties: kernel.type" in msg
    assert "'quartc' is not a registered kernel" in msg
    assert "did you mean 'quartic'?" in msg
    for k in ("cubicSpline", "quartic", "quintic", "wendlandC2"):
        assert k in msg


def test_unknown_key_in_control_dict(tutorial):
    case = tutorial("damBreak", {"system/controlDict:endTme": 0.1})
    msg = problems(case)
    assert "system/controlDict: endTme: unknown key 'endTme'; did you mean 'endTime'?" in msg


def test_bad_choice_lists_valid_choices(tutorial):
    case = tutorial("damBreak", {"system/controlDict:writeControl": "timestep"})
    msg = problems(case)
    assert "system/controlDict: writeControl: 'timestep' is not valid; did you mean 'timeStep'?" in msg
    assert "adjustableRunTime" in msg


def test_unknown_model_coefficient(tutorial):
    case = tutorial("damBreak", {"constant/sphProperties:viscosity.alfa": 0.1})
    msg = problems(case)
    assert "viscosity.alfa: unknown key 'alfa'; did you mean 'alpha'?" in msg


def test_unknown_family_and_missing_required(tutorial):
    case = tutorial("damBreak", {"constant/sphProperties:viscosty": {"type": "laminar"},
                                 "constant/sphProperties:viscosity": None})
    msg = problems(case)
    assert "unknown key 'viscosty'; did you mean 'viscosity'?" in msg
    assert "viscosity: required" in msg


def test_dimension_mismatch(tutorial):
    from sphfoam.case.foamdict import DimensionSet

    case = tutorial("damBreak", {"constant/transportProperties:nu":
                                 (DimensionSet((0, 2, -2, 0, 0, 0, 0)), 1e-6)})
    assert "do not match" in problems(case)


def test_syntax_error_has_line_and_column(tutorial):
    case = tutorial("damBreak")
    f = case / "system" / "controlDict"
    f.write_text(f.read_text().replace("writeInterval   20;", "writeInterval   20;\n    {"))
    msg = problems(case)
    assert "system/controlDict: syntax error: system/controlDict:" in msg
    assert msg.count("syntax error") == 1      # reported once, not per consumer


def test_cli_reports_one_screen_without_traceback(tutorial):
    case = tutorial("damBreak", {"constant/sphProperties:kernel.type": "quartc"})
    res = runner.invoke(app, ["check", str(case)])
    assert res.exit_code == 2
    assert "did you mean 'quartic'?" in res.output
    assert "Traceback" not in res.output
    res = runner.invoke(app, ["run", str(case)])
    assert res.exit_code == 2 and "Traceback" not in res.output


def test_models_lists_families():
    res = runner.invoke(app, ["models"])
    assert res.exit_code == 0
    for word in ("wendlandC2", "quartic", "tait", "artificial", "laminar", "stationaryGhosts",
                 "monaghan2007", "damBreakFront"):
        assert word in res.output
    assert "Undefined" not in res.output            # a coefficient without a default
    res = runner.invoke(app, ["models", "waveMaker"])
    assert "height (required)" in " ".join(res.output.split())
    res = runner.invoke(app, ["models", "kernal"])
    assert res.exit_code == 2 and "did you mean 'kernel'?" in res.output


def test_check_reports_a_broken_study_dictionary_but_not_a_log_naming_one(tutorial):
    """A shell log redirected into the case (``> log1``) quotes "studyDict" but is no study
    dictionary; a file called studyDict.* that does not parse is one, and is reported."""
    from sphfoam.check import check_case

    case = tutorial("hydrostaticTank")
    (case / "log1").write_text("study studyDict.mine: 2 run(s)\n| run | H18 |\n")
    check_case(case, study_runs=False)
    (case / "studyDict.mine").write_text("variants { a { dx 0.1; }\n")
    with pytest.raises(CaseError) as e:
        check_case(case, study_runs=False)
    assert "studyDict.mine" in str(e.value) and "log1" not in str(e.value)
