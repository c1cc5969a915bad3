"""Speed work of issue 12 that must not change results: the working precision
(``sphSchemes`` ``precision``), mirror ghosts kept with the Verlet neighbour list, and no
allocation in the step loop while the list is reused."""

from __future__ import annotations

import dataclasses
import tracemalloc

import numpy as np
import pytest

from sphfoam.assemble import build_simulation
from sphfoam.setup import setup_case
from sphfoam.case.case import Case
from sphfoam.engine.state import GHOST, ParticleState
from sphfoam.io.fields import read_state


def _sim(tutorial, name, edits):
    d = tutorial(name, dict({"system/controlDict:functions": {}}, **edits))
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    return build_simulation(case, ParticleState.from_fields(read_state(d / "0")))


def _real(sim):
    st = sim.state
    real = st.kind != GHOST
    order = np.argsort(st.id[real], kind="stable")
    return {k: np.asarray(getattr(st, k)[real][order], dtype=np.float64)
            for k in ("x", "y", "u", "v", "rho") + (("z", "w") if st.dim == 3 else ())}


# --- precision ---------------------------------------------------------------------------
def test_single_precision_compiles_float32_loops_and_keeps_a_hydrostatic_tank(tutorial):
    """``precision single``: the state (but positions), aux and coefficients are float32, the
    compiled rates take float32 arrays and accumulate in float32; 40 steps of the hydrostatic
    tank stay within 1e-4 dx (positions) and 1e-5 rho0 (density) of the double run."""
    runs = {}
    for prec in ("double", "single"):
        sim = _sim(tutorial, "hydrostaticTank", {"system/particleDict:dx": 0.025,
                                                 "system/sphSchemes:precision": prec})
        for _ in range(40):
            sim.step()
        runs[prec] = (sim, _real(sim))
    sim, single = runs["single"]
    st = sim.state
    f4 = np.dtype(np.float32)
    assert st.x.dtype == st.y.dtype == np.float64            # positions stay double
    assert all(getattr(st, k).dtype == f4 for k in ("u", "v", "rho", "m", "p", "c", "ax",
                                                   "drho", "sigma"))
    assert sim.prm.dtype == f4 and sim.aux.dtype == f4
    mod = sim.pipeline.module
    assert "precision=single" in sim.pipeline.selection.describe()
    (sig,) = mod.rates.signatures
    assert str(sig[0]) == "array(float64, 1d, C)" and str(sig[2]) == "array(float32, 1d, C)"
    assert str(sig[11]) == "array(float32, 1d, C)"           # prm
    src = sim.pipeline.source_path.read_text()
    assert "dx_ab = F4(xa - x[b])" in src and "acc_x = F4(0.0)" in src
    assert _local_types(sim, "rates", ("acc_x", "drho_a", "r2", "q", "fw", "pterm")) == \
        {"float32"}                                         # no promotion back to float64
    dsim, double = runs["double"]
    assert dsim.state.u.dtype == np.float64 and dsim.prm.dtype == np.float64
    assert "F4(" not in dsim.pipeline.source_path.read_text()
    dx, rho0 = 0.025, 1000.0
    for k in ("x", "y"):
        assert np.max(np.abs(single[k] - double[k])) < 1e-4 * dx
    assert np.max(np.abs(single["rho"] - double["rho"])) < 1e-5 * rho0
    assert 0 < np.max(np.abs(single["rho"] - double["rho"]))  # it did run in float32
    fields = st.to_fields(p=st.p)
    assert fields["rho"].dtype == fields["U"].dtype == np.float64   # written as double


def _local_types(sim, func, names):
    """numba's types of the locals ``names`` of the generated ``func``, compiled serially
    (the parallel loop body is outlined, out of reach of inspect_types)."""
    import importlib.util
    import io
    import re

    src = sim.pipeline.source_path.read_text().replace("parallel=True", "parallel=False")
    src = src.replace("cache=True", "cache=False").replace("prange(", "range(")
    path = sim.pipeline.source_path.with_name("serial_check.py")
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("sphfoam_serial_check", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    st = sim.state
    getattr(mod, func)(*sim._grid_args(), st.ax, st.ay, st.drho, st.sigma)
    out = io.StringIO()
    getattr(mod, func).inspect_types(file=out)
    found = set()
    for m in re.finditer(r"#\s+(\w+)(?:\.\d+)? = .*::\s*(\w+)", out.getvalue()):
        if m.group(1) in names:
            found.add(m.group(2))
    path.unlink()
    return found


def test_a_bad_precision_names_the_file_key_and_choices(tutorial):
    from sphfoam.case.errors import CaseError

    d = tutorial("hydrostaticTank", {"system/sphSchemes:precision": "half"})
    with pytest.raises(CaseError) as e:
        Case(d).schemes
    msg = str(e.value)
    assert "sphSchemes" in msg and "precision" in msg and "single" in msg


# --- mirror ghosts and the Verlet list ------------------------------------------------------
def test_mirror_ghosts_keep_the_list_and_give_the_rebuilt_results(tutorial):
    """A dam break with mirror ghosts stepped with the list reused (ghosts kept, dormant ones
    of mass 0) and with a new list every step: the same fields to round-off; the reused run
    did reuse, and at every step its active ghosts are the ghosts T(3.77) makes."""
    edits = {"system/particleDict:dx": 0.02,
             "constant/sphProperties:boundary": {"type": "mirrorGhosts", "noSlip": True}}
    out = {}
    for reuse in (True, False):
        sim = _sim(tutorial, "damBreak", edits)
        sim.reuse_neighbours = reuse
        bnd = sim.pipeline.selection.boundary
        for _ in range(120):
            sim.step()
            if reuse:
                st = sim.state
                count = np.zeros(st.n, dtype=np.int64)
                from sphfoam.models import mirror as gh
                gh.count_ghosts(st.x, st.y, st.kind, bnd.seg, bnd.corners, bnd.reach, count)
                assert int(bnd._active.sum()) == int(count.sum())
        out[reuse] = (sim.list_built, sim.list_reused, _real(sim))
    built, reused, a = out[True]
    assert reused > built > 1
    assert out[False][1] == 0
    b = out[False][2]
    for k in a:
        scale = np.max(np.abs(b[k])) or 1.0
        assert np.max(np.abs(a[k] - b[k])) <= 1e-9 * scale, k


# --- no allocation in the step loop -----------------------------------------------------------
def test_no_array_is_allocated_per_step_while_the_list_is_reused(tutorial):
    """Verlet (one evaluation a step, no density filter): over steps that reuse the neighbour
    list numpy allocates no particle array (tracemalloc's peak), and what numba's runtime
    allocates is freed within the step (its parallel launcher's small scheduling arrays, a
    few per prange region: 49 a step here)."""
    from numba.core.runtime import _nrt_python as nrt
    from numba.core.runtime import rtsys

    sim = _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.01,
                                      "system/sphSchemes:integrator": {"type": "verlet"},
                                      "constant/sphProperties:densityFilter": {"type": "none"}})
    for _ in range(3):
        sim.step()
    n = sim.state.n
    built = sim.list_built
    stats_were_on = nrt.memsys_stats_enabled()
    nrt.memsys_enable_stats()
    tracemalloc.start()
    try:
        before, _ = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        s0 = rtsys.get_allocation_stats()
        for _ in range(10):
            sim.step()
        s1 = rtsys.get_allocation_stats()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
        if not stats_were_on:
            nrt.memsys_disable_stats()
    assert sim.list_built == built          # the window reused the list
    made, freed = s1.alloc - s0.alloc, s1.free - s0.free
    assert made == freed and made <= 10 * 80      # freed in the step; a few per region
    assert n > 1500 and peak - before < 4 * n     # not one float array of the particles


# --- the per-pair cache of kernel values ------------------------------------------------------
def test_the_pair_cache_gives_the_uncached_rates_bit_for_bit(tutorial, monkeypatch):
    """With a prepass (XSPH) every particle walks its list before the rates: it stores the
    kernel gradient factor per listed pair and the rates and density loops read it. The
    rates, sigma and drho/dt equal those of the same selection generated without the cache."""
    from sphfoam.engine import build, plan
    from sphfoam.engine.terms import ContractError, Term

    d = tutorial("damBreak", {"system/particleDict:dx": 0.02,
                              "system/controlDict:functions": {},
                              "constant/sphProperties:velocityCorrection": {"type": "xsph"}})
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")))
    for _ in range(30):
        sim.step()
    pipe = sim.pipeline
    assert "fw" in pipe.pair_cache
    src = pipe.source_path.read_text()
    assert "pc[J_fw, k] = fw" in src and "fw = pc[J_fw, k]" in src
    st = sim.state
    sim.half_lists = False          # the gather both ways (the half lists sum in another order)
    sim.eos()
    sim.rates()
    cached = [a.copy() for a in (st.ax, st.ay, st.drho, st.sigma)]
    sim.density_rate()
    cached.append(st.drho.copy())

    monkeypatch.setattr(plan.Plan, "_pair_cache", lambda self: [])
    plain = build.build_pipeline(pipe.selection, case.context, pipe.core)
    assert plain.pair_cache == () and "pc[" not in plain.source_path.read_text()
    args = sim._grid_args()[:-1]                       # without the cache
    out = [np.zeros(st.n) for _ in range(4)]
    plain.prepass(*args)
    plain.rates(*args, *out)
    drho = np.zeros(st.n)
    plain.prepass(*args)
    plain.density_rate(*args, drho)
    for got, want in zip(cached, out + [drho]):
        assert np.array_equal(got, want)

    with pytest.raises(ContractError, match="does not define"):
        from sphfoam.engine import terms as T
        T.check([Term("bad", ("rates",), pair="x = 1", writes=("W",), cache=("Wab",))],
                set(), {})


# --- half lists: each pair once, for both particles ---------------------------------------
_HALF_SELECTIONS = {
    # the matched dam break's forms: T(3.17), T(3.25), T(3.32), Wendland C2, verlet
    "matched": {"constant/sphProperties:kernel": {"type": "wendlandC2", "hdx": 1.3},
                "constant/sphProperties:continuity": {"type": "densityWeighted"},
                "constant/sphProperties:momentum": {"type": "colagrossiLandrini"},
                "system/sphSchemes:integrator": {"type": "verlet", "everyN": 40}},
    # the tutorial's forms T(3.18), T(3.26), T(3.32) and monaghan2007's density pass
    "damBreak": {},
    # the flume's laminar viscosity T(3.38)
    "laminar": {"constant/sphProperties:viscosity": {"type": "laminar"}},
    # Fourtakas et al.'s hydrostatic delta-SPH (midpoint form: odd, so it has a reaction)
    # with delta+ shifting (its prepass over half lists: the concentration gradient's sums)
    "fourtakas": {"constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH"},
                  "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting"}},
    # the finite Gaussian with mirror ghosts and XSPH (P's kernel, walls and corrected
    # continuity velocity, odd in the pair)
    "mirror": {"constant/sphProperties:kernel": {"type": "gaussian", "hdx": 1.33},
               "constant/sphProperties:boundary": {"type": "mirrorGhosts", "noSlip": False},
               "constant/sphProperties:velocityCorrection": {"type": "xsph"}},
}


@pytest.mark.parametrize("name", list(_HALF_SELECTIONS))
def test_half_lists_give_the_gather_sums_to_round_off(tutorial, name):
    """Where every term declares its reaction, the rates and density passes run over half
    lists (rates_half, density_half); 60 steps of the dam break give the fields of the gather
    over full lists to round-off (the sums are taken in another order), and at the end the
    rates of one state agree to 1e-12 of the largest term."""
    edits = {"system/particleDict:dx": 0.02, **_HALF_SELECTIONS[name]}
    runs = {}
    for half in (True, False):
        sim = _sim(tutorial, "damBreak", edits)
        sim.half_lists = half
        for _ in range(60):
            sim.step()
        runs[half] = (sim, _real(sim))
    sim = runs[True][0]
    assert sim.pipeline.rates_half is not None and sim._half is not None
    assert runs[False][0]._half is None
    assert sim.pipeline.density_half is not None
    for k, want in runs[False][1].items():
        got = runs[True][1][k]
        scale = np.max(np.abs(want)) or 1.0
        assert np.max(np.abs(got - want)) <= 1e-10 * scale, k
    # a prepass whose terms declare their sums' reactions (XSPH) runs over half lists too
    assert (sim.pipeline.prepass_half is not None) == (sim.pipeline.prepass is not None)
    st = sim.state
    sim.eos()
    sim.rates()
    half = [a.copy() for a in (st.ax, st.ay, st.drho, st.sigma, *sim.aux)]
    sim.density_rate()
    half.append(st.drho.copy())
    sim.half_lists = False
    sim.rates()
    full = [a.copy() for a in (st.ax, st.ay, st.drho, st.sigma, *sim.aux)]
    sim.density_rate()
    full.append(st.drho.copy())
    for got, want in zip(half, full):
        scale = np.max(np.abs(want))
        assert scale > 0 and np.max(np.abs(got - want)) <= 1e-12 * scale
    assert any(not np.array_equal(g, w) for g, w in zip(half, full))   # another order
    wall = st.kind != 0
    assert np.all(half[0][wall] == 0) and np.all(half[3][wall] == 0)  # walls: no acc, sigma


def test_half_lists_only_where_every_term_mirrors(tutorial):
    """A term without a reaction or parity (C-SPH's corrected gradient in both passes, a repulsive wall force or the switched artificial
    viscosity in the rates) or a periodic axis keeps the gather over full lists for that
    pass."""
    from sphfoam.engine.plan import Plan

    for edits, density in (({"constant/sphProperties:viscosity": {"type": "improvedArtificial"}},
                            True),
                           ({"constant/sphProperties:kernelCorrection": {"type": "cspH"}},
                            False),
                           ({"constant/sphProperties:boundary": {"type": "repulsiveMonaghanKos"}},
                            True)):
        sim = _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.04, **edits})
        assert sim.pipeline.rates_half is None, edits
        assert (sim.pipeline.density_half is not None) == density, edits
        sim.step()
        assert (sim._half is not None) == density
    sel = _sim(tutorial, "poiseuille", {}).pipeline.selection
    # periodic across the bands (rows of cells along y): the last row's pairs wrap to the
    # first, so the gather
    assert sel.periodic_x and Plan(sel).half_terms("rates") is not None
    assert Plan(dataclasses.replace(sel, periodic_y=True)).half_terms("rates") is None


@pytest.mark.parametrize("name, edits", [
    ("poiseuille", {}),                                     # periodic along x, 2-D
    ("solitaryWave3D", {"system/particleDict:dx": 0.1,      # periodic along y, 3-D: a
                        "system/particleDict:fluid.water.max": [3.0, 1.1, 0.5],   # short
                        "system/particleDict:walls.flume.max": [3.0, 1.1, 1.2],   # flume,
                        "system/particleDict:walls.paddle.max": [0.0, 1.1, 1.2],  # 3 cells
                        "system/particleDict:domain.max": [4.0, 1.1, 2.5]}),      # across
])
def test_half_lists_across_a_periodic_axis(tutorial, name, edits):
    """Periodic along an axis the bands do not follow, the cell walk visits the wrapped cell
    in its place among the three (increasing index), so the list allows the half lists;
    their pairs across the period take the nearest image: 30 steps give the gather's fields
    to round-off, and the rates of one state agree to 1e-10 of the largest rate (the
    channel's rates are small differences of its pairs' terms)."""
    runs = {}
    for half in (True, False):
        sim = _sim(tutorial, name, edits)
        sim.half_lists = half
        for _ in range(30):
            sim.step()
        runs[half] = (sim, _real(sim))
    sim = runs[True][0]
    assert sim._half is not None and runs[False][0]._half is None
    speed = max(np.max(np.abs(runs[False][1][k])) for k in ("u", "v"))
    for k, want in runs[False][1].items():     # (v of the 3-D flume is 0 up to round-off)
        scale = speed if k in ("u", "v") else np.max(np.abs(want))
        assert np.max(np.abs(runs[True][1][k] - want)) <= 1e-10 * scale, k
    st = sim.state
    out = {}
    for half in (True, False):
        sim.half_lists = half
        sim.eos()
        sim.rates()
        out[half] = [a.copy() for a in (*st.accelerations, st.drho)]
    force = max(np.max(np.abs(a)) for a in out[False][:-1])
    for got, want in zip(out[True], out[False]):
        scale = np.max(np.abs(want)) if want is out[False][-1] else force
        assert scale > 0 and np.max(np.abs(got - want)) <= 1e-10 * scale


def test_reaction_and_parity_declarations_are_checked():
    """parity is 'even' or 'odd', of a definer or corrector of pair quantities only; a
    reaction belongs to a term with pair code of its own."""
    from sphfoam.engine import terms as T
    from sphfoam.engine.terms import ContractError, Term

    with pytest.raises(ContractError, match="parity"):
        T.check([Term("w", ("rates",), pair="Wab = 1.0", writes=("W",), parity="both")],
                set(), {})
    with pytest.raises(ContractError, match="parity"):
        T.check([Term("p", ("rates",), pair="acc_x += 1.0", writes=("acc",), parity="odd")],
                set(), {})
    with pytest.raises(ContractError, match="reaction"):
        T.check([Term("r", ("rates",), init="s = 0.0", writes=("acc",),
                      reaction="acc_b_x += 1.0")], set(), {})
    with pytest.raises(ContractError, match="sum"):
        T.check([Term("s", ("prepass",), init="t = 0.0", pair="s += 1.0",
                      writes=("aux.s",), sums=("s",))], set(), {})
    T.check([Term("g", ("rates",), pair="gWx = dx_ab", writes=("gradW",), parity="odd"),
             Term("a", ("rates",), pair="acc_x -= gWx", reads=("gradW",), writes=("acc",),
                  reaction="acc_b_x += gWx")], set(), {})


@pytest.mark.parametrize("dim", [2, 3])
def test_half_lists_give_the_same_results_with_one_and_two_threads(tutorial, dim):
    """The bands of the half-list loops (in 3-D the blocks of rows and their four colours)
    do not depend on the thread count, so neither does the order of any sum: 30 steps of
    the dam break (10 of the matched 3-D one) with one and with two threads are bit for bit
    equal."""
    import numba

    from test_three_d_engine import MATCHED3D, _small_matched_3d

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    before = numba.get_num_threads()
    out = {}
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            sim = _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.02}) if dim == 2 \
                else _small_matched_3d(Case(MATCHED3D))
            for _ in range(30 if dim == 2 else 10):
                sim.step()
            assert sim._half is not None
            out[threads] = _real(sim)
    finally:
        numba.set_num_threads(before)
    for k in out[1]:
        assert np.array_equal(out[1][k], out[2][k]), k


@pytest.mark.parametrize("nb, threads", [(1, 1), (5, 2), (10, 2), (18, 2), (9, 3), (64, 4)])
def test_the_bands_of_a_colour_are_dealt_to_the_threads_in_turn(nb, threads):
    """neighbours.deal_bands: each colour's order is a permutation of its bands, and the
    contiguous share prange gives thread t (the first shares one longer where they do not
    divide evenly) holds the colour's bands t, t + T, ...: a shallow tank's rows of water
    go to every thread, not the bottom half to the first (twelfth session)."""
    from sphfoam.engine.neighbours import deal_bands

    n = 7
    half = np.zeros(n + 2 * nb + 2, dtype=np.uint32)
    half[n:n + nb + 1] = np.linspace(0, n, nb + 1).astype(np.uint32)
    half[-1] = nb
    deal_bands(half, n, threads)
    order = half[n + nb + 1:n + 2 * nb + 1].astype(int)
    start = 0
    for colour in range(2):
        bands = list(range(colour, nb, 2))
        dealt = order[start:start + len(bands)]
        start += len(bands)
        assert sorted(dealt) == bands
        q, r = divmod(len(bands), threads)
        k = 0
        for t in range(threads):
            size = q + (t < r)
            assert list(dealt[k:k + size]) == bands[t::threads], (colour, t)
            k += size
    assert half[-1] == nb and np.array_equal(half[n:n + nb + 1],
                                             np.linspace(0, n, nb + 1).astype(np.uint32))


# --- the prepass before the density pass -------------------------------------------------
def test_density_pass_runs_without_a_prepass_it_does_not_read(tutorial, monkeypatch):
    """monaghan2007's density-only pass (D^1) needs the prepass only where its terms read what
    the prepass makes (XSPH's corrected velocity); the shifting vector is read by the next
    rates evaluation and the drift, after a prepass of their own. Skipping it there (the
    density loop then computes the kernel instead of reading the pair cache) changes no bit:
    25 steps of the dam break with delta+ shifting and Fourtakas's delta-SPH against the same
    run with the prepass forced before every pass."""
    from sphfoam.engine.pipeline import Pipeline

    edits = {"system/particleDict:dx": 0.03,
             "constant/sphProperties:densityFilter": {"type": "fourtakasDeltaSPH"},
             "constant/sphProperties:particleShifting": {"type": "deltaPlusShifting"}}
    runs = []
    for forced in (False, True):
        sim = _sim(tutorial, "damBreak", edits)
        assert sim.pipeline.module.PREPASS_BEFORE == ("rates",)
        assert sim.pipeline.pair_cache                       # the rates read the cache
        if forced:
            monkeypatch.setattr(Pipeline, "prepass_before", lambda self, stage: True)
        calls = []
        real = sim.pipeline.prepass_half              # (over half lists: shifting's sums)
        assert real is not None
        monkeypatch.setattr(type(sim.pipeline), "prepass_half", property(
            lambda self: (lambda *a: (calls.append(1), real(*a)))))
        for _ in range(25):
            sim.step()
        assert len(calls) == (3 if forced else 2) * 25
        runs.append(_real(sim))
        monkeypatch.undo()
    for k in runs[0]:
        assert np.array_equal(runs[0][k], runs[1][k]), k
    xsph = _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.04,
                                       "constant/sphProperties:velocityCorrection":
                                       {"type": "xsph"}})
    assert "density" in xsph.pipeline.module.PREPASS_BEFORE


# --- XSPH once per step ----------------------------------------------------------------------
def test_xsph_once_per_step_runs_one_prepass_a_step(tutorial, monkeypatch):
    """``velocityCorrection { type xsph; evaluation oncePerStep; }``: the prepass runs before
    the first evaluation of each step only (monaghan2007 evaluates three times), so the
    pipeline keeps no pair cache (it would be the first state's) and the later stages read
    the step's first dv_a. Over 40 steps of the dam break the fields stay within O(dt) of
    the every-stage scheme's: positions within 1e-5 of the water column's height (about
    20 mm of motion at the front), velocities within 1.5 % (rms). Outside a step a pass always
    runs its own prepass. With a shifting (every evaluation) in the same prepass the
    selection is refused, naming both."""
    from sphfoam.engine.pipeline import Pipeline
    from sphfoam.engine.terms import ContractError

    runs = {}
    for evaluation in ("everyStage", "oncePerStep"):
        sim = _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.03,
                                          "constant/sphProperties:velocityCorrection":
                                          {"type": "xsph", "evaluation": evaluation}})
        once = evaluation == "oncePerStep"
        assert sim.pipeline.prepass_once == once
        assert (sim.pipeline.pair_cache == ()) == once
        calls = []
        real = sim.pipeline.prepass_half
        monkeypatch.setattr(Pipeline, "prepass_half", property(
            lambda self: (lambda *a: (calls.append(1), real(*a)))))
        for _ in range(40):
            sim.step()
        assert len(calls) == (1 if once else 3) * 40
        if once:
            sim.eos()
            sim.rates()                                   # outside a step: its own prepass
            assert len(calls) == 41
        monkeypatch.undo()
        runs[evaluation] = _real(sim)
    a, b = runs["everyStage"], runs["oncePerStep"]
    assert any(not np.array_equal(a[k], b[k]) for k in a)
    for k in ("x", "y"):
        assert np.max(np.abs(a[k] - b[k])) < 1e-5 * 1.0, k
    speed = np.hypot(a["u"], a["v"])
    diff = np.hypot(a["u"] - b["u"], a["v"] - b["v"])
    # 0.67 % rms (dv_a grows with the flow from rest: held over a step it lags by dt / t,
    # 1/40 at the end)
    assert np.sqrt(np.mean(diff ** 2)) < 0.015 * np.sqrt(np.mean(speed ** 2))
    with pytest.raises(ContractError, match="once per step"):
        _sim(tutorial, "damBreak", {"system/particleDict:dx": 0.05,
                                    "constant/sphProperties:velocityCorrection":
                                    {"type": "xsph", "evaluation": "oncePerStep"},
                                    "constant/sphProperties:particleShifting":
                                    {"type": "deltaPlusShifting"}})
