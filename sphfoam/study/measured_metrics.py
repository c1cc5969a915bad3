"""Metrics against a measured time series shipped with a case (``metric`` family): the RMS
difference over a window and a peak's value and time, e.g. SPHERIC Test 2's gauges and
pressure sensors (``tutorials/damBreak3D``)::

    H2  { type measuredRMS; function heights; column "eta(0.992,0.5)";
          file "validation/test_case_2_exp_data.dat"; fileColumn 10; window (0 6); }
    P1  { type measuredPeak; function sensors; column P1;
          file "validation/test_case_2_exp_data.dat"; fileColumn 1; window (0.3 0.6); }

The measured file is whitespace-separated numbers (a first line that is not numbers is a
header and skipped; ``#`` comments too), time in its first column; ``fileColumn`` counts
from 0 (the time). The measurement is interpolated linearly at the simulated samples'
times.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, field_validator

from sphfoam.case.metrics_dict import MetricValue
from sphfoam.registry import register
from sphfoam.study.metrics import Metric, MetricCoeffs


class _MeasuredCoeffs(MetricCoeffs):
    column: str = Field(description="column of the function object's table, e.g. `P1`")
    file: str = Field(description="the measured series, relative to the case")
    fileColumn: int = Field(ge=1, description="its column (0 is the time)")
    window: tuple[float, float] = Field(description="(t0 t1): the times compared (s)")
    missing: Literal["skip", "zero"] = Field("skip", description=(
        "a NaN sample (e.g. a dry gauge, a sensor out of the water): `skip` it, or read it "
        "as `zero` (a height gauge over a dry floor)"))

    @field_validator("window")
    @classmethod
    def _order(cls, v):
        if not v[1] > v[0]:
            raise ValueError(f"window {v}: t1 must exceed t0")
        return v


class _Measured(Metric):
    #: any function object's table (the column names it)
    function_type = ""

    def check(self, functions) -> None:
        fn = self.coeffs.function
        if not isinstance(functions.get(fn), dict):
            from sphfoam.case.errors import did_you_mean

            self.fail("function", f"no function object '{fn}' in system/controlDict"
                      f"{did_you_mean(fn, functions) or ';'} defined: "
                      f"{', '.join(functions) or '(none)'}")

    def measured(self, case_path: Path) -> tuple[np.ndarray, np.ndarray]:
        c = self.coeffs
        f = Path(case_path) / c.file
        if not f.is_file():
            self.fail("file", f"{c.file} not found in the case")
        with f.open() as fh:
            first = fh.readline().split()
        try:
            [float(v) for v in first]
            skip = 0
        except ValueError:
            skip = 1
        data = np.loadtxt(f, skiprows=skip, comments="#", ndmin=2)
        if c.fileColumn >= data.shape[1]:
            self.fail("fileColumn", f"{c.file} has {data.shape[1]} columns (0 .. "
                      f"{data.shape[1] - 1})")
        return data[:, 0], data[:, c.fileColumn]

    def simulated(self, case_path: Path) -> tuple[np.ndarray, np.ndarray]:
        cols, data, rel = self.series(case_path)
        j = self.column(cols, self.coeffs.column, rel)
        t0, t1 = self.coeffs.window
        v = data[:, j]
        if self.coeffs.missing == "zero":
            v = np.where(np.isfinite(v), v, 0.0)
        keep = (data[:, 0] >= t0) & (data[:, 0] <= t1) & np.isfinite(v)
        if not keep.any():
            self.fail("window", f"{rel} has no finite {self.coeffs.column} in "
                      f"{t0:g} .. {t1:g} s")
        return data[keep, 0], v[keep]


@register
class MeasuredRMS(_Measured):
    """RMS of (simulated - measured) over ``window``, the measurement interpolated at the
    simulated samples' times; in the column's units. The RMS is itself the error: no
    relative error is given."""

    name = "measuredRMS"
    doc = "RMS difference between a function object's column and a measured series"
    Coeffs = _MeasuredCoeffs

    def measure(self, case_path, spec) -> MetricValue:
        t, v = self.simulated(case_path)
        tm, vm = self.measured(case_path)
        if t[-1] < self.coeffs.window[1] - 0.05 * (self.coeffs.window[1] - self.coeffs.window[0]):
            self.fail("window", f"the run's {self.coeffs.column} ends at {t[-1]:g} s, short of "
                      f"the window's {self.coeffs.window[1]:g} s (run longer)")
        ref = np.interp(t, tm, vm)
        return MetricValue(float(np.sqrt(np.mean((v - ref) ** 2))), None, None, "")


@register
class MeasuredPeak(_Measured):
    """The largest value within ``window`` (``quantity value``) or its time (``quantity
    time``), against the measured series' in the same window: the relative error."""

    name = "measuredPeak"
    doc = "peak value or time of a function object's column against a measured series"

    class Coeffs(_MeasuredCoeffs):
        quantity: Literal["value", "time"] = Field("value", description=(
            "`value`: the peak; `time`: when it occurs"))

    def measure(self, case_path, spec) -> MetricValue:
        t, v = self.simulated(case_path)
        tm, vm = self.measured(case_path)
        t0, t1 = self.coeffs.window
        inside = (tm >= t0) & (tm <= t1)
        if not inside.any():
            self.fail("window", f"{self.coeffs.file} has no sample in {t0:g} .. {t1:g} s")
        i = int(np.argmax(v))
        k = int(np.argmax(np.where(inside, vm, -np.inf)))
        if self.coeffs.quantity == "time":
            return self.value(t[i], tm[k])
        return self.value(v[i], vm[k])
