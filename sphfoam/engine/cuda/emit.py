"""The CUDA emitter: the pipeline module of ``cuda.jit`` kernels, from the plan.

The loop bodies of :mod:`sphfoam.engine.bodies` (the gather form: each particle ``a`` walks
its own full neighbour list and writes only its own outputs, so no atomics and results that
do not depend on the scheduling) go into one kernel per stage, one thread per particle
(``a = cuda.grid(1)``). The models' helper functions (their ``imports()`` lines, plain
jitted scalar functions) are compiled as device functions
(:func:`sphfoam.engine.cuda.device.device_function`). The cell walk that counts and fills
the neighbour list visits the cells by row (rows by layer in 3-D) and the particles by cell,
as the CPU's does: the same lists in the same order. The integrators' particle updates
(:mod:`sphfoam.engine.stepping`) become kernels the same way (:func:`generate_updates`).
"""

from __future__ import annotations


from sphfoam._version import __version__
from sphfoam.engine import generated
from sphfoam.engine.bodies import (LoopBodies, _block, cell_range, components, expand,
                                   particle_load)
from sphfoam.engine.plan import Plan, Selection

#: the arguments of every kernel over particles and their lists
def _args(dim: int, cache: bool) -> str:
    return ", ".join([*(ax for ax, _ in components(dim)), *(v for _, v in components(dim)),
                      "rho, p, c, m, kind, nb_start, nb_idx, prm, aux, fld"]
                     + (["pc"] if cache else []))


_HEAD = """\
    a = cuda.grid(1)
    if a >= kind.shape[0]:
        return
"""


def _walk(sel: Selection, body: str) -> str:
    """The 3 x 3 (x 3) cell walk around ``a`` (cells by row, rows by layer, particles by
    cell: the CPU's order, cells numbered (cz ncy + cy) ncx + cx, the three cells of an
    axis as :func:`~sphfoam.engine.bodies.cell_range` gives them), ``body`` for each b
    within ``reach2`` (b != a; where ``skip``, no pair of two non-fluid particles).
    Periodic axes wrap the cell index and the pair's relative position."""
    axes = [ax for ax, _ in components(sel.dim)]
    out = [f"i{ax} = min(max(int(({ax}a - {ax}0) * inv_cell), 0), nc{ax} - 1)" for ax in axes]
    ind = ""
    for ax in reversed(axes):
        lo, hi, cell = cell_range(sel, ax, f"i{ax}", f"nc{ax}", f"c{ax}")
        out.append(f"{ind}for c{ax}0 in range({lo}, {hi}):")
        out.append(f"{ind}    c{ax} = {cell}")
        ind += "    "
    out.append(f"{ind}cc = {'(cz * ncy + cy)' if sel.dim == 3 else 'cy'} * ncx + cx")
    out.append(f"{ind}for b in range(cell_start[cc], cell_start[cc + 1]):")
    ind += "    "
    for ax in axes:
        out.append(f"{ind}d{ax}_ab = {ax}a - {ax}[b]")
        if sel.periodic(ax):
            out += [f"{ind}if d{ax}_ab > 0.5 * l{ax}:", f"{ind}    d{ax}_ab -= l{ax}",
                    f"{ind}elif d{ax}_ab < -0.5 * l{ax}:", f"{ind}    d{ax}_ab += l{ax}"]
    out.append(f"{ind}r2 = " + " + ".join(f"d{ax}_ab * d{ax}_ab" for ax in axes))
    out.append(f"{ind}if r2 >= reach2 or b == a or not (fluid_a or kind[b] == FLUID):")
    out.append(f"{ind}    continue")
    out.append(_block(body, len(ind)))
    return "\n".join(out)


def helper_lines(imports) -> tuple[str, set[str]]:
    """The models' import lines with each imported helper bound to its device form:
    ``from M import f as g`` becomes ``from M import f as _host_g`` and
    ``g = device_function(_host_g)``. Returns (code, the helpers' names)."""
    lines, names = [], set()
    for line in imports:
        line = line.strip()
        if not line.startswith("from ") or " import " not in line:
            lines.append(line)
            continue
        mod, items = line[5:].split(" import ", 1)
        for item in items.split(","):
            item = item.strip()
            src, _, as_ = item.partition(" as ")
            name = (as_ or src).strip()
            names.add(name)
            lines.append(f"from {mod.strip()} import {src.strip()} as _host_{name}")
            lines.append(f"{name} = device_function(_host_{name})")
    return "\n".join(lines), names


def generate_source(sel: Selection, param_names: list[str]) -> str:
    """Python source of the CUDA pipeline module for ``sel`` (2-D or 3-D)."""
    plan = Plan(sel)
    asm = LoopBodies(plan, precision=sel.precision)
    dim = sel.dim
    helpers_code, helpers = helper_lines(sorted({ln for m in plan.models
                                                 for ln in m.imports()}))
    bind = "\n".join(f"{name} = prm[{i}]" for i, name in enumerate(param_names))
    cache = plan.cache
    ARGS = _args(dim, bool(cache))
    PLOAD = particle_load(dim)
    X = ", ".join(ax for ax, _ in components(dim))
    #: the cell grid (``CellList.grid``): origin, 1/side, counts per axis
    GRID = ", ".join([f"{ax}0" for ax in X.split(", ")] + ["inv_cell"]
                     + [f"nc{ax}" for ax in X.split(", ")])
    LOAD_X = expand("@a = @[a]", dim)
    consts = "\n".join([f"I_{a} = {i}" for i, a in enumerate(plan.aux)]
                       + [f"F_{a} = {i}" for i, a in enumerate(plan.fields)]
                       + [f"J_{a} = {i}" for i, a in enumerate(cache)])
    pre_before = tuple(x for x in ("rates", "density", "filter")
                       if x == "rates" or plan.needs_prepass(x)) \
        if plan.has_stage("prepass") else ()
    eos = asm.particle_code(plan.stage("particle", "all"), "final")
    out_a = ", ".join(f"out_a{ax}" for ax, _ in components(dim))
    prepass = asm.prepass_loops() if plan.has_stage("prepass") else []
    parts = [f'''"""sphfoam CUDA pipeline, generated for: {sel.describe()}; adjustTimeStep={sel.adjust_time_step}.

Generated by sphfoam {__version__} (sphfoam.engine.cuda.emit); do not edit.
"""
import math

import numpy as np
from numba import cuda

from sphfoam.engine.cuda.device import device_function

{helpers_code}

FLUID = 0
WALL = 1
GHOST = 2
DIM = {dim}
PARAMS = {tuple(param_names)!r}
AUX = {tuple(plan.aux)!r}
FIELDS = {tuple(plan.fields)!r}
PAIR_CACHE = {tuple(cache)!r}
{consts}
#: the passes the prepass runs before (the rates always)
PREPASS_BEFORE = {pre_before!r}
#: the prepass runs once per step, before the step's first evaluation
PREPASS_ONCE = {plan.prepass_once()}
#: the prepass's loops, one kernel each (prepass_0, prepass_1, ...)
N_PREPASS = {len(prepass)}
FLUID_PAIRS_ONLY = {plan.fluid_pairs_only}
HAS_STEP = {plan.has_stage("step")}
HAS_FILTER = {plan.has_stage("filter")}


@cuda.jit
def equation_of_state(rho, p, c, prm):
    """The equation of state of every particle (a stage with no neighbours)."""
    a = cuda.grid(1)
    if a >= rho.shape[0]:
        return
{_block(bind, 4)}
{_block(eos or "pass", 4)}


@cuda.jit
def count_neighbours({X}, kind, skip, cell_start, {GRID}, prm, reach2, count):
    """Neighbours of particle a within sqrt(reach2) (the cell side), from the cells."""
{_HEAD.replace("kind.shape", "x.shape")}{_block(bind, 4)}
{_block(LOAD_X, 4)}
    fluid_a = (not skip) or kind[a] == FLUID
    n_a = 0
{_block(_walk(sel, "n_a += 1"), 4)}
    count[a] = n_a


@cuda.jit
def fill_neighbours({X}, kind, skip, cell_start, {GRID}, prm, reach2, nb_start, nb_idx):
    """The neighbour list of a, nb_idx[nb_start[a]:nb_start[a + 1]], in the order of the
    cell walk (the CPU's order)."""
{_HEAD.replace("kind.shape", "x.shape")}{_block(bind, 4)}
{_block(LOAD_X, 4)}
    fluid_a = (not skip) or kind[a] == FLUID
    k = nb_start[a]
{_block(_walk(sel, "nb_idx[k] = b" + chr(10) + "k += 1"), 4)}
''']
    for i, body in enumerate(prepass):
        parts.append(f'''

@cuda.jit
def prepass_{i}({ARGS}):
    """Prepass loop {i}: per-particle quantities the pair terms need."""
{_HEAD}{_block(bind, 4)}
{_block(PLOAD, 4)}
{_block(body, 4)}
''')
    parts.append(f'''

@cuda.jit
def rates({ARGS}, {out_a}, out_drho, out_sigma, want_sigma):
    """dv/dt, drho/dt and sigma of T(3.89) of particle a (gather over its full list)."""
{_HEAD}{_block(bind, 4)}
{_block(PLOAD, 4)}
{_block(expand("acc_@ = 0.0", dim), 4)}
    drho_a = 0.0
    sigma_a = 0.0
    if kind[a] == FLUID:
{_block(asm.gather(plan.stage("rates", "fluid"), sigma=sel.adjust_time_step, cache="read"), 8)}
{_block(expand("acc_@ += g@", dim), 8)}
    else:
{_block(asm.wall_gather("rates"), 8)}
{_block(expand("out_a@[a] = acc_@", dim), 4)}
    out_drho[a] = drho_a
    if want_sigma:
        out_sigma[a] = sigma_a


@cuda.jit
def density_rate({ARGS}, out_drho):
    """drho/dt alone (the last stage of Monaghan's 2007 scheme, T(3.96))."""
{_HEAD}{_block(bind, 4)}
{_block(PLOAD, 4)}
    drho_a = 0.0
    if kind[a] == FLUID:
{_block(asm.gather(plan.stage("density", "fluid"), cache=plan.cache_mode("density")), 8)}
    else:
{_block(asm.wall_gather("density"), 8)}
    out_drho[a] = drho_a
''')
    if plan.has_stage("step"):
        fluid_step = plan.stage("step", "fluid")
        wall_step = plan.stage("step", "wall")
        fluid_code = (asm.gather(fluid_step) if any(not t.on_demand for t in fluid_step)
                      else "pass")
        wall_code = (asm.gather(wall_step) if any(not t.on_demand for t in wall_step)
                     else "pass")
        parts.append(f'''

@cuda.jit
def step_pass({ARGS}):
    """Once per step, after the re-sort: per-step state of the particles."""
{_HEAD}{_block(bind, 4)}
{_block(PLOAD, 4)}
    if kind[a] == FLUID:
{_block(fluid_code, 8)}
    else:
{_block(wall_code, 8)}
''')
    if plan.has_stage("filter"):
        filt = plan.stage("filter", "fluid")
        owner = next(t.owner for t in filt if not t.on_demand)
        parts.append(f'''

@cuda.jit
def density_filter({ARGS}, out_rho):
    """{owner.doc}"""
{_HEAD}{_block(bind, 4)}
{_block(PLOAD, 4)}
    rho_new = rhoa
    if kind[a] == FLUID:
{_block(asm.gather(filt), 8)}
    out_rho[a] = rho_new
''')
    src = "".join(parts)
    if sel.precision == "single":
        src = _working_precision(src, helpers)
    return src


#: kernels whose arithmetic is in the working precision (not the cell walk: positions)
_WORKING = ("equation_of_state", "rates", "density_rate", "step_pass", "density_filter")


def _working_precision(src: str, helpers) -> str:
    """The kernels of ``_WORKING`` and the prepasses in float32
    (:func:`sphfoam.engine.generated.working_precision`)."""
    return generated.working_precision(
        src, helpers, lambda name: name in _WORKING or name.startswith("prepass_"))


def generate_updates(integrator, dim: int = 2) -> str:
    """Python source of ``integrator``'s particle updates as kernels ``update_<name>``, one
    thread per particle; arguments: its arrays (``ARRAYS[name]``), then its scalars."""
    from sphfoam.engine.stepping import arrays_of, expand as sexpand

    parts = [f'''"""sphfoam CUDA particle updates of the integrator {integrator.name!r} ({dim}-D).

Generated by sphfoam {__version__} (sphfoam.engine.cuda.emit); do not edit.
"""
from numba import cuda

FLUID = 0
WALL = 1
GHOST = 2
ARRAYS = {{}}
''']
    for upd in integrator.updates:
        arrays = arrays_of(upd, dim)
        parts.append(f'''

ARRAYS[{upd.name!r}] = {tuple(arrays)!r}


@cuda.jit
def update_{upd.name}({", ".join(arrays + list(upd.scalars))}):
    a = cuda.grid(1)
    if a >= {arrays[0]}.shape[0]:
        return
{_block(sexpand(upd.setup, dim), 4)}
{_block(sexpand(upd.code, dim), 4)}
''')
    return "".join(parts)
