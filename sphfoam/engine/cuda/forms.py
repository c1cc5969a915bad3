"""The device forms of the models' run-time hooks (``sphfoam.models.base.HOOK_NAMES``).

A model's hooks run in Python on host arrays; the CUDA runtime keeps its arrays on the
device, so a model with hooks runs there only through a *device form*: a class that does
on device arrays what the hooks do, at the same points of a step. A model names its own
(``PipelineModel.device_form``, "module:Class") and the hooks it stands for
(``device_hooks``): the engine names no model. The refusals
(:func:`sphfoam.engine.cuda.build.refusals`) refuse a model with a hook no device form
stands for, by name; :class:`~sphfoam.engine.cuda.runtime.CudaSimulation` makes one device
form per selected model that has one (``cls(model)``) and calls its methods with a
:class:`~sphfoam.engine.cuda.context.DeviceContext` ``run`` at fixed points:

``attach(run)``                        once, when the simulation is built
``add_particles(run, cell, counts)``   at a list build, after binning (``cell`` per
                                       particle, ``counts`` per cell, the extra last cell
                                       for particles that leave): may append particles
                                       (``run.append``) and returns the cell array of all
``after_sort(run, order)``             after the sort by cell (and the removal of those
                                       binned outside)
``keeps_neighbours(run)``              whether what it added at the build still serves
``before_evaluation(run)``             before every equation of state, rates or density pass
``before_passes(run)``                 after it, before the pair passes of the rates and the
                                       density pass (not the equation of state's)
``after_rates(run)``                   after every evaluation of the rates
``walls_moved(run, offsets, velocities)``  prescribed wall motion at a stage time
``after_step(run)``                    at the end of each step
``summary()``                          a line for the end of the run's log

This module imports no CUDA: the refusals read it on any machine.
"""

from __future__ import annotations

import importlib


def covered_hooks(model) -> tuple[str, ...]:
    """The hooks of ``model`` its device form stands for (none without one)."""
    return tuple(getattr(model, "device_hooks", ())) if getattr(model, "device_form", "") \
        else ()


def device_forms(sel) -> list:
    """One device form per selected model that has one (in selection order)."""
    out = []
    for m in sel.models():
        form = getattr(m, "device_form", "")
        if form:
            module, cls = form.split(":")
            out.append(getattr(importlib.import_module(module), cls)(m))
    return out
