#!/usr/bin/env python
"""Speed versus accuracy of the registered models: steady Poiseuille flow at 20 particles across.

Base case: ``tutorials/poiseuille`` (quartic kernel hdx 1.3, Tait, differenceForm continuity,
symmetric momentum, laminar viscosity, stationaryGhosts, monaghan2007, no density filter,
velocity/kernel correction or turbulence model), re-laid at N = l/dx = 20 with
``tutorials/poiseuille/convergence.py``'s ``prepare`` and started at uniform density
(``uniform_start``), as the tutorial's Allrun does. Each variant changes one model
(``sphProperties`` or, for the integrator, ``sphSchemes``).

Per variant: the error of the centreline u_max against the start-up series T(3.42) at
t = 5 s (start-up), t = 30 s and the end time (default 120 s as the thesis; the start-up
decays as exp(-t/10 s) at 20 across, so t = 30 s is ~5 % of the transient left),
run seconds, steps, particle-steps/s, compile seconds (reported separately; the pipeline cache
lives in SPHFOAM_CACHE_DIR), and run seconds relative to the base. Every variant runs in its own
subprocess with a wall-clock limit; failures (exception, blow-up, time-out) are recorded as text.

    NUMBA_NUM_THREADS=1 python benchmarks/model_costs.py [--end-time 120] [--only base kernel ...]

Writes ``benchmarks/results/model-costs.{md,csv}`` and prints the table.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
TUTORIAL = REPO / "tutorials" / "poiseuille"
RESULTS = HERE / "results"
N_ACROSS = 20
T_STARTUP = 5.0
T_MID = 30.0
ALPHAS = (1.0, 3.0, 5.5, 10.0, 20.0, 40.0)      # artificial
ALPHAS_IMPROVED = (1.0, 3.0, 5.5, 10.0)

# (family, label, [(rel file, key, value), ...]) -- one change from the base each
def variants() -> list[tuple[str, str, list]]:
    sp, ss = "constant/sphProperties", "system/sphSchemes"
    v = [("base", "base (quartic, laminar, monaghan2007)", [])]
    for a in ALPHAS:
        v.append(("viscosity", f"artificial alpha={a:g}",
                  [(sp, "viscosity", {"type": "artificial", "alpha": a})]))
    for a in ALPHAS_IMPROVED:
        v.append(("viscosity", f"improvedArtificial alpha={a:g}",
                  [(sp, "viscosity", {"type": "improvedArtificial", "alpha": a})]))
    for k in ("cubicSpline", "quintic", "wendlandC2", "gaussian"):
        v.append(("kernel", k, [(sp, "kernel", {"type": k, "hdx": 1.3})]))
    # support 3h: the base's periodic length of 12 dx is < 3 neighbour cells; 13 dx is not
    for k in ("quintic", "gaussian"):
        v.append(("kernel", f"{k} (periodic length 13 dx)",
                  [(sp, "kernel", {"type": k, "hdx": 1.3}), ("columns", None, 13)]))
    v.append(("continuity", "densityWeighted", [(sp, "continuity", {"type": "densityWeighted"})]))
    v.append(("momentum", "colagrossiLandrini",
              [(sp, "momentum", {"type": "colagrossiLandrini"})]))
    for f in ("shepard", "mlsReinitialisation", "deltaSPH"):
        v.append(("densityFilter", f, [(sp, "densityFilter", {"type": f})]))
    v.append(("velocityCorrection", "xsph", [(sp, "velocityCorrection", {"type": "xsph"})]))
    v.append(("kernelCorrection", "cspH", [(sp, "kernelCorrection", {"type": "cspH"})]))
    for i in ("predictorCorrector", "verlet", "symplectic"):
        v.append(("integrator", i, [(ss, "integrator", {"type": i})]))
    v.append(("turbulence", "smagorinskySPS", [(sp, "turbulence", {"type": "smagorinskySPS"})]))
    return v


FAMILY_ORDER = ["base", "viscosity", "kernel", "continuity", "momentum", "densityFilter",
                "velocityCorrection", "kernelCorrection", "integrator", "turbulence"]


# --- one variant (runs in a subprocess) ---------------------------------------------------
def run_one(spec: dict) -> dict:
    sys.path.insert(0, str(TUTORIAL))
    import numpy as np

    import convergence as cv                      # tutorials/poiseuille/convergence.py
    from sphfoam.case import foamdict
    from sphfoam.case.case import Case
    from sphfoam.setup import setup_case
    from sphfoam.timeloop import run_case

    case = Path(spec["case"])
    end = float(spec["end_time"])
    cv.prepare(case, N_ACROSS, end, times=[T_STARTUP, T_MID])
    for rel, key, value in spec["edits"]:
        if rel == "columns":                      # re-lay the channel with another length
            pd_path = case / "system" / "particleDict"
            old = foamdict.read(pd_path)
            foamdict.write(pd_path, cv.particle_dict(N_ACROSS, width=cv.WIDTH, columns=value),
                           header=old.get("FoamFile"))
            continue
        path = case / rel
        d = foamdict.read(path)
        header = d.pop("FoamFile", None)
        d[key] = value
        foamdict.write(path, d, header=header)
    c = Case(case)
    setup_case(c, log=lambda *_: None)
    cv.uniform_start(case)
    t0 = time.perf_counter()
    rep = run_case(case, progress=False, echo=None)
    wall = time.perf_counter() - t0
    rows = cv.read_profile_summary(case)

    def err_at(t):
        i = int(np.argmin(np.abs(rows[:, 0] - t)))
        return float(rows[i, 0]), float(rows[i, 3])

    t5, e5 = err_at(T_STARTUP)
    t30, e30 = err_at(T_MID)
    tend, eend = float(rows[-1, 0]), float(rows[-1, 3])
    ok = all(math.isfinite(x) for x in (e5, eend))
    return {"t_startup": t5, "err_startup": e5, "err_30": e30, "t_end": tend, "err_end": eend,
            "u_end": float(rows[-1, 1]), "steps": rep.steps, "particles": rep.particles,
            "run_seconds": rep.run_seconds, "wall_seconds": wall,
            "psps": rep.particle_steps_per_second, "compile_seconds": rep.compile_seconds,
            "cache_hit": bool(rep.cache_hit), "end_reached": rep.end_time,
            "error": None if ok else "non-finite u_max (blow-up)"}


def run_variant(family, label, edits, end_time, workdir: Path, timeout: float) -> dict:
    case = workdir / (family + "_" + "".join(ch if ch.isalnum() else "_" for ch in label))
    spec = {"case": str(case), "end_time": end_time, "edits": edits}
    env = dict(os.environ, NUMBA_NUM_THREADS=os.environ.get("NUMBA_NUM_THREADS", "1"))
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, __file__, "--one", json.dumps(spec)],
                           capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"error": f"timed out after {timeout:.0f} s"}
    res = None
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            res = json.loads(line[7:])
    if res is None:
        tail = (p.stderr or p.stdout).strip().splitlines()
        msg = next((ln for ln in reversed(tail) if ln.strip()), f"exit {p.returncode}")
        res = {"error": msg.strip()[:200]}
    res["total_seconds"] = time.perf_counter() - t0
    return res


# --- table ------------------------------------------------------------------------------------
def fmt(x, spec):
    return "" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def write_outputs(rows: list[dict], end_time: float, out: Path) -> str:
    out.mkdir(parents=True, exist_ok=True)
    base = next((r for r in rows if r["family"] == "base" and not r.get("error")), None)
    base_s = base["run_seconds"] if base else None
    rows = sorted(rows, key=lambda r: (FAMILY_ORDER.index(r["family"]), r["order"]))
    cols = ["family", "variant", "err_5s_percent", "err_30s_percent", "err_end_percent", "t_end_s", "run_seconds",
            "steps", "particle_steps_per_s", "compile_seconds", "cache_hit", "runtime_vs_base",
            "failure"]
    with (out / "model-costs.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            e = r.get("error")
            rel = r["run_seconds"] / base_s if base_s and "run_seconds" in r else None
            w.writerow([r["family"], r["variant"], fmt(r.get("err_startup"), ".4f"), fmt(r.get("err_30"), ".4f"),
                        fmt(r.get("err_end"), ".4f"), fmt(r.get("t_end"), ".4g"),
                        fmt(r.get("run_seconds"), ".3f"), r.get("steps", ""),
                        fmt(r.get("psps"), ".0f"), fmt(r.get("compile_seconds"), ".2f"),
                        r.get("cache_hit", ""), fmt(rel, ".3f"), e or ""])
    particles = next((r["particles"] for r in rows if "particles" in r), "?")
    lines = ["# Model costs: speed versus accuracy, Poiseuille flow at 20 particles across", "",
             f"`tutorials/poiseuille` re-laid at l/dx = {N_ACROSS} ({particles} particles incl. "
             f"walls, periodic 12 dx unless noted), started from rest at uniform density, run to t = "
             f"{end_time:g} s; one model changed per row from the base (quartic hdx 1.3, "
             "laminar viscosity, differenceForm, symmetric, monaghan2007, no filter/correction/"
             "turbulence). Error = centreline u_max of the `velocityProfile` function object "
             "against T(3.42) at that time, in %. Single thread "
             f"(NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', '?')}); run seconds "
             "exclude compilation; compile seconds separately (cache hit = loaded from "
             "SPHFOAM_CACHE_DIR). Runtime vs base = run seconds / base run seconds.", "",
             "| family | variant | err t=5 s | err t=30 s | err end | t end (s) | run s | steps | "
             "particle-steps/s | compile s | runtime vs base |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.get("error") and "run_seconds" not in r:
            lines.append(f"| {r['family']} | {r['variant']} | FAILED: {r['error']} "
                         "| | | | | | | | |")
            continue
        rel = r["run_seconds"] / base_s if base_s else float("nan")
        e5 = f"{r['err_startup']:+.2f} %" if math.isfinite(r["err_startup"]) else "nan"
        e30 = f"{r['err_30']:+.2f} %" if math.isfinite(r["err_30"]) else "nan"
        ee = f"{r['err_end']:+.2f} %" if math.isfinite(r["err_end"]) else "nan"
        if r.get("error"):
            ee += f" ({r['error']})"
        comp = f"{r['compile_seconds']:.1f}" + (" (cached)" if r["cache_hit"] else "")
        lines.append(f"| {r['family']} | {r['variant']} | {e5} | {e30} | {ee} | {r['t_end']:g} | "
                     f"{r['run_seconds']:.2f} | {r['steps']} | {r['psps']:.3g} | {comp} | "
                     f"{rel:.2f} |")
    art = [r for r in rows if r["family"] == "viscosity" and "err_end" in r
           and math.isfinite(r["err_end"])]
    if art:
        for kind in ("artificial", "improvedArtificial"):
            sub = [r for r in art if r["variant"].startswith(kind + " ")]
            if sub:
                b = min(sub, key=lambda r: abs(r["err_end"]))
                lines.append("")
                lines.append(f"Best {kind}: {b['variant']} (end error {b['err_end']:+.2f} %).")
    text = "\n".join(lines) + "\n"
    (out / "model-costs.md").write_text(text)
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--end-time", type=float, default=120.0,
                    help="end time (s; default 120, as the thesis; 20 across is steady by ~60 s)")
    ap.add_argument("--timeout", type=float, default=240.0,
                    help="wall-clock limit per variant (s; default 120)")
    ap.add_argument("--only", nargs="+", help="families to run (base always runs)")
    ap.add_argument("--output", type=Path, default=RESULTS)
    a = ap.parse_args(argv)
    if a.one:
        print("RESULT " + json.dumps(run_one(json.loads(a.one))), flush=True)
        return 0
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    rows = []
    with tempfile.TemporaryDirectory(prefix="model_costs_") as tmp:
        for order, (family, label, edits) in enumerate(variants()):
            if a.only and family != "base" and family not in a.only:
                continue
            r = run_variant(family, label, edits, a.end_time, Path(tmp), a.timeout)
            r.update(family=family, variant=label, order=order)
            rows.append(r)
            if "run_seconds" in r:
                print(f"{family:18s} {label:32s} err5 {r['err_startup']:+7.2f} %  end "
                      f"{r['err_end']:+7.2f} %  run {r['run_seconds']:6.2f} s  "
                      f"{r['steps']:5d} steps  compile {r['compile_seconds']:5.1f} s"
                      + (f"  [{r['error']}]" if r.get("error") else ""), flush=True)
            else:
                print(f"{family:18s} {label:32s} FAILED: {r['error']}", flush=True)
            write_outputs(rows, a.end_time, a.output)
    print()
    print(write_outputs(rows, a.end_time, a.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
