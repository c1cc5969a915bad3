"""The device forms of the models' run-time hooks (``sphfoam.models.base.HOOK_NAMES``).

A model's hooks run in Python on host arrays; the CUDA runtime keeps its arrays on the
device, so a model with hooks runs there only through a *device form*: a class that does
on device arrays what the hooks do, at the same points of a step. :data:`DEVICE_FORMS`
names, per model (family, name), the class and the hooks it stands for; the refusals
(:func:`sphfoam.engine.cuda.build.refusals`) refuse a model with a hook no device form
stands for, by name, and :class:`~sphfoam.engine.cuda.runtime.CudaSimulation` makes one
device form per selected model and calls its methods at fixed points:

``attach(sim)``                        once, when the simulation is built
``add_particles(sim, cell, counts)``   at a list build, after binning (``cell`` per
                                       particle, ``counts`` per cell, the extra last cell
                                       for particles that leave): may append particles
                                       (``sim.append``) and returns the cell array of all
``after_sort(sim, order)``             after the sort by cell (and the removal of those
                                       binned outside)
``keeps_neighbours(sim)``              whether what it added at the build still serves
``before_evaluation(sim)``             before every equation of state, rates or density pass
``after_rates(sim)``                   after every evaluation of the rates
``walls_moved(sim, offsets, velocities)``  prescribed wall motion at a stage time
``after_step(sim)``                    at the end of each step
``summary()``                          a line for the end of the run's log

This module imports no CUDA: the refusals read it on any machine.
"""

from __future__ import annotations

import importlib

#: (family, name) -> (module, class, the model's hooks the device form stands for)
DEVICE_FORMS = {
    ("boundary", "mirrorGhosts"): (
        "sphfoam.engine.cuda.mirror", "MirrorGhostsDevice",
        ("attach", "before_neighbours", "add_particles", "keeps_neighbours", "after_sort",
         "before_evaluation", "after_rates", "walls_moved", "after_step", "summary")),
}


def covered_hooks(model) -> tuple[str, ...]:
    """The hooks of ``model`` its device form stands for (none without one)."""
    entry = DEVICE_FORMS.get((model.family, model.name))
    return entry[2] if entry else ()


def device_forms(sel) -> list:
    """One device form per selected model that has one (in selection order)."""
    out = []
    for m in sel.models():
        entry = DEVICE_FORMS.get((m.family, m.name))
        if entry:
            out.append(getattr(importlib.import_module(entry[0]), entry[1])(m))
    return out
