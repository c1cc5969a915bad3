"""Helpers of the channel tutorials (poiseuille, couette, turbulentChannel) that a copied case
needs wherever it is: its ``velocityProfile`` function object, its width, and the uniform
start that replaces the set-up's hydrostatic one (T §3.4.1).

The set-up makes the initial pressure hydrostatic along y with |g| even when g, as in these
channels, is the body force along the channel; :func:`uniform_start` rewrites ``CASE/0`` at
uniform density rho0 and mass rho0 dx^2 instead, optionally moving.
"""

from __future__ import annotations

from pathlib import Path

from sphfoam.case import foamdict
from sphfoam.case.case import Case
from sphfoam.io.fields import read_state, write_state


def profile_function(case: Path) -> str:
    """Name of the ``velocityProfile`` function object of a case's controlDict."""
    path = Path(case) / "system" / "controlDict"
    funcs = foamdict.read(path).get("functions", {}) or {}
    for name, spec in funcs.items():
        if isinstance(spec, dict) and spec.get("type") == "velocityProfile":
            return name
    raise SystemExit(f"{path}: no velocityProfile function object under 'functions'")


def channel_width(case: Path) -> float:
    """Channel width l of the case's velocityProfile function object (its key ``l``)."""
    funcs = foamdict.read(Path(case) / "system" / "controlDict").get("functions", {}) or {}
    return float(funcs[profile_function(case)]["l"])


def uniform_start(case: Path, velocity=None) -> None:
    """Rewrite ``case/0`` at rho = rho0, mass = rho0 dx^2, p = 0 (and u_x = velocity(y) of the
    fluid particles if given: a callable of y, or a number)."""
    c = Case(case)
    folder = Path(case) / "0"
    s = read_state(folder)
    rho0, dx = c.context.rho0, c.context.dx
    s["rho"][:] = rho0
    s["mass"][:] = rho0 * dx * dx
    if "p" in s:
        s["p"][:] = 0.0
    if velocity is not None:
        fluid = s["type"] == 0
        y = s["positions"][fluid, 1]
        s["U"][fluid, 0] = velocity(y) if callable(velocity) else float(velocity)
    write_state(folder, s, fmt=c.control.writeFormat, precision=c.control.writePrecision)
