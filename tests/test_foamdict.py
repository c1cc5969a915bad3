"""Tests for the OpenFOAM dictionary reader/writer (sphfoam.case.foamdict)."""

from __future__ import annotations

import string
import time

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from sphfoam.case.foamdict import (
    DimensionSet,
    FoamDictError,
    QuotedString,
    dumps,
    parse,
    read,
    write,
)


def assert_same(a, b, path="root"):
    """Equality that also checks types (int vs float, str vs QuotedString, ...)."""
    assert type(a) is type(b), f"{path}: {type(a).__name__} != {type(b).__name__} ({a!r} vs {b!r})"
    if isinstance(a, dict):
        assert list(a) == list(b), f"{path}: keys {list(a)} != {list(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), f"{path}: length {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{i}]")
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


# ---------------------------------------------------------------------------
# Hypothesis round trip
# ---------------------------------------------------------------------------

_first = string.ascii_letters + "_"
keys = st.builds(str.__add__, st.sampled_from(_first), st.text(_first + string.digits, max_size=10))
words = st.builds(
    str.__add__, st.sampled_from(_first), st.text(_first + string.digits + ".:<>+-/,|", max_size=12)
).filter(lambda w: "//" not in w)
quoted = st.text(
    alphabet=string.ascii_letters + string.digits + " \"\\'/*;{}()[]$#.,:-_+\t", max_size=20
).map(QuotedString)
floats = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.floats(min_value=-1e-3, max_value=1e-3, allow_nan=False),
    st.sampled_from([0.0, -0.0, 1e-05, 0.1, -1.0, 1e300, 5e-324, 1e16, 123456.789]),
)
ints = st.one_of(st.integers(-1000, 1000), st.integers(-(10**20), 10**20))
dimsets = st.lists(st.integers(-4, 4), min_size=7, max_size=7).map(DimensionSet)
scalars = st.one_of(ints, floats, words, quoted)


def dicts(values):
    return st.dictionaries(keys, values, max_size=5)


list_items = st.recursive(
    st.one_of(scalars, dimsets),
    lambda children: st.one_of(
        st.lists(children, max_size=6),
        dicts(st.one_of(scalars, st.lists(children, max_size=3))),
    ),
    max_leaves=20,
)
lists = st.lists(list_items, max_size=8)
tuples = st.lists(st.one_of(scalars, dimsets, st.lists(scalars, max_size=4)), min_size=2, max_size=5).map(tuple)
entry_values = st.recursive(
    st.one_of(scalars, dimsets, lists, tuples, st.none()),
    dicts,
    max_leaves=25,
)


@settings(max_examples=150, deadline=None)
@given(dicts(entry_values))
# a word after a list written over several lines, in a value with a dimension set: it was
# written on a line of its own, which the parser reads as a missing ';'
@example({"a0": None, "a": (DimensionSet((0, 0, 0, 0, 0, 0, 0)),
                            [-10**9, -10**12, -10**19, 1.0000000000000002e16], "a")})
def test_round_trip(d):
    text = dumps(d)
    assert_same(parse(text), d)


@settings(max_examples=30, deadline=None)
@given(dicts(entry_values), st.sampled_from([{"object": "sphProperties"}, {"class": "volVectorField"}]))
def test_round_trip_with_header(d, header):
    back = parse(dumps(d, header=header))
    foamfile = back.pop("FoamFile")
    assert foamfile["version"] == 2.0 and foamfile["format"] == "ascii"
    assert all(foamfile[k] == v for k, v in header.items())
    assert_same(back, {k: v for k, v in d.items() if k != "FoamFile"})


def test_round_trip_long_and_awkward_lists():
    d = {
        "values": [float(i) / 7 for i in range(50)],
        "counts": [3, [1, 2, 3], 0, [], -1, [4]],
        "field": ("nonuniform", "List<scalar>", 2, [1.5, 2.5]),
        "points": [[0, 0, 0], [1, 0, 0.5]],
        "q": QuotedString('say "hi" \\ bye'),
        "empty": {},
        "emptyList": [],
        "quoted key": 1,
        QuotedString("(U|p)"): 2,
    }
    text = dumps(d)
    assert "50\n(" in text  # long lists get a count prefix
    assert_same(parse(text), {**d, "quoted key": 1})


def test_write_and_read_file(tmp_path):
    path = tmp_path / "constant" / "sphProperties"
    write(path, {"kernel": "cubicSpline", "h": 0.01}, header={"object": "sphProperties"})
    text = path.read_text()
    assert text.index("FoamFile") < text.index("kernel")
    assert "kernel          cubicSpline;" in text
    d = read(path)
    assert d["FoamFile"]["object"] == "sphProperties"
    assert d["FoamFile"]["class"] == "dictionary"
    assert d["kernel"] == "cubicSpline" and d["h"] == 0.01


@pytest.mark.parametrize(
    "value",
    ["two words", "semi;colon", "", "3", "1e5", "$macro", "#dir", "a//b", 'q"uote', "(paren"],
)
def test_dumps_rejects_invalid_words(value):
    with pytest.raises(ValueError):
        dumps({"key": value})
    dumps({"key": QuotedString(value)})  # fine when quoted


@pytest.mark.parametrize("value", [float("nan"), float("inf"), ("one",), (1, (2, 3)), [None], (1, {"a": 1})])
def test_dumps_rejects_unwritable_values(value):
    with pytest.raises(ValueError):
        dumps({"key": value})


def test_dumps_bool_as_words():
    assert parse(dumps({"a": True, "b": False})) == {"a": "true", "b": "false"}


# ---------------------------------------------------------------------------
# Syntax features
# ---------------------------------------------------------------------------


def test_foamfile_header_and_basic_entries():
    d = parse(
        """
        FoamFile
        {
            version     2.0;
            format      ascii;
            class       dictionary;
            location    "constant";
            object      sphProperties;
        }
        kernel      cubicSpline;
        h           0.1;
        n           3;
        """
    )
    assert list(d) == ["FoamFile", "kernel", "h", "n"]
    assert d["FoamFile"]["location"] == "constant"
    assert type(d["FoamFile"]["location"]) is QuotedString
    assert_same(d["FoamFile"]["version"], 2.0)
    assert_same(d["n"], 3)


def test_numbers_and_words():
    d = parse(
        "a 3; b -2; c 1e-3; d 0.5; e -1.; f .5; g 1E+05; h +4;"
        "w1 on; w2 latestTime; w3 a.b; w4 nonUniform; w5 List<scalar>; w6 yes; w7 false; w8 1e; w9 -;"
    )
    assert_same([d[k] for k in "abcdefgh"], [3, -2, 1e-3, 0.5, -1.0, 0.5, 1e5, 4])
    assert_same(
        [d[f"w{i}"] for i in range(1, 10)],
        ["on", "latestTime", "a.b", "nonUniform", "List<scalar>", "yes", "false", "1e", "-"],
    )


def test_quoted_strings():
    d = parse(r'a "hello world"; b "with \"quotes\" and \\ backslash"; c "C:\path"; d "";')
    assert_same(d["a"], QuotedString("hello world"))
    assert d["b"] == 'with "quotes" and \\ backslash'
    assert d["c"] == "C:\\path"
    assert_same(d["d"], QuotedString(""))


def test_multi_token_values_and_none():
    d = parse("type  fixedValue; value uniform (0 0 0); nu nu [0 2 -1 0 0 0 0] 1e-06; flag;")
    assert d["type"] == "fixedValue"
    assert_same(d["value"], ("uniform", [0, 0, 0]))
    assert_same(d["nu"], ("nu", DimensionSet((0, 2, -1, 0, 0, 0, 0)), 1e-06))
    assert d["flag"] is None


def test_nested_dicts_and_optional_semicolon():
    d = parse("outer { inner { x 1; } ; y (1 2); }; z 3;")
    assert d == {"outer": {"inner": {"x": 1}, "y": [1, 2]}, "z": 3}


def test_lists():
    d = parse(
        """
        nested ((1 2) (-3 (4 5)) ());
        mixed (a "b" 1 2.5 [0 1 0 0 0 0 0]);
        counted 3(1 2 3);
        countedSpaced 2
        (
            (0 0 0)
            (1 1 1)
        );
        empty 0();
        uniform 4{0.5};
        uniformVec 2{(1 0 0)};
        boundary
        (
            inlet { type patch; faces ((0 1 2 3)); }
            walls
            {
                type wall;
            }
        );
        """
    )
    assert_same(d["nested"], [[1, 2], [-3, [4, 5]], []])
    assert_same(d["mixed"], ["a", QuotedString("b"), 1, 2.5, DimensionSet((0, 1, 0, 0, 0, 0, 0))])
    assert_same(d["counted"], [1, 2, 3])
    assert_same(d["countedSpaced"], [[0, 0, 0], [1, 1, 1]])
    assert_same(d["empty"], [])
    assert_same(d["uniform"], [0.5, 0.5, 0.5, 0.5])
    assert_same(d["uniformVec"], [[1, 0, 0], [1, 0, 0]])
    d["uniformVec"][0][0] = 9  # copies, not aliases
    assert d["uniformVec"][1] == [1, 0, 0]
    assert d["boundary"] == [
        "inlet", {"type": "patch", "faces": [[0, 1, 2, 3]]},
        "walls", {"type": "wall"},
    ]


def test_nonuniform_field_as_openfoam_writes_it():
    d = parse("internalField   nonuniform List<scalar>\n3\n(\n1\n2.5\n3\n)\n;\n")
    assert_same(d["internalField"], ("nonuniform", "List<scalar>", [1, 2.5, 3]))


def test_dimension_sets():
    d = parse("a [0 1 -1 0 0 0 0]; b [0 2 -1 0 0]; c [0 0.5 0 0 0 0 0];")
    assert_same(d["a"], DimensionSet((0, 1, -1, 0, 0, 0, 0)))
    assert len(d["b"]) == 5
    assert_same(d["c"][1], 0.5)


def test_comments_anywhere():
    d = parse(
        """/* header
        comment */ a /* x */ 1 /* y */; // end of line
        b // comment between key and value
        (1 /* in list */ 2 // line comment in list
        3);
        c/**/2;
        d { /* in dict */ e 4; // ... 
        }
        path a/b/c;
        //"""
    )
    assert d == {"a": 1, "b": [1, 2, 3], "c": 2, "d": {"e": 4}, "path": "a/b/c"}


def test_later_entries_override_and_merge():
    d = parse("a 1; s { x 1; t { p 1; q 2; } } a 2; s { y 2; t { q 3; } }")
    assert d == {"a": 2, "s": {"x": 1, "t": {"p": 1, "q": 3}, "y": 2}}
    d = parse("s { x 1; } s 5; t 5; t { x 1; }")
    assert d == {"s": 5, "t": {"x": 1}}


# ---------------------------------------------------------------------------
# Directives
# ---------------------------------------------------------------------------


def test_include_relative_to_including_file(tmp_path):
    (tmp_path / "system").mkdir()
    (tmp_path / "common").mkdir()
    (tmp_path / "common" / "defaults").write_text('rho 1000; nested { a 1; } #include "more"\n')
    (tmp_path / "common" / "more").write_text("g (0 0 -9.81); extra 7;")
    (tmp_path / "system" / "controlDict").write_text(
        'nu 1e-6;\nrho 1;\n#include "../common/defaults"\nnested { b 2; }\nextra 8;\nr $rho;\n'
    )
    d = read(tmp_path / "system" / "controlDict")
    assert d == {"nu": 1e-6, "rho": 1000, "nested": {"a": 1, "b": 2}, "g": [0, 0, -9.81], "extra": 8, "r": 1000}


def test_include_absolute_path_and_include_dir(tmp_path):
    inc = tmp_path / "inc"
    inc.write_text("x 1;")
    assert parse(f'#include "{inc}"') == {"x": 1}
    assert parse('#include "inc" y 2;', include_dir=tmp_path) == {"x": 1, "y": 2}
    assert parse('sub { #include "inc" }', filename=str(tmp_path / "dict")) == {"sub": {"x": 1}}


def test_include_sees_outer_macros(tmp_path):
    (tmp_path / "inc").write_text("b $a; c $:top.v;")
    d = parse('top { v 3; } a 1; sub { #include "inc" }', include_dir=tmp_path)
    assert d["sub"] == {"b": 1, "c": 3}


def test_include_if_present_missing(tmp_path):
    d = parse('a 1;\n#includeIfPresent "doesNotExist"\nb 2;', include_dir=tmp_path)
    assert d == {"a": 1, "b": 2}


def test_include_missing_is_error(tmp_path):
    with pytest.raises(FoamDictError) as info:
        parse('a 1;\n  #include "doesNotExist"\n', filename=str(tmp_path / "d"))
    assert (info.value.line, info.value.column) == (2, 12)
    assert "doesNotExist" in str(info.value)


def test_recursive_include_is_error(tmp_path):
    (tmp_path / "self").write_text('#include "self"')
    with pytest.raises(FoamDictError, match="nested too deeply"):
        read(tmp_path / "self")


def test_error_in_included_file_names_that_file(tmp_path):
    (tmp_path / "inc").write_text("a 1;\nb 2\n}")
    with pytest.raises(FoamDictError) as info:
        parse('x { #include "inc" }', filename=str(tmp_path / "main"), include_dir=tmp_path)
    assert info.value.filename == str(tmp_path / "inc")
    assert (info.value.line, info.value.column) == (3, 1)


def test_remove_and_input_mode():
    d = parse("a 1; b 2; c 3; d 4; sub { x 1; y 2; #remove x } #remove b #remove (c d) #inputMode merge e 5;")
    assert d == {"a": 1, "sub": {"y": 2}, "e": 5}
    assert parse('a 1; "b" 2; #remove ("b" missing)') == {"a": 1}


def test_unsupported_directive():
    with pytest.raises(FoamDictError, match="unsupported directive #calc inside a value"):
        parse('a #calc "1+2";')
    with pytest.raises(FoamDictError, match="unsupported directive #includeFunc"):
        parse("#includeFunc probes")


# ---------------------------------------------------------------------------
# Macros
# ---------------------------------------------------------------------------


def test_macro_simple_and_splice():
    d = parse("a 1; b $a; c ${a}; v uniform (0 0 1); w $v; l (1 2); m ($a $l 3); n $v extra;")
    assert d["b"] == 1 and d["c"] == 1
    assert_same(d["w"], ("uniform", [0, 0, 1]))
    assert_same(d["m"], [1, [1, 2], 3])
    assert_same(d["n"], ("uniform", [0, 0, 1], "extra"))


def test_macro_is_deep_copy():
    d = parse("a (1 (2 3)); b $a; s { x (1); } t $s;")
    d["b"][1][0] = 99
    d["t"]["x"].append(5)
    assert d["a"] == [1, [2, 3]] and d["s"] == {"x": [1]}


def test_macro_scoping():
    d = parse(
        """
        x 0;
        a { b { c 1; } x 10; }
        dotted { "k.l" 5; }
        sub
        {
            x 1;
            inner
            {
                x 2;
                cur $x;          // current scope first
                dot $.x;         // current scope
                up $..x;         // parent
                up2 $...x;       // grandparent
                scoped $a.b.c;   // 'a' found in an outer scope
                top $:x;
                topScoped $:a.x;
                keyWithDot $dotted.k.l;
                brace ${:a.b.c};
            }
        }
        """
    )
    inner = d["sub"]["inner"]
    assert (inner["cur"], inner["dot"], inner["up"], inner["up2"]) == (2, 2, 1, 0)
    assert (inner["scoped"], inner["top"], inner["topScoped"], inner["brace"]) == (1, 0, 10, 1)
    assert inner["keyWithDot"] == 5


def test_dict_macro_merge_and_copy():
    d = parse(
        """
        defaults { type fixedValue; value uniform 0; }
        inlet { $defaults; value uniform 1; }
        outlet { value uniform 2; $defaults; }
        copy $defaults;
        """
    )
    assert d["inlet"] == {"type": "fixedValue", "value": ("uniform", 1)}
    assert d["outlet"] == {"value": ("uniform", 0), "type": "fixedValue"}
    assert d["copy"] == d["defaults"] and d["copy"] is not d["defaults"]


def test_macro_sees_only_entries_so_far():
    with pytest.raises(FoamDictError, match=r"unknown macro \$b"):
        parse("a $b; b 1;")


def test_macro_errors():
    with pytest.raises(FoamDictError, match="does not refer to a dictionary"):
        parse("a 1; s { $a; }")
    with pytest.raises(FoamDictError, match="above the top level"):
        parse("a 1; b $..a;")
    with pytest.raises(FoamDictError, match=r"unknown macro \$s.y"):
        parse("s { x 1; } b $s.y;")


# ---------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------


def err(text, filename="constant/sphProperties", **kw) -> FoamDictError:
    with pytest.raises(FoamDictError) as info:
        parse(text, filename=filename, **kw)
    return info.value


def test_error_is_value_error_with_position_in_message():
    e = err("a 1;\nsub\n{\n    kernel cubicSpline\n}\n")
    assert isinstance(e, ValueError)
    assert (e.filename, e.line, e.column) == ("constant/sphProperties", 5, 1)
    assert str(e) == "constant/sphProperties:5:1: expected ';' after value of 'kernel'"
    assert e.message == "expected ';' after value of 'kernel'"


def test_missing_semicolon_at_end_of_file():
    e = err("a 1;\nb 2", filename=None)
    assert (e.line, e.column) == (2, 4)
    assert str(e) == "2:4: expected ';' after value of 'b'"


def test_missing_semicolon_before_brace():
    e = err("a 1\nb { c 1; }")
    assert (e.line, e.column) == (2, 3)


def test_unterminated_block_comment():
    e = err("a 1;\n  /* never closed\nb 2;\n")
    assert (e.line, e.column, e.message) == (2, 3, "unterminated comment")
    assert str(e).startswith("constant/sphProperties:2:3:")


def test_unterminated_string():
    e = err('a 1;\nb "abc\n\nc 3;')
    assert (e.line, e.column, e.message) == (2, 3, "unterminated string")


def test_unbalanced_braces():
    e = err("a 1;\nouter\n{\n    inner\n    {\n        x 1;\n    }\n")
    assert (e.line, e.column) == (3, 1)
    assert "unterminated dictionary" in e.message
    e = err("a 1;\n}\n")
    assert (e.line, e.column) == (2, 1)


def test_unterminated_list_and_bad_item():
    e = err("a 1;\nb (1 2\n  (3 4)\n")
    assert (e.line, e.column) == (2, 3) and "unterminated list" in e.message
    e = err("a (1 2;\nb 3;")
    assert (e.line, e.column) == (1, 7)
    assert "opened at line 1, column 3" in e.message
    e = err("a [0 1 0\n")
    assert (e.line, e.column) == (1, 3) and "unterminated dimension set" in e.message
    e = err("a [0 m 0];")
    assert "only numbers" in e.message


def test_unknown_macro_position():
    e = err("a 1;\nsub\n{\n    b   $nope;\n}\n")
    assert (e.line, e.column) == (4, 9)
    assert str(e) == "constant/sphProperties:4:9: unknown macro $nope"


def test_count_mismatch():
    e = err("a 1;\nb 3(1 2);")
    assert (e.line, e.column) == (2, 3) and "mismatch" in e.message
    e = err("b 2{1 2};")
    assert "exactly one value" in e.message


def test_other_syntax_errors():
    assert "expected a keyword" in err("(1 2 3)").message
    assert "unexpected character" in err("a 1; $ b;").message
    assert "expected ';' after macro entry" in err("d { } $d x;").message
    assert "unexpected '{'" not in err("a b { c 1; }").message  # reported as a missing ';'


# ---------------------------------------------------------------------------
# Linear time
# ---------------------------------------------------------------------------


def _best_time(text, repeats):
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        parse(text)
        best = min(best, time.perf_counter() - t0)
    return best


@pytest.mark.parametrize(
    "make",
    [
        lambda n: "values (" + " ".join(repr(0.5 + i * 1e-3) for i in range(n)) + ");",
        lambda n: "\n".join(f"key{i} {{ value {i}; }}" if i % 10 == 0 else f"key{i} {i * 0.5};" for i in range(n)),
    ],
    ids=["list", "dict"],
)
def test_linear_time(make):
    small, large = (50_000, 200_000) if "values" in make(1) else (5_000, 20_000)
    t_small = _best_time(make(small), 3)
    t_large = _best_time(make(large), 2)
    assert t_large < 3.0
    assert t_large / t_small < 8, f"{t_small:.3f}s -> {t_large:.3f}s for 4x the input"
