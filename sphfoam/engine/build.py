"""Build a pipeline: generate its module, cache it on disk, import and compile it.

The module for a selection (:func:`sphfoam.engine.emit_cpu.generate_source`) is written to
``<cache>/pipelines/<key>/``, where ``key`` hashes the generated source together with the
source of sphfoam's models and engine, then imported; its functions are compiled by numba
with ``cache=True``, so a second run of the same selection loads machine code from disk.
(Closures over jitted functions never reach numba's disk cache; generated modules do.)
"""

from __future__ import annotations

import dataclasses

import time

import numpy as np

from sphfoam.engine.generated import load_generated
from sphfoam.engine.emit_cpu import generate_source, generate_updates
from sphfoam.engine.pipeline import Pipeline, core_param_names
from sphfoam.engine.plan import Selection, core_parameters


def build_pipeline(sel: Selection, ctx, core: dict[str, float] | None = None, *,
                   domain_lo=(0.0, 0.0, 0.0), domain_hi=(1.0, 1.0, 1.0)) -> Pipeline:
    """Generate (or reuse) the module for ``sel``, import it and compile it.

    ``core`` (h, inv_h, support2, eta2, gravity and, for periodic axes, lx, ly, lz) defaults to
    :func:`core_parameters` of ``sel`` and ``ctx``; given, it must agree with them.
    """
    if getattr(ctx, "dim", sel.dim) != sel.dim:
        # the models' coefficients (the kernel's alpha_d / h^d) in the plan's dimension
        ctx = dataclasses.replace(ctx, dim=sel.dim)
    derived = core_parameters(sel, ctx, domain_lo, domain_hi)
    if core is None:
        core = derived
    else:
        for k in core_param_names(sel.dim):
            if not np.isclose(float(core[k]), derived[k], rtol=1e-12, atol=0.0):
                raise ValueError(f"core parameter {k} = {core[k]!r} differs from the one the "
                                 f"selection and case context give ({derived[k]!r})")
    params: dict[str, float] = {k: float(core[k]) for k in core_param_names(sel.dim)}
    for axis in "xyz"[:sel.dim]:
        if sel.periodic(axis):
            params[f"l{axis}"] = float(core[f"l{axis}"])
            params[f"half_l{axis}"] = 0.5 * float(core[f"l{axis}"])
    for mdl in sel.models():
        for k, val in mdl.params(ctx).items():
            if not k.startswith(mdl.prefix):
                raise ValueError(f"{mdl!r}: parameter {k!r} must start with {mdl.prefix!r}")
            params[k] = float(val)
    names = list(params)
    src = generate_source(sel, names)
    module, path = load_generated(src, "pipeline")
    prm = np.array([params[k] for k in names], dtype=sel.dtype)
    t0 = time.perf_counter()
    funcs = _warm_up(module, prm)
    seconds = time.perf_counter() - t0
    hits = sum(len(f.stats.cache_hits) for f in funcs)
    return Pipeline(module, prm, path, seconds, hits > 0, sel, dict(core),
                    fluid_pairs_only=bool(getattr(module, "FLUID_PAIRS_ONLY", False)))


def _warm_up(module, prm):
    """Compile (or load from numba's cache) every function with the real argument types."""
    n = 2
    dt = prm.dtype               # the working precision (positions and fields: double)
    f = np.zeros(n, dtype=dt)
    dim = getattr(module, "DIM", 2)
    x = np.array([0.0, 0.5 * float(prm[0])])
    coords = (x, *(np.zeros(n) for _ in range(dim - 1)))
    kind = np.zeros(n, dtype=np.int64)
    m = np.ones(n, dtype=dt)
    rho = np.full(n, 1000.0, dtype=dt)
    cell_start = np.array([0, 2], dtype=np.int64)
    aux = np.zeros((len(module.AUX), n), dtype=dt)
    fld = np.zeros((len(module.FIELDS), n))
    module.equation_of_state(rho, f.copy(), f.copy(), prm)
    count = np.zeros(n, dtype=np.int64)
    cells = (-1.0, -1.0, 1e-3, 1, 1) if dim == 2 else (-1.0, -1.0, -1.0, 1e-3, 1, 1, 1)
    grid = (*coords, kind, False, cell_start, *cells, prm, float(prm[0]) ** 2 * 16.0)
    module.count_neighbours(*grid, count)
    # sized from the count: with periodic axes the single cell is walked 3 x 3 (x 3)
    # times, so each particle finds its neighbour up to 9 (27) times (a fixed list of two
    # overflowed)
    nb_start = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    nb_idx = np.zeros(int(nb_start[-1]), dtype=np.uint32)
    module.fill_neighbours(*grid, nb_start, nb_idx)
    args = (*coords, *(f for _ in range(dim)), rho, f, f, m, kind, nb_start, nb_idx, prm,
            aux, fld)
    if getattr(module, "PAIR_CACHE", ()):
        args += (np.zeros((len(module.PAIR_CACHE), nb_idx.shape[0]), dtype=dt),)
    funcs = [module.equation_of_state, module.count_neighbours, module.fill_neighbours,
             module.rates, module.density_rate]
    module.rates(*args, *(f.copy() for _ in range(dim)), f.copy(), f.copy())
    module.density_rate(*args, f.copy())
    if hasattr(module, "prepass"):
        module.prepass(*args)
        funcs.append(module.prepass)
    if hasattr(module, "density_filter"):
        module.density_filter(*args, f.copy())
        funcs.append(module.density_filter)
    if hasattr(module, "step_pass"):
        module.step_pass(*args)
        funcs.append(module.step_pass)
    # [nb_mid | band starts | the bands' dealt order | nb]: one band of both particles (in
    # 3-D also the colour starts before nb: the band is colour 0's)
    half = np.array([0] * n + [0, n, 0] + ([0, 1, 1, 1, 1] if dim == 3 else []) + [1],
                    dtype=np.uint32)
    if hasattr(module, "rates_half"):
        module.rates_half(*args, half, *(f.copy() for _ in range(dim)), f.copy(), f.copy())
        funcs.append(module.rates_half)
    if hasattr(module, "density_half"):
        module.density_half(*args, half, f.copy())
        funcs.append(module.density_half)
    if hasattr(module, "prepass_half"):
        module.prepass_half(*args, half, np.zeros((len(module.PREPASS_SUMS), n), dtype=dt))
        funcs.append(module.prepass_half)
    return funcs


def build_updates(integrator, dim: int = 2):
    """The compiled module of ``integrator``'s particle updates (``update_<name>``,
    ``ARRAYS``), generated and cached as the pipelines are; numba compiles each function at
    its first call (for the state's precision) and caches it on disk."""
    return load_generated(generate_updates(integrator, dim), "update")[0]
