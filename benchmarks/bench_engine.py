#!/usr/bin/env python
"""Engine benchmark: compile time and run throughput of the generated SPH pipeline.

Case: 2-D dam break, a water column of width = height H in a tank 4 H long and 2 H high,
walled by 3 layers of stationary-ghost particles (as in the engine's smoke test), h = 1.3 dx,
Wendland C2, Tait, differenceForm continuity, symmetric momentum, artificial viscosity
(alpha 0.1), monaghan2007 integrator, adjustTimeStep with beta 0.2.

For every size N (total particles, dx chosen to hit N) and thread count it measures

* throughput over >= ``--seconds`` of stepping after ``--warmup`` steps:
  particle-steps/s, particle-force-evaluations/s (and per thread), pair interactions/s;
* where the time of a step goes (neighbour_update, eos, rates, time_step, density_rate,
  integrator updates, Python remainder), from an instrumented pass;
* neighbour statistics counted outside the timed region (pairs within the support, pairs
  the 3 x 3-cell loop has to test, wall-wall pairs);

and, once, the compile time of the pipeline: cold (fresh SPHFOAM_CACHE_DIR and
NUMBA_CACHE_DIR, in a subprocess) and cached (a second subprocess on the same directories).

Results: ``benchmarks/results/engine-<date>[-tag].json`` and
``benchmarks/results/engine-latest[-tag].md``. ``--quick`` = 10k particles, 1 s, tag "quick".
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent

# --- case -------------------------------------------------------------------------------
H = 1.0             # water column height = width (m)
TANK_LENGTH = 4.0   # tank length / H
TANK_HEIGHT = 2.0   # wall height / H
LAYERS = 3          # rows of wall particles
HDX = 1.3
RHO0 = 1000.0
G = 9.81
BETA = 0.2
MODELS = [
    ("kernel", {"type": "wendlandC2"}),
    ("equationOfState", {"type": "tait"}),
    ("continuity", {"type": "differenceForm"}),
    ("momentum", {"type": "symmetric"}),
    ("viscosity", {"type": "artificial", "alpha": 0.1}),
    ("boundary", {"type": "stationaryGhosts"}),
]
INTEGRATOR = {"type": "monaghan2007"}


def count_for(n: int) -> int:
    """Total particles for a column of n x n fluid particles."""
    nl = int(round(TANK_LENGTH * n))
    nh = int(round(TANK_HEIGHT * n))
    walls = (nl + 2 * LAYERS) * (nh + LAYERS) - nl * nh
    return n * n + walls


def n_for(total: int) -> int:
    """Fluid particles per column side whose total particle count is closest to ``total``."""
    best = 2
    for n in range(2, 5000):
        if abs(count_for(n) - total) < abs(count_for(best) - total):
            best = n
        if count_for(n) > total:
            break
    return best


def dam_break(total: int):
    """Positions, kinds and spacing of the dam break with about ``total`` particles."""
    import numpy as np

    n = n_for(total)
    dx = H / n
    nl = int(round(TANK_LENGTH * n))
    nh = int(round(TANK_HEIGHT * n))
    i = np.arange(n)
    X, Y = np.meshgrid((i + 0.5) * dx, (i + 0.5) * dx)
    xf, yf = X.ravel(), Y.ravel()
    iw = np.arange(-LAYERS, nl + LAYERS)
    jw = np.arange(-LAYERS, nh)
    IW, JW = np.meshgrid(iw, jw)
    IW, JW = IW.ravel(), JW.ravel()
    keep = ~((IW >= 0) & (IW < nl) & (JW >= 0))
    xw, yw = (IW[keep] + 0.5) * dx, (JW[keep] + 0.5) * dx
    x = np.r_[xf, xw]
    y = np.r_[yf, yw]
    kind = np.r_[np.zeros(len(xf), np.int64), np.ones(len(xw), np.int64)]
    return x, y, kind, dx, n


def build_selection():
    from sphfoam import registry
    from sphfoam.engine.plan import Selection

    return Selection(*(registry.build(f, s) for f, s in MODELS), adjust_time_step=True)


def make_context(dx):
    from sphfoam.models.base import CaseContext

    return CaseContext(dx=dx, h=HDX * dx, rho0=RHO0, nu=1e-6, g=(0.0, -G), fluid_height=H)


def build(dx):
    from sphfoam.engine.build import build_pipeline

    sel = build_selection()
    ctx = make_context(dx)
    return sel, ctx, build_pipeline(sel, ctx)


#: the cases ``--case`` runs through the case machinery (setup, assemble.build_simulation)
CASE_DIRS = {
    # the dam break matched with DualSPHysics 5.4 (issue 12): benchmarks/cases/damBreakMatched
    "matched": HERE / "cases" / "damBreakMatched",
    # the thesis flume (Goring paddle, quartic kernel, stationary ghosts, T ch. 4)
    "flume": REPO / "tutorials" / "solitaryWave",
    # P's wall case (finite Gaussian, XSPH, MLS every 20 steps, mirrored walls) with T's
    # monaghan2007 (the tutorial's integrator to the eleventh session: CASE_EDITS)
    "wall": REPO / "tutorials" / "solitaryWallRunup",
    # the same with XSPH's velocity once per step (velocityCorrection evaluation oncePerStep)
    "wallOnce": REPO / "tutorials" / "solitaryWallRunup",
    # the wall case with P's own time integration, the predictor-corrector P(37)-(38), for
    # monaghan2007 (two evaluations a step, no density-only pass): the tutorial as it is
    "wallPC": REPO / "tutorials" / "solitaryWallRunup",
    # wallPC with XSPH's velocity once per step, from the step's first state (the issue's
    # "XSPH's velocity computed once per step where the integrator allows it")
    "wallPCOnce": REPO / "tutorials" / "solitaryWallRunup",
    # the flume with issue 13's low-dissipation set-up (studyDict.lowDissipation's
    # fourtakasShift: Fourtakas's delta-SPH and delta+ shifting in place of Shepard)
    "flumeLowDiss": REPO / "tutorials" / "solitaryWave",
    # P's kernel and walls alone (finite Gaussian R = 4 dx, mirrored walls; no XSPH, no MLS):
    # what P's neighbour count costs before any of P's corrections (the floor of "wall")
    "wallBare": REPO / "tutorials" / "solitaryWallRunup",
    # flumeLowDiss with the shift's velocity correction (particleShifting correctVelocity)
    "flumeLowDissCv": REPO / "tutorials" / "solitaryWave",
    # flumeLowDiss with the anti-clumping term only near the free surface (R 0, surfaceR 0.2)
    "flumeLowDissRs": REPO / "tutorials" / "solitaryWave",
    # P's wall case with the flume's low-dissipation combination (studyDict.lowDissipation's
    # fourtakasQRs: quartic kernel, Fourtakas's delta-SPH, delta+ shifting R 0 / surfaceR 0.2,
    # no XSPH, no MLS, the hydrostatic mirrored bed)
    "wallLowDiss": REPO / "tutorials" / "solitaryWallRunup",
}
#: the thesis's optimum flume (Shepard every 40 steps, no shifting, Goring's paddle), which the
#: flume tutorial was until issue 35's best default: "flume" and the cases derived from it
THESIS_FLUME = {
    "constant/sphProperties:densityFilter": {"type": "shepard", "every": 40},
    "constant/sphProperties:particleShifting": {"type": "none"},
    "system/particleDict:walls.paddle.motion.waveMaker": {
        "type": "goring", "height": 0.15, "depth": 0.5, "extended": False},
}
#: dictionary edits of a --case beyond the size (``clone_case`` syntax)
CASE_EDITS = {
    "flume": THESIS_FLUME,
    # the tutorial integrates with P's predictor-corrector since the twelfth session; "wall"
    # and the cases derived from it keep T's monaghan2007, as every figure measured before
    "wall": {
        "system/sphSchemes:integrator": {"type": "monaghan2007"},
    },
    "wallOnce": {
        "system/sphSchemes:integrator": {"type": "monaghan2007"},
        "constant/sphProperties:velocityCorrection": {"type": "xsph", "epsilon": 0.5,
                                                      "evaluation": "oncePerStep"},
    },
    "wallPC": {
        "system/sphSchemes:integrator": {"type": "predictorCorrector"},
    },
    "wallPCOnce": {
        "system/sphSchemes:integrator": {"type": "predictorCorrector"},
        "constant/sphProperties:velocityCorrection": {"type": "xsph", "epsilon": 0.5,
                                                      "evaluation": "oncePerStep"},
    },
    "flumeLowDiss": {
        **THESIS_FLUME,
        "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH", "delta": 0.1,
                                                 "gamma": 7},
        "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting", "Ma": 0.1},
    },
    "flumeLowDissCv": {
        **THESIS_FLUME,
        "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH", "delta": 0.1,
                                                 "gamma": 7},
        "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting", "Ma": 0.1,
                                                    "correctVelocity": True},
    },
    "flumeLowDissRs": {
        **THESIS_FLUME,
        "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH", "delta": 0.1,
                                                 "gamma": 7},
        "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting", "Ma": 0.1,
                                                    "R": 0.0, "surfaceR": 0.2},
    },
    "wallLowDiss": {
        "system/sphSchemes:integrator": {"type": "monaghan2007"},
        "constant/sphProperties:kernel": {"type": "quartic", "hdx": 1.3},
        "constant/sphProperties:velocityCorrection": {"type": "none"},
        "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH", "delta": 0.1,
                                                 "gamma": 7},
        "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting", "Ma": 0.1,
                                                    "R": 0.0, "surfaceR": 0.2},
        "constant/sphProperties:boundary": {"type": "mirrorGhosts", "noSlip": False,
                                            "pressure": "hydrostatic"},
    },
    "wallBare": {
        "system/sphSchemes:integrator": {"type": "monaghan2007"},
        "constant/sphProperties:velocityCorrection": {"type": "none"},
        "constant/sphProperties:densityFilter": {"type": "none"},
    },
}
#: which case ``make_sim`` builds ("engine": the synthetic dam break above, no case directory)
CASE = "engine"
#: sphSchemes precision of the --case runs (--precision)
PRECISION = "double"

#: peers measured on this machine kind (issue 12): one thread, user CPU, start-up cancelled,
#: the matched dam break (23 018 particles)
REFERENCE = [
    ("DualSPHysics 5.4 CPU (generic build)", "Verlet", 2.88e6, 50e6),
    ("DualSPHysics 5.4 CPU (-march=native)", "Verlet", 3.33e6, 58e6),
    ("PySPH 1.0b2", "PEC", 1.49e6, 26e6),
    ("sphfoam before issue 12", "verlet", 2.15e6, 37e6),
    ("sphfoam before issue 12", "symplectic", 1.15e6, 40e6),
]


def _rss_bytes() -> int:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


_case_size_cache: dict = {}


def _case_size(src: Path) -> tuple[int, int, float]:
    """(particles, fluid particles, dx) of a case at its own resolution (set up once in a
    scratch folder)."""
    if src not in _case_size_cache:
        from sphfoam.case.case import Case
        from sphfoam.case.edit import clone_case
        from sphfoam.setup import setup_case

        with tempfile.TemporaryDirectory(prefix="sphfoam-bench-size-") as tmp:
            d = clone_case(src, Path(tmp) / src.name)
            case = Case(d)
            st = setup_case(case, log=lambda *_: None)
            _case_size_cache[src] = (int(st.n), int(st.n_fluid), float(case.particles.dx))
    return _case_size_cache[src]


def dx_for(total: int, n0: int, n_fluid0: int, dx0: float) -> float:
    """dx giving about ``total`` particles: the fluid count scales as 1/dx^2, the wall rows
    (a fixed number of layers along the walls) as 1/dx, so solve
    F dx0^2 / dx^2 + W dx0 / dx = total for 1/dx."""
    import math as _m

    a = n_fluid0 * dx0 * dx0
    b = (n0 - n_fluid0) * dx0
    if a <= 0.0:
        return dx0 * n0 / total
    z = (-b + _m.sqrt(b * b + 4.0 * a * total)) / (2.0 * a)
    return 1.0 / z


def state_bytes(sim) -> dict:
    """Bytes held per particle by the simulation's arrays (state, extra fields, neighbour
    list, aux, particle fields, cell starts): nbytes of each, divided by the particle count
    (the resident-memory growth of the first configuration includes the compiler)."""
    import numpy as np

    st = sim.state
    parts = {}
    from sphfoam.engine.state import PERSISTENT_F8, PERSISTENT_I8, SCRATCH

    parts["state"] = sum(getattr(st, k).nbytes for k in PERSISTENT_F8 + PERSISTENT_I8 + SCRATCH)
    parts["extra"] = sum(a.nbytes for a in st.extra.values())
    start, idx = sim._nb
    parts["neighbour list"] = (start.nbytes if start is not None else 0) + \
        (idx.nbytes if idx is not None else 0)
    parts["aux"] = sim.aux.nbytes
    pc = getattr(sim, "_pc", None)
    parts["pair cache"] = pc.nbytes if pc is not None else 0
    parts["fields"] = sim._fld.nbytes if isinstance(sim._fld, np.ndarray) else 0
    parts["cells"] = sim.cells.cell_start.nbytes
    ref = getattr(sim, "_ref", None)
    parts["list reference"] = sum(a.nbytes for a in ref) if ref is not None else 0
    n = max(st.n, 1)
    out = {k: v / n for k, v in parts.items()}
    out["total"] = sum(parts.values()) / n
    return out


def make_case_sim(name: str, total: int):
    """The simulation of a case directory (``CASE_DIRS``) at the dx that gives about
    ``total`` particles, set up hydrostatic and built as ``sphfoam run`` builds it, without
    function objects or writes."""
    import math as _m

    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.case.edit import clone_case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    src = CASE_DIRS[name]
    n0, nf0, dx0 = _case_size(src)
    dx = dx_for(total, n0, nf0, dx0)
    tmp = Path(tempfile.mkdtemp(prefix="sphfoam-bench-case-"))
    edits = {"system/particleDict:dx": dx, "system/controlDict:functions": {},
             **CASE_EDITS.get(name, {})}
    if PRECISION != "double":
        edits["system/sphSchemes:precision"] = PRECISION
    d = clone_case(src, tmp / src.name, edits)
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    state = ParticleState.from_fields(read_state(d / "0"))
    rss0 = _rss_bytes()
    sim = build_simulation(case, state)
    sim.step()
    st = sim.state
    mem = (_rss_bytes() - rss0) / max(st.n, 1)
    arrays = state_bytes(sim)
    return sim, dict(case=name, dx=dx, h=sim.h, n=int(st.n), n_fluid=int(st.n_fluid),
                     n_wall=int(st.n - st.n_fluid), cells=(sim.cells.ncx, sim.cells.ncy),
                     bytes_per_particle=arrays["total"], array_bytes_per_particle=arrays,
                     rss_bytes_per_particle=mem, precision=PRECISION,
                     models=sim.pipeline.selection.describe(),
                     integrator=sim.integrator.name)


def make_sim(total: int):
    """A fresh Simulation with about ``total`` particles: the case of ``--case`` or the
    synthetic dam break (the pipeline module is generated and compiled once per process;
    only its coefficient vector depends on dx)."""
    if CASE != "engine":
        return make_case_sim(CASE, total)
    return make_engine_sim(total)


def make_engine_sim(total: int):
    """The synthetic dam break with about ``total`` particles."""
    import numpy as np
    from sphfoam import registry
    from sphfoam.engine.simulation import Simulation
    from sphfoam.engine.state import ParticleState

    x, y, kind, dx, n = dam_break(total)
    sel, _, pipe = build(dx)
    ctx = make_context(dx)
    eos = sel.equationOfState
    p = RHO0 * G * np.maximum(H - y, 0.0)
    rho = eos.density(p, ctx)
    st = ParticleState(x, y, 0 * x, 0 * x, rho, rho * dx * dx, kind)
    h = HDX * dx
    pad = 2 * sel.kernel.support * h
    lo = (-LAYERS * dx - pad, -LAYERS * dx - pad)
    hi = (TANK_LENGTH * H + LAYERS * dx + pad, 1.25 * TANK_HEIGHT * H + pad)
    integ = registry.build("integrator", dict(INTEGRATOR))
    sim = Simulation(st, pipe, integ, domain_lo=lo,
                     domain_hi=hi, beta=BETA, force_condition=True, adjust_time_step=True,
                     delta_t=1e-4)
    return sim, dict(dx=dx, h=h, n_side=n, n=int(st.n), n_fluid=int(st.n_fluid),
                     n_wall=int(st.n - st.n_fluid), cells=(sim.cells.ncx, sim.cells.ncy))


# --- neighbour statistics (outside every timed region) -----------------------------------
_count_pairs = None


def _pair_counter():
    global _count_pairs
    if _count_pairs is None:
        from numba import njit, prange

        @njit(parallel=True, cache=False)
        def count_pairs(x, y, kind, cell_start, x0, y0, inv_cell, ncx, ncy, support2,
                        nb, cand, nb_wall):
            """Per particle: neighbours within the support (b != a, r2 < support2, exactly
            the pairs the gather loops evaluate), candidates tested in the 3 x 3 cells, and
            neighbours that are wall particles."""
            for a in prange(x.shape[0]):
                xa = x[a]
                ya = y[a]
                ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
                iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
                k = 0
                t = 0
                w = 0
                for cy in range(max(iy - 1, 0), min(iy + 2, ncy)):
                    for cx in range(max(ix - 1, 0), min(ix + 2, ncx)):
                        cc = cy * ncx + cx
                        for b in range(cell_start[cc], cell_start[cc + 1]):
                            t += 1
                            dxx = xa - x[b]
                            dyy = ya - y[b]
                            if dxx * dxx + dyy * dyy < support2 and b != a:
                                k += 1
                                if kind[b] != 0:
                                    w += 1
                nb[a] = k
                cand[a] = t
                nb_wall[a] = w

        _count_pairs = count_pairs
    return _count_pairs


def pipe_support2(sim) -> float:
    return sim.pipeline.support_radius ** 2


def neighbour_stats(sim, check_kdtree=False):
    import numpy as np

    sim.neighbour_update()      # sort for the current positions (what the next step does)
    st, cl = sim.state, sim.cells
    n = st.n
    nb = np.zeros(n, np.int64)
    cand = np.zeros(n, np.int64)
    nbw = np.zeros(n, np.int64)
    support2 = pipe_support2(sim)
    _pair_counter()(st.x, st.y, st.kind, cl.cell_start, cl.x0, cl.y0, 1.0 / cl.cell_size,
                    cl.ncx, cl.ncy, support2, nb, cand, nbw)
    fluid = st.kind == 0
    out = dict(
        pairs=int(nb.sum()),                          # ordered pairs a != b within support
        pairs_fluid_a=int(nb[fluid].sum()),
        pairs_wall_a=int(nb[~fluid].sum()),
        pairs_wall_wall=int(nbw[~fluid].sum()),       # contribute exactly 0 (u_ab = 0)
        candidates=int(cand.sum()),                   # distance tests in the 3 x 3 cells
        mean_neighbours=float(nb.mean()),
        mean_neighbours_fluid=float(nb[fluid].mean()) if fluid.any() else 0.0,
        max_neighbours=int(nb.max()),
    )
    if check_kdtree:
        from scipy.spatial import cKDTree

        pts = np.column_stack([st.x, st.y])
        tree = cKDTree(pts)
        r = math.sqrt(support2) * (1.0 - 1e-12)
        out["pairs_kdtree"] = int(tree.count_neighbors(tree, r)) - n
    return out


# --- machine contention probes -----------------------------------------------------------
def cpu_busy(interval=0.5):
    """Fraction of all CPUs busy (any process) over ``interval`` s, from /proc/stat."""
    def read():
        with open("/proc/stat") as f:
            v = [int(t) for t in f.readline().split()[1:]]
        idle = v[3] + (v[4] if len(v) > 4 else 0)
        return sum(v), idle
    try:
        t0, i0 = read()
        time.sleep(interval)
        t1, i1 = read()
    except OSError:
        return float("nan")
    return 1.0 - (i1 - i0) / max(t1 - t0, 1)


def wait_idle(max_wait, threshold=0.15):
    """Wait (up to ``max_wait`` s) until the machine is idle; return the busy fraction."""
    t_end = time.perf_counter() + max_wait
    busy = cpu_busy()
    while busy > threshold and time.perf_counter() < t_end:
        busy = cpu_busy(1.0)
    return busy


_probe_fn = None


def parallel_launch_us(threads, calls=200):
    """Median wall time of an almost empty numba prange region at ``threads`` threads: the
    fixed cost every parallel stage pays (large when another process holds a core)."""
    global _probe_fn
    import numba
    import numpy as np

    if _probe_fn is None:
        @numba.njit(parallel=True, cache=False)
        def probe(a):
            for i in numba.prange(a.shape[0]):
                a[i] += 1.0
        _probe_fn = probe
    a = np.zeros(1024)
    numba.set_num_threads(threads)
    _probe_fn(a)
    ts = []
    for _ in range(calls):
        t0 = time.perf_counter()
        _probe_fn(a)
        ts.append(time.perf_counter() - t0)
    return 1e6 * float(np.median(ts))


_speed_fn = None


def speed_probe_ms(repeats=7):
    """Median time (ms) of a fixed serial numba loop of scalar arithmetic (a sqrt, a
    division and a few products per iteration, as a pair loop has): the speed the machine
    gives one thread just now. On the shared development VM the same loop took 3.8 to 17 ms
    within a minute (issue 12, fourth session), so a configuration whose probe reads well
    above the run's smallest ran on a slowed machine: compare rates at equal probe."""
    global _speed_fn
    import numba
    import numpy as np

    if _speed_fn is None:
        @numba.njit(cache=False)
        def probe(n):
            s = 0.0
            x = 1.0
            for i in range(n):
                x = x * 1.0000001 + 1e-9
                s += math.sqrt(x) / (x + 1.0) * 0.5
            return s
        _speed_fn = probe
        _speed_fn(10)
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        _speed_fn(1_000_000)
        ts.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(ts))


# --- timing ------------------------------------------------------------------------------
def timed_steps(sim, seconds, min_steps=5):
    times = []
    t_start = time.perf_counter()
    while True:
        t0 = time.perf_counter()
        sim.step()
        t1 = time.perf_counter()
        times.append(t1 - t0)
        if t1 - t_start >= seconds and len(times) >= min_steps:
            break
    return times


def best_chunk(times, chunk_seconds=0.5):
    """Mean step time of the fastest run of consecutive steps lasting ~``chunk_seconds``."""
    import numpy as np

    t = np.asarray(times)
    k = max(1, min(len(t), int(math.ceil(chunk_seconds / max(float(np.median(t)), 1e-12)))))
    sums = np.convolve(t, np.ones(k), mode="valid")
    return float(sums.min() / k)


class _Timer:
    def __init__(self):
        self.total = {}
        self.calls = {}
        self.each = {}

    def wrap(self, name, fn):
        def wrapped(*a, **k):
            t0 = time.perf_counter()
            r = fn(*a, **k)
            dt = time.perf_counter() - t0
            self.total[name] = self.total.get(name, 0.0) + dt
            self.calls[name] = self.calls.get(name, 0) + 1
            self.each.setdefault(name, []).append(dt)
            return r
        return wrapped


STAGES = ["neighbour_update", "  bin", "  sort", "  permute", "eos", "rates", "time_step",
          "density_rate", "integrator_update", "other (python)"]


def stage_breakdown(sim, seconds, min_steps=5):
    """Time each stage inside real steps by wrapping the stage methods of ``sim`` and the
    integrator's numba kernels (module globals, restored afterwards; nothing is edited)."""
    from sphfoam.models import integrators as integ_mod

    tm = _Timer()
    st = sim.state
    patched_sim = ["neighbour_update", "eos", "rates", "density_rate", "time_step"]
    for name in patched_sim:
        setattr(sim, name, tm.wrap(name, getattr(sim, name)))
    sim.cells.bin = tm.wrap("  bin", sim.cells.bin)
    sim.cells.sort = tm.wrap("  sort", sim.cells.sort)
    st.apply = tm.wrap("  permute", st.apply)
    kern = [k for k in ("_monaghan_half", "_monaghan_kick", "_drift", "_density_update",
                        "_verlet_step", "_symplectic_half", "_symplectic_velocity_density",
                        "_symplectic_drift", "_pc_predict", "_pc_correct")
            if hasattr(integ_mod, k)]
    saved = {k: getattr(integ_mod, k) for k in kern}
    for k in kern:
        setattr(integ_mod, k, tm.wrap("integrator_update", saved[k]))
    try:
        times = timed_steps(sim, seconds, min_steps)
    finally:
        for k, f in saved.items():
            setattr(integ_mod, k, f)
        for name in patched_sim:
            delattr(sim, name)
        del sim.cells.bin, sim.cells.sort, st.apply
    nsteps = len(times)
    total = sum(times)
    top = ["neighbour_update", "eos", "rates", "time_step", "density_rate", "integrator_update"]
    out = {}
    for s in STAGES:
        if s == "other (python)":
            t = total - sum(tm.total.get(k, 0.0) for k in top)
            calls = nsteps
        else:
            t = tm.total.get(s, 0.0)
            calls = tm.calls.get(s, 0)
        each = tm.each.get(s)
        out[s] = dict(ms_per_step=1e3 * t / nsteps, calls_per_step=calls / nsteps,
                      ms_per_call=1e3 * t / calls if calls else 0.0,
                      ms_per_call_median=1e3 * sorted(each)[len(each) // 2] if each else
                      1e3 * t / calls if calls else 0.0,
                      share=t / total if total else 0.0)
    return dict(steps=nsteps, ms_per_step=1e3 * total / nsteps, stages=out)


def bench_config(total, threads, args, steps=None):
    """One size at one thread count; ``steps``: time exactly that many steps (the first
    thread count's window, so that every thread count times the same stretch of the flow)."""
    import numba
    import numpy as np

    busy_before = wait_idle(args.wait_idle) if args.wait_idle > 0 else cpu_busy()
    launch_us = parallel_launch_us(threads)
    probe_before = speed_probe_ms()
    numba.set_num_threads(threads)
    sim, info = make_sim(total)
    fe = sim.integrator.force_evaluations_per_step
    for _ in range(args.warmup):
        sim.step()
    ns0 = neighbour_stats(sim, check_kdtree=(threads == args.threads[0]))
    c0, w0 = time.process_time(), time.perf_counter()
    times = (timed_steps(sim, 0.0, min_steps=steps) if steps
             else timed_steps(sim, args.seconds))
    cpu_util = (time.process_time() - c0) / ((time.perf_counter() - w0) * threads)
    ns1 = neighbour_stats(sim)
    steps = len(times)
    el = float(sum(times))
    n = info["n"]
    pairs = 0.5 * (ns0["pairs"] + ns1["pairs"])
    probe_after = speed_probe_ms()
    stages = stage_breakdown(sim, args.stage_seconds)
    ms_rates = stages["stages"]["rates"]["ms_per_call"]
    ms_drate = stages["stages"]["density_rate"]["ms_per_call"]
    res = dict(
        **info, threads=threads, steps=steps, seconds=el,
        sim_time=sim.time, last_dt=sim.last_dt,
        ms_per_step=1e3 * el / steps, ms_per_step_median=1e3 * float(np.median(times)),
        # fastest ~0.5 s chunk of the window: robust to intermittent load from other processes
        ms_per_step_best=1e3 * best_chunk(times),
        # cost of a step grows as the flow develops (more approaching pairs, see README)
        drift=float(np.median(times[-max(1, steps // 4):])
                    / np.median(times[:max(1, steps // 4)])),
        particle_steps_per_s=n * steps / el,
        force_evaluations_per_step=fe,
        particle_force_evals_per_s=n * steps * fe / el,
        particle_force_evals_per_s_per_thread=n * steps * fe / el / threads,
        pair_interactions_per_s=pairs * fe * steps / el,
        # every pass over the pairs, including density_rate (the 3rd pair loop of a step)
        pair_loop_visits_per_s=pairs * (fe + 1) * steps / el,
        ns_per_pair_rates=1e6 * ms_rates / pairs * threads if pairs else 0.0,
        ns_per_pair_density_rate=1e6 * ms_drate / pairs * threads if pairs else 0.0,
        neighbours_start=ns0, neighbours_end=ns1,
        mean_neighbours=0.5 * (ns0["mean_neighbours"] + ns1["mean_neighbours"]),
        stage_breakdown=stages,
        removed=int(sum(r.count for r in sim.removals)),
        machine_busy_before=busy_before,       # all CPUs, any process, before the config
        parallel_launch_us=launch_us,          # empty prange region at this thread count
        # the machine's serial speed just before and after the timed window (speed_probe_ms)
        speed_probe_ms=(probe_before, probe_after),
        cpu_utilisation=cpu_util,              # process CPU time / (wall x threads), timed
        loadavg_after=os.getloadavg()[0],
    )
    return res


# --- compile time (subprocesses) --------------------------------------------------------
def compile_child(total):
    """Run in a fresh interpreter: import + build + first steps, print one JSON line."""
    t0 = time.perf_counter()
    import numba  # noqa: F401
    import numpy  # noqa: F401
    import sphfoam.engine.build  # noqa: F401
    import sphfoam.engine.simulation  # noqa: F401
    import sphfoam.models  # noqa: F401
    t1 = time.perf_counter()
    if CASE == "engine":
        x, y, kind, dx, n = dam_break(total)
        sel, ctx, pipe = build(dx)
        t2 = time.perf_counter()
        sim, info = make_sim(total)
    else:
        sim, info = make_sim(total)
        pipe = sim.pipeline
        t2 = time.perf_counter()
    t3 = time.perf_counter()
    sim.step()
    t4 = time.perf_counter()
    sim.step()
    t5 = time.perf_counter()
    print("JSON:" + json.dumps(dict(
        import_s=t1 - t0, build_s=t2 - t1, compile_seconds=pipe.compile_seconds,
        cache_hit=bool(pipe.cache_hit), import_build_s=t2 - t0,
        first_step_s=t4 - t3, second_step_s=t5 - t4,
        engine_jit_s=(t4 - t3) - (t5 - t4), n=info["n"],
        source=str(pipe.source_path))))


def measure_compile(cache_dir: Path, small_n: int):
    env = dict(os.environ)
    env["SPHFOAM_CACHE_DIR"] = str(cache_dir / "sphfoam")
    env["NUMBA_CACHE_DIR"] = str(cache_dir / "numba")
    out = {}
    for label in ("cold", "cached"):
        t0 = time.perf_counter()
        cp = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--_compile-child",
                             str(small_n), "--case", CASE, "--precision", PRECISION],
                            env=env, capture_output=True,
                            text=True,
                            cwd=str(REPO))
        wall = time.perf_counter() - t0
        if cp.returncode != 0:
            raise RuntimeError(f"compile child ({label}) failed:\n{cp.stdout}\n{cp.stderr}")
        line = [ln for ln in cp.stdout.splitlines() if ln.startswith("JSON:")][-1]
        d = json.loads(line[5:])
        d["process_wall_s"] = wall
        out[label] = d
    return out


# --- reporting --------------------------------------------------------------------------
def _si(v):
    for unit, f in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(v) >= f:
            return f"{v / f:.2f} {unit}"
    return f"{v:.2f}"


THROUGHPUT_COLS = [
    ("N", lambda r: f"{r['n']:,}"),
    ("fluid", lambda r: f"{r['n_fluid']:,}"),
    ("dx (mm)", lambda r: f"{1e3 * r['dx']:.2f}"),
    ("thr", lambda r: str(r["threads"])),
    ("steps", lambda r: str(r["steps"])),
    ("ms/step", lambda r: f"{r['ms_per_step']:.2f}"),
    ("best ms/step", lambda r: f"{r['ms_per_step_best']:.2f}"),
    ("particle-steps/s", lambda r: _si(r["particle_steps_per_s"])),
    ("p-force-evals/s", lambda r: _si(r["particle_force_evals_per_s"])),
    ("per thread", lambda r: _si(r["particle_force_evals_per_s_per_thread"])),
    ("pair interactions/s", lambda r: _si(r["pair_interactions_per_s"])),
    ("mean nbrs", lambda r: f"{r['mean_neighbours']:.1f}"),
    ("vs DualSPHysics", lambda r: f"{r['particle_steps_per_s'] / r['threads'] / REFERENCE[0][2]:.2f}"
     if r.get("case") == "matched" else "-"),
    ("bytes/particle", lambda r: f"{r['bytes_per_particle']:.0f}" if "bytes_per_particle" in r
     else "-"),
    ("speedup", lambda r: f"{r.get('speedup', 1.0):.2f}"),
    ("drift", lambda r: f"{r['drift']:.2f}"),
    ("launch (us)", lambda r: f"{r['parallel_launch_us']:.0f}"),
    ("probe (ms)", lambda r: "/".join(f"{v:.1f}" for v in r["speed_probe_ms"])
     if "speed_probe_ms" in r else "-"),
    ("cpu util", lambda r: f"{100 * r['cpu_utilisation']:.0f}%"),
    ("busy before", lambda r: f"{100 * r['machine_busy_before']:.0f}%"),
]

COMPILE_COLS = [
    ("build", lambda k, d: k),
    ("compile_seconds", lambda k, d: f"{d['compile_seconds']:.2f}"),
    ("cache hit", lambda k, d: str(d["cache_hit"])),
    ("import (s)", lambda k, d: f"{d['import_s']:.2f}"),
    ("build (s)", lambda k, d: f"{d['build_s']:.2f}"),
    ("import+build (s)", lambda k, d: f"{d['import_build_s']:.2f}"),
    ("1st step JIT (s)", lambda k, d: f"{d['engine_jit_s']:.2f}"),
    ("process wall (s)", lambda k, d: f"{d['process_wall_s']:.2f}"),
]


def stage_rows(r):
    rows = []
    for s, d in r["stage_breakdown"]["stages"].items():
        rows.append([s, f"{d['calls_per_step']:.0f}", f"{d['ms_per_call']:.3f}",
                     f"{d['ms_per_call_median']:.3f}", f"{d['ms_per_step']:.3f}",
                     f"{100 * d['share']:.1f}%"])
    return rows


def markdown_table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def print_tables(results):
    try:
        from rich.console import Console
        from rich.table import Table

        con = Console(width=200)

        def show(title, header, rows):
            t = Table(title=title)
            for h in header:
                t.add_column(h, justify="right")
            for r in rows:
                t.add_row(*r)
            con.print(t)
    except ImportError:  # plain aligned text
        def show(title, header, rows):
            w = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
            print(f"\n{title}")
            print("  ".join(h.rjust(w[i]) for i, h in enumerate(header)))
            for r in rows:
                print("  ".join(c.rjust(w[i]) for i, c in enumerate(r)))

    if results.get("compile"):
        show("Pipeline compile time", [c[0] for c in COMPILE_COLS],
             [[f(k, d) for _, f in COMPILE_COLS] for k, d in results["compile"].items()])
    show("Run throughput", [c[0] for c in THROUGHPUT_COLS],
         [[f(r) for _, f in THROUGHPUT_COLS] for r in results["runs"]])
    show("Reference: the matched dam break in other codes, this machine kind, one thread",
         ["code", "integrator", "particle-steps/s", "pair interactions/s"], reference_rows())
    for r in results["runs"]:
        show(f"Stages, N={r['n']:,}, {r['threads']} thread(s), "
             f"{r['stage_breakdown']['ms_per_step']:.2f} ms/step instrumented",
             ["stage", "calls/step", "ms/call", "median ms/call", "ms/step", "share"], stage_rows(r))


def reference_rows():
    return [[code, integ, _si(ps), _si(pi)] for code, integ, ps, pi in REFERENCE]


def write_markdown(results, path: Path):
    meta = results["meta"]
    lines = [f"# Engine benchmark ({meta['date']})", "",
             f"Case: {meta['case']}", "",
             f"Machine: {meta['cpu']}, {meta['cores']} cores; python {meta['python']}, "
             f"numba {meta['numba']} (threading layer {meta['threading_layer']}), "
             f"numpy {meta['numpy']}; commit {meta['commit']}.", "",
             f"Command: `{meta['command']}`", ""]
    if results.get("compile"):
        lines += ["## Compile time", "",
                  "cold = fresh SPHFOAM_CACHE_DIR and NUMBA_CACHE_DIR in a new process; "
                  "cached = a second new process on the same directories. "
                  "`compile_seconds` is `Pipeline.compile_seconds`; *1st step JIT* is the "
                  "first step minus the second (engine helpers: cell list, integrator, "
                  "time step).", "",
                  markdown_table([c[0] for c in COMPILE_COLS],
                                 [[f(k, d) for _, f in COMPILE_COLS]
                                  for k, d in results["compile"].items()]), ""]
    lines += ["## Throughput", "",
              "particle-force-evals = N x steps x force_evaluations_per_step (2 for "
              "monaghan2007); pair interactions = ordered pairs a != b within the support "
              "x force evaluations (the density_rate pass, a third pair loop per step, "
              "is not counted; see JSON `pair_loop_visits_per_s`). speedup = vs the first "
              "thread count, over the same steps (each thread count times as many steps "
              "as the first did in its window, so all time the same stretch of the flow). "
              "best ms/step = the fastest ~0.5 s run of consecutive steps "
              "(less sensitive to other processes; every rate uses the whole window). "
              "drift = median step time of the last quarter of the window / of the first "
              "quarter (the pair loops get dearer as the flow develops). launch = median wall time of an empty numba prange region at "
              "that thread count (a few us on an idle machine; milliseconds when another "
              "process holds a core); cpu util = process CPU time / (wall x threads) in the "
              "timed window; busy before = all-CPU load just before the configuration; "
              "probe = the median time of a fixed serial loop of scalar arithmetic just "
              "before / after the timed window (speed_probe_ms: the speed the machine gives "
              "one thread; it varies by 2x and more on a shared VM, so compare rows at equal "
              "probe).",
              "",
              markdown_table([c[0] for c in THROUGHPUT_COLS],
                             [[f(r) for _, f in THROUGHPUT_COLS] for r in results["runs"]]),
              "", "Reference (issue 12): the matched dam break (benchmarks/cases/damBreakMatched, "
              "23 018 particles) in other codes on this machine kind, one thread, user CPU, "
              "start-up cancelled:", "",
              markdown_table(["code", "integrator", "particle-steps/s",
                              "pair interactions/s"], reference_rows()),
              "", "## Neighbours", "",
              markdown_table(["N", "pairs", "mean nbrs (all / fluid)", "candidates / pair",
                              "wall-a pairs", "wall-wall pairs"],
                             [[f"{r['n']:,}", f"{r['neighbours_start']['pairs']:,}",
                               f"{r['neighbours_start']['mean_neighbours']:.1f} / "
                               f"{r['neighbours_start']['mean_neighbours_fluid']:.1f}",
                               f"{r['neighbours_start']['candidates'] / r['neighbours_start']['pairs']:.2f}",
                               f"{r['neighbours_start']['pairs_wall_a']:,}",
                               f"{r['neighbours_start']['pairs_wall_wall']:,}"]
                              for r in results["runs"] if r["threads"] == results["runs"][0]["threads"]]),
              "", "## Stages", ""]
    for r in results["runs"]:
        lines += [f"**N = {r['n']:,}, {r['threads']} thread(s)** — "
                  f"{r['stage_breakdown']['ms_per_step']:.2f} ms/step instrumented, "
                  f"{r['ms_per_step']:.2f} ms/step plain; rates {r['ns_per_pair_rates']:.1f} "
                  f"ns/pair x thread, density_rate {r['ns_per_pair_density_rate']:.1f} "
                  "ns/pair x thread", "",
                  markdown_table(["stage", "calls/step", "ms/call", "median ms/call", "ms/step", "share"],
                                 stage_rows(r)), ""]
    path.write_text("\n".join(lines))


def meta(args):
    import numba
    import numpy as np

    cpu = platform.processor() or "?"
    try:
        for ln in Path("/proc/cpuinfo").read_text().splitlines():
            if ln.startswith("model name"):
                cpu = ln.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO,
                                capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "sphfoam"], cwd=REPO,
                               capture_output=True, text=True).stdout.strip()
        commit += " (sphfoam/ modified)" if dirty else ""
    except OSError:
        commit = "?"
    try:
        layer = numba.threading_layer()
    except ValueError:
        layer = "not yet initialised"
    return dict(date=_dt.datetime.now().isoformat(timespec="seconds"), cpu=cpu,
                cores=os.cpu_count(), numba_max_threads=numba.config.NUMBA_NUM_THREADS,
                python=platform.python_version(), numba=numba.__version__,
                numpy=np.__version__, threading_layer=layer, commit=commit,
                command=" ".join([Path(sys.argv[0]).name] + sys.argv[1:]),
                case=(f"{CASE}: {CASE_DIRS[CASE].relative_to(REPO)} with dx scaled to each N"
                      if CASE != "engine" else
                      f"dam break, column {H} m x {H} m, tank {TANK_LENGTH * H} m long, walls "
                      f"{TANK_HEIGHT * H} m high, {LAYERS} layers of stationary ghosts; "
                      f"h = {HDX} dx; " + ", ".join(f"{f}={s['type']}" for f, s in MODELS) +
                      f", alpha 0.1; integrator {INTEGRATOR['type']}, beta {BETA}"),
                env={k: os.environ.get(k) for k in ("OMP_WAIT_POLICY", "NUMBA_THREADING_LAYER",
                                                    "NUMBA_NUM_THREADS", "OMP_NUM_THREADS")},
                loadavg=os.getloadavg(),
                args={k: v for k, v in vars(args).items() if not k.startswith("_")})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 40_000, 160_000],
                    help="target total particle counts (default: 10000 40000 160000)")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2],
                    help="numba thread counts (default: 1 2)")
    ap.add_argument("--seconds", type=float, default=3.0,
                    help="minimum timed seconds per measurement (default 3)")
    ap.add_argument("--stage-seconds", type=float, default=None,
                    help="seconds of the instrumented stage pass (default: = --seconds / 2)")
    ap.add_argument("--warmup", type=int, default=20, help="warm-up steps (default 20)")
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: 10k particles, 1 s per measurement, tag 'quick'")
    ap.add_argument("--no-compile", action="store_true", help="skip the compile-time part")
    ap.add_argument("--compile-n", type=int, default=2000,
                    help="particles of the case the compile subprocesses step (default 2000)")
    ap.add_argument("--wait-idle", type=float, default=60.0,
                    help="before each configuration wait up to this many seconds for the "
                    "machine to be idle (< 15%% busy; 0 = do not wait; default 60)")
    ap.add_argument("--tag", default=None, help="suffix of the result file names")
    ap.add_argument("--out-dir", type=Path, default=HERE / "results")
    ap.add_argument("--case", choices=["engine", *CASE_DIRS], default="engine",
                    help="engine: the synthetic dam break (default); matched: the dam break "
                    "matched with DualSPHysics (benchmarks/cases/damBreakMatched); flume: "
                    "tutorials/solitaryWave; wall: tutorials/solitaryWallRunup (P's set-up); "
                    "flumeLowDiss: the flume with Fourtakas's delta-SPH and delta+ shifting "
                    "(issue 13's low-dissipation set-up)")
    ap.add_argument("--precision", choices=["double", "single"], default="double",
                    help="sphSchemes precision of the --case runs (default double)")
    ap.add_argument("--_compile-child", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    global CASE, PRECISION
    CASE = args.case
    PRECISION = args.precision
    if PRECISION != "double" and CASE == "engine":
        ap.error("--precision single needs --case (matched, flume or wall)")
    if CASE != "engine" and args.tag is None:
        args.tag = CASE + ("" if PRECISION == "double" else "-" + PRECISION)

    if args._compile_child is not None:
        compile_child(args._compile_child)
        return 0
    if args.quick:
        args.sizes = [10_000]
        args.seconds = 1.0
        args.tag = "quick" if args.tag is None else args.tag
    if args.stage_seconds is None:
        args.stage_seconds = max(0.5, args.seconds / 2)

    results = {"compile": None, "runs": []}
    if not args.no_compile:
        with tempfile.TemporaryDirectory(prefix="sphfoam-bench-") as tmp:
            busy = wait_idle(args.wait_idle) if args.wait_idle > 0 else cpu_busy()
            print(f"compile: cold and cached builds in subprocesses (cache {tmp}; machine "
                  f"{100 * busy:.0f}% busy) ...", flush=True)
            results["compile"] = measure_compile(Path(tmp), args.compile_n)
            results["compile"]["cold"]["machine_busy_before"] = busy
            for k, d in results["compile"].items():
                print(f"  {k}: compile_seconds {d['compile_seconds']:.2f} s, import+build "
                      f"{d['import_build_s']:.2f} s, cache_hit {d['cache_hit']}", flush=True)

    # this process builds into a private cache as well (does not touch ~/.cache/sphfoam)
    with tempfile.TemporaryDirectory(prefix="sphfoam-bench-run-") as tmp:
        os.environ["SPHFOAM_CACHE_DIR"] = tmp
        import numba

        maxthr = numba.config.NUMBA_NUM_THREADS
        threads = [t for t in args.threads if 1 <= t <= maxthr]
        if len(threads) != len(args.threads):
            print(f"note: numba allows at most {maxthr} threads; running {threads}")
        args.threads = threads
        for total in args.sizes:
            base = None
            first_steps = None
            for thr in threads:
                print(f"run: N ~ {total:,}, {thr} thread(s) ...", flush=True)
                r = bench_config(total, thr, args, first_steps)
                first_steps = first_steps or r["steps"]
                base = base or r["ms_per_step"]      # speedup vs the first thread count
                r["speedup"] = base / r["ms_per_step"]
                ck = r["neighbours_start"].get("pairs_kdtree")
                if ck is not None and ck != r["neighbours_start"]["pairs"]:
                    print(f"  WARNING: pair count {r['neighbours_start']['pairs']} != "
                          f"cKDTree {ck}")
                print(f"  N={r['n']:,}: {r['steps']} steps, {r['ms_per_step']:.2f} ms/step, "
                      f"{_si(r['particle_steps_per_s'])} particle-steps/s, parallel launch "
                      f"{r['parallel_launch_us']:.0f} us, cpu util "
                      f"{100 * r['cpu_utilisation']:.0f}%", flush=True)
                if (r["parallel_launch_us"] > 500 or r["machine_busy_before"] > 0.15
                        or r["cpu_utilisation"] < 0.85):
                    print("  WARNING: the machine is shared (another process is using the "
                          "CPUs); timings, 2-thread ones above all, are not representative",
                          flush=True)
                results["runs"].append(r)
        results["meta"] = meta(args)

    print_tables(results)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    day = _dt.date.today().isoformat()
    suffix = f"-{args.tag}" if args.tag else ""
    jpath = args.out_dir / f"engine-{day}{suffix}.json"
    mpath = args.out_dir / f"engine-latest{suffix}.md"
    jpath.write_text(json.dumps(results, indent=1, default=str))
    write_markdown(results, mpath)
    print(f"wrote {jpath.relative_to(REPO) if jpath.is_relative_to(REPO) else jpath} and "
          f"{mpath.relative_to(REPO) if mpath.is_relative_to(REPO) else mpath}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
