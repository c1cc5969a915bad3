"""Studies: one base case, variants x resolutions, run in parallel and tabulated.

``sphfoam study STUDYDICT`` does by machine what the thesis did by hand in T Tables 4.1-4.3:
it clones the base case once per (variant, resolution), runs the clones in parallel processes
(or on a Dask cluster: the same ``concurrent.futures`` code path), and collects per run the
cost (wall time, compile time, steps, particles, particle-steps/s) and the case's error
metrics (``system/metricsDict``, the ``metric`` family).  Each run keeps its own
``result.json``, so an interrupted study resumes where it stopped and no result is lost.

Output in the study directory: ``study.csv``, ``study.md`` (runtime relative to the
baseline variant, like T Table 4.3) and ``pareto.png`` (error against cost, Pareto front
marked).
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import os
import shutil
import time as wallclock
import traceback
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, field_validator

from sphfoam.case import foamdict
from sphfoam.case.edit import RESULTS
from sphfoam.case.errors import CaseError, Problem, did_you_mean, from_validation
from sphfoam.case.paths import check_name, inside
from sphfoam.case.schemas import SPH_FAMILIES, Strict

RESULT = "result.json"
#: a case's dictionary folders: never a study's directory, never left out of a clone
CASE_FOLDERS = ("system", "constant", "0")


class StudyDict(Strict):
    """The study dictionary (OpenFOAM syntax, any file name)."""

    baseCase: str = Field(".", description="the case every run is cloned from, relative to "
                          "the study dictionary's folder")
    directory: str = Field("study", description="where the runs and the tables go, relative to "
                           "the study dictionary's folder (and inside it), or an absolute "
                           "path to put them elsewhere on purpose")
    resolutions: list[float] = Field(default_factory=list, description=(
        "particle spacings dx (m) to run every variant at; empty: the base case's dx"))
    set: dict[str, Any] = Field(default_factory=dict, description=(
        "overrides applied to every run before the variant's own (same form as a variant)"))
    variants: dict[str, dict[str, Any]] = Field(default_factory=dict, description=(
        "name { description \"...\"; key value; ... }: dictionary overrides of each variant. "
        "A key is a dotted path whose first word names an entry of one of the case's "
        "dictionaries (viscosity.type, maxCo, dx, waves.incident.height) or, in quotes, "
        "\"system/controlDict:endTime\"; a sub-dictionary value replaces the whole entry. "
        "A variant's own resolutions (dx list) replace the study's for that variant"))
    axes: dict[str, dict[str, dict[str, Any]]] = Field(default_factory=dict, description=(
        "axis { level { overrides } ... }: every combination of one level per axis is a run "
        "(named level_level...), listed before the variants"))
    baseline: str | None = Field(None, description="variant whose wall time is 1.00 in the "
                                 "relative-runtime column (default: the first)")
    metrics: dict[str, Any] | None = Field(None, description=(
        "replaces the base case's system/metricsDict metrics (same form)"))
    pareto: str | None = Field(None, description="metric whose |error| is plotted against cost "
                               "(default: the metricsDict's pareto, else the first metric)")
    jobs: int = Field(1, ge=1, description="runs at once (local processes)")
    threads: int = Field(1, ge=1, description=(
        "numba threads of each run, pinned (the runs' controlDict threads is not used)"))
    scheduler: str | None = Field(None, description="address of a Dask distributed scheduler "
                                  "(tcp://host:8786); the case folders must be on a file "
                                  "system its workers share")

    @field_validator("resolutions")
    @classmethod
    def _positive(cls, v):
        if any(not (x > 0) for x in v):
            raise ValueError("every resolution (dx) must be > 0")
        return v


def _own_resolutions(v) -> list[float] | str:
    """A variant's own ``resolutions``: positive spacings, or the reason they are not."""
    vals = v if isinstance(v, (list, tuple)) else [v]
    try:
        dxs = [float(x) for x in vals]
    except (TypeError, ValueError):
        return f"expected a list of particle spacings dx (m), got {v!r}"
    if not dxs or any(not (x > 0) for x in dxs):
        return f"every resolution (dx) must be > 0, got {v!r}"
    return dxs


@dataclass
class RunSpec:
    """One run of a study: what to clone, with which overrides, where."""

    name: str
    variant: str
    description: str
    dx: float | None
    path: str
    threads: int
    metrics: dict | None
    source: str | None = None       # the study dictionary, when it declares the metrics


@dataclass
class Study:
    source: Path
    spec: StudyDict
    base: Path
    root: Path
    runs: list[RunSpec] = field(default_factory=list)
    edits: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def pareto_metric(self) -> str | None:
        if self.spec.pareto:
            return self.spec.pareto
        if self.spec.metrics is None:
            md = self.base / "system" / "metricsDict"
            if md.is_file():
                d = foamdict.read(md)
                if d.get("pareto"):
                    return str(d["pareto"])
                return next(iter(d.get("metrics", {})), None)
        return next(iter(self.spec.metrics or {}), None)


# --- reading the study dictionary --------------------------------------------------------------
def _dict_files(base: Path) -> dict[str, set[str]]:
    """Top-level keys each dictionary of the base case has or may have."""
    from sphfoam.case.case import FILES, SPH_PROPERTIES

    files: dict[str, set[str]] = {}
    for rel, schema in FILES.values():
        files[rel] = set(schema.model_fields)
    files[SPH_PROPERTIES] = set(SPH_FAMILIES)
    for folder in ("system", "constant"):
        for f in sorted((base / folder).glob("*")):
            if f.is_file():
                rel = f"{folder}/{f.name}"
                try:
                    keys = set(foamdict.read(f)) - {"FoamFile"}
                except Exception:       # not a dictionary (a table, a mesh): not editable here
                    continue
                files.setdefault(rel, set()).update(keys)
    return files


def resolve_key(files: dict[str, set[str]], key: str) -> tuple[str, str] | str:
    """``(file, dotted key)`` for an override key, or an error message."""
    if ":" in key:
        rel, dotted = key.split(":", 1)
        if rel not in files:
            return f"no dictionary {rel!r} in the base case; have: {', '.join(sorted(files))}"
        return rel, dotted
    head = key.split(".")[0]
    owners = [rel for rel, keys in files.items() if head in keys]
    if len(owners) == 1:
        return owners[0], key
    if not owners:
        every = sorted(set().union(*files.values()))
        return (f"'{head}' is not an entry of any dictionary of the base case"
                f"{did_you_mean(head, every)} write \"file:key\" to name the file")
    return (f"'{head}' is an entry of {' and '.join(owners)}: write \"{owners[0]}:{key}\" "
            f"to say which")


def load(path: Path | str, only: list[str] | None = None) -> Study:
    """Read and check a study dictionary; lists its runs (nothing is cloned yet)."""
    path = Path(path).resolve()
    rel = path.name
    if not path.is_file():
        raise CaseError.single(str(path), "", "study dictionary not found")
    try:
        raw = {k: v for k, v in foamdict.read(path).items() if k != "FoamFile"}
    except foamdict.FoamDictError as e:
        raise CaseError([Problem(rel, "", f"syntax error: {e}")]) from None
    except UnicodeDecodeError as e:
        raise CaseError([Problem(rel, "", f"not a text dictionary: byte {e.object[e.start]:#04x} "
                                 f"at offset {e.start} is not UTF-8")]) from None
    try:
        spec = StudyDict.model_validate(raw)
    except ValidationError as e:
        raise from_validation(e, rel, StudyDict) from None
    base = (path.parent / spec.baseCase).resolve()
    if not (base / "system" / "controlDict").is_file():
        raise CaseError.single(rel, "baseCase", f"{base} is not a case (no system/controlDict)")
    root = (path.parent / spec.directory).resolve()
    if not Path(spec.directory).is_absolute() and not inside(root, path.parent):
        raise CaseError.single(rel, "directory", f"{spec.directory!r} lies outside the study "
                               f"dictionary's folder {path.parent}; give an absolute path to "
                               "put the study elsewhere on purpose")
    if root == base or root in base.parents or (root.parent == base and root.name in
                                                 CASE_FOLDERS):
        raise CaseError.single(rel, "directory", "must not be the base case, a folder holding "
                               "it, or one of its dictionary folders")
    study = Study(path, spec, base, root)
    files = _dict_files(base)
    problems: list[Problem] = []

    def named(where: str, name) -> bool:
        """A variant's, level's or run's name becomes a folder of the study: one plain
        path component, never '..' or '/abs'."""
        try:
            check_name(name)
            return True
        except ValueError as e:
            problems.append(Problem(rel, where, str(e)))
            return False

    own_dx: dict[str, list[float]] = {}

    def edits_of(where: str, overrides: dict) -> tuple[str, dict]:
        out, desc = {}, ""
        for k, v in overrides.items():
            if k == "description":
                desc = str(v)
                continue
            if k == "resolutions" and where.startswith("variants."):
                dxs = _own_resolutions(v)
                if isinstance(dxs, str):
                    problems.append(Problem(rel, f"{where}.resolutions", dxs))
                else:
                    own_dx[where.removeprefix("variants.")] = dxs
                continue
            r = resolve_key(files, str(k))
            if isinstance(r, str):
                problems.append(Problem(rel, f"{where}.{k}", r))
            else:
                out[f"{r[0]}:{r[1]}"] = v
        return desc, out

    _, common = edits_of("set", spec.set)
    variants: list[tuple[str, str, dict]] = []
    if spec.axes:
        levels = []
        for axis, lv in spec.axes.items():
            if not lv or not all(isinstance(v, dict) for v in lv.values()):
                problems.append(Problem(rel, f"axes.{axis}", "expected level { overrides } "
                                        "entries"))
                continue
            levels.append([(str(n), *edits_of(f"axes.{axis}.{n}", ov)) for n, ov in lv.items()
                           if named(f"axes.{axis}.{n}", n)])
        for combo in itertools.product(*levels):
            name = "_".join(c[0] for c in combo)
            desc = ", ".join(c[1] for c in combo if c[1])
            ed = {}
            for c in combo:
                ed.update(c[2])
            variants.append((name, desc, ed))
    for name, ov in spec.variants.items():
        if not named(f"variants.{name}", name):
            continue
        if not isinstance(ov, dict):
            problems.append(Problem(rel, f"variants.{name}", "expected a sub-dictionary of "
                                    "overrides"))
            continue
        desc, ed = edits_of(f"variants.{name}", ov)
        variants.append((str(name), desc, ed))
    if not variants:
        problems.append(Problem(rel, "variants", "no variants and no axes: nothing to run"))
    names = [v[0] for v in variants]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        problems.append(Problem(rel, "variants", f"duplicate run names: {', '.join(dup)}"))
    if spec.baseline is not None and spec.baseline not in names:
        problems.append(Problem(rel, "baseline", f"'{spec.baseline}' is not a variant"
                                f"{did_you_mean(spec.baseline, names)} variants: "
                                f"{', '.join(names)}"))
    dxs = spec.resolutions or [None]

    def run_name(name, dx):
        return name if dx is None else f"{name}_dx{dx:g}"

    if only:
        runs = {run_name(n, dx) for n in names for dx in own_dx.get(n, dxs)}
        unknown = [o for o in only if o not in names and o not in runs]
        if unknown:
            problems.append(Problem(rel, "variants", f"--only {', '.join(unknown)}: no such "
                                    f"variant or run; variants: {', '.join(names)}"))
    if problems:
        raise CaseError(problems)
    from sphfoam.case.metrics_dict import load_metrics

    load_metrics(base, spec.metrics, source=rel)       # bad metrics: one screen, before runs
    for name, desc, ed in variants:
        for dx in own_dx.get(name, dxs):
            run = run_name(name, dx)
            if only and name not in only and run not in only:
                continue
            edits = {**common, **ed}
            if dx is not None:
                edits["system/particleDict:dx"] = dx
            study.runs.append(RunSpec(run, name, desc, dx, str(root / run), spec.threads,
                                      spec.metrics, rel if spec.metrics else None))
            study.edits[run] = edits
    return study


def prepare(study: Study, rerun: bool = False, log=print) -> list[RunSpec]:
    """Clone the base case for every run without a result yet and validate every clone
    (all problems on one screen before anything runs). A run a stopped study left with
    written times continues from the last of them (``startFrom latestTime``) when its
    dictionaries are still what the study makes of it, and is kept aside as ``<run>.old``
    otherwise (``rerun``: every run starts again). Returns the runs still to do."""
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.setup.sanity import check_geometry

    study.root.mkdir(parents=True, exist_ok=True)
    todo, problems = [], []
    ignore = study_folders(study)
    for run in study.runs:
        path = Path(run.path)
        if path.is_symlink() or path.parent.resolve() != study.root or path.name in (
                "", ".", ".."):
            # run names are plain names (load checks them): this is a guard, never reached
            raise CaseError.single(study.source.name, "variants", f"run folder {path} is not "
                                   f"a plain folder directly inside the study {study.root}")
        if not rerun and (path / RESULT).is_file():
            continue
        if not rerun and _latest_time(path) > 0.0:
            # an interrupted run (its study was stopped): continue it from its last written
            # time when it is still the same case; a run of another definition is kept aside
            fresh = clone_case(study.base, path.with_name(f".{path.name}.clone"),
                               study.edits[run.name], ignore=ignore)
            if _same_dictionaries(fresh, path):
                shutil.rmtree(fresh)
                todo.append(run)
                continue
            shutil.rmtree(fresh)
            kept = _aside(path)
            log(f"study: {run.name} was begun with other settings; its results are kept "
                f"in {kept} and it starts again")
        clone_case(study.base, path, study.edits[run.name], ignore=ignore)
        try:
            c = Case(path)
            c.validate()
            check_geometry(c)
        except CaseError as e:
            problems.extend(Problem(f"{run.name}/{p.file}", p.key, p.message)
                            for p in e.problems)
        todo.append(run)
    if problems:
        raise CaseError(problems)
    return todo


def _latest_time(path: Path) -> float:
    """The latest time after 0 a run folder holds particles of (an interrupted run's), else 0."""
    from sphfoam.case.times import list_times
    from sphfoam.io.fields import has_particles

    return max([t for t, p in list_times(path) if t > 0.0 and has_particles(p)], default=0.0)


def _case_files(path: Path) -> dict[str, Path]:
    """The dictionaries that define a case (``constant/`` and ``system/``, as ``clone_case``
    copies them), by relative path; what lies beside them (the study dictionaries, scripts,
    notes, logs) does not change a run."""
    import fnmatch

    out = {}
    for top in ("constant", "system"):
        for f in (path / top).rglob("*"):
            rel = f.relative_to(path)
            # results inside them are left out, as clone_case leaves them out
            if not f.is_file() or any(fnmatch.fnmatch(part, pat) for part in rel.parts
                                      for pat in RESULTS):
                continue
            out[rel.as_posix()] = f
    return out


def _same_dictionaries(a: Path, b: Path) -> bool:
    """Whether two case folders hold the same dictionaries, byte for byte."""
    fa, fb = _case_files(a), _case_files(b)
    return fa.keys() == fb.keys() and all(fa[k].read_bytes() == fb[k].read_bytes()
                                          for k in fa)


def _aside(path: Path) -> Path:
    """Rename a run folder to the first free ``<name>.old``, ``<name>.old1``, ..."""
    for i in itertools.count():
        dst = path.with_name(f"{path.name}.old{i or ''}")
        if not dst.exists():
            path.rename(dst)
            return dst
    raise AssertionError("unreachable")


def study_folders(study: Study) -> tuple[str, ...]:
    """The folders of the base case that hold studies' runs, which are not cloned into the
    runs: this study's directory when it lies inside the base case, and the ``directory``
    of every other study dictionary (``studyDict*``) of the base case."""
    roots = [study.root]
    for other in sorted(study.base.glob("studyDict*")):
        try:
            d = foamdict.read(other).get("directory",
                                         StudyDict.model_fields["directory"].default)
        except (foamdict.FoamDictError, UnicodeDecodeError, OSError):
            continue
        if isinstance(d, str) and d:
            roots.append((other.parent / d).resolve())
    folders = (r.relative_to(study.base).parts[0] for r in roots if study.base in r.parents)
    return tuple(dict.fromkeys(f for f in folders if f not in CASE_FOLDERS))


# --- one run (in a worker process) -------------------------------------------------------------
def run_one(spec: RunSpec) -> dict:
    """Set up and run one clone, evaluate its metrics, write ``result.json``. Never raises:
    a blow-up, a case error or a crash is an outcome in the table."""
    import numba

    numba.set_num_threads(max(1, min(spec.threads, numba.config.NUMBA_NUM_THREADS)))
    from sphfoam.case.case import Case
    from sphfoam.engine.health import BlowUp
    from sphfoam.case.metrics_dict import evaluate_metrics
    from sphfoam.setup.settling import setup_case
    from sphfoam.timeloop import run_case

    path = Path(spec.path)
    row: dict[str, Any] = {"run": spec.name, "variant": spec.variant,
                           "description": spec.description, "dx": spec.dx}
    t0 = wallclock.perf_counter()
    report = None
    resumed = _latest_time(path)
    if resumed > 0.0:
        # continued from a stopped study's last write: wall time and steps are this part's
        row["resumedFrom"] = resumed
    try:
        case = Case(path)
        state = setup_case(case, log=lambda m: None)
        row["particles"] = int(state.n)
        row["fluid"] = int(state.n_fluid)
        report = run_case(case, progress=False, echo=None, threads=spec.threads)
        row["outcome"] = "ok"
    except BlowUp as e:
        report = e.report
        d = e.diagnosis
        row["outcome"] = f"blowUp:{d.kind}"
        row["diagnosis"] = d.message
        row["failTime"] = d.fail_time
        row["lastGood"] = d.last_good
    except CaseError as e:
        row["outcome"] = "caseError"
        row["diagnosis"] = "; ".join(str(p) for p in e.problems)
    except Exception as e:          # a crash is a result too; the traceback goes to the log
        row["outcome"] = "crash"
        row["diagnosis"] = f"{type(e).__name__}: {e}"
        with open(path / "log.sphfoam", "a") as fh:
            fh.write(traceback.format_exc())
    row["totalSeconds"] = wallclock.perf_counter() - t0
    if report is not None:
        row.update(steps=report.steps, particles=report.particles,
                   endTime=report.end_time, wallSeconds=report.run_seconds,
                   compileSeconds=report.compile_seconds,
                   particleStepsPerSecond=report.particle_steps_per_second)
    if row["outcome"] in ("ok",) or row["outcome"].startswith("blowUp"):
        try:
            vals = evaluate_metrics(path, spec.metrics, strict=False, source=spec.source)
        except CaseError as e:
            vals = {}
            row["metricsError"] = "; ".join(str(p) for p in e.problems)
        bad = []
        for name, mv in vals.items():
            row[name] = mv.value
            row[f"{name} err %"] = mv.error
            if mv.problem:
                bad.append(f"{name}: {mv.problem}")
        if bad:
            row["metricsError"] = "; ".join(bad)
    (path / RESULT).write_text(json.dumps(row, indent=1, default=_json_default))
    return row


def _json_default(o):
    if isinstance(o, float) and not math.isfinite(o):
        return None
    return str(o)


# --- executing ---------------------------------------------------------------------------------
@contextmanager
def executor(jobs: int, threads: int, scheduler: str | None = None) -> Executor:
    """Local processes, or a Dask cluster's executor: both are concurrent.futures executors."""
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise CaseError.single("studyDict", "scheduler", "running on a Dask cluster needs "
                                   "the distributed package: pip install 'sphfoam[dask]'") \
                from None
        client = Client(scheduler)
        try:
            yield client.get_executor()
        finally:
            client.close()
        return
    import multiprocessing as mp

    # workers are spawned (not forked from a process that may hold numba threads) and get
    # their thread count before numba starts
    old = os.environ.get("NUMBA_NUM_THREADS")
    os.environ["NUMBA_NUM_THREADS"] = str(threads)
    try:
        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn"),
                                 initializer=follow_parent, initargs=(os.getpid(),)) as ex:
            yield ex
    finally:
        if old is None:
            os.environ.pop("NUMBA_NUM_THREADS", None)
        else:
            os.environ["NUMBA_NUM_THREADS"] = old


#: seconds a worker whose study has gone gives its run to finish the step and write (then it
#: idles, its result having nowhere to go) before it quits
ORPHAN_GRACE = 60.0


def follow_parent(parent: int, poll: float = 1.0, grace: float = ORPHAN_GRACE) -> None:
    """Worker initialiser: when the study process goes (killed, or its terminal closed), stop
    this worker's run as Ctrl-C does (the time loop finishes its step and writes the state;
    the run gets no result, so the study started again runs it again, from there with
    ``startFrom latestTime``), then quit; without it the runs went on computing, orphaned,
    for as long as they had left."""
    import signal
    import threading

    # a study started in the background (nohup, `&` in a script) hands its workers SIGINT
    # ignored, and Python then keeps ignoring it: Ctrl-C's KeyboardInterrupt back on
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def watch():
        while os.getppid() == parent:
            wallclock.sleep(poll)
        os.kill(os.getpid(), signal.SIGINT)
        wallclock.sleep(grace)
        os._exit(1)

    threading.Thread(target=watch, name="sphfoam-follow-parent", daemon=True).start()


def run_study(study: Study, *, jobs: int | None = None, scheduler: str | None = None,
              rerun: bool = False, log=print) -> list[dict]:
    """Run every run without a result, then collect the table, CSV and plot."""
    todo = prepare(study, rerun=rerun, log=log)
    jobs = jobs or study.spec.jobs
    scheduler = scheduler or study.spec.scheduler
    done = len(study.runs) - len(todo)
    log(f"study {study.source.name}: {len(study.runs)} run(s), {done} already done, "
        f"{len(todo)} to run ({'Dask ' + scheduler if scheduler else f'{jobs} local process(es)'}"
        f", {study.spec.threads} thread(s) each) in {study.root}")
    if todo:
        with executor(jobs, study.spec.threads, scheduler) as ex:
            futures = {ex.submit(run_one, r): r for r in todo}
            for fut in as_completed(futures):
                r = futures[fut]
                try:
                    row = fut.result()
                except Exception as e:      # the worker process itself died
                    row = {"run": r.name, "variant": r.variant, "dx": r.dx,
                           "outcome": "crash", "diagnosis": f"{type(e).__name__}: {e}"}
                    Path(r.path).mkdir(parents=True, exist_ok=True)
                    (Path(r.path) / RESULT).write_text(json.dumps(row, indent=1))
                log(f"  {row['run']}: {row['outcome']}"
                    + (f" in {row['wallSeconds']:.1f} s" if row.get("wallSeconds") else "")
                    + (f" ({row['diagnosis']})" if row.get("diagnosis") else ""))
    rows = collect(study)
    log(f"wrote {study.root / 'study.csv'}, {study.root / 'study.md'}"
        + (f", {study.root / 'pareto.png'}" if (study.root / "pareto.png").is_file() else ""))
    return rows


# --- tables and the Pareto plot ----------------------------------------------------------------
BASE_COLUMNS = ["run", "variant", "description", "dx", "outcome", "particles", "steps",
                "endTime", "wallSeconds", "compileSeconds", "particleStepsPerSecond",
                "relativeRuntime"]
TAIL_COLUMNS = ["diagnosis", "failTime", "lastGood", "metricsError"]


def _rows(study: Study) -> list[dict]:
    rows = []
    for r in study.runs:
        f = Path(r.path) / RESULT
        if f.is_file():
            row = json.loads(f.read_text())
            if row.get("dx") is None:       # set by an override, not the resolutions list
                row["dx"] = _case_dx(Path(r.path))
            rows.append(row)
    return rows


def _case_dx(path: Path) -> float | None:
    try:
        return float(foamdict.read(path / "system" / "particleDict")["dx"])
    except Exception:                       # no readable particleDict: leave it blank
        return None


def relative_runtimes(rows: list[dict], baseline: str | None) -> None:
    """Wall time over the baseline variant's at the same dx (T Table 4.3's last column)."""
    if not rows:
        return
    base = baseline or rows[0]["variant"]
    ref = {r.get("dx"): r.get("wallSeconds") for r in rows
           if r["variant"] == base and r.get("outcome") == "ok"}
    for r in rows:
        b = ref.get(r.get("dx"))
        w = r.get("wallSeconds")
        r["relativeRuntime"] = w / b if (b and w and r.get("outcome") == "ok") else None


def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both cost and error (lower is better)."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def collect(study: Study) -> list[dict]:
    rows = _rows(study)
    relative_runtimes(rows, study.spec.baseline)
    metric_cols: list[str] = []
    for r in rows:
        for k in r:
            if k not in BASE_COLUMNS and k not in TAIL_COLUMNS and k not in metric_cols \
                    and k not in ("fluid", "totalSeconds"):
                metric_cols.append(k)
    cols = BASE_COLUMNS + metric_cols + TAIL_COLUMNS
    study.root.mkdir(parents=True, exist_ok=True)
    with open(study.root / "study.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in cols})
    (study.root / "study.md").write_text(markdown(rows, metric_cols, study))
    _plot(study, rows)
    return rows


def _fmt(v, key=""):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if isinstance(v, float):
        if key in ("wallSeconds", "compileSeconds", "totalSeconds"):
            return f"{v:.1f}"
        if key == "relativeRuntime":
            return f"{v:.2f}"
        if key.endswith("err %"):
            return f"{v:+.1f}"
        if key == "particleStepsPerSecond":
            return f"{v:.3g}"
        return f"{v:.4g}"
    return str(v).replace("|", "/")


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and math.isfinite(v)


def markdown(rows: list[dict], metric_cols: list[str], study: Study) -> str:
    head = ["run", "description", "dx", "particles", "steps", "wall s", "compile s",
            "particle-steps/s", "runtime vs " + (study.spec.baseline or
                                                 (rows[0]["variant"] if rows else "first"))]
    keys = ["run", "description", "dx", "particles", "steps", "wallSeconds", "compileSeconds",
            "particleStepsPerSecond", "relativeRuntime"]
    # a metric column with no value in any run (e.g. errors of a metric without a reference)
    # stays in the CSV but not in the table
    shown = [k for k in metric_cols if any(_finite(r.get(k)) for r in rows)]
    head += shown + ["outcome"]
    keys += shown + ["outcome"]
    out = [f"# Study {study.source.name}: base case {study.base.name}", "",
           "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        out.append("| " + " | ".join(_fmt(r.get(k), k) for k in keys) + " |")
    failed = [r for r in rows if r.get("outcome") != "ok"]
    if failed:
        out += ["", "## Runs that did not finish", ""]
        for r in failed:
            out.append(f"- **{r['run']}**: {r.get('outcome')}"
                       + (f" at t = {r['failTime']:.4g} s" if r.get("failTime") is not None
                          else "")
                       + (f": {r['diagnosis']}" if r.get("diagnosis") else "")
                       + (f" (last good state: {r['lastGood']})" if r.get("lastGood") else ""))
    resumed = [r for r in rows if r.get("resumedFrom")]
    if resumed:
        out += ["", "## Runs continued after a stop", "",
                "Their steps, wall seconds and particle-steps/s are those of the part after "
                "the restart.", ""]
        out += [f"- **{r['run']}**: from t = {r['resumedFrom']:g} s" for r in resumed]
    return "\n".join(out) + "\n"


def _plot(study: Study, rows: list[dict]) -> None:
    metric = study.pareto_metric
    key = f"{metric} err %" if metric else None
    pts, labels = [], []
    for r in rows:
        e, w = r.get(key) if key else None, r.get("wallSeconds")
        if r.get("outcome") == "ok" and e is not None and w and math.isfinite(e):
            pts.append((float(w), abs(float(e))))
            labels.append(r["run"])
    png = study.root / "pareto.png"
    if not pts:
        png.unlink(missing_ok=True)
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    front = pareto_front(pts)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.scatter([p[0] for p in pts], [p[1] for p in pts], c="0.5", zorder=2, label="runs")
    fp = sorted((pts[i] for i in front))
    ax.plot([p[0] for p in fp], [p[1] for p in fp], "o-", c="C3", zorder=3,
            label="Pareto front")
    for (x, y), lab in zip(pts, labels):
        ax.annotate(lab, (x, y), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.set(xlabel="wall time (s)", ylabel=f"|{metric} error| (%)",
           title=f"{study.source.name}: error against cost")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def dump(study: Study) -> list[dict]:
    """The runs as plain dicts (``sphfoam study --dry-run``)."""
    return [dict(asdict(r), edits=study.edits[r.name]) for r in study.runs]
