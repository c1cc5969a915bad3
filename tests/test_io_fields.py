"""Tests for time-directory helpers and particle field files."""

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sphfoam.case.times import latest_time, list_times, time_name
from sphfoam.io.fields import has_particles, read_field, read_state, write_field, write_state

FLOATS = st.floats(allow_nan=False, allow_infinity=False, width=64)
SIZES = st.integers(0, 50)


# ----------------------------------------------------------------------------- times
@pytest.mark.parametrize(
    "t, name",
    [(0.5, "0.5"), (1.0, "1"), (0.1 + 0.2, "0.3"), (1e-05, "1e-05"), (12.25, "12.25"), (0, "0"), (0.0, "0")],
)
def test_time_name(t, name):
    assert time_name(t) == name


def test_time_name_precision():
    assert time_name(1 / 3, precision=3) == "0.333"
    assert time_name(123456789.0) == "1.23457e+08"


def test_list_times(tmp_path):
    for d in ["10", "2", "0", "1e-05", "0.5", "constant", "system", "VTK", "postProcessing", "nan", "1_0"]:
        (tmp_path / d).mkdir()
    (tmp_path / "3").write_text("a file, not a time dir")
    times = list_times(tmp_path)
    assert [p.name for _, p in times] == ["0", "1e-05", "0.5", "2", "10"]
    assert [t for t, _ in times] == [0.0, 1e-05, 0.5, 2.0, 10.0]
    assert latest_time(tmp_path) == (10.0, tmp_path / "10")


def test_latest_time_empty(tmp_path):
    (tmp_path / "constant").mkdir()
    assert list_times(tmp_path) == []
    assert latest_time(tmp_path) is None


# ----------------------------------------------------------------------------- fields
def _roundtrip(tmp_path, a, **kw):
    p = tmp_path / "f"
    write_field(p, a, **kw)
    return read_field(p)


@settings(max_examples=60, deadline=None)
@given(a=st.one_of(arrays(np.float64, SIZES, elements=FLOATS), arrays(np.float64, st.tuples(SIZES, st.just(2)), elements=FLOATS)))
def test_binary_float_bit_exact(tmp_path_factory, a):
    b = _roundtrip(tmp_path_factory.mktemp("b"), a)
    assert b.dtype == np.float64 and b.shape == a.shape
    assert a.tobytes() == b.tobytes()


@settings(max_examples=40, deadline=None)
@given(a=arrays(np.int64, SIZES, elements=st.integers(-(2**63), 2**63 - 1)))
def test_label_roundtrip(tmp_path_factory, a):
    d = tmp_path_factory.mktemp("l")
    for fmt in ("binary", "ascii"):
        b = _roundtrip(d, a, fmt=fmt)
        assert b.dtype == np.int64 and b.shape == a.shape
        np.testing.assert_array_equal(a, b)


@settings(max_examples=60, deadline=None)
@given(a=st.one_of(arrays(np.float64, SIZES, elements=FLOATS), arrays(np.float64, st.tuples(SIZES, st.just(2)), elements=FLOATS)))
def test_ascii_precision17_bit_exact(tmp_path_factory, a):
    b = _roundtrip(tmp_path_factory.mktemp("a"), a, fmt="ascii", precision=17)
    assert b.shape == a.shape
    assert a.tobytes() == b.tobytes()


def test_extreme_and_empty(tmp_path):
    a = np.array([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, -1.7976931348623157e308, np.pi])
    for fmt in ("binary", "ascii"):
        b = _roundtrip(tmp_path, a, fmt=fmt, precision=17)
        assert a.tobytes() == b.tobytes()
    for empty in (np.zeros(0), np.zeros((0, 2)), np.zeros(0, dtype=np.int64)):
        for fmt in ("binary", "ascii"):
            b = _roundtrip(tmp_path, empty, fmt=fmt)
            assert b.shape == empty.shape and b.dtype == empty.dtype


def test_ascii_precision6(tmp_path):
    rng = np.random.default_rng(0)
    a = rng.normal(size=(1000, 2)) * 10.0 ** rng.integers(-20, 20, size=(1000, 2))
    b = _roundtrip(tmp_path, a, fmt="ascii", precision=6)
    np.testing.assert_allclose(b, a, rtol=1e-5, atol=0)


def test_ascii_format_and_header(tmp_path):
    p = tmp_path / "U"
    write_field(p, np.array([[1.0, 2.5], [-3.0, 0.125]]), fmt="ascii", location="0.5/lagrangian/particles")
    text = p.read_text()
    assert "class       vector2DField;" in text and 'location    "0.5/lagrangian/particles";' in text
    assert "object      U;" in text
    assert "\n2\n(\n(1 2.5)\n(-3 0.125)\n)\n;\n" in text


def test_binary_layout(tmp_path):
    p = tmp_path / "rho"
    a = np.array([1.0, 2.0, 3.0])
    write_field(p, a)
    raw = p.read_bytes()
    assert b"format      binary;" in raw and b"class       scalarField;" in raw
    assert raw.endswith(b"3\n(" + a.astype("<f8").tobytes() + b")\n;\n")


def test_reject_bad_shapes(tmp_path):
    for bad in (np.zeros((3, 3)), np.zeros((2, 2, 2)), np.zeros((3, 2), dtype=int), np.array(["a"]), np.zeros(3, complex)):
        with pytest.raises(ValueError):
            write_field(tmp_path / "x", bad)
    with pytest.raises(ValueError):
        write_field(tmp_path / "x", np.zeros(3), fmt="hdf5")


def test_read_handwritten_ascii(tmp_path):
    p = tmp_path / "p"
    p.write_text(
        """/*--------------------------------*- C++ -*----------------------------------*\\
  =========                 |
  \\\\      /  F ield         | hand written
\\*---------------------------------------------------------------------------*/
FoamFile
{
    version 2.0;   // a trailing comment
    format  ascii;
    /* block
       comment */
    class   scalarField;
    arch    "LSB;label=64;scalar=64";
    location "0/lagrangian/particles";
    object  p;
}
// * * * * * //

4
(
1.5
  -2e-3
3
7
)
;
"""
    )
    np.testing.assert_array_equal(read_field(p), [1.5, -2e-3, 3.0, 7.0])
    q = tmp_path / "U"
    q.write_text("FoamFile{format ascii;class vector2DField;object U;}\n2((1 2) (3 4));\n")
    np.testing.assert_array_equal(read_field(q), [[1, 2], [3, 4]])
    r = tmp_path / "type"
    r.write_text("FoamFile\n{\n format ascii;\n class labelField;\n}\n3{7}\n")
    np.testing.assert_array_equal(read_field(r), [7, 7, 7])


def test_read_errors(tmp_path):
    p = tmp_path / "f"
    p.write_text("not a foam file")
    with pytest.raises(ValueError):
        read_field(p)
    p.write_text("FoamFile{format ascii;class volScalarField;}\n1(1)\n;")
    with pytest.raises(ValueError, match="class"):
        read_field(p)
    p.write_text("FoamFile{format ascii;class scalarField;}\n3(1 2)\n;")
    with pytest.raises(ValueError):
        read_field(p)
    write_field(p, np.arange(10.0))
    p.write_bytes(p.read_bytes()[:-20])
    with pytest.raises(ValueError, match="truncated"):
        read_field(p)


def test_ascii_read_is_fast(tmp_path):
    p = tmp_path / "big"
    write_field(p, np.random.default_rng(1).random(1_000_000), fmt="ascii")
    t0 = time.perf_counter()
    a = read_field(p)
    assert a.shape == (1_000_000,)
    assert time.perf_counter() - t0 < 2.0  # typically ~0.3 s; loose bound for slow CI


# ----------------------------------------------------------------------------- states
def _state(n=7):
    rng = np.random.default_rng(n)
    return {
        "positions": rng.random((n, 2)),
        "U": rng.normal(size=(n, 2)),
        "rho": 1000 + rng.random(n),
        "type": rng.integers(0, 3, n),
    }


@pytest.mark.parametrize("fmt, precision", [("binary", 6), ("ascii", 17)])
def test_state_roundtrip(tmp_path, fmt, precision):
    s = _state()
    td = tmp_path / "0.5"
    assert not has_particles(td)
    write_state(td, s, fmt=fmt, precision=precision)
    assert has_particles(td)
    cloud = td / "lagrangian" / "particles"
    assert sorted(p.name for p in cloud.iterdir()) == sorted(s)  # no temp files left
    assert 'location    "0.5/lagrangian/particles";' in (cloud / "rho").read_bytes().decode("latin-1")
    (cloud / ".rho.123.tmp").write_bytes(b"garbage")  # stray temp files are ignored
    r = read_state(td)
    assert set(r) == set(s)
    for k in s:
        assert r[k].dtype == s[k].dtype and r[k].tobytes() == s[k].tobytes()
    write_state(td, {"rho": np.zeros(7)})  # overwrite in place
    np.testing.assert_array_equal(read_state(td)["rho"], 0.0)


def test_read_state_missing(tmp_path):
    with pytest.raises(FileNotFoundError, match="particles"):
        read_state(tmp_path / "1")
    (tmp_path / "1" / "lagrangian" / "particles").mkdir(parents=True)
    assert not has_particles(tmp_path / "1")
    assert read_state(tmp_path / "1") == {}
