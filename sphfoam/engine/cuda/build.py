"""Build the CUDA pipeline of a selection: refuse what has no device form (by name), generate
the module (:mod:`sphfoam.engine.cuda.emit`), cache it on disk and import it. numba-cuda
compiles each kernel at its first launch."""

from __future__ import annotations

import numpy as np

from sphfoam.engine.cuda.forms import covered_hooks
from sphfoam.engine.generated import load_generated
from sphfoam.engine.plan import Selection

#: the core coefficients every pipeline reads first (the same slots as the CPU's)
CORE = ("h", "inv_h", "support2", "eta2", "gx", "gy")

#: the run-time hooks (``sphfoam.models.base.HOOK_NAMES``): Python between stages on host
#: arrays, which the device runtime does not run; a model's device form
#: (:mod:`sphfoam.engine.cuda.forms`) stands for those it names
_HOOKS = ("attach", "before_neighbours", "add_particles", "keeps_neighbours", "after_sort",
          "before_evaluation", "after_rates", "after_density_rate", "walls_moved",
          "after_step", "advection_velocity", "summary")


class Unsupported(ValueError):
    """A selected model or case feature with no device form (the message names it)."""


def refusals(sel: Selection, motions=None) -> list[str]:
    """What of ``sel`` the CUDA backend has no form of, each named ("family name: why")."""
    out = []
    if sel.dim != 2:
        out.append("3-D cases: the CUDA backend runs two dimensions")
    for m in sel.models():
        covered = covered_hooks(m)
        hooks = [h for h in _HOOKS if m.implements(h) and h not in covered]
        if hooks:
            out.append(f"{m.family} {m.name!r}: its run-time hooks ({', '.join(hooks)}) run "
                       "on host arrays (no device form)")
    return out


def check_supported(sel: Selection, motions=None) -> None:
    bad = refusals(sel, motions)
    if bad:
        raise Unsupported("backend cuda cannot run this case: " + "; ".join(bad)
                          + " (use backend cpu)")


def parameters(sel: Selection, ctx, domain_lo, domain_hi) -> dict[str, float]:
    """The coefficient vector by name: h, 1/h, support^2, eta^2, gravity, the periods, then
    the models' own (each under its prefix)."""
    h = ctx.h
    support = ctx.support or sel.kernel.support_radius(h)
    params = dict(h=h, inv_h=1.0 / h, support2=support * support, eta2=ctx.eta2,
                  gx=ctx.g[0], gy=ctx.g[1])
    for i, axis in enumerate("xy"):
        if sel.periodic(axis):
            params[f"l{axis}"] = float(domain_hi[i] - domain_lo[i])
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

        d = [cuda.to_device(np.ascontiguousarray(a, dtype=self.prm.dtype))
             for a in (rho, p, c)]
        n = rho.shape[0]
        self.module.equation_of_state[max(1, (n + 127) // 128), 128](*d, cuda.to_device(prm))
        p[:] = d[1].copy_to_host()
        c[:] = d[2].copy_to_host()


def build_updates(integrator, dim: int = 2):
    """The module of ``integrator``'s particle updates as kernels (cached on disk)."""
    from sphfoam.engine.cuda.emit import generate_updates

    return load_generated(generate_updates(integrator, dim), "cudaupdate")[0]
