"""The CPU emitter: the pipeline module for numba's CPU threads, from the plan.

The loop bodies (:mod:`sphfoam.engine.bodies`) go into ``@njit(parallel=True)`` functions,
a ``prange`` over the particles (or, for the half-list loops, over bands of cell rows in two
colours); the cell walk that builds the neighbour list reads the rows of the cell grid as
contiguous slices of the sorted particles. The working precision is a property of the
emitted code: in single precision the loops of the working arrays carry float32 literals and
round the models' helper results and the pairs' relative positions to float32
(:func:`working_precision`); the cell walk stays in double.
"""

from __future__ import annotations

from sphfoam._version import __version__
from sphfoam.engine import generated
from sphfoam.engine.bodies import (LoopBodies, _block, _indent, cell_range, components, expand,
                                   particle_load)
from sphfoam.engine.fastmath import FASTMATH_SOURCE
from sphfoam.engine.plan import Plan, Selection


#: the loop of the half-list functions over the particles of each band of cell rows, in two
#: colours (see ``rates_half``'s docstring), with a's state loaded
_HALF_BANDS = """\
n = x.shape[0]
nb = int(half[half.shape[0] - 1])
for colour in range(2):
    dealt = n + nb + 1 + colour * ((nb + 1) // 2)
    for j in prange((nb + 1 - colour) // 2):
        ib = n + int(half[dealt + j])
        for a in range(half[ib], half[ib + 1]):
{body}"""


#: the 3-D form: blocks of rows within layers of cells, in four colours whose segments of the
#: dealt order start at the colour starts (``neighbours.half_blocks``)
_HALF_BLOCKS = """\
n = x.shape[0]
nb = int(half[half.shape[0] - 1])
order = n + nb + 1
for colour in range(4):
    c0 = int(half[order + nb + colour])
    for j in prange(int(half[order + nb + colour + 1]) - c0):
        ib = n + int(half[order + c0 + j])
        for a in range(half[ib], half[ib + 1]):
{body}"""


def _half_bands(dim: int, *parts: str) -> str:
    """``_HALF_BANDS`` (``_HALF_BLOCKS`` in 3-D) with ``parts`` (code of particle a) as the
    body."""
    body = "\n".join([particle_load(dim), "ma = m[a]\nkinda = kind[a]",
                      *(_block(x, 0) for x in parts)])
    return (_HALF_BLOCKS if dim == 3 else _HALF_BANDS).format(body=_block(body, 12))


#: the 3 x 3 cell walk around particle ``a``, run once per step to build the neighbour list
_CELLS = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
for cy0 in range({ylo}, {yhi}):
    cy = {cy}
    for cx0 in range({xlo}, {xhi}):
        cx = {cx}
        cc = cy * ncx + cx
        for b in range(cell_start[cc], cell_start[cc + 1]):
            dx_ab = xa - x[b]
            dy_ab = ya - y[b]
{wrap}            r2 = dx_ab * dx_ab + dy_ab * dy_ab
            if r2 >= reach2 or b == a{keep}:
                continue
{body}
"""


#: the same walk where the x axis is not periodic: the three cells of a row are consecutive,
#: so their particles are one range of the sorted arrays (the same candidates in the same
#: order); ``ok`` says whether b is listed, with no branch to mispredict (about 1/3 of the
#: candidates in the 3 x 3 cells are within the cell side)
_CELLS_ROWS = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
cx_lo = max(ix - 1, 0)
cx_hi = min(ix + 2, ncx)
for cy0 in range({ylo}, {yhi}):
    row = {cy} * ncx
    lo = cell_start[row + cx_lo]
    hi = cell_start[row + cx_hi]{rowskip}
    xs = x[lo:hi]
    ys = y[lo:hi]
{kslice}    for j in range(hi - lo):
        b = lo + j
        dx_ab = xa - xs[j]
        dy_ab = ya - ys[j]
{wrap}        r2 = dx_ab * dx_ab + dy_ab * dy_ab
        ok = (r2 < reach2){notself}{keep}
{body}{after}
"""


#: the 3 x 3 x 3 cell walk in three dimensions (cells numbered (cz ncy + cy) ncx + cx)
_CELLS_3D = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
iz = min(max(int((za - z0) * inv_cell), 0), ncz - 1)
for cz0 in range({zlo}, {zhi}):
    cz = {cz}
    for cy0 in range({ylo}, {yhi}):
        cy = {cy}
        for cx0 in range({xlo}, {xhi}):
            cx = {cx}
            cc = (cz * ncy + cy) * ncx + cx
            for b in range(cell_start[cc], cell_start[cc + 1]):
                dx_ab = xa - x[b]
                dy_ab = ya - y[b]
                dz_ab = za - z[b]
{wrap}                r2 = dx_ab * dx_ab + dy_ab * dy_ab + dz_ab * dz_ab
                if r2 >= reach2 or b == a{keep}:
                    continue
{body}
"""

#: the same where x is not periodic: the three cells of a row along x, one range
_CELLS_ROWS_3D = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
iz = min(max(int((za - z0) * inv_cell), 0), ncz - 1)
cx_lo = max(ix - 1, 0)
cx_hi = min(ix + 2, ncx)
for cz0 in range({zlo}, {zhi}):
    cz = {cz}
    for cy0 in range({ylo}, {yhi}):
        row = (cz * ncy + {cy}) * ncx
        lo = cell_start[row + cx_lo]
        hi = cell_start[row + cx_hi]{rowskip}
        xs = x[lo:hi]
        ys = y[lo:hi]
        zs = z[lo:hi]
{kslice}        for j in range(hi - lo):
            b = lo + j
            dx_ab = xa - xs[j]
            dy_ab = ya - ys[j]
            dz_ab = za - zs[j]
{wrap}            r2 = dx_ab * dx_ab + dy_ab * dy_ab + dz_ab * dz_ab
            ok = (r2 < reach2){notself}{keep}
{body}{after}
"""


#: where the list leaves out pairs of two non-fluid particles, a non-fluid particle skips a
#: row with no fluid particle (``fluid_upto``: the fluid particles before each sorted index)
_ROW_SKIP = """
    if not fluid_a and fluid_upto[hi] == fluid_upto[lo]:
        continue"""


def _cell_walk_3d(bodies, body: str, rows: str | None, count: bool, after: str) -> str:
    sel = bodies.plan.sel
    wrap = bodies._wrap()
    xlo, xhi, cx = cell_range(sel, "x", "ix", "ncx", "cx")
    ylo, yhi, cy = cell_range(sel, "y", "iy", "ncy", "cy")
    zlo, zhi, cz = cell_range(sel, "z", "iz", "ncz", "cz")
    fo = bodies.plan.fluid_pairs_only
    if rows is not None and not sel.periodic_x:
        notself = "" if count and bodies.plan.counts_self() else " & (b != a)"
        cy = f"({cy})"
        return _CELLS_ROWS_3D.format(ylo=ylo, yhi=yhi, cy=cy, zlo=zlo, zhi=zhi, cz=cz,
                                     notself=notself,
                                     keep=" & (fluid_a | (ks[j] == FLUID))" if fo else "",
                                     kslice="        ks = kind[lo:hi]\n" if fo else "",
                                     rowskip=_ROW_SKIP.replace("\n", "\n    ") if fo else "",
                                     wrap=_block(wrap, 12) + ("\n" if wrap else ""),
                                     body=_block(rows, 12),
                                     after=("\n" + _block(after, 8)) if after else "")
    return _CELLS_3D.format(xlo=xlo, xhi=xhi, ylo=ylo, yhi=yhi, zlo=zlo, zhi=zhi, cx=cx,
                            cy=cy, cz=cz,
                            keep=(" or not (fluid_a or kind[b] == FLUID)" if fo else ""),
                            wrap=_block(wrap, 16) + ("\n" if wrap else ""),
                            body=_block(body, 16))


def cell_walk(bodies, body: str, rows: str | None = None, count: bool = False,
              after: str = "") -> str:
    """The 3 x 3 cell gather around particle ``a`` (within ``reach2``), for the list:
    ``body`` for each b within reach, or, where x is not periodic, ``rows`` for every
    candidate of the three row ranges (contiguous slices of the sorted particles), with
    ``ok`` true for those within reach (and, for ``count`` where ``counts_self``, for a
    itself), then ``after`` once per row (its candidates are ``lo`` .. ``hi`` - 1)."""
    sel = bodies.plan.sel
    if sel.dim == 3:
        return _cell_walk_3d(bodies, body, rows, count, after)
    xlo, xhi, cx = cell_range(sel, "x", "ix", "ncx", "cx")
    ylo, yhi, cy = cell_range(sel, "y", "iy", "ncy", "cy")
    if rows is not None and not sel.periodic_x:
        cy = f"({cy})"
        wrap = bodies._wrap()
        notself = "" if count and bodies.plan.counts_self() else " & (b != a)"
        fo = bodies.plan.fluid_pairs_only
        return _CELLS_ROWS.format(ylo=ylo, yhi=yhi, cy=cy, notself=notself,
                                  keep=" & (fluid_a | (ks[j] == FLUID))" if fo else "",
                                  kslice="    ks = kind[lo:hi]\n" if fo else "",
                                  rowskip=_ROW_SKIP if fo else "",
                                  wrap=_block(wrap, 8) + ("\n" if wrap else ""),
                                  body=_block(rows, 8),
                                  after=("\n" + _block(after, 4)) if after else "")
    wrap = bodies._wrap()
    return _CELLS.format(xlo=xlo, xhi=xhi, ylo=ylo, yhi=yhi, cx=cx, cy=cy,
                         keep=(" or not (fluid_a or kind[b] == FLUID)"
                               if bodies.plan.fluid_pairs_only else ""),
                         wrap=_block(wrap, 12) + ("\n" if wrap else ""),
                         body=_block(body, 12))


def _args_base(dim: int) -> str:
    """The arguments every loop over particles takes: positions, velocities, the state."""
    return ", ".join([*(ax for ax, _ in components(dim)), *(v for _, v in components(dim)),
                      "rho, p, c, m, kind, nb_start, nb_idx, prm, aux, fld"])


def generate_source(sel: Selection, param_names: list[str]) -> str:
    """Python source of the pipeline module for ``sel``, assembled by stage from the terms
    the selected models declare (see :mod:`sphfoam.engine.terms`)."""
    plan = Plan(sel)
    asm = LoopBodies(plan, precision=sel.precision)
    imports = sorted({line for m in plan.models for line in m.imports()})
    bind = "\n".join(f"{name} = prm[{i}]" for i, name in enumerate(param_names))
    aux = plan.aux
    aux_const = "\n".join(f"I_{a} = {i}" for i, a in enumerate(aux))
    fields = plan.fields
    fld_const = "\n".join(f"F_{a} = {i}" for i, a in enumerate(fields))
    cache = plan.cache
    cache_const = "".join(f"\nJ_{a} = {i}" for i, a in enumerate(cache))
    #: the arguments of every loop over pairs (``pc``: the per-pair cache, when there is one)
    dim = sel.dim
    _ARGS = _args_base(dim) + (", pc" if cache else "")
    X = ", ".join(ax for ax, _ in components(dim))            # the positions' arrays
    grid = ("x0, y0, inv_cell, ncx, ncy" if dim == 2 else
            "x0, y0, z0, inv_cell, ncx, ncy, ncz")             # the cell grid
    load_x = expand("@a = @[a]", dim)
    out_a = ", ".join(f"out_a{ax}" for ax, _ in components(dim))
    PLOAD = particle_load(dim)
    eos = asm.particle_code(plan.stage("particle", "all"), "final")
    # the passes the prepass runs before (rates always; see Plan.needs_prepass)
    prepass_before = ("\n#: the passes the prepass runs before (the rates always)\nPREPASS_BEFORE = "
                      + repr(tuple(x for x in ("rates", "density", "filter")
                                   if x == "rates" or plan.needs_prepass(x)))
                      + "\n#: the prepass runs once per step, before the step's first evaluation"
                      + f"\nPREPASS_ONCE = {plan.prepass_once()}"
                      if plan.has_stage("prepass") else "")

    # the sums of the half-list prepass, one row each of its array ``hs``
    hsums = plan.prepass_half_sums()
    half_sums = ("\n#: the per-particle sums of prepass_half (rows of its array hs)\nPREPASS_SUMS = "
                 + repr(tuple(hsums)) + "".join(f"\nS_{n} = {i}" for i, n in enumerate(hsums))
                 if hsums else "")
    parts = [f'''"""sphfoam pipeline, generated for: {sel.describe()}; adjustTimeStep={sel.adjust_time_step}.

Generated by sphfoam {__version__} (sphfoam.engine.emit_cpu); do not edit.
"""
import math

import numpy as np
from numba import njit, prange

{chr(10).join(imports)}

FLUID = 0
WALL = 1
GHOST = 2
#: the dimension of the case
DIM = {dim}
PARAMS = {tuple(param_names)!r}
AUX = {tuple(aux)!r}
{aux_const}
FIELDS = {tuple(fields)!r}
{fld_const}
PAIR_CACHE = {tuple(cache)!r}{cache_const}{prepass_before}{half_sums}
#: the neighbour list may leave out pairs of two non-fluid particles (Plan.fluid_pairs_only)
FLUID_PAIRS_ONLY = {plan.fluid_pairs_only}
#: the fill pass's contiguous chunks of particles (each makes its buffers once)
FILL_CHUNKS = 64


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def equation_of_state(rho, p, c, prm):
{_block(bind, 4)}
    for a in prange(rho.shape[0]):
{_block(eos or "pass", 8)}
''']
    fill_loop = _fill_loop(asm, load_x, rows=not sel.periodic_x)
    # the fluid particles before each index of the sorted particles, for the rows' skip
    fluid_upto = ("""
    fluid_upto = np.empty(x.shape[0] + 1, dtype=np.int64)
    fluid_upto[0] = 0
    for b in range(x.shape[0]):
        fluid_upto[b + 1] = fluid_upto[b] + (1 if kind[b] == FLUID else 0)"""
                  if plan.fluid_pairs_only and not sel.periodic_x else "")
    parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def count_neighbours({X}, kind, skip, cell_start, {grid}, prm, reach2,
                     count):
    """Neighbours of every particle within sqrt(reach2) (the cell side), from the cells;
    with ``skip``, none of a non-fluid particle's non-fluid neighbours."""
{_block(bind, 4)}{fluid_upto}
    for a in prange(x.shape[0]):
{_block(load_x, 8)}
        fluid_a = (not skip) or kind[a] == FLUID
        n_a = 0
{_block(cell_walk(asm, "n_a += 1", "n_a += ok", count=True), 8)}
        count[a] = n_a{_self_count(plan)}


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def fill_neighbours({X}, kind, skip, cell_start, {grid}, prm, reach2,
                    nb_start, nb_idx):
    """The neighbour list: b of particle a in nb_idx[nb_start[a]:nb_start[a + 1]], in the
    order of the cell walk (cells by row, particles by cell); with ``skip``, no pair of two
    non-fluid particles."""
{_block(bind, 4)}{fluid_upto}
{_block(fill_loop, 4)}
''')
    if plan.has_stage("prepass"):
        loops = "".join(f'''
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
{_block(body, 8)}''' for body in asm.prepass_loops())
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def prepass({_ARGS}):
    """Per-particle quantities the pair terms need: {", ".join(aux)}."""
{_block(bind, 4)}{loops}
''')
    fluid_rates = plan.stage("rates", "fluid")
    parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def rates({_ARGS}, {out_a}, out_drho, out_sigma):
    """dv/dt, drho/dt and sigma of T(3.89) for every particle (gather over neighbours);
    an empty out_sigma: no sigma (an evaluation whose time step is not taken from it)."""
{_block(bind, 4)}
    want_sigma = out_sigma.shape[0] > 0
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
{_block(expand("acc_@ = 0.0", dim), 8)}
        drho_a = 0.0
        sigma_a = 0.0
        if kind[a] == FLUID:
{_block(asm.gather(fluid_rates, sigma=sel.adjust_time_step, cache="read"), 12)}
{_block(expand("acc_@ += g@", dim), 12)}
        else:
{_block(asm.wall_gather("rates"), 12)}
{_block(expand("out_a@[a] = acc_@", dim), 8)}
        out_drho[a] = drho_a
        if want_sigma:
            out_sigma[a] = sigma_a


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def density_rate({_ARGS}, out_drho):
    """drho/dt alone (the last stage of Monaghan's 2007 scheme, T(3.96))."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
        drho_a = 0.0
        if kind[a] == FLUID:
{_block(asm.gather(plan.stage("density", "fluid"), cache=plan.cache_mode("density")), 12)}
        else:
{_block(asm.wall_gather("density"), 12)}
        out_drho[a] = drho_a
''')
    if plan.has_stage("step"):
        step = plan.stage("step", "wall")
        fluid_step = plan.stage("step", "fluid")
        if not any(not t.on_demand for t in fluid_step):
            parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def step_pass({_ARGS}):
    """Once per step, after the re-sort: per-step state of wall particles."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
        if kind[a] != FLUID:
{_block(PLOAD, 12)}
{_block(asm.gather(step), 12)}
''')
        else:
            # step terms that apply to fluid particles (e.g. a free-surface detection)
            wall_part = (asm.gather(step) if any(not t.on_demand for t in step)
                         else "pass")
            parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def step_pass({_ARGS}):
    """Once per step, after the re-sort: per-step state of fluid and wall particles."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
        if kind[a] == FLUID:
{_block(asm.gather(fluid_step), 12)}
        else:
{_block(wall_part, 12)}
''')
    if plan.has_stage("filter"):
        filt = plan.stage("filter", "fluid")
        owner = next(t.owner for t in filt if not t.on_demand)
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def density_filter({_ARGS}, out_rho):
    """{owner.doc}"""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
        rho_new = rhoa
        if kind[a] == FLUID:
{_block(asm.gather(filt), 12)}
        out_rho[a] = rho_new
''')
    for stage, name, outs in (("rates", "rates_half", f"{out_a}, out_drho, out_sigma"),
                              ("density", "density_half", "out_drho")):
        body = asm.half_loop(stage, sigma=stage == "rates" and sel.adjust_time_step)
        if body is None:
            continue
        zero = "\n".join(f"{o}[a] = 0.0" for o in outs.split(", ") if o != "out_sigma")
        if stage == "rates":
            zero += "\nif want_sigma:\n    out_sigma[a] = 0.0"
            start = expand("acc_@ = 0.0", dim) + "\ndrho_a = 0.0\nsigma_a = 0.0"
            end = ("if kinda == FLUID:\n" + _indent(expand("acc_@ += g@", dim)) + "\n"
                   + expand("out_a@[a] += acc_@", dim) + "\nout_drho[a] += drho_a\n"
                   "if want_sigma and sigma_a > out_sigma[a]:\n    out_sigma[a] = sigma_a")
        else:
            start = "drho_a = 0.0"
            end = "out_drho[a] += drho_a"
        want = "\n    want_sigma = out_sigma.shape[0] > 0" if stage == "rates" else ""
        bands_doc = ("(consecutive cell rows): the bands run in two colours, so that no two "
                     "threads write\n    the same particle (a's neighbours b > a lie in a's "
                     "band or the next)") if dim == 2 else \
            ("(rows of cells within layers, neighbours.half_blocks): the bands run in four "
             "colours,\n    so that no two threads write the same particle")
        sigma_doc = ("\n    An empty out_sigma: no sigma (an evaluation whose time step is not "
                     "taken from it).") if stage == "rates" else ""
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def {name}({_ARGS}, half, {outs}):
    """{"rates" if stage == "rates" else "density_rate"} over half lists, the same sums in another order: each
    listed pair a < b once, for both particles (the terms' reactions). half[a] (a < n) is
    where the neighbours b > a start in a's list and half[n + i] the first particle of band
    i {bands_doc}.{sigma_doc}"""
{_block(bind, 4)}{want}
    for a in prange(x.shape[0]):
{_block(zero, 8)}
{_block(_half_bands(dim, start, body, end), 4)}
''')
    if plan.prepass_half_terms() is not None:
        zero = "\n".join(f"hs[S_{n}, a] = 0.0" for n in plan.prepass_half_sums())
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def prepass_half({_ARGS}, half, hs):
    """The prepass over half lists, the same sums in another order: each listed pair a < b
    once, for both particles (the terms' reactions), in the colours of bands of
    ``rates_half``; the sums {", ".join(plan.prepass_half_sums())} in ``hs`` (one row each),
    then each particle's final code."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(zero, 8)}
{_block(_half_bands(dim, asm.prepass_half_loop()), 4)}
    for a in prange(x.shape[0]):
{_block(PLOAD, 8)}
{_block(asm.prepass_half_final(), 8)}
''')
    src = "".join(parts)
    if sel.precision == "single":
        src = working_precision(src, imports)
    return src


#: functions whose loops run in the working precision (not the cell walk, which bins and
#: measures positions in double)
_SINGLE_FUNCS = ("equation_of_state", "prepass", "rates", "density_rate", "step_pass",
                 "density_filter", "rates_half", "density_half", "prepass_half")


def working_precision(src: str, imports) -> str:
    """The pipeline source with its working loops (``_SINGLE_FUNCS``) in float32
    (:func:`sphfoam.engine.generated.working_precision`; the relative positions of the
    pairs are rounded where the bodies form them, ``LoopBodies(precision="single")``)."""
    return generated.working_precision(src, generated.helper_names(imports),
                                       lambda name: name in _SINGLE_FUNCS)


def _fill_loop(asm, load_x: str, rows: bool) -> str:
    """The fill pass's loop over the particles. A particle whose count is 0 (a wall
    particle with no fluid near) is not walked. Where the walk reads rows (x not periodic),
    a row's candidates are tested in one loop into ``okb``, which vectorises like the count
    pass, and a second loop appends those within reach to ``listed``, a's list, copied into
    ``nb_idx`` at the end (about twice as fast as a test and a store per candidate); the two
    buffers are made once per chunk of particles (``FILL_CHUNKS``), as long as the longest
    row of three cells and the 3^DIM cells."""
    head = [load_x, "k = nb_start[a]", "k_end = nb_start[a + 1]",
            "if k == k_end:              # none: no walk", "    continue",
            "fluid_a = (not skip) or kind[a] == FLUID"]
    pad = ["while k < k_end:            # (never: the count pass walked the same cells)",
           "    nb_idx[k] = a", "    k += 1"]
    store = "if k < k_end:\n    nb_idx[k] = b\n    k += 1"
    if not rows:
        body = "\n".join(head + [cell_walk(asm, store)] + pad)
        return f"for a in prange(x.shape[0]):\n{_block(body, 4)}"
    walk = cell_walk(asm, store, "okb[j] = ok",
                     after="for j in range(hi - lo):\n    listed[kk] = lo + j\n    kk += okb[j]")
    body = "\n".join(head + ["kk = 0", walk,
                             "kk = min(kk, k_end - k)",
                             "for q in range(kk):", "    nb_idx[k + q] = listed[q]",
                             "k += kk"] + pad)
    return f"""\
widest = 0
for cc in range(cell_start.shape[0] - 1):
    widest = max(widest, cell_start[cc + 1] - cell_start[cc])
n_all = x.shape[0]
for chunk in prange(FILL_CHUNKS):
    okb = np.empty(3 * widest + 1, dtype=np.bool_)
    listed = np.empty(3 ** DIM * widest + 1, dtype=np.int64)
    for a in range(chunk * n_all // FILL_CHUNKS, (chunk + 1) * n_all // FILL_CHUNKS):
{_block(body, 8)}"""


def _self_count(plan) -> str:
    """What the count pass subtracts for particle a itself where its row walk counts it
    (``counts_self``): 1, or, where the list leaves out pairs of two non-fluid particles, 1
    for a fluid particle only (a non-fluid one does not count itself)."""
    if not plan.counts_self():
        return ""
    return " - (1 if fluid_a else 0)" if plan.fluid_pairs_only else " - 1"


def generate_updates(integrator, dim: int = 2) -> str:
    """Python source of the module of ``integrator``'s particle updates
    (:mod:`sphfoam.engine.stepping`): one ``@njit(parallel=True)`` function ``update_<name>``
    a update, its arrays (``ARRAYS[name]``, in order of first use) then its scalars."""
    from sphfoam.engine.stepping import arrays_of, expand

    parts = [f'''"""sphfoam particle updates of the integrator {integrator.name!r} ({dim}-D).

Generated by sphfoam {__version__} (sphfoam.engine.emit_cpu); do not edit.
"""
from numba import njit, prange

FLUID = 0
WALL = 1
GHOST = 2
ARRAYS = {{}}
''']
    for upd in integrator.updates:
        arrays = arrays_of(upd, dim)
        args = ", ".join(arrays + list(upd.scalars))
        parts.append(f'''

ARRAYS[{upd.name!r}] = {tuple(arrays)!r}


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def update_{upd.name}({args}):
{_block(expand(upd.setup, dim), 4)}
    for a in prange({arrays[0]}.shape[0]):
{_block(expand(upd.code, dim), 8)}
''')
    return "".join(parts)
