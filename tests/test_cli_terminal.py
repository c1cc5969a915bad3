"""The terminal: flags shown as flags, one-sentence command summaries, shell completion, no
hard wrap when piped, and a progress bar that shares rich's console with the log lines and
ends at 100 %."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys

import pytest
from rich.console import Console
from typer.testing import CliRunner

from sphfoam.cli import app

runner = CliRunner()
COMMANDS = [c.name or c.callback.__name__ for c in app.registered_commands]


@pytest.mark.parametrize("command", COMMANDS + ["export vtk", ""])
def test_help_shows_flags_without_a_value_type(command):
    r = runner.invoke(app, [*command.split(), "--help"], prog_name="sphfoam")
    assert r.exit_code == 0, r.output
    assert "<bool>" not in r.output
    assert "--help" in r.output


def test_boolean_options_are_flags():
    out = runner.invoke(app, ["run", "--help"]).output
    assert re.search(r"--no-progress\s{2,}no progress bar", out)
    out = runner.invoke(app, ["setup", "--help"]).output
    assert re.search(r"--force\s{2,}overwrite", out)


def test_every_command_summary_is_one_sentence():
    """The first paragraph of each command's docstring (typer's summary in `sphfoam --help`)
    is one line ending with a full stop, so the list never breaks mid-sentence."""
    for c in app.registered_commands:
        first, *rest = c.callback.__doc__.strip().split("\n\n")
        assert "\n" not in first and first.endswith("."), (c.callback.__name__, first)
        assert len(first) <= 100, first
        # typer keeps the line breaks of later paragraphs: one line each
        assert all("\n" not in p.strip() for p in rest), (c.callback.__name__, rest)
    out = runner.invoke(app, ["--help"]).output
    assert "Run a study: variants x resolutions of a base case, in parallel," in out


def _main(env_extra: dict, *args) -> subprocess.CompletedProcess:
    env = {**os.environ, **env_extra}
    code = "import sys; sys.argv[0] = 'sphfoam'; from sphfoam.cli import main; main()"
    return subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True,
                          text=True, timeout=120)


def test_shell_completion(monkeypatch):
    """``--show-completion`` is a flag: the shell is detected from the parent processes,
    which a run in the background (no shell above it) does not have, so the test says it."""
    import typer.completion

    monkeypatch.setattr(typer.completion, "_get_shell_name", lambda: "bash")
    r = runner.invoke(app, ["--show-completion"], prog_name="sphfoam")
    assert r.exit_code == 0 and "complete -o default -F _sphfoam_completion sphfoam" in \
        r.output, (r.output, repr(r.exception))
    assert "--install-completion" in runner.invoke(app, ["--help"]).output
    r = _main({"_SPHFOAM_COMPLETE": "complete_bash", "COMP_WORDS": "sphfoam ren",
               "COMP_CWORD": "1"})
    assert r.stdout.split() == ["render"], r.stderr
    r = _main({"_SPHFOAM_COMPLETE": "complete_bash", "COMP_WORDS": "sphfoam setup --fo",
               "COMP_CWORD": "2"})
    assert r.stdout.split() == ["--force"], r.stderr


def test_piped_output_is_not_wrapped_at_80_columns(tutorial):
    case = tutorial("damBreak", {"system/particleDict:dx": 0.05})
    r = _main({"COLUMNS": "80"}, "setup", str(case))             # stdout is a pipe
    assert r.returncode == 0, r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("setup:"))
    assert len(line) > 80 and line.endswith(f"written to {case / '0'}")


ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def test_progress_bar_and_log_lines_share_the_console_and_end_at_100(tutorial):
    """A terminal console (forced): every log line comes out on a line of its own, never
    after bar characters, and the last frame of the bar reads 100%."""
    from sphfoam.timeloop import run_case

    case = tutorial("damBreak", {"system/particleDict:dx": 0.05,
                                 "system/controlDict:endTime": 0.02,
                                 "system/controlDict:writeInterval": 0.01,
                                 "system/controlDict:functions": {}})
    buf = io.StringIO()
    con = Console(file=buf, force_terminal=True, width=150, color_system=None)
    run_case(case, progress=True, echo=lambda m: con.print(m, markup=False), console=con)
    text = ANSI.sub("", buf.getvalue()).replace("\r", "\n")
    lines = [ln for ln in text.split("\n") if ln.strip()]
    logged = (case / "log.sphfoam").read_text().splitlines()
    for msg in logged:
        assert any(ln.startswith(msg[:60]) for ln in lines), msg      # not glued to the bar
    bars = [ln for ln in lines if "━" in ln]
    assert bars and "100%" in bars[-1], bars[-1:]
    assert not any("━" in ln and "written" in ln for ln in lines)
