"""Device functions and the fixed kernels of the CUDA backend: the models' helpers as device
functions, the cell list (binning, a deterministic counting sort), the exclusive scan, the
permutation of the state and the reductions of the time step and the list's check.

Imported only once numba.cuda can run (:func:`sphfoam.engine.cuda.cuda_module`).
"""

from __future__ import annotations

import math
import types

import numpy as np
from numba import cuda

_DEVICE: dict[int, object] = {}


def device_function(fn):
    """``fn`` (a plain jitted scalar function, or a Python one) compiled as a CUDA device
    function; the jitted functions it calls become device functions too."""
    key = id(fn)
    if key in _DEVICE:
        return _DEVICE[key]
    py = getattr(fn, "py_func", fn)
    glb = dict(py.__globals__)
    for name in py.__code__.co_names:
        v = glb.get(name)
        if v is not None and hasattr(v, "py_func"):
            glb[name] = device_function(v)
    clone = types.FunctionType(py.__code__, glb, py.__name__, py.__defaults__,
                               py.__closure__)
    out = cuda.jit(device=True)(clone)
    _DEVICE[key] = out
    return out


THREADS = 128


def blocks(n: int) -> int:
    return max(1, (int(n) + THREADS - 1) // THREADS)


# --- the cell list ----------------------------------------------------------------------------
@cuda.jit
def bin_particles(x, y, x0, y0, inv_cell, ncx, ncy, lx, ly, cell, counts):
    """Cell of particle a (wrapped into the box along periodic axes, ``lx``/``ly`` > 0);
    outside the box (or not finite): the extra last cell ``ncx ncy``, sorted after all
    others. ``counts`` per cell, by atomics (a count: independent of the order)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    if lx > 0.0:
        x[a] = x0 + (x[a] - x0) % lx
    if ly > 0.0:
        y[a] = y0 + (y[a] - y0) % ly
    fx = (x[a] - x0) * inv_cell
    fy = (y[a] - y0) * inv_cell
    if fx >= 0.0 and fx < ncx and fy >= 0.0 and fy < ncy:
        c = int(fy) * ncx + int(fx)
    else:
        c = ncx * ncy
    cell[a] = c
    cuda.atomic.add(counts, c, 1)


@cuda.jit
def scan_chunks(src, dst, chunk, sums):
    """Exclusive scan of each chunk of ``src`` into ``dst[1:]`` (dst[i + 1] = sum src[:i+1]
    within the chunk); the chunk's total into ``sums``."""
    j = cuda.grid(1)
    n = src.shape[0]
    lo = j * chunk
    if lo >= n:
        return
    hi = min(lo + chunk, n)
    s = 0
    for i in range(lo, hi):
        s += src[i]
        dst[i + 1] = s
    sums[j] = s


@cuda.jit
def scan_totals(sums):
    """Exclusive scan of the chunks' totals, in place (one thread: a few thousand)."""
    if cuda.grid(1) != 0:
        return
    s = 0
    for j in range(sums.shape[0]):
        t = sums[j]
        sums[j] = s
        s += t


@cuda.jit
def scan_add(dst, chunk, sums):
    i = cuda.grid(1)
    if i == 0:
        dst[0] = 0
    if i >= dst.shape[0] - 1:
        return
    dst[i + 1] += sums[i // chunk]


def exclusive_scan(src, dst, scratch=None):
    """dst[0] = 0, dst[i + 1] = src[0] + ... + src[i] (integers: exact, any order)."""
    n = src.shape[0]
    chunk = max(256, int(math.sqrt(max(n, 1))) + 1)
    nch = (n + chunk - 1) // chunk
    if scratch is None or scratch.shape[0] < max(nch, 1):
        scratch = cuda.device_array(max(nch, 1), dtype=np.int64)
    sums = scratch[:max(nch, 1)]
    if n == 0:
        dst[:1] = np.zeros(1, dtype=dst.dtype)
        return scratch
    scan_chunks[blocks(nch), THREADS](src, dst, chunk, sums)
    scan_totals[1, 1](sums)
    scan_add[blocks(n), THREADS](dst, chunk, sums)
    return scratch


@cuda.jit
def scatter(cell, cell_start, fill, order):
    """Particle a into the range of its cell (slot by an atomic: in any order; the ranges
    are ordered by particle index afterwards, ``order_cells``)."""
    a = cuda.grid(1)
    if a >= cell.shape[0]:
        return
    c = cell[a]
    k = cuda.atomic.add(fill, c, 1)
    order[cell_start[c] + k] = a


@cuda.jit
def order_cells(cell_start, order):
    """The particles of each cell by increasing index (insertion sort: a few per cell): the
    sort is stable, the same order whatever the scheduling."""
    c = cuda.grid(1)
    if c >= cell_start.shape[0] - 1:
        return
    lo = cell_start[c]
    hi = cell_start[c + 1]
    for i in range(lo + 1, hi):
        v = order[i]
        j = i - 1
        while j >= lo and order[j] > v:
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = v


@cuda.jit
def permute(src, order, dst):
    """dst[i] = src[order[i]]."""
    i = cuda.grid(1)
    if i >= order.shape[0]:
        return
    dst[i] = src[order[i]]


@cuda.jit
def extend(src, dst):
    """dst[i] = src[i] where src has an element, 0 after (an array grown at its end)."""
    i = cuda.grid(1)
    if i >= dst.shape[0]:
        return
    dst[i] = src[i] if i < src.shape[0] else 0


@cuda.jit
def extend_rows(src, dst):
    """Rows of a 2-D array grown at their end: dst[:, i] = src[:, i], 0 after."""
    i = cuda.grid(1)
    if i >= dst.shape[1]:
        return
    for r in range(dst.shape[0]):
        dst[r, i] = src[r, i] if i < src.shape[1] else 0


@cuda.jit
def permute_rows(src, order, dst):
    """Rows of a 2-D array: dst[:, i] = src[:, order[i]]."""
    i = cuda.grid(1)
    if i >= order.shape[0]:
        return
    for r in range(src.shape[0]):
        dst[r, i] = src[r, order[i]]


# --- reductions (min and max are exact: the result does not depend on the order) -----------
@cuda.jit
def time_step_reduce(h, c, sigma, ax, ay, kind, out):
    """out[0] = min over fluid particles of h / (c_a + sigma_a), T(3.89); out[1] = max of
    |F_a|^2 for T(3.90). Per block in shared memory, then one atomic per block."""
    smin = cuda.shared.array(128, dtype=np.float64)
    smax = cuda.shared.array(128, dtype=np.float64)
    a = cuda.grid(1)
    t = cuda.threadIdx.x
    dmin = math.inf
    fmax = 0.0
    if a < c.shape[0] and kind[a] == 0:
        dmin = h / (c[a] + sigma[a])
        fmax = ax[a] * ax[a] + ay[a] * ay[a]
    smin[t] = dmin
    smax[t] = fmax
    cuda.syncthreads()
    s = 64
    while s > 0:
        if t < s:
            smin[t] = min(smin[t], smin[t + s])
            smax[t] = max(smax[t], smax[t + s])
        cuda.syncthreads()
        s //= 2
    if t == 0:
        cuda.atomic.min(out, 0, smin[0])
        cuda.atomic.max(out, 1, smax[0])


@cuda.jit
def displacement_reduce(x, y, xr, yr, u, v, x0, y0, x1, y1, lx, ly, out):
    """out[0] = max displacement^2 since (xr, yr) (nearest image on periodic axes), out[1]
    = max speed^2, out[2] = 1 if a particle is outside the box or not finite (a NaN counts
    as an infinite displacement)."""
    sd = cuda.shared.array(128, dtype=np.float64)
    sv = cuda.shared.array(128, dtype=np.float64)
    a = cuda.grid(1)
    t = cuda.threadIdx.x
    d2 = 0.0
    v2 = 0.0
    if a < x.shape[0]:
        xa = x[a]
        ya = y[a]
        if lx > 0.0:
            xa = x0 + (xa - x0) % lx
        if ly > 0.0:
            ya = y0 + (ya - y0) % ly
        if not (xa >= x0 and xa < x1 and ya >= y0 and ya < y1):
            out[2] = 1.0
        dx = xa - xr[a]
        dy = ya - yr[a]
        if lx > 0.0:
            if dx > 0.5 * lx:
                dx -= lx
            elif dx < -0.5 * lx:
                dx += lx
        if ly > 0.0:
            if dy > 0.5 * ly:
                dy -= ly
            elif dy < -0.5 * ly:
                dy += ly
        d2 = dx * dx + dy * dy
        v2 = float(u[a]) * float(u[a]) + float(v[a]) * float(v[a])
        if not (d2 >= 0.0):
            d2 = math.inf
        if not (v2 >= 0.0):
            v2 = math.inf
    sd[t] = d2
    sv[t] = v2
    cuda.syncthreads()
    s = 64
    while s > 0:
        if t < s:
            sd[t] = max(sd[t], sd[t + s])
            sv[t] = max(sv[t], sv[t + s])
        cuda.syncthreads()
        s //= 2
    if t == 0:
        cuda.atomic.max(out, 0, sd[0])
        cuda.atomic.max(out, 1, sv[0])


@cuda.jit
def prescribe_patch(x, y, u, v, patch, x0, y0, which, ox, oy, uu, vv):
    """Particles of wall entry ``which``: r = r0 + d(t), v = d'(t)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    if patch[a] == which:
        x[a] = x0[a] + ox
        y[a] = y0[a] + oy
        u[a] = uu
        v[a] = vv
