"""``sphfoam check``: every dictionary a case has, validated without running anything.

Besides the dictionaries :meth:`Case.validate` reads (controlDict, sphSchemes, particleDict,
transportProperties, g, sphProperties, waveProperties, the function objects and wall
motions), this checks ``system/metricsDict`` when the case has one, and every study
dictionary beside the case's ``system/`` folder (a file whose header says ``object
studyDict;`` or that has ``variants`` or ``axes``). All problems come back in one CaseError.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from sphfoam.case import foamdict
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError, Problem
from sphfoam.setup.settling import check_settling
from sphfoam.setup.sanity import check_geometry

__all__ = ["check_case", "study_dicts", "CheckReport"]


@dataclass
class CheckReport:
    case: Case
    metrics: object | None = None           # the MetricSet of system/metricsDict
    studies: dict[str, object] = field(default_factory=dict)   # file name -> Study


_STUDY_HEADER = re.compile(rb"\bobject\s+studyDict\s*;")


def study_dicts(path: Path) -> list[Path]:
    """The study dictionaries lying in a case folder (not in system/ or constant/)."""
    out = []
    for f in sorted(Path(path).iterdir()):
        if not f.is_file() or f.name.startswith((".", "log.")) or f.suffix in (
                ".py", ".md", ".png", ".csv", ".json", ".dat", ".txt", ".sh"):
            continue
        try:
            head = f.read_bytes()[:65536]
        except OSError:
            continue
        if b"studyDict" not in head and b"variants" not in head and b"axes" not in head:
            continue
        try:
            d = foamdict.read(f)
        except (ValueError, OSError):
            # a file that does not parse is reported only where it says it is a study
            # dictionary (its name, or a FoamFile header "object studyDict"): a log the
            # user redirected into the case folder names studyDict in its text too
            if f.name.startswith("studyDict") or _STUDY_HEADER.search(head):
                out.append(f)
            continue
        hdr = d.get("FoamFile") if isinstance(d.get("FoamFile"), dict) else {}
        if str(hdr.get("object", "")) == "studyDict" or "variants" in d or "axes" in d:
            out.append(f)
    return out


def check_case(path: Path | str, study_runs: bool = True) -> CheckReport:
    """Validate every dictionary of the case at ``path`` (CaseError with all problems).
    ``study_runs``: also clone and validate every run of each study dictionary
    (:func:`validate_runs`)."""
    from sphfoam.case.metrics_dict import METRICS_DICT, load_metrics
    import sphfoam.study as st

    case = Case(path)
    if not case.path.is_dir():
        raise CaseError.single(str(path), "", "not a case directory (expected constant/ and "
                               "system/)")
    problems: list[Problem] = []
    report = CheckReport(case)
    try:
        case.validate()
        check_geometry(case)
        check_settling(case)
    except CaseError as e:
        problems.extend(e.problems)
    if (case.path / METRICS_DICT).is_file():
        try:
            report.metrics = load_metrics(case.path)
            _check_metrics(report.metrics, case)
        except CaseError as e:
            problems.extend(p for p in e.problems if str(p) not in map(str, problems))
    for f in study_dicts(case.path):
        try:
            report.studies[f.name] = s = st.load(f)
            if study_runs:
                validate_runs(s)
        except CaseError as e:
            problems.extend(Problem(p.file if p.file.startswith(f.name) else
                                    f"{f.name}: {p.file}", p.key, p.message)
                            for p in e.problems)
    if problems:
        raise CaseError(problems)
    return report


def _check_metrics(mset, case: Case) -> None:
    """Each metric against the function objects of the case's controlDict."""
    try:
        functions = case.control.functions
    except CaseError:
        return                                  # reported by validate already
    mset.check(case.path, functions)


def validate_runs(study) -> None:
    """Every run of a study, cloned with its overrides into a temporary folder and validated
    (its metrics too), as ``sphfoam study`` would before running anything."""
    import tempfile

    import sphfoam.study as st
    from sphfoam.case.edit import clone_case
    from sphfoam.case.metrics_dict import load_metrics

    problems: list[Problem] = []
    ignore = st.study_folders(study)
    with tempfile.TemporaryDirectory(prefix="sphfoam-check-") as tmp:
        for run in study.runs:
            where = f"{study.source.name}: run {run.name}"
            try:
                path = clone_case(study.base, Path(tmp) / run.name, study.edits[run.name],
                                  ignore=ignore)
                c = Case(path)
                c.validate()
                check_geometry(c)
                check_settling(c)
                _check_metrics(load_metrics(path, run.metrics, source=run.source), c)
            except CaseError as e:
                problems.extend(Problem(f"{where}: {p.file}", p.key, p.message)
                                for p in e.problems)
            except (ValueError, TypeError) as e:   # an override the dictionary cannot hold
                problems.append(Problem(study.source.name, "variants",
                                        f"run {run.name}: {e}"))
    if problems:
        raise CaseError(problems)
