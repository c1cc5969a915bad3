"""Prescribed wall motions and wave makers: tables (inline, file; linear, spline) and the
sinusoidal piston; bad input gives one-screen errors naming the key."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydantic import ValidationError

from sphfoam import registry
from sphfoam.case.case import Case
from sphfoam.case.edit import set_entry
from sphfoam.case.errors import CaseError

ROWS = [(0.0, (0.0, 0.0)), (1.0, (0.1, 0.0)), (3.0, (0.1, -0.2))]


def table(**kw):
    return registry.build("motion", {"type": "displacementTable", **kw})


def test_linear_table_interpolates_and_holds_at_the_ends():
    m = table(table=ROWS)
    assert m.displacement(0.5) == pytest.approx((0.05, 0.0))
    assert m.displacement(2.0) == pytest.approx((0.1, -0.1))
    assert m.velocity(0.5) == pytest.approx((0.1, 0.0))
    assert m.velocity(2.0) == pytest.approx((0.0, -0.1))
    assert m.displacement(-1.0) == (0.0, 0.0) and m.velocity(-1.0) == (0.0, 0.0)
    assert m.displacement(9.0) == pytest.approx((0.1, -0.2)) and m.velocity(9.0) == (0.0, 0.0)


def test_spline_table_passes_through_the_rows_with_consistent_velocity():
    m = table(table=ROWS, interpolation="spline")
    for t, d in ROWS:
        assert m.displacement(t) == pytest.approx(d, abs=1e-12)
    for t in (0.3, 1.7, 2.6):
        e = 1e-6
        fd = [(a - b) / (2 * e) for a, b in zip(m.displacement(t + e), m.displacement(t - e))]
        assert m.velocity(t) == pytest.approx(fd, rel=1e-5, abs=1e-9)


def test_table_from_a_file_in_the_case(tmp_path):
    (tmp_path / "constant").mkdir()
    np.savetxt(tmp_path / "constant" / "paddle.dat",
               [[t, d[0], d[1]] for t, d in ROWS], header="t dx dy")
    m = table(file="constant/paddle.dat")
    m.resolve(tmp_path)
    assert m.displacement(2.0) == pytest.approx(table(table=ROWS).displacement(2.0))


def test_a_3d_table_and_file_give_three_components(tmp_path):
    rows = [(t, (*d, 0.5 * d[0])) for t, d in ROWS]
    m = table(table=rows)
    assert m.components == 3
    assert m.displacement(2.0) == pytest.approx((0.1, -0.1, 0.05))
    assert m.velocity(2.0) == pytest.approx((0.0, -0.1, 0.0))
    assert m.velocity(9.0) == (0.0, 0.0, 0.0)
    (tmp_path / "constant").mkdir()
    np.savetxt(tmp_path / "constant" / "paddle.dat", [[t, *d] for t, d in rows])
    f = table(file="constant/paddle.dat", interpolation="spline")
    assert f.components is None
    f.resolve(tmp_path)
    assert f.components == 3
    for t, d in rows:
        assert f.displacement(t) == pytest.approx(d, abs=1e-12)


@pytest.mark.parametrize("kw", [{}, {"table": ROWS, "file": "x.dat"},
                                {"table": [(0.0, (0.0, 0.0)), (1.0, (0.0, 0.0, 0.0))]},
                                {"table": [(0.0, (0.0,)), (1.0, (0.0,))]},
                                {"table": [(0.0, (0.0, 0.0))]},
                                {"table": [(1.0, (0.0, 0.0)), (0.5, (0.0, 0.0))]}])
def test_bad_tables_are_rejected(kw):
    with pytest.raises(ValidationError):
        table(**kw)


def test_missing_table_file_is_a_case_error_naming_the_key(tutorial):
    case = tutorial("wavePaddle")
    set_entry(case, "system/particleDict", "walls.paddle.motion",
              {"type": "displacementTable", "file": "constant/nope.dat"})
    with pytest.raises(CaseError, match=r"system/particleDict: walls.paddle.motion.file: "
                                        r"constant/nope.dat: no such file"):
        Case(case).validate()


def test_unknown_wave_maker_names_the_choices(tutorial):
    case = tutorial("wavePaddle")
    set_entry(case, "system/particleDict", "walls.paddle.motion.waveMaker.type", "goringg")
    with pytest.raises(CaseError, match="did you mean 'goring'"):
        Case(case).validate()


def test_sinusoidal_piston_starts_from_rest_and_its_velocity_is_the_derivative():
    mk = registry.build("waveMaker", {"type": "sinusoidal", "stroke": 0.04, "period": 1.0,
                                      "rampTime": 1.0})
    assert mk.position(0.0) == 0.0 and mk.velocity(0.0) == 0.0
    for t in (0.2, 0.7, 1.3, 2.25):
        e = 1e-6
        assert mk.velocity(t) == pytest.approx((mk.position(t + e) - mk.position(t - e)) / (2 * e),
                                               rel=1e-6, abs=1e-9)
    assert mk.position(2.25) == pytest.approx(0.02 * math.sin(2 * math.pi * 2.25))
    paddle = registry.build("motion", {"type": "pistonPaddle", "direction": (0.0, 2.0),
                                       "waveMaker": {"type": "sinusoidal", "stroke": 0.04,
                                                     "period": 1.0}})
    assert paddle.displacement(0.25) == pytest.approx((0.0, 0.02))
