"""Error metrics of a finished run against its reference (``metric`` family, ``sphfoam study``).

A case declares its metrics in ``system/metricsDict``::

    metrics
    {
        H18      { type waveHeight; function gauges; x 18; reference 0.15; }
        celerity { type celerity; function crest; theory boussinesq; height 0.15; depth 0.5; }
    }
    pareto   H18;      // the metric whose |error| a study plots against cost

Each metric reads what a function object of ``system/controlDict`` wrote under
``postProcessing/<function>/<startTime>/`` (see :mod:`sphfoam.sampling`). Time series are
joined over the start-time folders of a restarted run (rows of an older folder up to the
start of the next, as OpenFOAM's post-processing does); end-of-run summaries come from the
newest folder. The error is signed and relative, (value - reference)/reference in percent.
"""

from __future__ import annotations

import abc
import math
import re
from pathlib import Path
from typing import Any, ClassVar, Literal, NoReturn

import numpy as np
from pydantic import Field, ValidationError, field_validator, model_validator

import sphfoam.registry as registry
from sphfoam.case.errors import CaseError, did_you_mean, from_validation
from sphfoam.case.metrics_dict import CONTROL_DICT, METRICS_DICT, MetricValue, relative_error
from sphfoam.io.tables import join_series, read_table, start_folders
from sphfoam.registry import Coeffs, Model, register



def _label(v: float) -> str:
    return f"{v:g}"


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-6 * max(1.0, abs(a), abs(b))


def _as_list(v):
    return [v] if isinstance(v, (int, float)) else v


# --- the family --------------------------------------------------------------------------------
class MetricCoeffs(Coeffs):
    function: str = Field(description="name of the function object in system/controlDict "
                          "whose output is read")

    @field_validator("function", check_fields=False)
    @classmethod
    def _plain(cls, v):
        from sphfoam.case.paths import check_name

        return check_name(v)


class Metric(Model, abc.ABC):
    """Base of the metrics: ``evaluate(case_path)`` -> :class:`MetricValue`.

    Problems (function object missing from system/controlDict or of another type, output not
    written, gauge absent, wave not arrived) raise a :class:`CaseError` naming the metrics
    file and ``metrics.<entry>.<key>``.
    """

    family = "metric"
    #: the functionObject type whose output the metric reads
    function_type: ClassVar[str]
    #: entry name in the metrics dictionary and the file it came from (set by the loader)
    entry: str = ""
    source: str = METRICS_DICT
    Coeffs = MetricCoeffs

    @property
    def unit(self) -> str:
        return ""

    # --- errors ----------------------------------------------------------------------------
    def key(self, sub: str = "") -> str:
        return f"metrics.{self.entry or self.name}" + (f".{sub}" if sub else "")

    def fail(self, sub: str, message: str) -> NoReturn:
        raise CaseError.single(self.source, self.key(sub), message)

    # --- against system/controlDict ----------------------------------------------------------
    def check(self, functions: dict[str, Any]) -> None:
        """Check the metric against the function objects of system/controlDict (raw specs)."""
        fn = self.coeffs.function
        spec = functions.get(fn)
        if not isinstance(spec, dict):
            self.fail("function", f"no function object '{fn}' in {CONTROL_DICT}"
                      f"{did_you_mean(fn, functions) or ';'} defined: "
                      f"{', '.join(functions) or '(none)'}")
        if spec.get("type") != self.function_type:
            self.fail("function", f"function object '{fn}' of {CONTROL_DICT} is a "
                      f"{spec.get('type')}, not a {self.function_type}")

    # --- output --------------------------------------------------------------------------------
    def _rel(self, path: Path, case_path: Path) -> str:
        try:
            return str(path.relative_to(case_path))
        except ValueError:
            return str(path)

    def folders(self, case_path: Path) -> list[tuple[float, Path]]:
        fn = self.coeffs.function
        folders = start_folders(case_path, fn)
        if not folders:
            self.fail("function", f"no output in postProcessing/{fn}/: the function object "
                      f"'{fn}' has not run (run the case, or `sphfoam sample CASE -f {fn}`)")
        return folders

    def series(self, case_path: Path, filename: str | None = None
               ) -> tuple[list[str], np.ndarray, str]:
        """(columns, rows, newest file) of a time series, joined over the start-time folders
        (rows of an older folder before the next folder's start time)."""
        case_path = Path(case_path)
        fn = self.coeffs.function
        filename = filename or f"{fn}.dat"
        folders = self.folders(case_path)
        newest = folders[-1][1] / filename
        rel = self._rel(newest, case_path)
        if not newest.is_file():
            self.fail("function", f"{rel} not found: the function object '{fn}' has not "
                      "written it")
        cols, data = join_series(folders, filename)
        if data.shape[0] == 0:
            self.fail("function", f"{rel} holds no samples yet")
        return cols, data, rel

    def column(self, cols: list[str], name: str, rel: str) -> int:
        if name not in cols:
            self.fail("function", f"{rel} has no column '{name}' (columns: {', '.join(cols)}); "
                      f"is '{self.coeffs.function}' a {self.function_type}?")
        return cols.index(name)

    def peak(self, t: np.ndarray, v: np.ndarray, sub: str, what: str, rel: str) -> int:
        """Row of the largest finite value; fails when there is none, or when it is the last
        sample (still rising: the peak has not been reached within the output)."""
        ok = np.isfinite(v)
        if not ok.any():
            self.fail(sub, f"{what} is NaN throughout {rel} (no water there)")
        i = int(np.argmax(np.where(ok, v, -np.inf)))
        if i == v.size - 1:
            self.fail(sub, f"{what} is still rising at the last sample (t = {t[-1]:g} s) of "
                      f"{rel}: its maximum is not reached within the output (run longer)")
        return i

    # --- evaluation ----------------------------------------------------------------------------
    def evaluate(self, case_path) -> MetricValue:
        """The metric of the run in ``case_path`` (checked against its system/controlDict
        when there is one)."""
        from sphfoam.case.case import Case

        case_path = Path(case_path).resolve()
        spec = None
        if (case_path / CONTROL_DICT).is_file():
            functions = Case(case_path).read_dict(CONTROL_DICT).get("functions") or {}
            self.check(functions)
            spec = functions[self.coeffs.function]
        return self.measure(case_path, spec)

    @abc.abstractmethod
    def measure(self, case_path: Path, spec: dict | None) -> MetricValue:
        """Read the output; ``spec`` is the function object's controlDict entry, if known."""

    def known_reference(self) -> float | None:
        """The reference as far as it is known without any output (for a failed metric)."""
        return getattr(self.coeffs, "reference", None)

    def value(self, value: float, reference: float | None) -> MetricValue:
        return MetricValue(float(value), None if reference is None else float(reference),
                           relative_error(value, reference), self.unit)


# --- wave gauges ---------------------------------------------------------------------------
class _GaugeCoeffs(MetricCoeffs):
    function: str = Field("gauges", description="the waveGauges function object")
    x: float = Field(description="gauge position (m): one of the function object's gauges `x`")


class _GaugeMetric(Metric):
    function_type = "waveGauges"

    def check(self, functions):
        super().check(functions)
        xs = [float(v) for v in _as_list(functions[self.coeffs.function].get("x", []))
              if isinstance(v, (int, float))]
        if not any(_close(v, self.coeffs.x) for v in xs):
            self._no_gauge(f"function object '{self.coeffs.function}' of {CONTROL_DICT}", xs)

    def _no_gauge(self, where: str, xs) -> NoReturn:
        self.fail("x", f"no gauge at x = {_label(self.coeffs.x)} in {where}; gauges at x = "
                  f"{', '.join(_label(v) for v in xs) or '(none)'}")

    def gauge(self, case_path) -> tuple[np.ndarray, np.ndarray, str]:
        """(t, eta) of the gauge at x."""
        cols, data, rel = self.series(case_path)
        xs = {}
        for j, c in enumerate(cols):
            m = re.fullmatch(r"eta\((.+)\)", c)
            if m:
                try:
                    xs[j] = float(m[1])
                except ValueError:
                    pass
        hit = [j for j, v in xs.items() if _close(v, self.coeffs.x)]
        if not hit:
            self._no_gauge(rel, xs.values())
        return data[:, 0], data[:, hit[0]], rel


@register
class WaveHeight(_GaugeMetric):
    """Largest surface elevation eta recorded at one gauge of a ``waveGauges`` object (the
    wave height at that gauge, e.g. H18 of T Table 4.3), against the target height."""

    name = "waveHeight"
    doc = "maximum elevation at a waveGauges gauge against the target wave height " \
          "(H18 of T Table 4.3)"

    class Coeffs(_GaugeCoeffs):
        reference: float | None = Field(None, gt=0, description=(
            "wave height to compare with (m); default: the case's own, the paddle's wave maker's "
            "height or the initial wave's (constant/waveProperties)"))

    @property
    def unit(self):
        return "m"

    def measure(self, case_path, spec):
        t, eta, rel = self.gauge(case_path)
        i = self.peak(t, eta, "x", f"eta at x = {_label(self.coeffs.x)}", rel)
        ref = self.coeffs.reference
        if ref is None:
            ref = case_wave_height(case_path)
        return self.value(eta[i], ref)


def case_wave_height(case_path) -> float | None:
    """The target height of the case's wave: its wave maker's, else its first initial
    wave's; None when it has neither."""
    from sphfoam.case.case import Case

    case = Case(case_path)
    try:
        for mot in case.models.motions.values():
            maker = getattr(mot, "maker", None)
            wave = maker.solitary_wave() if maker is not None else None
            if wave is not None:
                return wave[0]
        for w, _ in case.waves.values():
            return float(w.height)
    except CaseError:               # not a whole case (output files only): no default
        pass
    return None


@register
class ArrivalTime(_GaugeMetric):
    """Time of the largest elevation at one gauge of a ``waveGauges`` object: when the crest
    passes it (resolution: the object's writeInterval)."""

    name = "arrivalTime"
    doc = "time the crest passes a waveGauges gauge (its maximum) against a given time"

    class Coeffs(_GaugeCoeffs):
        reference: float | None = Field(None, description="arrival time to compare with (s)")

    @property
    def unit(self):
        return "s"

    def measure(self, case_path, spec):
        t, eta, rel = self.gauge(case_path)
        i = self.peak(t, eta, "x", f"eta at x = {_label(self.coeffs.x)}", rel)
        return self.value(t[i], self.coeffs.reference)


# --- crest tracker -------------------------------------------------------------------------
@register
class Celerity(Metric):
    """Celerity fitted by a ``crestTracker`` (its ``celerity.dat``: the least-squares slope of
    x_c(t) over its fit window, T Table 4.3) against a given celerity or that of a
    solitary-wave theory (``sphfoam models waveTheory``) for ``height`` and ``depth``.
    A restarted run is refitted over the joined crest samples with the window of
    system/controlDict."""

    name = "celerity"
    doc = "crestTracker's fitted celerity against a given c or a waveTheory's c(H, d) " \
          "(T Table 4.3)"
    function_type = "crestTracker"

    class Coeffs(MetricCoeffs):
        function: str = Field("crest", description="the crestTracker function object")
        reference: float | None = Field(None, gt=0, description=(
            "celerity to compare with (m/s); or give theory, height and depth"))
        theory: str | None = Field(None, description=(
            "solitary-wave theory whose celerity is the reference (sphfoam models "
            "waveTheory), e.g. boussinesq: c = sqrt(g (d + H)), T(4.4)"))
        height: float | None = Field(None, gt=0, description="wave height H (m), with theory")
        depth: float | None = Field(None, gt=0, description="still-water depth d (m), with theory")
        g: float = Field(9.81, gt=0, description="gravity (m/s^2), with theory")

        @field_validator("theory")
        @classmethod
        def _theory(cls, v):
            if v is not None and v not in registry.names("waveTheory"):
                raise ValueError(str(registry.UnknownModel("waveTheory", v,
                                                           registry.names("waveTheory"))))
            return v

        @model_validator(mode="after")
        def _one(self):
            if (self.reference is None) == (self.theory is None):
                raise ValueError("give exactly one of reference (m/s) or theory (with height "
                                 "and depth)")
            if self.theory is not None and (self.height is None or self.depth is None):
                raise ValueError(f"theory {self.theory} needs the wave height and depth")
            if self.theory is None and (self.height is not None or self.depth is not None):
                raise ValueError("height and depth are only used with theory")
            return self

    @property
    def unit(self):
        return "m/s"

    def known_reference(self) -> float:
        c = self.coeffs
        if c.reference is not None:
            return c.reference
        return registry.build("waveTheory", {"type": c.theory}).solitary(
            c.height, c.depth, g=c.g).c

    def measure(self, case_path, spec):
        folders = self.folders(case_path)
        if len(folders) > 1 and spec is not None:
            return self.value(self._refit(case_path, spec), self.known_reference())
        f = folders[-1][1] / "celerity.dat"
        rel = self._rel(f, case_path)
        if not f.is_file():
            self.fail("function", f"{rel} not found: the crestTracker '{self.coeffs.function}' "
                      "writes it at the end of the run (has the run finished?)")
        cols, data = read_table(f)
        j = self.column(cols, "c", rel)
        c = float(data[-1, j]) if data.shape[0] else float("nan")
        if not math.isfinite(c):
            self.fail("function", f"no celerity in {rel}: fewer than two crest samples in "
                      "the fit window (fitFrom, fitTo, minHeight)")
        return self.value(c, self.known_reference())

    def _refit(self, case_path, spec) -> float:
        """The crestTracker's own fit over the crest samples of every start-time folder."""
        from sphfoam.sampling.waves import fit_celerity

        try:
            fc = registry.get("functionObject", self.function_type).Coeffs.model_validate(
                {k: v for k, v in spec.items() if k != "type"})
        except ValidationError as e:
            raise from_validation(e, CONTROL_DICT, prefix=f"functions.{self.coeffs.function}"
                                  ) from None
        cols, data, rel = self.series(case_path)
        xc = data[:, self.column(cols, "xCrest", rel)]
        ec = data[:, self.column(cols, "etaCrest", rel)]
        sel = np.isfinite(xc) & (xc >= fc.fitFrom) & (xc <= fc.fitTo) & (ec >= fc.minHeight)
        c, _, _ = fit_celerity(data[sel, 0], xc[sel])
        if not math.isfinite(c):
            self.fail("function", f"no celerity from {rel}: fewer than two crest samples in "
                      "the fit window (fitFrom, fitTo, minHeight)")
        return c


@register
class PeakElevation(Metric):
    """Highest crest eta_c ever recorded by a ``crestTracker``: e.g. the peak of two solitary
    waves colliding head-on (P §4), against a given elevation such as A1 + A2."""

    name = "peakElevation"
    doc = "highest crest seen by a crestTracker (collision peak, P §4) against a given " \
          "elevation, e.g. A1 + A2"
    function_type = "crestTracker"

    class Coeffs(MetricCoeffs):
        function: str = Field("crest", description="the crestTracker function object")
        reference: float | None = Field(None, gt=0, description=(
            "elevation to compare with (m), e.g. A1 + A2 for a head-on collision"))

    @property
    def unit(self):
        return "m"

    def measure(self, case_path, spec):
        cols, data, rel = self.series(case_path)
        ec = data[:, self.column(cols, "etaCrest", rel)]
        i = self.peak(data[:, 0], ec, "function", "the crest height", rel)
        return self.value(ec[i], self.coeffs.reference)


@register
class MeanCrest(Metric):
    """Mean crest height recorded by a ``crestTracker`` while its crest lies between ``xFrom``
    and ``xTo`` (every sample at least ``minHeight`` high): the wave's height along a stretch
    of flume, which does not ride on the surface's ripples at one gauge as a gauge's maximum
    does (docs/low-dissipation.md: 127 samples over 2-18 m at d/dx = 20 moved by 0.1 % of H
    between two runs that differ in nothing physical, a gauge's maximum by up to 2.6 %)."""

    name = "meanCrest"
    doc = "mean crest height of a crestTracker between two positions against a given " \
          "height, e.g. the wave's H"
    function_type = "crestTracker"

    class Coeffs(MetricCoeffs):
        function: str = Field("crest", description="the crestTracker function object")
        xFrom: float = Field(description="first crest position (m) of the mean")
        xTo: float = Field(description="last crest position (m) of the mean")
        minHeight: float = Field(0.0, ge=0.0, description=(
            "samples whose crest is lower than this (m) are left out (a ripple ahead of "
            "the wave)"))
        reference: float | None = Field(None, gt=0, description="height to compare with (m)")

        @model_validator(mode="after")
        def _window(self):
            if not self.xTo > self.xFrom:
                raise ValueError(f"xTo {self.xTo} must be beyond xFrom {self.xFrom}")
            return self

    @property
    def unit(self):
        return "m"

    def measure(self, case_path, spec):
        c = self.coeffs
        cols, data, rel = self.series(case_path)
        xc = data[:, self.column(cols, "xCrest", rel)]
        ec = data[:, self.column(cols, "etaCrest", rel)]
        sel = np.isfinite(xc) & (xc >= c.xFrom) & (xc <= c.xTo) & (ec >= c.minHeight)
        if not sel.any():
            self.fail("function", f"no crest sample in {rel} between x = {c.xFrom} and "
                      f"{c.xTo} m (at least minHeight {c.minHeight} m high)")
        return self.value(float(ec[sel].mean()), c.reference)


# --- run-up ----------------------------------------------------------------------------------
@register
class MaxRunUp(Metric):
    """Largest run-up R recorded by a ``runUp`` function object (wall or beach), divided by
    ``depth`` when given (eta_max/H of P Fig. 7), against a given value in the same units."""

    name = "runUp"
    doc = "maximum run-up of a runUp function object, optionally R/d (P Fig. 7), against a " \
          "given value"
    function_type = "runUp"

    class Coeffs(MetricCoeffs):
        function: str = Field("runUp", description="the runUp function object")
        depth: float | None = Field(None, gt=0, description=(
            "still-water depth d (m): the value is R/d (dimensionless); default R in m"))
        reference: float | None = Field(None, gt=0, description=(
            "run-up to compare with, in the units of the value (m, or R/d with depth)"))

    @property
    def unit(self):
        return "m" if self.coeffs.depth is None else "-"

    def measure(self, case_path, spec):
        cols, data, rel = self.series(case_path)
        r = data[:, self.column(cols, "runUp", rel)]
        i = self.peak(data[:, 0], r, "function", "the run-up", rel)
        return self.value(r[i] / (self.coeffs.depth or 1.0), self.coeffs.reference)


# --- channel flows -----------------------------------------------------------------------------
@register
class ChannelMaxVelocity(Metric):
    """Velocity of a ``velocityProfile`` at its last sampled time (or the first sampled at or
    after ``time``), from its ``uMax.dat``: the centreline velocity (u_max of Poiseuille flow)
    or the largest bin, against the start-up series the object evaluated at that time,
    T(3.42) Poiseuille or T(3.46) Couette (``reference`` replaces it, e.g. for logLaw)."""

    name = "channelMaxVelocity"
    doc = "centreline (u_max) or largest-bin velocity of a velocityProfile against the " \
          "start-up series T(3.42) / T(3.46)"
    function_type = "velocityProfile"

    class Coeffs(MetricCoeffs):
        function: str = Field("profile", description="the velocityProfile function object")
        quantity: Literal["centre", "maxBin"] = Field("centre", description=(
            "`centre`: the centreline velocity, u_max of Poiseuille flow; `maxBin`: the "
            "largest bin velocity (against the theory in that bin)"))
        time: float | None = Field(None, ge=0, description=(
            "the first sampled time at or after this (s); default the last sampled time"))
        reference: float | None = Field(None, description=(
            "velocity to compare with (m/s) instead of the object's theory"))

    @property
    def unit(self):
        return "m/s"

    def check(self, functions):
        super().check(functions)
        theory = functions[self.coeffs.function].get("theory", "none")
        if theory == "none" or (theory == "logLaw" and self.coeffs.quantity == "maxBin"):
            self.fail("function", f"velocityProfile '{self.coeffs.function}' has theory "
                      f"{theory}: it writes no {'uMax.dat' if theory == 'none' else 'maxBin'}; "
                      "use theory poiseuille or couette")

    def measure(self, case_path, spec):
        c = self.coeffs
        cols, data, rel = self.series(case_path, "uMax.dat")
        i = data.shape[0] - 1
        if c.time is not None:
            later = np.flatnonzero(data[:, 0] >= c.time - 1e-9 * max(1.0, c.time))
            if not later.size:
                self.fail("time", f"no sample at or after t = {c.time:g} s in {rel} (last: "
                          f"{data[-1, 0]:g} s)")
            i = int(later[0])
        name, theory = ("uCentre", "uCentreTheory") if c.quantity == "centre" else \
            ("uMaxBins", "uMaxBinsTheory")
        v = float(data[i, self.column(cols, name, rel)])
        ref = c.reference
        if ref is None and theory in cols:
            ref = float(data[i, cols.index(theory)])
        return self.value(v, ref)


# --- dam break -------------------------------------------------------------------------------
@register
class SurgeFront(Metric):
    """Surge front Z = z/H0 of a ``damBreakFront`` object at the dimensionless times
    T = t sqrt(g/H0) of ``times`` (interpolated linearly between samples) against Martin &
    Moyce (1952), T(3.81). The value is the mean Z over those T, the reference the mean of
    Martin & Moyce's, and the error the mean of the signed relative errors at each T (not the
    error of the means)."""

    name = "damBreakFront"
    doc = "surge front Z(T) of damBreakFront against Martin & Moyce (1952), T(3.81): mean " \
          "Z and mean signed error over the given T"
    function_type = "damBreakFront"

    class Coeffs(MetricCoeffs):
        function: str = Field("front", description="the damBreakFront function object")
        times: list[float] = Field([1.0, 2.0, 3.0], min_length=1, description=(
            "dimensionless times T = t sqrt(g/H0) at which Z is compared, within the "
            "Martin & Moyce data (0.43 <= T <= 3.32)"))

        @field_validator("times", mode="before")
        @classmethod
        def _one(cls, v):
            return _as_list(v)

        @field_validator("times")
        @classmethod
        def _in_data(cls, v):
            from sphfoam.sampling.damBreak import MM_FRONT

            lo, hi = float(MM_FRONT[0, 0]), float(MM_FRONT[-1, 0])
            bad = [t for t in v if not lo <= t <= hi]
            if bad:
                raise ValueError(f"T = {', '.join(map(_label, bad))} outside the Martin & "
                                 f"Moyce data ({lo:g} <= T <= {hi:g})")
            return v

    @property
    def unit(self):
        return "-"

    def martin_moyce(self) -> np.ndarray:
        """Martin & Moyce's Z at the times T."""
        from sphfoam.sampling.damBreak import martin_moyce

        front, _ = martin_moyce()
        return np.interp(np.asarray(self.coeffs.times, dtype=float), front[:, 0], front[:, 1])

    def known_reference(self):
        return float(self.martin_moyce().mean())

    def measure(self, case_path, spec):

        cols, data, rel = self.series(case_path)
        T = data[:, self.column(cols, "T", rel)]
        Z = data[:, self.column(cols, "Z", rel)]
        ok = np.isfinite(T) & np.isfinite(Z)
        T, Z = T[ok], Z[ok]
        want = np.asarray(self.coeffs.times, dtype=float)
        late = want[(want < T.min()) | (want > T.max())] if T.size else want
        if late.size:
            self.fail("times", f"T = {', '.join(map(_label, late))} not sampled in {rel} "
                      + (f"(T = {T.min():.3g} .. {T.max():.3g})" if T.size else "(no samples)"))
        order = np.argsort(T, kind="stable")
        z = np.interp(want, T[order], Z[order])
        zm = self.martin_moyce()
        return MetricValue(float(z.mean()), float(zm.mean()),
                           float(np.mean(100.0 * (z - zm) / zm)), self.unit)
