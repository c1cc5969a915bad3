"""The ``sphfoam`` command: one utility per job, like OpenFOAM's."""

from __future__ import annotations

from pathlib import Path
from typing import Literal, Optional

import typer
from rich.console import Console
from rich.panel import Panel
from rich.table import Table

from sphfoam._version import __version__

app = typer.Typer(add_completion=True, no_args_is_help=True,
                  help="sphfoam: SPH for free-surface water flows, driven like an OpenFOAM case.")
export_app = typer.Typer(no_args_is_help=True, help="Export results for other tools.")
app.add_typer(export_app, name="export")
console = Console()
err_console = Console(stderr=True)


def _flags_take_no_value() -> None:
    """typer's rich help prints a value type after on/off flags (``--force <bool>``), though
    they take none (typer 0.2x); show them as the bare flags they are."""
    from typer.core import TyperOption

    show = getattr(TyperOption, "display_type_rich", None)
    if show is None or getattr(show, "flags_fixed", False):   # (another typer: nothing to fix)
        return

    def display_type_rich(self, ctx):
        return None if (self.is_flag or self.count) else show(self, ctx)

    display_type_rich.flags_fixed = True
    TyperOption.display_type_rich = display_type_rich


_flags_take_no_value()
_state = {"debug": False}


#: exit codes (README, docs/user-guide.md): 0 ok, 1 OS error, 2 case error, 3 blow-up,
#: 130 interrupted
EXIT_OS, EXIT_CASE, EXIT_BLOWUP, EXIT_INTERRUPTED = 1, 2, 3, 130


def _fail(title: str, body: str, code: int = EXIT_CASE, markup: bool = False):
    """One red panel on stderr, then exit ``code``. ``body`` is plain text (escaped here, so
    user words such as ``[/bold]`` print as written) unless ``markup``."""
    from rich.markup import escape

    err_console.print(Panel(body if markup else escape(body), title=escape(title),
                            border_style="red", expand=False))
    raise typer.Exit(code)


def _os_error_text(e: OSError) -> str:
    where = f"{e.filename}: " if getattr(e, "filename", None) else ""
    what = e.strerror or str(e)
    return f"{where}{what}" + (f" (and {e.filename2})" if getattr(e, "filename2", None) else "")


def _handle(e: BaseException, command: str):
    """The one screen a failed command prints; never a traceback (unless --debug)."""
    from sphfoam.case.errors import CaseError

    if type(e).__module__.split(".")[0] in ("click", "typer"):    # typer.Exit and friends
        raise e
    if _state["debug"]:
        raise e
    if isinstance(e, CaseError):
        _fail("case error", "\n".join(f"• {p}" for p in e.problems))
    if isinstance(e, KeyboardInterrupt):
        from sphfoam.timeloop import Interrupted

        if isinstance(e, Interrupted) and e.written:
            err_console.print("[yellow]interrupted: the current state was written to "
                              f"{escape_(e.written)}; `sphfoam run` continues from it "
                              "(startFrom latestTime).")
        elif isinstance(e, Interrupted):
            err_console.print("[yellow]interrupted: the current state was NOT written; "
                              f"the latest complete time directory is {escape_(e.latest)}.")
        elif command == "run":
            err_console.print("[yellow]interrupted before the time loop started: no state was "
                              "written by this run (the state was NOT written).")
        else:
            err_console.print(f"[yellow]interrupted: {escape_(command)} stopped.")
        raise typer.Exit(EXIT_INTERRUPTED)
    if isinstance(e, MemoryError):
        _fail("out of memory", f"{command}: not enough memory (MemoryError); a coarser dx "
              "or fewer particles would fit", code=EXIT_OS)
    if isinstance(e, OSError):
        hint = ""
        if command == "run":
            hint = ("\nthe time directories written before are complete: `sphfoam run` "
                    "restarts from the latest (startFrom latestTime)")
        _fail("error", f"{type(e).__name__}: {_os_error_text(e)}{hint}", code=EXIT_OS)
    if isinstance(e, (ValueError, KeyError, LookupError, UnicodeError)):
        _fail("error", f"{type(e).__name__}: {e}")
    _fail("internal error", f"{command}: {type(e).__name__}: {e}\nthis is a bug in sphfoam; "
          "`sphfoam --debug ...` shows the traceback", code=EXIT_OS)


def escape_(text) -> str:
    from rich.markup import escape

    return escape(str(text))


def _guard(fn, *args, **kwargs):
    """Run ``fn``; turn user-facing errors into one screen, no traceback (unless --debug)."""
    try:
        return fn(*args, **kwargs)
    except BaseException as e:   # noqa: BLE001 -- every outcome gets its screen or exit code
        if isinstance(e, SystemExit):
            raise
        _handle(e, getattr(fn, "__name__", "sphfoam"))


def _guarded(fn):
    """A command whose every error (user, OS, Ctrl-C) becomes one screen and an exit code."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except BaseException as e:   # noqa: BLE001
            if isinstance(e, SystemExit):
                raise
            _handle(e, fn.__name__.replace("export_", "export "))

    return wrapper


def _case(path: Path):
    from sphfoam.case.case import Case

    if not path.is_dir():
        _fail("case error", f"{path}: not a case directory (expected constant/ and system/)")
    return Case(path)


def _threads(value: Optional[str]):
    """``-j N`` or ``-j auto``: overrides controlDict ``threads`` (None: use controlDict's)."""
    if value is None:
        return None
    if value.strip() == "auto":
        return "auto"
    try:
        n = int(value)
    except ValueError:
        n = 0
    if n < 1:
        raise typer.BadParameter(f"{value!r}: expected auto or a whole number of threads >= 1",
                                 param_hint="'-j' / '--threads'")
    return n


def _version(value: bool):
    if value:
        console.print(f"sphfoam {__version__}")
        raise typer.Exit()


@app.callback()
def main_callback(debug: bool = typer.Option(False, "--debug", help="show tracebacks"),
                  version: bool = typer.Option(False, "--version", callback=_version,
                                               is_eager=True, help="print the version")):
    _state["debug"] = debug


@app.command()
@_guarded
def run(case: Path = typer.Argument(Path("."), help="case directory"),
        threads: Optional[str] = typer.Option(
            None, "--threads", "-j", metavar="N|auto", callback=_threads,
            help="numba threads, or auto (overrides controlDict threads)"),
        end_time: Optional[float] = typer.Option(None, "--end-time",
                                                 help="stop here instead of endTime"),
        no_progress: bool = typer.Option(False, "--no-progress", help="no progress bar"),
        backend: Optional[str] = typer.Option(None, "--backend", metavar="cpu|cuda",
                                              help="overrides sphSchemes backend")):
    """Run CASE from its start time (setting up particles first if 0/ has none)."""
    from sphfoam.engine.health import BlowUp
    from sphfoam.timeloop import run_case

    c = _case(case)
    if backend is not None:
        if backend not in ("cpu", "cuda"):
            _fail("run", f"--backend {backend}: valid are cpu, cuda")
        object.__setattr__(c.schemes, "backend", backend)
    try:
        rep = run_case(c, progress=not no_progress and console.is_terminal, echo=_echo,
                       end_time=end_time, console=console, threads=threads)
    except BlowUp as e:
        if _state["debug"]:
            raise
        _fail("blow-up", _blow_up_text(e.diagnosis, c.path), code=EXIT_BLOWUP, markup=True)
    _say(f"[green]done[/]: {rep.steps} steps, {rep.particles} particles, run "
                  f"{rep.run_seconds:.1f} s + compile {rep.compile_seconds:.1f} s "
                  f"({'cached' if rep.cache_hit else 'cold'}); "
                  f"{rep.particle_steps_per_second:.3g} particle-steps/s")


def _say(msg: str) -> None:
    """One message line, never hard-wrapped (rich wraps at 80 columns when the output is not
    a terminal: CI logs and pipes would get lines cut in two)."""
    console.print(msg, soft_wrap=True)


def _echo(line: str) -> None:
    """A log line of a run, on the console the progress bar draws on (so it goes above the
    bar), taken literally (no rich markup in it), never hard-wrapped."""
    console.print(line, markup=False, soft_wrap=True)


def _blow_up_text(d, path: Path) -> str:
    """One screen: the diagnosis's own lines (what, when, where, which particles, the last
    good time directory), then where to look next."""
    from rich.markup import escape

    lines = d.lines()
    if d.last_good:
        lines.append(f"`sphfoam run` restarts from {path / d.last_good} (startFrom latestTime)")
    if d.file:
        lines.append(f"diagnosis: {d.file}")
    lines.append(f"log: {path / 'log.sphfoam'}")
    return escape("\n".join(lines))


@app.command()
@_guarded
def setup(case: Path = typer.Argument(Path("."), help="case directory"),
          force: bool = typer.Option(False, "--force", help="overwrite existing particles in 0/")):
    """Generate particles from system/particleDict into 0/ (hydrostatic, at rest).

    Also writes the one-cell constant/polyMesh and CASE.foam that ParaView's OpenFOAM reader opens.
    """
    from sphfoam.io.fields import has_particles
    from sphfoam.setup.settling import setup_case

    c = _case(case)
    if has_particles(c.path / "0") and not force:
        _fail("setup", f"{c.path / '0'} already holds particles; use --force to overwrite")
    setup_case(c, _echo)


@app.command()
@_guarded
def check(case: Path = typer.Argument(Path("."), help="case directory, or a study "
                                      "dictionary")):
    """Validate every dictionary of CASE (or one study dictionary) without running it.

    system/, constant/, system/metricsDict and the study dictionaries beside them, each study's runs included.
    """
    from sphfoam.check import check_case

    if case.is_file():
        import sphfoam.study as st

        s = st.load(case)
        console.print(f"{escape_(case.name)}: valid, {len(s.runs)} run(s) of base case "
                      f"{escape_(s.base)} in {escape_(s.root)}")
        return
    _case(case)
    rep = check_case(case)
    c = rep.case
    ctx = c.context
    t = Table(title=f"{escape_(c.name)}: valid", show_header=False)
    for fam, m in c.models.sph.items():
        t.add_row(fam, escape_(m.name),
                  escape_(dict(m.coeffs)) if type(m.coeffs).model_fields else "")
    t.add_row("integrator", escape_(c.models.integrator.name), "")
    for name, fo in c.models.functions.items():
        t.add_row("function", escape_(f"{name} ({fo.name})"), "")
    t.add_row("dx, h, c0", f"{ctx.dx:g} m, {ctx.h:g} m, {ctx.c0:.4g} m/s", "")
    t.add_row("time", f"0 .. {c.control.endTime:g} s, write every {c.control.writeInterval:g} "
              f"({c.control.writeControl})", "")
    for name, r in c.particles.fluid.items():
        if getattr(r, "grid", None) is not None:    # a rotated lattice (particles on a slope)
            t.add_row("fluid", escape_(f"{name} ({r.type})"),
                      escape_(f"grid at {r.grid.angle:g} deg from {tuple(r.grid.origin)}; "
                              f"seam minSpacing {c.particles.minSpacing:g} dx"))
    if c.control.settling is not None:
        t.add_row("settling", f"{c.control.settling.endTime:g} s before t = 0, walls still",
                  "layout kept as 0.unsettled/")
    if rep.metrics is not None:
        t.add_row("metricsDict", escape_(", ".join(rep.metrics.metrics)), "")
    for name, s in rep.studies.items():
        t.add_row("study", escape_(name), f"{len(s.runs)} run(s)")
    console.print(t)


@app.command()
@_guarded
def models(family: Optional[str] = typer.Argument(None, help="only this family")):
    """List the registered models (the words you may write after `type`)."""
    import sphfoam.registry as registry

    fams = registry.families()
    if family and family not in fams:
        from sphfoam.case.errors import did_you_mean

        _fail("models", f"unknown family '{family}'{did_you_mean(family, fams)} "
              f"families: {', '.join(fams)}")
    for fam, entries in fams.items():
        if family and fam != family:
            continue
        t = Table(title=f"{fam}: {registry.FAMILIES[fam]}", title_justify="left")
        t.add_column("type", style="bold")
        t.add_column("description")
        t.add_column("coefficients (default)")
        from sphfoam.docs import default_text, dimensions_of, dimensions_text

        dims = {name: dimensions_of(fam, cls) for name, cls in entries.items()}
        if any(d is not None for d in dims.values()):
            t.add_column("cases")
        for name, cls in entries.items():
            coeffs = ", ".join(f"{k} ({default_text(f, code=str)})"
                               for k, f in cls.Coeffs.model_fields.items())
            extra = [dimensions_text(dims[name])] if len(t.columns) > 3 else []
            t.add_row(name, cls.doc, coeffs, *extra)
        if not entries:
            t.add_row("-", "(none registered yet)", "")
        console.print(t)


@app.command()
@_guarded
def sample(case: Path = typer.Argument(Path("."), help="case directory"),
           func: Optional[list[str]] = typer.Option(None, "--func", "-f",
                                                    help="only this function object")):
    """Evaluate function objects of system/controlDict on the written time directories."""
    from sphfoam.postprocess import sample as do_sample

    c = _case(case)
    do_sample(c.path, func, log=_echo)


@app.command()
@_guarded
def plot(case: Path = typer.Argument(Path("."), help="case directory"),
         theory: str = typer.Option("mcCowan", "--theory", help="wave theory to compare with "
                                    "(sphfoam models waveTheory)"),
         func: Optional[list[str]] = typer.Option(None, "--func", "-f",
                                                  help="only this function object"),
         height: Optional[float] = typer.Option(None, help="wave height H (default: from "
                                                "the Goring paddle or constant/waveProperties)"),
         depth: Optional[float] = typer.Option(None, help="still water depth d")):
    """PNG of every function object against its reference (theory or experiment)."""
    import sphfoam.registry as registry
    from sphfoam.postprocess import plot_case

    c = _case(case)
    if theory not in registry.names("waveTheory"):
        _fail("bad option", f"--theory: {str(registry.UnknownModel('waveTheory', theory, registry.names('waveTheory')))}")
    _guard(plot_case, c.path, func, theory, height, depth, log=_say)


@app.command()
@_guarded
def render(case: Path = typer.Argument(Path("."), help="case directory"),
           field: str = typer.Option("U", "--field", "-f", help="colour by this field: U "
                                     "(|U|), Ux, Uy (Uz in 3-D), p, rho or any scalar "
                                     "field written"),
           time: Optional[list[float]] = typer.Option(None, "--time", "-t",
                                                      help="only these times"),
           movie: Literal["auto", "gif", "mp4", "none"] = typer.Option(
               "auto", "--movie", help="auto: mp4 when ffmpeg is on the PATH, else gif"),
           fps: float = typer.Option(5.0, "--fps", min=0.1, help="movie frames per second"),
           width: int = typer.Option(1000, "--width", min=200, help="frame width in pixels"),
           value_range: Optional[tuple[float, float]] = typer.Option(
               None, "--range", help="colour range LO HI (default: min..max over all frames)"),
           box: Optional[tuple[float, float, float, float]] = typer.Option(
               None, "--box", help="show only X0 Y0 X1 Y1 (m); 3-D: of the slice, in its "
               "plane's two axes"),
           slice_at: Optional[str] = typer.Option(
               None, "--slice", help="3-D: the slice's plane AXIS=VALUE, e.g. y=0.2 "
               "(default: y through the middle)"),
           slab: Optional[float] = typer.Option(
               None, "--slab", help="3-D: the slice's thickness (m; default dx)")):
    """PNG frames of the particles coloured by a field (3-D: a view and a slice), and a GIF."""
    from sphfoam.render import render_case

    c = _case(case)
    _guard(render_case, c.path, field, time, movie=movie, fps=fps, width=width,
           value_range=value_range, box=box, slice_at=slice_at, slab=slab, log=_say)


@app.command()
@_guarded
def study(studydict: Path = typer.Argument(..., help="study dictionary"),
          jobs: Optional[int] = typer.Option(None, "--jobs", "-n",
                                             help="runs at once (default: the dictionary's jobs)"),
          scheduler: Optional[str] = typer.Option(None, "--scheduler",
                                                  help="Dask scheduler address (tcp://host:8786)"),
          only: Optional[list[str]] = typer.Option(None, "--only", help="only this variant, or this one run (variant_dxDX)"),
          rerun: bool = typer.Option(False, "--rerun", help="rerun runs that have a result"),
          dry_run: bool = typer.Option(False, "--dry-run",
                                       help="list the runs and their overrides; run nothing"),
          collect_only: bool = typer.Option(False, "--collect",
                                            help="only rebuild the tables and plot")):
    """Run a study: variants x resolutions of a base case, in parallel, with tables and a plot.

    Writes study.csv, study.md (runtime relative to the baseline, as T Table 4.3), pareto.png.
    """
    import sphfoam.study as st

    s = st.load(studydict, only)
    if dry_run:
        t = Table(title=f"{studydict.name}: {len(s.runs)} run(s) in {s.root}")
        for c in ("run", "dx", "overrides"):
            t.add_column(c)
        for r in st.dump(s):
            t.add_row(escape_(r["name"]), "" if r["dx"] is None else f"{r['dx']:g}",
                      escape_("; ".join(f"{k} {v}" for k, v in r["edits"].items())))
        console.print(t)
        return
    if collect_only:
        rows = st.collect(s)
    else:
        rows = st.run_study(s, jobs=jobs, scheduler=scheduler, rerun=rerun, log=_echo)
    console.print(escape_((s.root / "study.md").read_text()) if rows else "no results yet")


def _metrics_or_hint(mset, path, keep_going):
    """The metrics; a metric that cannot be evaluated stops them with a hint at -k."""
    from sphfoam.case.errors import CaseError, Problem

    try:
        return mset.evaluate(path, strict=not keep_going)
    except CaseError as e:
        raise CaseError([*e.problems, Problem(
            "sphfoam metrics --keep-going", "", "shows the other metrics, these as NaN")])


@app.command()
@_guarded
def metrics(case: Path = typer.Argument(Path("."), help="case directory"),
            keep_going: bool = typer.Option(False, "--keep-going", "-k",
                                            help="show a metric that cannot be evaluated as "
                                            "NaN instead of stopping"),
            as_json: bool = typer.Option(False, "--json",
                                         help="print the metrics as JSON (NaN as null) "
                                         "instead of a table")):
    """Error metrics of system/metricsDict for the finished run in CASE."""
    import math

    from sphfoam.case.metrics_dict import load_metrics

    c = _case(case)
    mset = _guard(load_metrics, c.path)
    values = _guard(_metrics_or_hint, mset, c.path, keep_going)
    if as_json:
        import json

        def finite(v):
            return None if v is None or not math.isfinite(v) else float(v)

        doc = {"case": str(c.path), "pareto": mset.pareto,
               "metrics": {name: {"type": mset.metrics[name].name, "value": finite(mv.value),
                                  "reference": finite(mv.reference),
                                  "error_percent": finite(mv.error), "unit": mv.unit,
                                  "problem": mv.problem}
                           for name, mv in values.items()}}
        typer.echo(json.dumps(doc, indent=2))
        return

    def num(v, fmt):
        return "-" if v is None else ("nan" if not math.isfinite(v) else format(v, fmt))

    t = Table(title=f"{c.name}: metrics (system/metricsDict)", title_justify="left")
    for col in ("metric", "type", "value", "reference", "error %", "unit"):
        t.add_column(col, justify="right" if col in ("value", "reference", "error %")
                     else "left")
    for name, mv in values.items():
        label = f"{name} (pareto)" if name == mset.pareto else name
        t.add_row(escape_(label), escape_(mset.metrics[name].name), num(mv.value, ".6g"),
                  num(mv.reference, ".6g"), num(mv.error, "+.3f"), escape_(mv.unit))
    console.print(t)
    for name, mv in values.items():
        if mv.problem:
            err_console.print(f"[yellow]{escape_(name)}[/]: {escape_(mv.problem)}")


@export_app.command("vtk")
@_guarded
def export_vtk(case: Path = typer.Argument(Path("."), help="case directory"),
               time: Optional[list[float]] = typer.Option(None, "--time", "-t",
                                                          help="only these times")):
    """Write VTK/<case>.pvd for ParaView: per time a <case>_<t>.vtm of fluid and walls.

    Replaces the previous export (times not selected with -t are removed); fails when there is nothing to export.
    """
    from sphfoam.io.vtk import export_case

    c = _case(case)
    pvd = _guard(export_case, c.path, times=time)
    _say(f"wrote {escape_(pvd)}")


@export_app.command("foam")
@_guarded
def export_foam(case: Path = typer.Argument(Path("."), help="case directory")):
    """Make CASE open in ParaView's OpenFOAM reader: write CASE.foam and the one-cell mesh.

    Time directories of earlier sphfoam versions are rewritten in the cloud layout (values unchanged).
    """
    from sphfoam.api import prepare_case

    c = _case(case)
    foam, upgraded = _guard(prepare_case, c.path)
    if upgraded:
        _say(f"rewrote {len(upgraded)} time director{'y' if len(upgraded) == 1 else 'ies'}"
             f" in the OpenFOAM cloud layout: {escape_(', '.join(upgraded))}")
    _say(escape_(f"wrote {foam} and {c.path / 'constant' / 'polyMesh'}: paraview {foam}"))


def main():
    app()


if __name__ == "__main__":
    main()
