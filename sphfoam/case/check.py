"""``sphfoam check``: every dictionary a case has, validated without running anything.

Besides the dictionaries :meth:`Case.validate` reads (controlDict, sphSchemes, particleDict,
transportProperties, g, sphProperties, waveProperties, the function objects and wall
motions), this checks ``system/metricsDict`` when the case has one, and every study
dictionary beside the case's ``system/`` folder (a file whose header says ``object
studyDict;`` or that has ``variants`` or ``axes``). All problems come back in one CaseError.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from sphfoam.case import foamdict
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError, Problem

__all__ = ["check_case", "study_dicts", "CheckReport"]


@dataclass
class CheckReport:
    case: Case
    metrics: object | None = None           # the MetricSet of system/metricsDict
    studies: dict[str, object] = field(default_factory=dict)   # file name -> Study


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
            # a file that names studyDict in its header but does not parse: report it
            if b"studyDict" in head:
                out.append(f)
            continue
        hdr = d.get("FoamFile") if isinstance(d.get("FoamFile"), dict) else {}
        if str(hdr.get("object", "")) == "studyDict" or "variants" in d or "axes" in d:
            out.append(f)
    return out


def check_case(path: Path | str) -> CheckReport:
    """Validate every dictionary of the case at ``path`` (CaseError with all problems)."""
    from sphfoam.models.metrics import METRICS_DICT, load_metrics
    from sphfoam import study as st

    case = Case(path)
    if not case.path.is_dir():
        raise CaseError.single(str(path), "", "not a case directory (expected constant/ and "
                               "system/)")
    problems: list[Problem] = []
    report = CheckReport(case)
    try:
        case.validate()
    except CaseError as e:
        problems.extend(e.problems)
    if (case.path / METRICS_DICT).is_file():
        try:
            report.metrics = load_metrics(case.path)
        except CaseError as e:
            problems.extend(p for p in e.problems if str(p) not in map(str, problems))
    for f in study_dicts(case.path):
        try:
            report.studies[f.name] = st.load(f)
        except CaseError as e:
            problems.extend(Problem(p.file if p.file == f.name else f"{f.name}: {p.file}",
                                    p.key, p.message) for p in e.problems)
    if problems:
        raise CaseError(problems)
    return report
