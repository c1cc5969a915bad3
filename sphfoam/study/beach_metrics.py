"""Metrics of a wave on a beach (T ch. 5): the breaking time of a ``breakingPoint`` and the
position of the maximum run-up of a ``runUp mode beach`` (sphfoam.sampling.beach)."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field

from sphfoam.study.metrics import Metric, MetricCoeffs
from sphfoam.registry import register
from sphfoam.sampling.beach import read_breaking


# --- metrics -----------------------------------------------------------------------------------
@register
class BreakingTime(Metric):
    """Time from the crest passing the toe gauge to the breaking point, or the breaking time
    itself, of a ``breakingPoint`` function object (its ``summary.dat``), against a given
    value (T §5.5.1: 1.96 s in the laboratory, 2.06 s by the thesis's SPH)."""

    name = "breakingTime"
    doc = "toe-to-breaking time (or breaking time or x) of a breakingPoint function object, " \
          "against a given value"
    function_type = "breakingPoint"

    class Coeffs(MetricCoeffs):
        function: str = Field("breakingPoint", description="the breakingPoint function object")
        quantity: Literal["toeToBreaking", "time", "x"] = Field("toeToBreaking", description=(
            "`toeToBreaking`: time from the crest at the toe gauge to breaking (s); `time`: "
            "the breaking time (s); `x`: where it breaks (m)"))
        criterion: Literal["geometric", "kinematic"] | None = Field(None, description=(
            "which criterion's breaking point; default the function object's own"))
        reference: float | None = Field(None, description="value to compare with")

    @property
    def unit(self):
        return "m" if self.coeffs.quantity == "x" else "s"

    def measure(self, case_path, spec):
        folders = self.folders(case_path)
        path = folders[-1][1] / "summary.dat"
        rel = self._rel(path, case_path)
        if not path.is_file():
            self.fail("function", f"{rel} not found: the function object "
                      f"'{self.coeffs.function}' has not run to its end")
        rows = read_breaking(path)
        crit = self.coeffs.criterion or next(iter(rows), "geometric")
        row = rows.get(crit)
        if row is None or not math.isfinite(row.get(self.coeffs.quantity, math.nan)):
            self.fail("function", f"{rel}: no breaking point by the {crit} criterion (the "
                      "wave did not break within the run, or never passed the toe gauge)")
        return self.value(row[self.coeffs.quantity], self.coeffs.reference)


@register
class RunUpPosition(Metric):
    """x (or time) of the maximum run-up on a beach, from a ``runUp mode beach`` function
    object, against a given value (T Table 5.1: 10.43 m from the toe gauge in the
    laboratory)."""

    name = "runUpPosition"
    doc = "x (or time) of the maximum run-up of a runUp mode beach function object, against " \
          "a given value"
    function_type = "runUp"

    class Coeffs(MetricCoeffs):
        function: str = Field("runUp", description="the runUp function object (mode beach)")
        quantity: Literal["x", "time"] = Field("x", description=(
            "`x`: where the shoreline is at the maximum run-up (m); `time`: when (s)"))
        origin: float = Field(0.0, description=(
            "subtracted from x, e.g. the toe gauge's x to measure as T does"))
        reference: float | None = Field(None, description="value to compare with")

    @property
    def unit(self):
        return "m" if self.coeffs.quantity == "x" else "s"

    def check(self, functions):
        super().check(functions)
        if functions[self.coeffs.function].get("mode") != "beach":
            self.fail("function", f"runUp '{self.coeffs.function}' is not mode beach: only a "
                      "beach's shoreline has a position")

    def measure(self, case_path, spec):
        cols, data, rel = self.series(case_path)
        r = data[:, self.column(cols, "runUp", rel)]
        i = self.peak(data[:, 0], r, "function", "the run-up", rel)
        if self.coeffs.quantity == "time":
            return self.value(data[i, 0], self.coeffs.reference)
        x = data[i, self.column(cols, "xShore", rel)]
        return self.value(x - self.coeffs.origin, self.coeffs.reference)
