"""The particles' packing against their volumes in still water (issue 35, the flume's drift).

Clones the flume tutorial (``tutorials/solitaryWave``, its models as shipped) into a still
tank: the same depth d = 0.5 m, ``--length`` m long, walls on the bed and both ends, no
paddle, no function objects, at ``--dx``; runs it to ``--end`` on one thread and reports at
every written time

* **fraction**: the bulk's fluid fraction sum_b V_b W(x - x_b), V_b = m_b / rho_b, at a grid
  of points 0.1-0.35 m above the bed and 0.15 L-0.85 L along (1 where the particles take up
  the room their volumes say; above 1 where they pack closer);
* **level**: the water's height by its volumes, sum V_b / L, and by its particles, the mean
  over the middle columns (dx wide) of the highest particle + dx/2;
* **u_rms**: the fluid's rms speed (the stirring of still water);
* **drho/dz**: the bulk density's slope (0.1-0.4 m) against the Tait equation's hydrostatic
  one at the same density, T(3.27) differentiated: rho0 g / (c0^2 (rho/rho0)^(gamma-1)).

With ``--budget``, at each written time, the two rates that move the bulk's
fraction apart from its volumes (the flow moves both the kernel sums and the densities
through the continuity equation, so it does not):

* **shift**: the rate at which the shift alone changes the kernel sums rho*_a = sum_b m_b W_ab,
  d ln rho*_a / dt with every fluid particle moved along its delta_u (a finite difference of
  the sums; the continuity equation does not see it);
* **plain**: the same for the shift without its anti-clumping term (R = 0 on the same
  state; the anti-clumping term's part is shift - plain);
* **filter**: the density filter's rate D_a / rho_a (the rates with the case's delta-SPH
  filter minus the rates with its strength delta c0 set to 0, on the written state; 0 for
  a periodic filter or none);
* **budget**: shift - filter, the rate of ln(fraction) they make, to compare with the
  fraction's own change between written times (printed at the end for the second half).
  Single states are noisy (the still water is stirred at a few cm/s): average over many
  (``--write 0.05``).

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/packing.py --dx 0.0125
    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/packing.py --dx 0.0125 \\
        --edit "constant/sphProperties:particleShifting={'type': 'none'}"
    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/packing.py --dx 0.0125 --end 4 \\
        --write 0.05 --budget
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from breathing import parse_edits  # noqa: E402  (a sibling script's --edit parsing)

ROOT = Path(__file__).resolve().parents[1]
DEPTH = 0.5


def still_tank(dx, length, end, write, edits=None, keep=None):
    """Clone the flume tutorial into the still tank; return its folder."""
    import sphfoam

    e = {"system/particleDict:dx": dx,
         "system/particleDict:fluid": {"water": {"type": "box", "min": [0, 0],
                                                 "max": [length, DEPTH]}},
         "system/particleDict:walls": {"tank": {"type": "box", "min": [0, 0],
                                                "max": [length, 1.6 * DEPTH], "layers": 3,
                                                "open": ["top"]}},
         "system/controlDict:endTime": end, "system/controlDict:writeInterval": write,
         "system/controlDict:functions": {}}
    e.update(edits or {})
    dst = Path(keep) if keep else Path(tempfile.mkdtemp(prefix="packing-")) / "stillTank"
    # the flume's metrics read its gauges, which the still tank does not have
    case = sphfoam.clone_case(ROOT / "tutorials" / "solitaryWave", dst, e)
    (Path(dst) / "system" / "metricsDict").unlink(missing_ok=True)
    return case, dst


def measure_time(case, dst, t, length):
    """The row of one written time (see the module docstring)."""
    from scipy.spatial import cKDTree

    from sphfoam import api

    kern, ctx = case.models.sph["kernel"], case.context
    h, dx = ctx.h, ctx.dx
    reach = float(kern.support) * h
    s = api.read_time(dst, t)
    f = s["type"] == 0
    x, rho = s["positions"][f], s["rho"][f]
    V = s["mass"][f] / rho
    tree = cKDTree(x)
    frac = []
    for px in np.linspace(0.15 * length, 0.85 * length, 15):
        for py in np.linspace(0.1, 0.35, 6):
            idx = tree.query_ball_point((px, py), reach)
            r = np.linalg.norm(x[idx] - (px, py), axis=1)
            frac.append(float((V[idx] * kern.W(r, h)).sum()))
    cols = np.floor(x[:, 0] / dx).astype(int)
    mid = [c for c in np.unique(cols) if 3 <= c < round(length / dx) - 3]
    top = np.array([x[cols == c, 1].max() for c in mid]) + 0.5 * dx
    u = s["U"][f]
    bulk = (x[:, 1] > 0.1) & (x[:, 1] < 0.4) & (x[:, 0] > 0.1 * length) & (x[:, 0] < 0.9 * length)
    slope, icpt = np.polyfit(x[bulk, 1], rho[bulk], 1)
    eos = case.models.sph["equationOfState"]
    gamma = float(getattr(eos.coeffs, "gamma", 1.0))
    r = (slope * 0.25 + icpt) / ctx.rho0
    hydro = -ctx.rho0 * abs(ctx.g[-1]) / (ctx.c0 ** 2 * r ** (gamma - 1.0))
    return {"t": t, "fraction": round(float(np.mean(frac)), 5),
            "level_volume": round(float(V.sum() / length), 5),
            "level_particles": round(float(top.mean()), 5),
            "u_rms": round(float(np.sqrt((u ** 2).sum(axis=1).mean())), 5),
            "drho_dz_ratio": round(float(slope / hydro), 4)}


def bulk_of(x, length):
    """The fluid particles of the bulk the fraction is read in."""
    return ((x[:, 0] > 0.15 * length) & (x[:, 0] < 0.85 * length)
            & (x[:, 1] > 0.1) & (x[:, 1] < 0.35))


def kernel_sums(kern, h, x, w, rows):
    """sum_b w_b W(x_a - x_b) for the particles ``rows`` (all particles as neighbours)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(x)
    pairs = tree.sparse_distance_matrix(tree, float(kern.support) * h, output_type="coo_matrix")
    # the self pair is kept (its distance, 0, is stored explicitly)
    val = w[pairs.col] * kern.W(pairs.data, h)
    return np.bincount(pairs.row, val, minlength=len(x))[rows]


def budget_time(case, dst, t, length):
    """The shift's and the density filter's rates in the bulk at one written time
    (see the module docstring)."""
    from sphfoam import api
    from sphfoam.assemble import build_simulation
    from sphfoam.engine.state import ParticleState

    sim = build_simulation(case, ParticleState.from_fields(api.read_time(dst, t)))
    sim.neighbour_update()
    sim.step_pass()
    sim.eos()
    sim.rates()
    st = sim.state
    fluid = st.kind == 0
    x = np.column_stack([st.x, st.y])
    bulk = bulk_of(x[fluid], length)
    idx = sim.pipeline.aux_index
    kern, h = case.models.sph["kernel"], case.context.h
    ln0 = np.log(kernel_sums(kern, h, x, st.m, fluid))
    eps = 1e-4                                   # s: the shifts move by 0.1 mm/(m/s)

    def shift_rate():
        du = np.where(fluid, sim.aux[idx("shift_du")], 0.0)
        dv = np.where(fluid, sim.aux[idx("shift_dv")], 0.0)
        ln1 = np.log(kernel_sums(kern, h, x + eps * np.column_stack([du, dv]), st.m, fluid))
        return float(((ln1 - ln0) / eps)[bulk].mean())

    names = list(sim.pipeline.module.PARAMS)

    def without(params):
        """The rates again with the parameters ``params`` set to 0 (then restored)."""
        keep = {k: sim.prm[names.index(k)] for k in params}
        for k in params:
            sim.prm[names.index(k)] = 0.0
        sim.rates()
        for k, v in keep.items():
            sim.prm[names.index(k)] = v

    shift, full = shift_rate(), st.drho.copy()
    # the delta-SPH filters' strength delta c0 is one parameter: the rates without it
    filt = 0.0
    if "filt_dc0" in names:
        without(["filt_dc0"])
        filt = float(((full - st.drho) / st.rho)[fluid][bulk].mean())
    # the shift without its anti-clumping term (R and surfaceR 0): its plain part
    without([k for k in ("shift_r", "shift_rs") if k in names])
    plain = shift_rate()
    return {"shift_rate": shift, "plain_rate": plain, "filter_rate": filt,
            "budget_rate": shift - filt}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dx", type=float, default=0.0125, help="d/dx = 0.5/dx (0.0125: 40)")
    ap.add_argument("--length", type=float, default=1.0)
    ap.add_argument("--end", type=float, default=5.0)
    ap.add_argument("--write", type=float, default=1.0)
    ap.add_argument("--edit", action="append", default=[], metavar="FILE:KEY=VALUE")
    ap.add_argument("--keep", default=None, help="run in this folder and keep it")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--budget", action="store_true",
                    help="also the shift's and the filter's rates of the fraction (1/s)")
    a = ap.parse_args(argv)
    import sphfoam

    edits = parse_edits(a.edit)
    case, dst = still_tank(a.dx, a.length, a.end, a.write, edits, a.keep)
    sphfoam.run(case)
    times = np.arange(0.0, a.end + 1e-9, a.write)
    rows = [measure_time(case, dst, float(round(t, 9)), a.length) for t in times]
    if a.budget:
        if case.models.sph["particleShifting"].name == "none":
            ap.error("--budget reads the shift's delta_u: the case selects no particleShifting")
        for r in rows:
            r.update(budget_time(case, dst, r["t"], a.length))
    if a.json:
        print(json.dumps({"dx": a.dx, "length": a.length, "edits": edits, "rows": rows}))
    else:
        print(f"still tank {a.length} m x {DEPTH} m, dx {a.dx} (d/dx {DEPTH / a.dx:g}), "
              f"edits {edits or 'none'}: {dst}")
        print(f"{'t':>5} {'fraction':>9} {'level V':>8} {'level p':>8} {'u_rms':>7} "
              f"{'drho/dz':>8}" + (f" {'shift':>10} {'plain':>10} {'filter':>10} {'budget':>10}"
                                   if a.budget else ""))
        for r in rows:
            print(f"{r['t']:5.2f} {r['fraction']:9.4f} {r['level_volume']:8.4f} "
                  f"{r['level_particles']:8.4f} {r['u_rms']:7.4f} {r['drho_dz_ratio']:8.4f}"
                  + (f" {r['shift_rate']:10.2e} {r['plain_rate']:10.2e} {r['filter_rate']:10.2e} "
                     f"{r['budget_rate']:10.2e}" if a.budget else ""))
        if a.budget and len(rows) > 2:
            later = rows[len(rows) // 2:]
            span = later[-1]["t"] - later[0]["t"]
            seen = np.log(later[-1]["fraction"] / later[0]["fraction"]) / span
            mean = {k: np.mean([r[k] for r in later])
                    for k in ("shift_rate", "plain_rate", "filter_rate", "budget_rate")}
            print(f"second half ({later[0]['t']:g}-{later[-1]['t']:g} s, {len(later)} times), "
                  f"1/s: shift {mean['shift_rate']:.2e} (plain {mean['plain_rate']:.2e}, "
                  f"anti-clumping {mean['shift_rate'] - mean['plain_rate']:.2e}), filter "
                  f"{mean['filter_rate']:.2e}, budget {mean['budget_rate']:.2e}; observed "
                  f"d ln(fraction)/dt {seen:.2e}")
    return rows


if __name__ == "__main__":
    sys.exit(main() and 0)
