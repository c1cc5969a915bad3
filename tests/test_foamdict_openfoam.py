"""The dictionary reader on OpenFOAM's own syntax (issue 15): words with parentheses,
units in dimension sets, regex keys, scoping, $FOAM_CASE, refused code and special
files, binary/non-UTF-8 files, and large lists read straight into numpy arrays."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from sphfoam.case import foamdict
from sphfoam.case.foamdict import DimensionSet, FoamDictError, QuotedString, dumps, lookup, parse, read
from sphfoam.case.asciinum import parse_numbers

# ---------------------------------------------------------------------------
# Words with balanced parentheses
# ---------------------------------------------------------------------------

FV_SCHEMES = r"""/*--------------------------------*- C++ -*----------------------------------*\
  =========                 |
  \\      /  F ield         | OpenFOAM: The Open Source CFD Toolbox
   \\    /   O peration     | Website:  https://openfoam.org
    \\  /    A nd           | Version:  11
     \\/     M anipulation  |
\*---------------------------------------------------------------------------*/
FoamFile
{
    format      ascii;
    class       dictionary;
    object      fvSchemes;
}
// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //

ddtSchemes
{
    default         Euler;
}

gradSchemes
{
    default         Gauss linear;
    grad(U)         cellLimited Gauss linear 1;
}

divSchemes
{
    default         none;
    div(phi,U)      Gauss linearUpwind grad(U);
    div(phi,k)      Gauss upwind;
    div(phi,epsilon) Gauss upwind;
    div(phi,(p|rho)) Gauss linear;
    div((nuEff*dev2(T(grad(U))))) Gauss linear;
    div(phi,Yi_h)   Gauss limitedLinear 1;
}

laplacianSchemes
{
    default         Gauss linear corrected;
    laplacian(nuEff,U) Gauss linear limited corrected 0.33;
}

interpolationSchemes
{
    default         linear;
    interpolate(HbyA) linear;
}

species         (CH4 O2 CH2(S) CO2);

// ************************************************************************* //
"""


def test_fvschemes_all_div_entries_survive():
    d = parse(FV_SCHEMES)
    div = d["divSchemes"]
    assert list(div) == ["default", "div(phi,U)", "div(phi,k)", "div(phi,epsilon)",
                         "div(phi,(p|rho))", "div((nuEff*dev2(T(grad(U)))))", "div(phi,Yi_h)"]
    assert div["div(phi,U)"] == ("Gauss", "linearUpwind", "grad(U)")
    assert div["div(phi,k)"] == ("Gauss", "upwind")
    assert div["div(phi,Yi_h)"] == ("Gauss", "limitedLinear", 1)
    assert d["gradSchemes"]["grad(U)"] == ("cellLimited", "Gauss", "linear", 1)
    assert d["laplacianSchemes"]["laplacian(nuEff,U)"] == ("Gauss", "linear", "limited",
                                                          "corrected", 0.33)
    assert d["interpolationSchemes"]["interpolate(HbyA)"] == "linear"
    assert d["species"] == ["CH4", "O2", "CH2(S)", "CO2"]
    # written back and read again: the same keys and values
    assert parse(dumps(d)) == d


def test_words_with_parentheses_next_to_lists():
    d = parse("a (x(1) y); b f(x) (1 2); c 3(1 2 3); e List<scalar> 2(1 2); g (grad(U) (0 1));")
    assert d["a"] == ["x(1)", "y"]
    assert d["b"] == ("f(x)", [1, 2])
    assert d["c"] == [1, 2, 3]  # a count, not a word
    assert d["e"] == ("List<scalar>", [1, 2])
    assert d["g"] == ["grad(U)", [0, 1]]


@pytest.mark.parametrize("text", ["value uniform(0 0 0);", "a div(phi,U ;", "a f((x);"])
def test_unclosed_parenthesis_in_a_word_is_an_error(text):
    with pytest.raises(FoamDictError, match="not closed"):
        parse(text)


# ---------------------------------------------------------------------------
# Dimension sets
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("text, exps, factor", [
    ("[0 1 -1 0 0 0 0]", (0, 1, -1, 0, 0, 0, 0), 1.0),
    ("[velocity]", (0, 1, -1, 0, 0, 0, 0), 1.0),
    ("[m/s]", (0, 1, -1, 0, 0, 0, 0), 1.0),
    ("[kg m^-3]", (1, -3, 0, 0, 0, 0, 0), 1.0),
    ("[kg*m^-3]", (1, -3, 0, 0, 0, 0, 0), 1.0),
    ("[m^2/s]", (0, 2, -1, 0, 0, 0, 0), 1.0),
    ("[m/s^2]", (0, 1, -2, 0, 0, 0, 0), 1.0),
    ("[kinematicViscosity]", (0, 2, -1, 0, 0, 0, 0), 1.0),
    ("[N/m^2]", (1, -1, -2, 0, 0, 0, 0), 1.0),
    ("[J/kg/K]", (0, 2, -2, -1, 0, 0, 0), 1.0),
    ("[g/cm^3]", (1, -3, 0, 0, 0, 0, 0), 1000.0),
    ("[l/s]", (0, 3, -1, 0, 0, 0, 0), 1e-3),
    ("[bar]", (1, -1, -2, 0, 0, 0, 0), 1e5),
    ("[(mol/cm^3)^-0.5/s]", (0, 1.5, -1, 0, -0.5, 0, 0), 1e-3),
    ("[ m / s ]", (0, 1, -1, 0, 0, 0, 0), 1.0),
])
def test_dimension_sets_numeric_units_and_names(text, exps, factor):
    d = parse(f"nu {text} 2;")
    dims, value = d["nu"]
    assert isinstance(dims, DimensionSet) and value == 2
    assert tuple(dims) == exps
    assert math.isclose(dims.factor, factor, rel_tol=1e-12)


def test_units_write_back_as_written():
    d = parse("U [m/s] 1; rho [kg m^-3] 1000; p [0 2 -2 0 0 0 0] 0;")
    text = dumps(d)
    assert "[m/s]" in text and "[kg m^-3]" in text and "[0 2 -2 0 0 0 0]" in text
    back = parse(text)
    assert back == d and back["U"][0].units == "m/s" and back["rho"][0].units == "kg m^-3"


def test_unknown_unit_is_a_clear_error():
    with pytest.raises(FoamDictError) as info:
        parse("a 1;\nnu [m^2/furlong] 1e-6;", filename="constant/transportProperties")
    e = info.value
    assert (e.filename, e.line) == ("constant/transportProperties", 2)
    assert "unknown unit 'furlong'" in e.message and "velocity" in e.message and "\n" not in str(e)


def test_units_convert_values_in_the_case_schema():
    from sphfoam.case.schemas import TransportProperties

    t = TransportProperties.model_validate(parse("rho0 [g/cm^3] 1; nu [mm^2/s] 1;"))
    assert math.isclose(t.rho0, 1000.0) and math.isclose(t.nu, 1e-6)
    t = TransportProperties.model_validate(parse("rho0 rho0 [density] 998; nu [kinematicViscosity] 1e-6;"))
    assert (t.rho0, t.nu) == (998, 1e-6)


def test_dimension_set_missing_its_semicolon_is_one_line():
    text = "dimensions      [0 1 -2 0 0 0 0]\nvalue           (0 -9.81);\n"
    with pytest.raises(FoamDictError) as info:
        parse(text, filename="constant/g")
    e = info.value
    assert (e.line, e.column) == (1, 33)
    assert str(e) == ("constant/g:1:33: expected ';' after value of 'dimensions' "
                      "(a dimension set, then 'value' on line 2)")
    with pytest.raises(FoamDictError, match="missing ']'") as info:
        parse("nu [0 2 -1 0 0 0 0 1e-6;\nrho0 1000;")
    assert info.value.line == 1


def test_dimension_set_missing_semicolon_through_the_case(tmp_path):
    from sphfoam.case.case import Case
    from sphfoam.case.errors import CaseError

    (tmp_path / "system").mkdir()
    (tmp_path / "constant").mkdir()
    (tmp_path / "constant" / "g").write_text("dimensions [0 1 -2 0 0 0 0]\nvalue (0 -9.81);\n")
    with pytest.raises(CaseError) as info:
        Case(tmp_path).gravity
    text = str(info.value)
    assert "constant/g" in text and "expected ';'" in text and len(text.splitlines()) <= 3


# ---------------------------------------------------------------------------
# Regex keys and their lookup order
# ---------------------------------------------------------------------------

FV_SOLUTION = """
solvers
{
    p
    {
        solver          GAMG;
        tolerance       1e-06;
    }
    "(U|k|epsilon)"
    {
        solver          smoothSolver;
        tolerance       1e-05;
    }
    "(U|k)Final"
    {
        $U;
        relTol          0;
    }
    "k.*"
    {
        solver          PBiCGStab;
    }
    epsilon
    {
        solver          exact;
    }
}
kSolver $solvers.k;
"""


def test_regex_keys_lookup_order_and_macros():
    d = parse(FV_SOLUTION)
    s = d["solvers"]
    assert QuotedString("(U|k|epsilon)") in s
    assert lookup(s, "p")["solver"] == "GAMG"
    assert lookup(s, "U")["solver"] == "smoothSolver"
    assert lookup(s, "epsilon")["solver"] == "exact"  # exact key before any pattern
    assert lookup(s, "k")["solver"] == "PBiCGStab"  # the last pattern defined wins
    assert lookup(s, "kFinal")["solver"] == "PBiCGStab"
    assert lookup(s, "UFinal") == {"solver": "smoothSolver", "tolerance": 1e-05, "relTol": 0}
    assert lookup(s, "nope", None) is None
    with pytest.raises(KeyError):
        lookup(s, "nope")
    assert d["kSolver"] == {"solver": "PBiCGStab"}  # $solvers.k through "k.*"
    with pytest.raises(FoamDictError, match=r"unknown macro \$solvers.pFinal"):
        parse(FV_SOLUTION + "pFinal $solvers.pFinal;")


def test_remove_with_a_regex_and_invalid_regex_key():
    d = parse('Ux 1; Uy 2; p 3; "U.*" 4; #remove "U.*"')
    assert d == {"p": 3}
    with pytest.raises(FoamDictError, match="not a valid regular expression"):
        parse('"(U|k" 1;')


# ---------------------------------------------------------------------------
# Scoping: dot syntax, slash syntax, '!' and other files
# ---------------------------------------------------------------------------


def test_slash_and_bang_scoping(tmp_path):
    (tmp_path / "testSlashDict2").write_text(
        "internalField 5.6;\nactive\n{\n    type fixedValue;\n    value.air $internalField;\n}\n")
    text = """
    internalField 3.4;
    active
    {
        type fixedValue;
        value.air $internalField;
    }
    inactive
    {
        type anotherFixedValue;
        value $../active/value.air;
        anotherValue $!active/value.air;
        sub
        {
            value $../../active/value.air;
            anotherValue $!active/value.air;
            dotStyle $:active.value.air;
        }
    }
    "U.*" { solver GAMG; }
    e.air { $U.air; }
    external { value $testSlashDict2!active/value.air; }
    active2 { $testSlashDict2!active; }
    direct $active/type;
    """
    d = parse(text, include_dir=tmp_path)
    assert d["inactive"]["value"] == 3.4 and d["inactive"]["anotherValue"] == 3.4
    assert d["inactive"]["sub"] == {"value": 3.4, "anotherValue": 3.4, "dotStyle": 3.4}
    assert d["e.air"] == {"solver": "GAMG"}
    assert d["external"] == {"value": 5.6}
    assert d["active2"] == {"type": "fixedValue", "value.air": 5.6}
    assert d["direct"] == "fixedValue"
    with pytest.raises(FoamDictError, match="above the top level"):
        parse("a 1; b $../a;")
    with pytest.raises(FoamDictError, match=r"unknown macro \$!nope/x"):
        parse("a { x 1; } b $!nope/x;")


def test_input_syntax_slash_keeps_dots_in_keys():
    d = parse("#inputSyntax slash;\na { b 1; } a.b 2; c $a.b; e $a/b;")
    assert (d["c"], d["e"]) == (2, 1)
    d = parse("#inputSyntax dot;\na { b 1; } c $a.b;")
    assert d["c"] == 1
    with pytest.raises(FoamDictError, match="'slash' or 'dot'"):
        parse("#inputSyntax colon;")


# ---------------------------------------------------------------------------
# $FOAM_CASE, $FOAM_CASENAME and paths
# ---------------------------------------------------------------------------


def _case(tmp_path):
    case = tmp_path / "myCase"
    for sub in ("system", "constant", "common"):
        (case / sub).mkdir(parents=True)
    return case


def test_foam_case_in_include_paths(tmp_path):
    case = _case(tmp_path)
    (case / "common" / "defaults").write_text("rho 1000;")
    (case / "constant" / "more").write_text("nu 1e-6;")
    (case / "system" / "controlDict").write_text(
        '#include "$FOAM_CASE/common/defaults"\n#include "${FOAM_CASE}/constant/more"\n'
        '#include "<constant>/more"\nname $FOAM_CASENAME;\nwhere $FOAM_CASE;\n')
    d = read(case / "system" / "controlDict")
    assert d == {"rho": 1000, "nu": 1e-6, "name": "myCase", "where": str(case.resolve())}
    assert isinstance(d["where"], QuotedString)
    assert foamdict.expand("$FOAM_CASE/a:$FOAM_CASENAME", case) == f"{case}/a:myCase"


def test_include_paths_stay_in_the_case_unless_absolute(tmp_path):
    case = _case(tmp_path)
    outside = tmp_path / "outside"
    outside.write_text("x 1;")
    ctl = case / "system" / "controlDict"
    ctl.write_text('#include "../../outside"\n')
    with pytest.raises(FoamDictError, match="outside the case directory"):
        read(ctl)
    ctl.write_text('#include "$FOAM_CASE/../outside"\n')
    with pytest.raises(FoamDictError, match="outside the case directory"):
        read(ctl)
    ctl.write_text(f'#include "{outside}"\n')  # absolute: on purpose
    assert read(ctl) == {"x": 1}
    ctl.write_text('#include "$HOME/x"\n')
    with pytest.raises(FoamDictError, match="only \\$FOAM_CASE and \\$FOAM_CASENAME"):
        read(ctl)
    with pytest.raises(FoamDictError, match="case directory is not known"):
        parse('#include "$FOAM_CASE/x"', include_dir=outside.parent)


# ---------------------------------------------------------------------------
# Code directives, special files, size limits, no echo of included contents
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("text", [
    '#calc "1 + 2"',
    'a #calc "$b * 2";',
    "#codeStream { code #{ os << 1; #}; }",
    "a #codeStream { code #{ os << 1; #}; };",
    "code #{\n    system(\"rm -rf ~\");\n#};",
    'a #eval "1 + 2";',
])
def test_code_is_never_executed(text):
    with pytest.raises(FoamDictError, match="never compiles or executes code"):
        parse(text)


@pytest.mark.parametrize("target", ["/dev/zero", "/dev/null", "/dev/stdin"])
def test_include_of_special_files_is_refused(target):
    if not os.path.exists(target):
        pytest.skip(f"{target} does not exist here")
    for directive in ("#include", "#includeIfPresent"):
        with pytest.raises(FoamDictError, match="not a regular file"):
            parse(f'{directive} "{target}"')


def test_include_of_fifo_and_directory_is_refused(tmp_path):
    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this platform")
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(FoamDictError, match="not a regular file"):
        parse('#include "fifo"', include_dir=tmp_path)  # returns at once: never opened
    with pytest.raises(FoamDictError, match="is a directory"):
        parse('#include "."', include_dir=tmp_path)
    with pytest.raises(FoamDictError, match="not a regular file"):
        read(tmp_path / "fifo")


def test_include_size_is_limited(tmp_path, monkeypatch):
    monkeypatch.setattr(foamdict, "MAX_FILE_BYTES", 1000)
    (tmp_path / "big").write_text("x 1;\n" * 300)
    with pytest.raises(FoamDictError, match="limited to"):
        parse('#include "big"', include_dir=tmp_path)


def test_included_contents_are_never_echoed(tmp_path):
    secret = "s3cr3t-Passw0rd"
    (tmp_path / "inc").write_text(f"root:{secret}:0:0\n{secret} {secret} {{\n")
    for text in ('#include "inc"', 'a { #include "inc" }'):
        with pytest.raises(FoamDictError) as info:
            parse(text, include_dir=tmp_path)
        assert secret not in str(info.value) and "inc" in str(info.value)
    (tmp_path / "inc2").write_text(f"a ${secret};")
    with pytest.raises(FoamDictError) as info:
        parse('#include "inc2"', include_dir=tmp_path)
    assert secret not in str(info.value)


# ---------------------------------------------------------------------------
# Binary and non-UTF-8 files
# ---------------------------------------------------------------------------


def test_binary_and_latin1_files_name_the_file(tmp_path):
    p = tmp_path / "transportProperties"
    p.write_bytes("nu 1e-6; // viscosit\xe9\n".encode("latin-1"))
    with pytest.raises(FoamDictError) as info:
        read(p)
    e = info.value
    assert e.filename == str(p) and (e.line, e.column) == (1, 21)
    assert "0xe9" in e.message and "UTF-8" in e.message
    p.write_bytes(b"FoamFile { format binary; class scalarField; }\n2(\x00\x00\x00\x00\x00\x00\xf0?)")
    with pytest.raises(FoamDictError, match="binary file") as info:
        read(p)
    assert info.value.filename == str(p)
    p.write_bytes(b"FoamFile { format binary; class scalarField; }\n1(?\xf0)")
    with pytest.raises(FoamDictError, match="binary"):
        read(p)
    p.write_bytes(b"FoamFile { format binary; class dictionary; }\n a 1;")
    assert read(p)["a"] == 1  # a binary header with no list data is fine (as in OpenFOAM)
    p.write_text("nu 1e-6; // viscosité\n", encoding="utf-8")
    assert read(p) == {"nu": 1e-6}


def test_binary_particle_field_through_the_dictionary_reader(tmp_path):
    from sphfoam.io.fields import write_field

    write_field(tmp_path / "rho", np.array([1000.0, 999.5, 1001.25]), fmt="binary")
    with pytest.raises(FoamDictError, match="sphfoam.io.fields") as info:
        read(tmp_path / "rho")
    assert info.value.filename == str(tmp_path / "rho")


def test_case_reports_bad_bytes_as_a_case_error(tmp_path):
    from sphfoam.case.case import Case
    from sphfoam.case.errors import CaseError

    (tmp_path / "system").mkdir()
    (tmp_path / "system" / "controlDict").write_bytes(b"endTime 1; // \xff\n")
    with pytest.raises(CaseError) as info:
        Case(tmp_path).control
    assert "system/controlDict" in str(info.value) and "0xff" in str(info.value)


# ---------------------------------------------------------------------------
# Large nonuniform lists straight into numpy
# ---------------------------------------------------------------------------


def test_nonuniform_lists_come_back_as_numpy_arrays(path):
    rng = np.random.default_rng(3)
    v = rng.standard_normal((500, 3)) * 10.0 ** rng.integers(-25, 25, (500, 3))
    s = v[:, 0]
    lab = rng.integers(-10**12, 10**12, 300)
    text = (
        "internalField nonuniform List<vector>\n500\n(\n"
        + "".join("(%r %r %r)\n" % tuple(r) for r in v.tolist()) + ")\n;\n"
        + "p nonuniform List<scalar> 500(" + " ".join("%.6g" % x for x in s) + ");\n"
        + "ids nonuniform List<label> 300\n(\n" + "\n".join(map(str, lab)) + "\n);\n"
        + "two nonuniform List<vector2D> 100(" + "(1 2) " * 100 + ");\n"
        + "after 1;\n"
    )
    d = parse(text)
    kind, typ, arr = d["internalField"]
    assert (kind, typ) == ("nonuniform", "List<vector>")
    assert isinstance(arr, np.ndarray) and arr.shape == (500, 3) and arr.dtype == np.float64
    assert arr.tobytes() == v.tobytes()  # bit for bit
    p = d["p"][2]
    assert p.tobytes() == np.array([float("%.6g" % x) for x in s]).tobytes()
    assert d["ids"][2].dtype == np.int64 and np.array_equal(d["ids"][2], lab)
    assert d["two"][2].shape == (100, 2)
    assert d["after"] == 1
    back = parse(dumps(d))  # the writer takes arrays; they read back equal
    assert np.array_equal(back["internalField"][2], arr) and back["after"] == 1


def test_list_that_is_not_plain_numbers_takes_the_general_path(path):
    body = "(1 2 3) " * 99 + "(1 2)"
    d = parse(f"a List<vector> 100({body});")  # a 2-vector: read as lists, not misread
    assert isinstance(d["a"][1], list) and d["a"][1][-1] == [1, 2]
    with pytest.raises(FoamDictError, match="mismatch"):
        parse("a List<scalar> 120(" + "1 " * 119 + ");")
    d = parse("a List<scalar> 100(" + "1 " * 99 + "x);")
    assert isinstance(d["a"][1], list) and d["a"][1][-1] == "x"


@pytest.fixture(params=["compiled", "small"])
def path(request, monkeypatch):
    """Run a test through the numba pass and through the regex + numpy path."""
    from sphfoam.case import asciinum

    monkeypatch.setattr(asciinum, "COMPILED_MIN_BYTES", 0 if request.param == "compiled" else 1 << 60)
    return request.param


@pytest.mark.parametrize("fmt", ["%r", "%.17g", "%.6g", "%.15g", "%.18e", "%.16g", "%.25g"])
def test_parse_numbers_is_exact(fmt, path):
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.standard_normal(3000) * 10.0 ** rng.integers(-40, 40, 3000),
                        rng.random(1000),
                        [0.0, -0.0, 5e-324, 1.7976931348623157e308, 1e22, 1e23, 0.1, 2.0 ** 53 + 1]])
    text = " ".join(fmt % v for v in x.tolist())
    ref = np.array([float(t) for t in text.split()])
    got = parse_numbers(text, ref.size)
    assert got.tobytes() == ref.tobytes()


def test_parse_numbers_midpoints_and_rejects(path):
    import decimal

    rng = np.random.default_rng(11)
    toks = []
    for x in rng.random(300).tolist():  # exact halfway points between neighbouring doubles
        h = (decimal.Decimal(x) + decimal.Decimal(float(np.nextafter(x, 2.0)))) / 2
        toks += [format(h, ".18g"), format(h, "f")]
    ref = np.array([float(t) for t in toks])
    assert parse_numbers(" ".join(toks), len(toks)).tobytes() == ref.tobytes()
    assert parse_numbers("1 2 x", 3) is None
    assert parse_numbers("1 2", 3) is None
    assert parse_numbers("1 nan", 2) is None
    assert parse_numbers("(1 2) (3)", 4, 2) is None
    assert parse_numbers("1.5 2", 2, integer=True) is None
    assert parse_numbers(b"(1 2)\n(3 4)", 4, 2).tolist() == [[1.0, 2.0], [3.0, 4.0]]
    assert parse_numbers("-5 99999999999999999999999", 2, integer=True) is None  # > int64
    assert parse_numbers("-5 9223372036854775807", 2, integer=True).tolist() == [-5, 2**63 - 1]
    assert parse_numbers("-9223372036854775808 0", 2, integer=True).tolist() == [-2**63, 0]
    assert parse_numbers("1-2 3", 2) is None and parse_numbers("(1 2)(3 4)", 4, 2).shape == (2, 2)
    assert parse_numbers("1 (2)", 2) is None and parse_numbers("1e5 .5 +.5 -2.", 4).tolist() == [
        1e5, 0.5, 0.5, -2.0]


def test_array_path_follows_the_count_rule():
    # a count after a space on the same line is an ordinary item, for long lists too
    d = parse("a List<scalar> 150 (" + "1 " * 150 + ");")
    assert d["a"][1] == 150 and isinstance(d["a"][2], list)
    d = parse("a List<scalar> 150\n  (" + "1 " * 150 + ");")
    assert isinstance(d["a"][1], np.ndarray) and d["a"][1].shape == (150,)


def test_foam_case_in_a_table_file_name(tmp_path):
    from sphfoam import registry

    (tmp_path / "constant").mkdir()
    rows = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [2.0, 1.0, 0.0]]
    np.savetxt(tmp_path / "constant" / "paddle.dat", rows)
    for name in ("$FOAM_CASE/constant/paddle.dat", "<constant>/paddle.dat"):
        m = registry.build("motion", {"type": "displacementTable", "file": name})
        m.resolve(tmp_path)
        assert m.displacement(1.5) == pytest.approx((0.75, 0.0))


def test_deep_nesting_and_nul_in_an_include_name_are_clean_errors(tmp_path):
    for text in ["a " + "(" * 5000 + ";", "a " + "{ b " * 5000, "a " + "[" * 3000]:
        with pytest.raises(FoamDictError):
            parse(text)
    (tmp_path / "deep").write_text("x " + "(" * 150 + ")" * 150 + ";")
    with pytest.raises(FoamDictError, match="nested more than"):
        parse("a { " * 100 + '#include "deep"' + " }" * 100, include_dir=tmp_path)
    with pytest.raises(FoamDictError, match="NUL"):
        parse('#include "a\x00b"', include_dir=tmp_path)


def test_case_refuses_a_fifo_or_directory_as_a_dictionary(tmp_path):
    from sphfoam.case.case import Case
    from sphfoam.case.errors import CaseError

    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this platform")
    (tmp_path / "system").mkdir()
    os.mkfifo(tmp_path / "system" / "controlDict")
    with pytest.raises(CaseError, match="not a regular file"):
        Case(tmp_path).control
    (tmp_path / "system" / "particleDict").mkdir()
    with pytest.raises(CaseError, match="is a directory"):
        Case(tmp_path).particles
