"""The narrow runtime interface of contract v2 (issue 32): models reach a running simulation
only through the public :class:`~sphfoam.engine.context.RunContext` their hooks receive, and
their term code calls only helpers a device can compile."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import pytest

from sphfoam import registry

MODELS = Path(__file__).resolve().parent.parent / "sphfoam" / "models"


def _module_texts():
    return {p.name: p.read_text() for p in sorted(MODELS.glob("*.py"))}


def test_models_reach_no_private_state_of_the_engine():
    """No model reads the simulation's private state (``sim._nb``, ``run._x``) or the
    generated module (``.module.``): the hooks' context names what they may see."""
    bad = []
    for name, text in _module_texts().items():
        for i, line in enumerate(text.splitlines(), 1):
            code = line.split("#", 1)[0]
            if re.search(r"\b(sim|run)\._\w", code) or ".module." in code or \
                    re.search(r"\bsim\.pipeline\b|\brun\.pipeline\b", code):
                bad.append(f"{name}:{i}: {line.strip()}")
    assert not bad, "\n".join(bad)


def test_hooks_receive_the_run_context(tutorial):
    """Every hook of a selected model is called with the RunContext, not the Simulation."""
    import sphfoam
    from sphfoam.engine.context import RunContext

    d = tutorial("damBreak", {"system/particleDict:dx": 0.04,
                              "system/controlDict:functions": {},
                              "constant/sphProperties:velocityCorrection": {"type": "xsph"}})
    seen = []
    from sphfoam.models.corrections import XSPH

    original = XSPH.advection_velocity

    def spy(self, run, u, v):
        seen.append(type(run))
        return original(self, run, u, v)

    XSPH.advection_velocity = spy
    try:
        sphfoam.run(sphfoam.Case(d), end_time=0.002)
    finally:
        XSPH.advection_velocity = original
    assert seen and all(t is RunContext for t in seen)


def _imported_helpers():
    """(model, helper) for every jitted helper a registered pipeline model imports into
    its term code (``imports()``)."""
    import importlib

    from sphfoam.models.base import PipelineModel

    out = []
    for family in registry.FAMILIES:
        for name in registry.names(family):
            if not issubclass(registry.get(family, name), PipelineModel):
                continue                   # no term code (motions, function objects, ...)
            m = registry.build(family, {"type": name})
            for line in m.imports():
                if line.strip() == "import math":       # device functions have math
                    continue
                mod, names = line.replace("from ", "", 1).split(" import ")
                module = importlib.import_module(mod.strip())
                for item in names.split(","):
                    real = item.split(" as ")[0].strip()
                    out.append((f"{family} {name!r}", real, getattr(module, real)))
    return out


@pytest.mark.parametrize("who, name, fn", _imported_helpers(),
                         ids=lambda v: v if isinstance(v, str) else "")
def test_term_helpers_are_device_compilable(who, name, fn):
    """A helper that term code calls is a plain jitted scalar function: not parallel, no
    prange, no allocation, no printing, so that a device backend can compile it as a device
    function."""
    assert hasattr(fn, "py_func"), f"{who}: {name} is not a jitted function"
    assert not fn.targetoptions.get("parallel"), f"{who}: {name} is parallel"
    src = inspect.getsource(fn.py_func)
    for host in ("prange", "np.empty", "np.zeros", "np.ones", "print(", "np.array("):
        assert host not in src, f"{who}: {name} calls {host} (host only)"


def _integrators():
    return [registry.build("integrator", {"type": n}) for n in registry.names("integrator")]


@pytest.mark.parametrize("integ", _integrators(), ids=lambda m: m.name)
def test_integrators_are_declared_updates_the_backend_runs(integ):
    """An integrator declares its per-particle updates (no compiled loop of its own: the
    backend compiles them) and names only the contract's arrays; written once with ``@``,
    each expands to two and to three components."""
    import ast

    from sphfoam.engine.emit_cpu import generate_updates
    from sphfoam.engine.stepping import arrays_of
    from sphfoam.engine.updates import ParticleUpdates

    text = (MODELS / "integrators.py").read_text()
    assert "prange" not in text and "@njit" not in text
    assert integ.updates
    ParticleUpdates(integ)              # refuses an array that is not the contract's
    for upd in integ.updates:
        a2, a3 = arrays_of(upd, 2), arrays_of(upd, 3)
        if "x" in a2:
            assert "z" in a3 and "z" not in a2
        if "u" in a2:
            assert "w" in a3
    ast.parse(generate_updates(integ, 3))


def test_the_simulation_owns_the_time_step():
    """No integrator writes the simulation's time or step: ``step`` returns what it
    advanced and the simulation keeps it (``Simulation.last_dt``)."""
    text = (MODELS / "integrators.py").read_text()
    assert "last_dt" not in text and ".time +=" not in text
