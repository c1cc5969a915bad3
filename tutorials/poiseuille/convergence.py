#!/usr/bin/env python
"""Convergence of steady Poiseuille flow with the particle spacing, T Tables 3.1-3.2.

Runs this tutorial at several resolutions N = l/dx ("particles across" as T Table 3.1 counts
them: N - 1 fluid rows, the first wall row on each wall line), takes the steady centreline
velocity u_max from the ``velocityProfile`` function object, and for every three resolutions
in the ratio 2 (N, 2N, 4N) the observed order p of T(3.49), the Richardson extrapolation
phi_0 = phi_s + (phi_s - phi_2s)/(2^p - 1) of T(3.51) (the continuum solution), the particle
spacing convergence index PSCI = 1.25 |eps|/(2^p - 1) of T(3.53)-(3.54) for the fine and the
coarse pair, and the asymptotic-range check PSCI_coarse / (2^p PSCI_fine) ~ 1 of T(3.55).

    python convergence.py                      # N = 10, 20, 40 (a minute or two)
    python convergence.py --fine               # also 80 and 160 (the thesis' range; long)
    python convergence.py --particles 20 40 80 --end-time 120

Writes ``postProcessing/convergence/convergence.{md,csv}``, ``richardson.csv`` and
``convergence.png`` (the error in u_max against dx, T Fig 3.11); the runs themselves are kept
in ``postProcessing/convergence/N<N>/``. The case dictionaries are this tutorial's: only the
particle layout (system/particleDict), the end time and the sampling change per resolution.

``python convergence.py --uniform-start CASE [--velocity U]`` (used by the Allrun of this
tutorial and of turbulentChannel) rewrites the particles that
``sphfoam setup`` put in ``CASE/0`` at uniform density rho0 and mass rho0 dx^2: the set-up
makes the initial pressure hydrostatic along y with |g| even when g, as here, is the body
force along the channel, which with c0 = 1e-3 m/s is a 6.5 % density variation (and makes
the steady u_max 5.7 % too high instead of 2.2 %). ``--velocity U`` also sets the fluid moving.
"""

from __future__ import annotations

import argparse
import csv
import math
import shutil
import sys
import time
from pathlib import Path

import numpy as np

import sphfoam
from sphfoam.case import foamdict
from sphfoam.case.case import Case
from sphfoam.reference import channel_theory as ct
from sphfoam.setup.channel import channel_width as _width
from sphfoam.setup.channel import profile_function, uniform_start  # noqa: F401 (re-exported)

HERE = Path(__file__).resolve().parent
#: channel width of T section 3.4.1 (m)
WIDTH = 0.01
#: periodic length of the channel in particle spacings (>= 3 neighbour cells of 1.05 x 2.5 h)
COLUMNS = 14
#: the safety factor of the PSCI, Roache (1998), T(3.53)
SAFETY = 1.25


# --- cases -------------------------------------------------------------------------------------
def particle_dict(n: int, width: float = WIDTH, columns: int = COLUMNS) -> dict:
    """system/particleDict of the channel with N = width/dx: fluid rows at y = dx .. (N-1) dx,
    the first of 3 wall rows on each wall line, periodic in x over ``columns`` dx."""
    dx = width / n
    length = columns * dx
    lo, hi = 0.5 * dx, width - 0.5 * dx
    return {
        "dx": dx,
        "fluid": {"channel": {"type": "box", "min": [0, lo], "max": [length, hi]}},
        "walls": {
            "bottom": {"type": "polyline", "points": [[0, lo], [length, lo]], "side": "right",
                       "layers": 3},
            "top": {"type": "polyline", "points": [[0, hi], [length, hi]], "side": "left",
                    "layers": 3},
        },
        "domain": {"min": [0, -4 * dx], "max": [length, width + 4 * dx], "periodic": ["x"]},
    }


def _edit(path: Path, edit) -> None:
    d = foamdict.read(path)
    header = d.pop("FoamFile", None)
    edit(d)
    foamdict.write(path, d, header=header)


def prepare(dst: Path, n: int, end_time: float, times=(), template: Path = HERE,
            plot: bool = False) -> Path:
    """A copy of a channel tutorial's constant/ and system/ (this one by default; the couette
    tutorial has the same layout) at resolution N, writing only the end time. The walls keep
    the template's velocities."""
    if dst.exists():
        shutil.rmtree(dst)
    dst.mkdir(parents=True)
    for sub in ("constant", "system"):
        shutil.copytree(template / sub, dst / sub)
    pd_path = dst / "system" / "particleDict"
    old = foamdict.read(pd_path)
    new = particle_dict(n, width=_width(template))
    for name, wall in new["walls"].items():
        if "velocity" in old.get("walls", {}).get(name, {}):
            wall["velocity"] = old["walls"][name]["velocity"]
    foamdict.write(pd_path, new, header=old.get("FoamFile"))
    name = profile_function(dst)

    def control(d):
        d["endTime"] = float(end_time)
        d["writeInterval"] = float(end_time)
        d["functions"] = {name: {**d["functions"][name], "times": [float(t) for t in times],
                                 "plot": "yes" if plot else "no"}}

    _edit(dst / "system" / "controlDict", control)
    return dst


def read_profile_summary(case: Path) -> np.ndarray:
    """Rows (time, uCentre, uCentreTheory, centreError%, ...) of the function object's uMax.dat."""
    name = profile_function(case)
    files = sorted((case / "postProcessing" / name).glob("*/uMax.dat"))
    if not files:
        raise FileNotFoundError(f"{case}: no postProcessing/{name}/*/uMax.dat")
    return np.atleast_2d(np.loadtxt(files[-1]))


def run_resolution(case: Path, start: str = "rest", threads: int | None = 1) -> dict:
    """Set up (uniform density), run, and return the final centreline velocity of a case
    against the steady Poiseuille u_max (and the rows of its uMax.dat)."""
    import numba

    old = numba.get_num_threads()
    if threads:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        c = Case(case)
        sphfoam.setup_case(c)
        vel = None
        width = _width(Path(case))
        F, nu = c.gravity[0], c.transport.nu
        if start == "theory":
            vel = lambda y: ct.poiseuille_steady(y, F, nu, width)   # noqa: E731
        uniform_start(case, vel)
        t0 = time.perf_counter()
        rep = sphfoam.run(case)
        wall = time.perf_counter() - t0
    finally:
        numba.set_num_threads(old)
    rows = read_profile_summary(case)
    steady = ct.poiseuille_umax(F, nu, width) if F else float("nan")
    u = float(rows[-1][1])
    return {"dx": c.context.dx, "u_max": u, "theory": steady,
            "error": 100.0 * (u / steady - 1.0), "time": float(rows[-1][0]),
            "steps": rep.steps, "particles": rep.particles, "seconds": wall, "rows": rows}


# --- Richardson extrapolation, T(3.47)-(3.55) -------------------------------------------------
def richardson(phi_s: float, phi_2s: float, phi_4s: float, ratio: float = 2.0) -> dict:
    """Order, continuum solution, PSCI and asymptotic-range check from three solutions whose
    spacings are s, 2s, 4s (T(3.49)-(3.55))."""
    num, den = phi_2s - phi_4s, phi_s - phi_2s
    p = math.log(num / den) / math.log(ratio) if num * den > 0 else float("nan")
    rp = ratio ** p - 1.0
    phi0 = phi_s + (phi_s - phi_2s) / rp
    psci_fine = SAFETY * abs((phi_2s - phi_s) / phi_s) / rp
    psci_coarse = SAFETY * abs((phi_4s - phi_2s) / phi_2s) / rp
    return {"p": p, "phi0": phi0, "psci_fine": psci_fine, "psci_coarse": psci_coarse,
            "asymptotic": psci_coarse / (ratio ** p * psci_fine)}


def triples(ns: list[int]) -> list[tuple[int, int, int]]:
    """(N, 2N, 4N) among the resolutions, coarsest first."""
    s = set(ns)
    return [(n, 2 * n, 4 * n) for n in sorted(ns) if 2 * n in s and 4 * n in s]


# --- the study ----------------------------------------------------------------------------------
def study(ns: list[int], end_time: float, start: str, threads: int, out: Path,
          echo=print) -> tuple[list[dict], list[dict]]:
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for n in sorted(ns):
        case = prepare(out / f"N{n}", n, end_time)
        r = run_resolution(case, start, threads)
        r["N"] = n
        results.append(r)
        echo(f"N = {n:4d}: dx = {r['dx']:.4g} m, u_max = {r['u_max']:.6g} m/s, error "
             f"{r['error']:+.3f} % ({r['particles']} particles, {r['steps']} steps, "
             f"{r['seconds']:.1f} s)")
    by_n = {r["N"]: r for r in results}
    rich = []
    for n1, n2, n4 in triples(ns):
        # n4 is the finest: phi_s
        rr = richardson(by_n[n4]["u_max"], by_n[n2]["u_max"], by_n[n1]["u_max"])
        rr["set"] = (n4, n2, n1)
        rr["theory"] = by_n[n4]["theory"]
        rich.append(rr)
    write_outputs(results, rich, end_time, start, out)
    return results, rich


def write_outputs(results, rich, end_time, start, out: Path) -> None:
    with (out / "convergence.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["particles_across", "dx_m", "u_max_m_per_s", "u_max_theory_m_per_s",
                    "error_percent", "particles", "steps", "run_seconds"])
        for r in results:
            w.writerow([r["N"], f"{r['dx']:.6g}", f"{r['u_max']:.8g}", f"{r['theory']:.8g}",
                        f"{r['error']:.4f}", r["particles"], r["steps"], f"{r['seconds']:.1f}"])
    with (out / "richardson.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["particles", "order_p", "continuum_m_per_s", "continuum_error_percent",
                    "psci_fine_percent", "psci_coarse_percent", "asymptotic_check"])
        for r in rich:
            w.writerow([" ".join(map(str, r["set"])), f"{r['p']:.4f}", f"{r['phi0']:.6g}",
                        f"{100 * (r['phi0'] / r['theory'] - 1):.3f}",
                        f"{100 * r['psci_fine']:.3f}", f"{100 * r['psci_coarse']:.3f}",
                        f"{r['asymptotic']:.4f}"])
    lines = ["# Steady Poiseuille flow: convergence with the particle spacing", "",
             f"sphfoam, this tutorial's dictionaries; steady state at t = {end_time:g} s "
             f"(started {'from rest' if start == 'rest' else 'from the steady profile T(3.40)'});"
             " u_max = centreline velocity of the `velocityProfile` function object; theory "
             "u_max = F l^2/(8 nu), T(3.41).", "",
             "## Maximum velocity (T Table 3.1)", "",
             "| particles across | dx (m) | u_max (m/s) | error | thesis error |",
             "|---|---|---|---|---|"]
    thesis = {20: 3.14, 40: 2.16, 60: 1.84, 80: 1.68, 100: 1.58, 120: 1.52, 140: 1.47,
              160: 1.44}
    for r in results:
        th = f"{thesis[r['N']]:.2f} %" if r["N"] in thesis else ""
        lines.append(f"| {r['N']} | {r['dx']:.3e} | {r['u_max']:.5e} | {r['error']:+.2f} % | "
                     f"{th} |")
    lines += ["", "## Richardson extrapolation (T Table 3.2)", ""]
    if rich:
        lines += ["| particles | order p | continuum u_max (m/s) | vs theory | PSCI fine | "
                  "PSCI coarse | asymptotic check |", "|---|---|---|---|---|---|---|"]
        for r in rich:
            lines.append(f"| {', '.join(map(str, r['set']))} | {r['p']:.2f} | {r['phi0']:.4e} | "
                         f"{100 * (r['phi0'] / r['theory'] - 1):+.2f} % | "
                         f"{100 * r['psci_fine']:.2f} % | {100 * r['psci_coarse']:.2f} % | "
                         f"{r['asymptotic']:.3f} |")
        lines += ["", "Thesis: (80, 40, 20) p = 1.00, continuum 1.012e-4 m/s, PSCI 0.59 % / "
                  "1.18 %, check 0.995; (160, 80, 40) p = 1.02, 1.012e-4, 0.29 % / 0.58 %, "
                  "0.998."]
    else:
        lines.append("(needs three resolutions in the ratio 2, e.g. 10 20 40)")
    (out / "convergence.md").write_text("\n".join(lines) + "\n")
    try:
        plot(results, rich, out)
    except Exception as exc:          # the tables matter more than the figure
        print(f"convergence.png not written: {exc}", file=sys.stderr)


def plot(results, rich, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dx = np.array([r["dx"] for r in results])
    err = np.array([r["u_max"] / r["theory"] - 1.0 for r in results])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(dx, 100 * err, "o-", label="sphfoam")
    thesis = np.array([[5.00e-4, 3.14], [2.50e-4, 2.16], [1.67e-4, 1.84], [1.25e-4, 1.68],
                       [1.00e-4, 1.58], [8.33e-5, 1.52], [7.14e-5, 1.47], [6.25e-5, 1.44]])
    ax.plot(thesis[:, 0], thesis[:, 1], "k^", label="thesis, T Table 3.1")
    for r in rich:
        ax.plot([0.0], [100 * (r["phi0"] / r["theory"] - 1.0)], "s",
                label=f"continuum ({', '.join(map(str, r['set']))}), p = {r['p']:.2f}")
    ax.set(xlabel="dx (m)", ylabel="error in u_max (%)", xlim=(0, None),
           title="steady Poiseuille flow (T Fig 3.11)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "convergence.png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--particles", type=int, nargs="+", default=[10, 20, 40],
                    help="resolutions N = l/dx (default: 10 20 40)")
    ap.add_argument("--fine", action="store_true", help="also N = 80 and 160 (long)")
    ap.add_argument("--end-time", type=float, default=120.0,
                    help="steady state is taken at this time (s; default 120, as the thesis)")
    ap.add_argument("--start", choices=["rest", "theory"], default="rest",
                    help="start from rest (default) or from the steady profile T(3.40), "
                         "which reaches the steady state sooner")
    ap.add_argument("--threads", type=int, default=1, help="numba threads (default 1)")
    ap.add_argument("--output", type=Path, default=HERE / "postProcessing" / "convergence")
    ap.add_argument("--uniform-start", type=Path, metavar="CASE",
                    help="only rewrite CASE/0 at uniform density and mass, then stop")
    ap.add_argument("--velocity", type=float, default=None,
                    help="with --uniform-start: also set the fluid's u_x to this (m/s)")
    a = ap.parse_args(argv)
    if a.uniform_start is not None:
        uniform_start(a.uniform_start, a.velocity)
        print(f"{a.uniform_start / '0'}: uniform density rho0 and mass rho0 dx^2"
              + (f", u_x = {a.velocity:g} m/s" if a.velocity is not None else ""))
        return 0
    ns = sorted(set(a.particles + ([80, 160] if a.fine else [])))
    _, rich = study(ns, a.end_time, a.start, a.threads, a.output)
    print((a.output / "convergence.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
