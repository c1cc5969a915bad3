"""The model-engine contract (sphfoam.engine.terms): declared terms, conflicts found before
anything compiles, an engine and a runner that name no model, one schedule, no import cycle."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

import sphfoam
from sphfoam import registry
from sphfoam.case.schemas import SPH_FAMILIES
from sphfoam.engine import terms as T
from sphfoam.engine.emit_cpu import generate_source
from sphfoam.engine.pipeline import CORE_PARAMS
from sphfoam.engine.plan import Plan, Selection
from sphfoam.engine.schedule import Schedule
from sphfoam.models.base import CaseContext, PipelineModel

PKG = Path(sphfoam.__file__).parent
CTX = CaseContext(dx=0.01, h=0.013, rho0=1000.0, nu=1e-6, g=(0.0, -9.81), fluid_height=0.3,
                  c0=20.0)
BASE = {"kernel": {"type": "wendlandC2"}, "equationOfState": {"type": "tait"},
        "continuity": {"type": "differenceForm"}, "momentum": {"type": "symmetric"},
        "viscosity": {"type": "artificial"}, "boundary": {"type": "stationaryGhosts"}}


def selection(**over) -> Selection:
    specs = {f: BASE.get(f, {"type": d}) for f, d in SPH_FAMILIES.items()}
    specs.update(over)
    return Selection(**{f: registry.build(f, s) for f, s in specs.items()})


def source(sel: Selection) -> str:
    names = list(CORE_PARAMS) + [k for m in sel.models() for k in m.params(CTX)]
    return generate_source(sel, names)


# --- conflicts, before anything compiles -----------------------------------------------------
class _GradientTwin(PipelineModel):
    """A second kernel correction written for this test: it corrects grad W too."""

    family = "kernelCorrection"
    name = "testGradientTwin"
    doc = "test model: scales grad W (conflicts with csph)"
    prefix = "kc_"

    def terms(self):
        return [T.Term("twin", ("rates",), pair="gWx *= 1.0", applies=("all",),
                       reads=("gradW",), corrects=("gradW",))]


class _Orphan(PipelineModel):
    family = "velocityCorrection"
    name = "testOrphan"
    doc = "test model: reads an auxiliary field nothing writes"
    prefix = "vc_"

    def terms(self):
        return [T.Term("orphan", ("rates",), pair="acc_x += aux[I_nobody, b]",
                       reads=("aux.nobody",), writes=("acc",))]


def test_two_models_correcting_the_gradient_are_named():
    sel = selection(kernelCorrection={"type": "csph"})
    sel.turbulence = _GradientTwin()       # a second corrector in another slot
    with pytest.raises(T.ContractError) as e:
        Plan(sel)
    msg = str(e.value)
    assert "csph" in msg and "testGradientTwin" in msg and "gradW" in msg


def test_a_term_reading_an_unwritten_field_is_named():
    sel = selection()
    sel.velocityCorrection = _Orphan()
    with pytest.raises(T.ContractError, match="testOrphan.*'nobody'"):
        Plan(sel)


def test_unknown_stage_and_kind_are_refused():
    class Bad(_Orphan):
        name = "testBad"

        def terms(self):
            return [T.Term("bad", ("postStep",), sees=("walls",))]

    sel = selection()
    sel.velocityCorrection = Bad()
    with pytest.raises(T.ContractError, match="testBad.*stage.*postStep.*neighbour kind"):
        Plan(sel)


def test_components_are_expanded_through_the_contract():
    assert T.expand_components("acc_@ -= p * gW@\nq = 1") == \
        "acc_x -= p * gWx\nacc_y -= p * gWy\nq = 1"
    assert T.expand_components("acc_@ += lam * U@_ab") == \
        "acc_x += lam * u_ab\nacc_y += lam * v_ab"
    three = T.expand_components("acc_@ += lam * U@_ab", (("x", "u"), ("y", "v"), ("z", "w")))
    assert three.splitlines()[-1] == "acc_z += lam * w_ab"


def test_a_component_that_takes_another_local_s_name_is_refused():
    """In 3-D ``sU@`` is ``su``, ``sv``, ``sw``: beside a weight sum ``sw`` its w component
    would overwrite it (Adami's wall once summed its weights and w velocities into one
    variable, the bed's pressure fell to zero within three steps); a vector assigned row by
    row and as ``n@`` is one vector, not a clash."""
    code = "sw = 0.0\nsU@ = 0.0\nsw += Wab\n"
    assert T.expand_components(code).splitlines()[:3] == ["sw = 0.0", "su = 0.0", "sv = 0.0"]
    with pytest.raises(T.ContractError, match=r"'sU@' written out over x, y, z gives sw"):
        T.expand_components(code, T.AXES)
    rows = "if d:\n    nx = 1.0\n    ny = 0.0\n    nz = 0.0\nelse:\n    n@ = g@\n"
    assert "nz = gz" in T.expand_components(rows, T.AXES)


# --- declarations agree with the code ---------------------------------------------------------
def _pipeline_models():
    for fam, models in registry.families().items():
        for name, cls in models.items():
            if issubclass(cls, PipelineModel):
                yield cls()
                if hasattr(cls.Coeffs, "model_fields") and "symmetric" in \
                        cls.Coeffs.model_fields:
                    yield cls(cls.Coeffs(symmetric=False))


@pytest.mark.parametrize("model", list(_pipeline_models()), ids=lambda m: f"{m.family}-{m.name}")
def test_declared_reads_and_writes_match_the_code(model):
    """What a term reads and writes is declared: the test reads the code so that the
    generator never has to."""
    assert_declarations_match(model)


def assert_declarations_match(model):
    """Every quantity the terms' code uses is declared (also used for models' non-default
    options, e.g. tests/test_walllaw.py)."""
    for t in model.terms():
        # the 2-D form, its @ and declared names written out (sphfoam.engine.terms)
        code = "\n".join(T.expand_components(t.code(p, 2), T.AXES[:2])
                         for p in ("init", "pair", "final"))
        declared = set(T.expand_names(t.reads + t.writes + t.corrects))
        assert ("Wab" in code) == ("W" in declared), (t.name, "W")
        assert ("gWx" in code or "gW@" in code) == ("gradW" in declared), (t.name, "gradW")
        for a in re.findall(r"aux\[I_(\w+),", code):
            assert f"aux.{a}" in declared, (t.name, a)
        for f in re.findall(r"fld\[F_(\w+),", code):
            assert f"field.{f}" in declared, (t.name, f)
        if "acc_" in code:
            assert "acc" in declared
        if "drho_a +=" in code:
            assert "drho" in declared


# --- the engine and the runner name no model --------------------------------------------------
#: registered names that are also ordinary words of the engine's own vocabulary
_GENERIC = {"lines", "none", "forces", "slices"}   # also plain words of the engine's text
#: attributes that belong to one family or model (read through hooks, never by the engine)
_FAMILY_ATTRS = ("coeffs.noSlip", ".noSlip ", "no_slip", ".every", "wall_density_evolves", "advects_positions", ".ghosts",
                 "aux[0]", "aux[1]", "filter_pair", "gradient_code", "eos.B", "coeffs.gamma",
                 "coeffs.hdx", "maker.name", "prm[2]")


def test_engine_and_runner_name_no_model():
    names = {n for models in registry.families().values() for n in models} - _GENERIC
    files = sorted((PKG / "engine").glob("*.py")) + [
        PKG / f for f in ("setup/settling.py", "timeloop.py", "assemble.py", "setup/initial.py",
                          "io/timedirs.py")]
    found = []
    for f in files:
        text = f.read_text()
        for n in names:
            if re.search(rf"\b{re.escape(n)}\b", text):
                found.append(f"{f.name}: {n}")
        for attr in _FAMILY_ATTRS:
            if attr in text:
                found.append(f"{f.name}: {attr}")
    assert not found, found


def test_generated_loops_follow_the_neighbour_kinds():
    """A repulsive wall enters only the viscous (no-slip) and force terms; a free-slip one
    only the force; stationary ghosts enter everything (no branch at all), and with
    ``noSlip no`` everything but the viscous term."""
    ghosts = source(selection())
    rep = source(selection(boundary={"type": "repulsiveMonaghanKos"}))
    slip = source(selection(boundary={"type": "repulsiveMonaghanKos", "noSlip": False}))
    rates = lambda s: s[s.index("def rates"):s.index("def density_rate")]  # noqa: E731
    assert "kindb ==" not in rates(ghosts)
    r = rates(rep)
    assert "if kindb == FLUID:" in r and "else:" in r
    wall_part = r[r.index("else:", r.index("if kindb == FLUID:")):]
    assert "f_viscosity" in wall_part.split("s_ab")[0]           # viscosity at a no-slip wall
    s = rates(slip)
    wall_part = s[s.index("else:", s.index("if kindb == FLUID:")):]
    assert "f_viscosity" not in wall_part.split("s_ab")[0]
    # stationary ghosts with noSlip no: wet walls in every term but the viscous one
    wet = rates(source(selection(boundary={"type": "stationaryGhosts", "noSlip": False})))
    fluid_part = wet[wet.index("if kindb == FLUID:"):wet.index("else:", wet.index("if kindb == FLUID:"))]
    wall_part = wet[wet.index("else:", wet.index("if kindb == FLUID:")):]
    assert "f_viscosity" in fluid_part and "f_viscosity" not in wall_part.split("s_ab")[0]
    assert "acc_x" in wall_part.split("s_ab")[0]                 # the pressure term stays


def test_free_slip_stationary_ghosts_leave_the_wet_walls_out_of_every_viscous_term():
    """With ``noSlip no`` the viscosity's term and the SPS stress see no wet wall; every
    other term sees them as before; ``noSlip yes`` (the default) changes nothing."""
    for visc in ({"type": "artificial"}, {"type": "laminar"}):
        sees = {}
        for no_slip in (True, False):
            plan = Plan(selection(viscosity=visc, turbulence={"type": "smagorinskySPS"},
                                  boundary={"type": "stationaryGhosts", "noSlip": no_slip}))
            sees[no_slip] = {t.name: plan.sees(t) for t in plan.terms}
        for name, seen in sees[True].items():
            t_free = sees[False][name]
            if name in ("viscosity", "spsStress"):
                assert "wetWall" in seen and "wetWall" not in t_free, name
            else:
                assert t_free == seen, name
        assert {"viscosity", "spsStress"} <= set(sees[True])


def test_the_kernel_value_is_computed_only_where_read():
    plain = source(selection())
    xsph = source(selection(velocityCorrection={"type": "xsph"}))
    assert "Wab" not in plain
    funcs = {f.split("(")[0]: f for f in xsph.split("\ndef ")[1:]}
    assert "Wab = kern_w" in funcs["prepass"] and "Wab = kern_w" in funcs["prepass_half"]
    for name in ("rates", "density_rate", "rates_half", "density_half"):
        assert "Wab" not in funcs[name], name


def test_the_old_csph_word_still_selects_csph():
    assert registry.get("kernelCorrection", "cspH") is registry.get("kernelCorrection", "csph")
    assert "csph" in registry.names("kernelCorrection")
    assert "cspH" not in registry.names("kernelCorrection")


# --- one schedule ---------------------------------------------------------------------------
def test_schedule_is_a_function_of_step_and_time():
    ts = Schedule("timeStep", 20)
    assert [i for i in range(1, 61) if ts.due(i, 0.0, 0.0)] == [20, 40, 60]
    rt = Schedule("runTime", 0.05)
    times = np.linspace(0.0, 0.2, 41)
    due = [round(t, 6) for t0, t in zip(times[:-1], times[1:]) if rt.due(0, t, t0)]
    assert due == [0.05, 0.1, 0.15, 0.2]
    assert Schedule("writeTime").due(3, 1.0, 0.9, wrote=True)
    assert not Schedule("writeTime").due(3, 1.0, 0.9, wrote=False)
    assert rt.next_time(0.05) == pytest.approx(0.1) and rt.next_time(0.07) == pytest.approx(0.1)
    f = Schedule.every(3)
    assert [i for i in range(10) if f.due_before_step(i)] == [3, 6, 9]
    with pytest.raises(ValueError, match="interval"):
        Schedule("runTime", float("inf"))


def test_function_objects_sample_the_same_after_a_restart(tutorial):
    """The same sampled times and the same values, restarted half way or not (a timeStep
    and a runTime function object)."""
    from sphfoam.timeloop import run_case

    common = {"type": "damBreakFront", "wallX": 0.0, "H0": 0.25, "plot": False}
    fos = {"front": {**common, "writeControl": "timeStep", "writeInterval": 7},
           "frontT": {**common, "writeControl": "runTime", "writeInterval": 0.0013}}
    edits = {"system/particleDict:dx": 0.0125, "system/controlDict:endTime": 0.02,
             "system/controlDict:writeInterval": 0.01, "system/controlDict:functions": fos}
    def rows(case, name):
        out = {}
        for folder in sorted((case / "postProcessing" / name).iterdir()):
            data = np.loadtxt(folder / f"{name}.dat", ndmin=2)
            for r in data:
                out[float(r[0])] = tuple(r[1:])
        return out

    full = tutorial("damBreak", edits)
    run_case(full, progress=False, echo=None)
    uninterrupted = {name: rows(full, name) for name in fos}
    part = tutorial("damBreak", {**edits, "system/controlDict:endTime": 0.01})  # replaces it
    run_case(part, progress=False, echo=None)
    from sphfoam.case.edit import set_entry

    set_entry(part, "system/controlDict", "endTime", 0.02)
    run_case(part, progress=False, echo=None)
    for name in fos:
        a, b = uninterrupted[name], rows(part, name)
        assert len(a) > 3, name
        assert sorted(a) == sorted(b), name
        assert all(np.array_equal(a[t], b[t], equal_nan=True) for t in a), name


# --- packages without circles -----------------------------------------------------------------
def _imports(path: Path) -> set[str]:
    """The sphfoam modules ``path`` imports: ``import sphfoam`` and ``from sphfoam import x``
    name the package root (``sphfoam/__init__.py``, which runs them), relative imports are
    resolved against ``path``'s package."""
    rel = path.relative_to(PKG.parent).with_suffix("").parts
    package = rel[:-1]                      # the package a relative import starts from
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package[:len(package) - node.level + 1]
                base = ".".join(up + ((base,) if base else ()))
            if base:
                out.add(base)
                out |= {f"{base}.{a.name}" for a in node.names}
    return {n for n in out if n == "sphfoam" or n.startswith("sphfoam.")}


def test_package_import_graph_has_no_cycle():
    """Subpackages and top-level modules of sphfoam, and the package root itself (reached by
    ``import sphfoam``, ``from sphfoam import x``), every import counted (function-level and
    ``TYPE_CHECKING`` ones too): the graph is acyclic."""
    def unit(mod: str) -> str:
        return ".".join(mod.split(".")[:2])

    graph: dict[str, set[str]] = {}
    for f in PKG.rglob("*.py"):
        rel = f.relative_to(PKG.parent).with_suffix("")
        mod = ".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts)
        for dep in _imports(f):
            u, v = unit(mod), unit(dep)
            if u != v and v in {unit(m) for m in _all_units()}:
                graph.setdefault(u, set()).add(v)
    state: dict[str, int] = {}

    def visit(n, path):
        state[n] = 1
        for m in graph.get(n, ()):
            if state.get(m) == 1:
                raise AssertionError("import cycle: " + " -> ".join(path + [n, m]))
            if m not in state:
                visit(m, path + [n])
        state[n] = 2

    for n in list(graph):
        if n not in state:
            visit(n, [])


def _all_units():
    for f in PKG.rglob("*.py"):
        rel = f.relative_to(PKG.parent).with_suffix("")
        parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
        yield ".".join(parts[:2])


# --- one neighbour list, reused while valid (issue 12) ---------------------------------------
def test_the_reused_neighbour_list_holds_every_pair_at_every_evaluation(tutorial):
    """A dam break stepped with the list reused between builds: at every evaluation of the
    rates (mid-step stages included) every pair within the support is in the list."""
    from scipy.spatial import cKDTree

    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    d = tutorial("damBreak", {"system/particleDict:dx": 0.0125,
                              "system/controlDict:functions": {}})
    case = Case(d)
    setup_case(case, log=lambda *_: None)
    sim = build_simulation(case, ParticleState.from_fields(read_state(d / "0")))
    rates = sim.rates
    checked = []

    def checked_rates():
        st = sim.state
        start, idx = sim._nb
        pts = np.column_stack([st.x, st.y])
        pairs = cKDTree(pts).query_pairs(sim.pipeline.support_radius * (1 - 1e-9),
                                         output_type="ndarray")
        owner = np.repeat(np.arange(st.n), np.diff(start))
        listed = owner * st.n + idx[:start[-1]]
        if sim.pipeline.fluid_pairs_only:       # still walls: wall pairs add nothing
            fluid = st.kind == 0
            pairs = pairs[fluid[pairs[:, 0]] | fluid[pairs[:, 1]]]
        want = np.concatenate([pairs[:, 0] * st.n + pairs[:, 1],
                               pairs[:, 1] * st.n + pairs[:, 0]])
        missing = ~np.isin(want, listed)
        assert not missing.any(), (sim.step_index, int(missing.sum()))
        checked.append(len(pairs))
        return rates()

    sim.rates = checked_rates
    for _ in range(400):
        sim.step()
    assert sim.list_reused > sim.list_built > 3     # the flow moved: rebuilt, and reused
    assert len(checked) == 2 * 400 and min(checked) > 0


def test_pairs_of_two_non_fluid_particles_are_left_out_only_where_no_term_reads_them(tutorial):
    """P's wall case (mirror ghosts, XSPH): no term keeps what a pair of two ghosts adds, so
    the list leaves those pairs out (Plan.fluid_pairs_only) and still holds every pair
    within the support with a fluid particle; 30 steps give bitwise the state of the full
    list. The dam break's wall particles sum their continuity over wall neighbours too:
    with its walls still those pairs add exactly 0 (v_ab = 0) and the list leaves them out;
    with a wall velocity (the tank sliding, as a Couette plate) it keeps them."""
    import dataclasses

    from scipy.spatial import cKDTree

    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    def build(name, edits):
        d = tutorial(name, {"system/controlDict:functions": {}, **edits})
        case = Case(d)
        setup_case(case, log=lambda *_: None)
        return build_simulation(case, ParticleState.from_fields(read_state(d / "0")))

    wall = {"system/particleDict:dx": 1.25, "system/controlDict:endTime": 1.0}
    sims = [build("solitaryWallRunup", wall) for _ in range(2)]
    assert sims[0].pipeline.fluid_pairs_only
    sims[1].pipeline = dataclasses.replace(sims[1].pipeline, fluid_pairs_only=False)
    for _ in range(30):
        for s in sims:
            s.step()
    a, b = (s.state for s in sims)
    assert a.n == b.n and sims[0].list_built > 1
    for f in ("x", "y", "u", "v", "rho"):
        assert np.array_equal(getattr(a, f), getattr(b, f)), f
    (start, idx), (start_f, _) = sims[0]._nb, sims[1]._nb
    owner = np.repeat(np.arange(a.n), np.diff(start))
    listed = idx[:start[-1]].astype(np.int64)
    fluid = a.kind == 0
    assert np.all(fluid[owner] | fluid[listed])                 # no pair of two non-fluid
    assert start[-1] < 0.97 * start_f[-1]                      # ... and there were some
    pairs = cKDTree(np.column_stack([a.x, a.y])).query_pairs(
        sims[0].pipeline.support_radius * (1 - 1e-9), output_type="ndarray")
    pairs = pairs[fluid[pairs[:, 0]] | fluid[pairs[:, 1]]]
    want = np.concatenate([pairs[:, 0] * a.n + pairs[:, 1], pairs[:, 1] * a.n + pairs[:, 0]])
    assert np.isin(want, owner * a.n + listed).all()
    dam = build("damBreak", {"system/particleDict:dx": 0.05})
    assert dam.pipeline.fluid_pairs_only and dam.pipeline.selection.still_walls
    dam = build("damBreak", {"system/particleDict:dx": 0.05,
                             "system/particleDict:walls.tank.velocity": [0.01, 0.0]})
    assert not dam.pipeline.fluid_pairs_only


@pytest.mark.parametrize("name, edits", [
    ("solitaryWallRunup", {"system/particleDict:dx": 1.25, "system/controlDict:endTime": 1.0,
                           "system/sphSchemes:integrator": {"type": "predictorCorrector"}}),
    ("damBreak", {"system/particleDict:dx": 0.05,
                  "system/sphSchemes:integrator": {"type": "symplectic"}}),
])
def test_an_evaluation_no_time_step_is_taken_from_skips_sigma(tutorial, name, edits):
    """predictorCorrector and symplectic take dt from the step's first evaluation only
    (``time_step_from_first_evaluation``): the mid-step evaluation skips sigma of T(3.89).
    30 steps give bitwise the state of evaluations that all compute it, and state.sigma is
    the first evaluation's."""
    from sphfoam.assemble import build_simulation
    from sphfoam.setup import setup_case
    from sphfoam.case.case import Case
    from sphfoam.engine.state import ParticleState
    from sphfoam.io.fields import read_state

    def build():
        d = tutorial(name, {"system/controlDict:functions": {}, **edits})
        case = Case(d)
        setup_case(case, log=lambda *_: None)
        return build_simulation(case, ParticleState.from_fields(read_state(d / "0")))

    skip, full = build(), build()
    assert skip.integrator.time_step_from_first_evaluation
    full.integrator.time_step_from_first_evaluation = False
    first = []
    rates = skip.rates

    def recording():
        wrote = skip._evaluations == 0
        rates()
        if wrote:
            first.append(skip.state.sigma.copy())

    skip.rates = recording
    for _ in range(30):
        skip.step()
        full.step()
        assert np.array_equal(skip.state.sigma, first[-1])
    assert len(first) == 30
    a, b = skip.state, full.state
    for f in ("x", "y", "u", "v", "rho"):
        assert np.array_equal(getattr(a, f), getattr(b, f)), f
    assert not np.array_equal(a.sigma, b.sigma)    # the full one's is the mid-step's
