"""Build the CUDA pipeline of a selection: refuse what has no device form (by name), generate
the module (:mod:`sphfoam.engine.cuda.emit`), cache it on disk and import it. numba-cuda
compiles each kernel at its first launch."""

from __future__ import annotations

import dataclasses

import numpy as np

from sphfoam.engine.cuda.forms import covered_hooks
from sphfoam.engine.generated import load_generated
from sphfoam.engine.hookforms import uncovered
from sphfoam.engine.plan import Selection, core_parameters, missing_dimension

#: the core coefficients every pipeline reads first (the same slots as the CPU's; "gz" too
#: in 3-D)
CORE = ("h", "inv_h", "support2", "eta2", "gx", "gy")

#: the run-time hooks (``sphfoam.models.base.HOOK_NAMES``): Python between stages on host
#: arrays, which the device runtime runs only in their declared forms
#: (``sphfoam.engine.hookforms``, :mod:`sphfoam.engine.cuda.hooks`) or through the model's
#: device form (:mod:`sphfoam.engine.cuda.forms`)
_HOOKS = ("attach", "before_neighbours", "add_particles", "keeps_neighbours", "after_sort",
          "before_evaluation", "before_passes", "after_rates", "after_density_rate",
          "walls_moved", "after_step", "advection_velocity", "summary")


class Unsupported(ValueError):
    """A selected model or case feature with no device form (the message names it)."""


def refusals(sel: Selection, motions=None) -> list[str]:
    """What of ``sel`` the CUDA backend has no form of, each named ("family name: why")."""
    out = []
    for m in sel.models():
        why = missing_dimension(m, sel.dim)
        if why is not None:
            out.append(why)
            continue
        if getattr(m, "device_form", "") and sel.dim not in getattr(m, "device_dims",
                                                                    (2, 3)):
            out.append(f"{m.family} {m.name!r}: its device form has no {sel.dim}-D form")
            continue
        covered = covered_hooks(m)
        hooks = [h for h in uncovered(m, _HOOKS) if h not in covered]
        if hooks:
            out.append(f"{m.family} {m.name!r}: its run-time hooks ({', '.join(hooks)}) run "
                       "on host arrays (no device form)")
    for m in (motions or {}).values():
        if sel.dim not in getattr(m, "dims", (2,)):
            out.append(f"motion {m.name!r}: no {sel.dim}-D form")
    return out


def check_supported(sel: Selection, motions=None) -> None:
    bad = refusals(sel, motions)
    if bad:
        raise Unsupported("backend cuda cannot run this case: " + "; ".join(bad)
                          + " (use backend cpu)")


def parameters(sel: Selection, ctx, domain_lo, domain_hi) -> dict[str, float]:
    """The coefficient vector by name: the core (:func:`~sphfoam.engine.plan.core_parameters`:
    h, 1/h, support^2, eta^2, gravity per component, the periods), half the periods, then
    the models' own (each under its prefix)."""
    if getattr(ctx, "dim", sel.dim) != sel.dim:
        # the models' coefficients (the kernel's alpha_d / h^d) in the selection's dimension
        ctx = dataclasses.replace(ctx, dim=sel.dim)
    params = core_parameters(sel, ctx, domain_lo, domain_hi)
    for axis in "xyz"[:sel.dim]:
        if sel.periodic(axis):
            params[f"half_l{axis}"] = 0.5 * params[f"l{axis}"]
    for mdl in sel.models():
        for k, val in mdl.params(ctx).items():
            if not k.startswith(mdl.prefix):
                raise ValueError(f"{mdl!r}: parameter {k!r} must start with {mdl.prefix!r}")
            params[k] = float(val)
    return {k: float(v) for k, v in params.items()}


class CudaPipeline:
    """The generated kernels of one selection and its coefficients (host copy)."""

    def __init__(self, sel: Selection, ctx, domain_lo, domain_hi, motions=None):
        from sphfoam.engine.cuda.emit import generate_source

        check_supported(sel, motions)
        self.selection = sel
        self.params = parameters(sel, ctx, domain_lo, domain_hi)
        names = list(self.params)
        self.src = generate_source(sel, names)
        self.module, self.source_path = load_generated(self.src, "cudapipeline")
        self.prm = np.array([self.params[k] for k in names], dtype=sel.dtype)
        self.h = float(self.params["h"])
        self.support_radius = float(np.sqrt(self.params["support2"]))
        #: numba-cuda compiles each kernel at its first launch (in the first step)
        self.compile_seconds = 0.0
        self.cache_hit = False

    def equation_of_state(self, rho, p, c, prm):
        """The equation of state on host arrays (diagnostics): copied there and back."""
        from numba import cuda

        from sphfoam.engine.cuda.device import THREADS, blocks

        d = [cuda.to_device(np.ascontiguousarray(a, dtype=self.prm.dtype))
             for a in (rho, p, c)]
        n = rho.shape[0]
        self.module.equation_of_state[blocks(n), THREADS](*d, cuda.to_device(prm))
        p[:] = d[1].copy_to_host()
        c[:] = d[2].copy_to_host()


def build_updates(integrator, dim: int = 2):
    """The module of ``integrator``'s particle updates as kernels (cached on disk)."""
    from sphfoam.engine.cuda.emit import generate_updates

    return load_generated(generate_updates(integrator, dim), "cudaupdate")[0]
