"""``system/metricsDict`` (and a study's own metrics): loading, checking against the
case's function objects, and evaluation after a run. The metrics themselves are the
``metric`` family (``sphfoam.study.metrics``), built through the registry."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from sphfoam.case.case import Case, build_model
from sphfoam.case.errors import CaseError, Problem, from_validation
from sphfoam.case.schemas import MetricsDict

METRICS_DICT = "system/metricsDict"
CONTROL_DICT = "system/controlDict"


@dataclass
class MetricValue:
    """One evaluated metric. ``error`` is (value - reference)/reference in %, None without a
    reference, NaN when it cannot be formed; ``problem`` says why ``value`` is NaN when the
    metric failed under ``evaluate_metrics(..., strict=False)``."""

    value: float
    reference: float | None
    error: float | None
    unit: str
    problem: str | None = None


def relative_error(value: float, reference: float | None) -> float | None:
    """Signed relative error in %, (value - reference)/reference 100; None without a
    reference, NaN when either is not finite or the reference is 0."""
    if reference is None:
        return None
    v, r = float(value), float(reference)
    if not (math.isfinite(v) and math.isfinite(r)) or r == 0.0:
        return float("nan")
    return 100.0 * (v - r) / r


@dataclass
class MetricSet:
    """The metrics of a case (or of a study's own spec), built and validated."""

    metrics: dict[str, Any]
    pareto: str | None
    source: str = METRICS_DICT

    def check(self, case_path, functions: dict | None = None) -> None:
        """Check every metric against the function objects of the case's system/controlDict
        (or ``functions``, already read; before a run: nothing is read from
        postProcessing)."""
        if functions is None:
            functions = Case(case_path).read_dict(CONTROL_DICT).get("functions") or {}
        problems: list[Problem] = []
        for m in self.metrics.values():
            try:
                m.check(functions)
            except CaseError as e:
                problems.extend(e.problems)
        if problems:
            raise CaseError(problems)

    def evaluate(self, case_path, strict: bool = True) -> dict[str, MetricValue]:
        """Every metric of the run in ``case_path``. ``strict``: one CaseError listing every
        metric that cannot be evaluated; otherwise those are NaN with their ``problem``."""
        out, problems = {}, []
        for name, m in self.metrics.items():
            try:
                out[name] = m.evaluate(case_path)
            except CaseError as e:
                problems.extend(e.problems)
                ref = m.known_reference()
                out[name] = MetricValue(float("nan"), ref, None if ref is None else float("nan"),
                                        m.unit, "; ".join(str(p) for p in e.problems))
        if strict and problems:
            raise CaseError(problems)
        return out


def _spec_of(spec: dict) -> dict:
    """A metrics spec given as the whole dictionary ({metrics {...}; pareto ...}) or as the
    ``metrics`` mapping alone (as a studyDict writes it)."""
    inner = spec.get("metrics")
    if isinstance(inner, dict) and "type" not in inner:
        return dict(spec)
    return {"metrics": dict(spec)}


def load_metrics(case_path=None, spec: dict | None = None, *, source: str | None = None
                 ) -> MetricSet:
    """Build the metrics of ``spec`` or else of ``case_path``/system/metricsDict; errors (unknown
    type, bad keys, unknown pareto) are one CaseError naming ``source`` and the key path."""

    if spec is None:
        source = source or METRICS_DICT
        raw = Case(case_path).read_dict(METRICS_DICT)
    else:
        source = source or "metrics spec"
        raw = _spec_of(spec)
    problems: list[Problem] = []
    try:
        md = MetricsDict.model_validate(raw)
        entries, pareto = md.metrics, md.pareto
    except ValidationError as e:                 # report the entries' problems too
        problems.extend(from_validation(e, source, MetricsDict).problems)
        entries, pareto = raw.get("metrics"), None
        entries = entries if isinstance(entries, dict) else {}
    metrics: dict[str, Any] = {}
    for name, entry in entries.items():
        m = build_model("metric", entry, source, f"metrics.{name}", problems)
        if m is not None:
            m.entry, m.source = name, source
            metrics[name] = m
    if problems:
        raise CaseError(problems)
    return MetricSet(metrics, pareto, source)


def evaluate_metrics(case_path, spec: dict | None = None, strict: bool = True, *,
                     source: str | None = None) -> dict[str, MetricValue]:
    """Metrics of the finished run in ``case_path``: those of ``spec`` (a study's own, the
    ``metrics`` mapping or a whole metricsDict) or else of its system/metricsDict.

    A bad metrics spec always raises a CaseError. A metric that cannot be evaluated (output
    missing, gauge absent, wave not arrived) raises with ``strict``; with ``strict=False`` it
    comes back as NaN with the reason in ``MetricValue.problem``.
    """
    return load_metrics(case_path, spec, source=source).evaluate(case_path, strict=strict)
