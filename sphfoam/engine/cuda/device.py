"""Device functions and the fixed kernels of the CUDA backend: the models' helpers as device
functions, the cell list (binning, a deterministic counting sort), the exclusive scan, the
permutation of the state and the reductions of the time step and the list's check. One
form serves both dimensions: the kernels over positions take the third axis and ``three``.

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


_BOUND: dict[tuple[int, int], object] = {}


def kernel_with(template, name: str, global_name: str, function, factory: tuple[str, str]):
    """A copy of the kernel ``template`` (a plain Python function) named ``name``, with the
    jitted scalar ``function`` bound as its global ``global_name``, compiled as a device
    function (as :func:`device_function` binds helpers): one per (template, function).
    ``factory`` (module, name) is the function that makes it from ``function``, recorded as
    ``made_by`` for the PTX check (:mod:`sphfoam.cudaptx`)."""
    key = (id(template), id(function))
    if key not in _BOUND:
        glb = dict(template.__globals__, **{global_name: device_function(function)})
        kernel = cuda.jit(types.FunctionType(template.__code__, glb, name))
        py = getattr(function, "py_func", function)
        kernel.made_by = (*factory, py.__module__, py.__name__)
        _BOUND[key] = kernel
    return _BOUND[key]


THREADS = 128


def blocks(n: int) -> int:
    return max(1, (int(n) + THREADS - 1) // THREADS)


# --- the cell list ----------------------------------------------------------------------------
@cuda.jit(device=True)
def wrap(x, x0, lx):
    """x wrapped into [x0, x0 + lx) along a periodic axis (``lx`` > 0), else x."""
    if lx > 0.0:
        return x0 + (x - x0) % lx
    return x


@cuda.jit(device=True)
def nearest_image(dx, lx):
    """dx to the nearest image along a periodic axis (``lx`` > 0), else dx."""
    if lx > 0.0:
        if dx > 0.5 * lx:
            return dx - lx
        if dx < -0.5 * lx:
            return dx + lx
    return dx


@cuda.jit
def bin_particles(x, y, z, x0, y0, z0, inv_cell, ncx, ncy, ncz, lx, ly, lz, three, cell,
                  counts):
    """Cell (iz ncy + iy) ncx + ix of particle a (wrapped into the box along periodic axes,
    ``lx``/``ly``/``lz`` > 0); outside the box (or not finite): the extra last cell ``ncx ncy
    ncz``, sorted after all others. ``three``: a third axis (else ``z`` is not read, iz = 0,
    ncz = 1). ``counts`` per cell, by atomics (a count: independent of the order)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    x[a] = wrap(x[a], x0, lx)
    y[a] = wrap(y[a], y0, ly)
    fx = (x[a] - x0) * inv_cell
    fy = (y[a] - y0) * inv_cell
    inside = fx >= 0.0 and fx < ncx and fy >= 0.0 and fy < ncy
    iz = 0
    if three:
        z[a] = wrap(z[a], z0, lz)
        fz = (z[a] - z0) * inv_cell
        inside = inside and fz >= 0.0 and fz < ncz
        if inside:
            iz = int(fz)
    if inside:
        c = (iz * ncy + int(fy)) * ncx + int(fx)
    else:
        c = ncx * ncy * ncz
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
MIN, MAX, SUM = 0, 1, 2


@cuda.jit(device=True)
def _combine(a, b, op):
    if op == MIN:
        return min(a, b)
    if op == MAX:
        return max(a, b)
    return a + b


@cuda.jit(device=True)
def tree_reduce(sa, sb, t, op_a, op_b):
    """Two block reductions at once in shared memory, a fixed tree (so a sum's order does not
    depend on the scheduling): sa[0] = op_a over sa, sb[0] = op_b over sb (MIN, MAX or SUM).
    Every thread of the block calls it after writing its own sa[t], sb[t]."""
    cuda.syncthreads()
    s = THREADS // 2
    while s > 0:
        if t < s:
            sa[t] = _combine(sa[t], sa[t + s], op_a)
            sb[t] = _combine(sb[t], sb[t + s], op_b)
        cuda.syncthreads()
        s //= 2


@cuda.jit
def time_step_reduce(h, c, sigma, ax, ay, az, three, kind, out):
    """out[0] = min over fluid particles of h / (c_a + sigma_a), T(3.89); out[1] = max of
    |F_a|^2 for T(3.90) (with ``az`` where ``three``). Per block in shared memory, then one
    atomic per block."""
    smin = cuda.shared.array(THREADS, dtype=np.float64)
    smax = cuda.shared.array(THREADS, dtype=np.float64)
    a = cuda.grid(1)
    t = cuda.threadIdx.x
    dmin = math.inf
    fmax = 0.0
    if a < c.shape[0] and kind[a] == 0:
        dmin = h / (c[a] + sigma[a])
        fmax = ax[a] * ax[a] + ay[a] * ay[a]
        if three:
            fmax += az[a] * az[a]
    smin[t] = dmin
    smax[t] = fmax
    tree_reduce(smin, smax, t, MIN, MAX)
    if t == 0:
        cuda.atomic.min(out, 0, smin[0])
        cuda.atomic.max(out, 1, smax[0])


@cuda.jit
def displacement_reduce(x, y, z, xr, yr, zr, u, v, w, x0, y0, z0, x1, y1, z1, lx, ly, lz,
                        three, out):
    """out[0] = max displacement^2 since (xr, yr, zr) (nearest image on periodic axes),
    out[1] = max speed^2, out[2] = 1 if a particle is outside the box [x0, x1) x [y0, y1)
    (x [z0, z1)) or not finite (a NaN counts as an infinite displacement). ``three``: a
    third axis (else ``z``, ``zr``, ``w`` are not read)."""
    sd = cuda.shared.array(THREADS, dtype=np.float64)
    sv = cuda.shared.array(THREADS, dtype=np.float64)
    a = cuda.grid(1)
    t = cuda.threadIdx.x
    d2 = 0.0
    v2 = 0.0
    if a < x.shape[0]:
        xa = wrap(x[a], x0, lx)
        ya = wrap(y[a], y0, ly)
        inside = xa >= x0 and xa < x1 and ya >= y0 and ya < y1
        dx = nearest_image(xa - xr[a], lx)
        dy = nearest_image(ya - yr[a], ly)
        d2 = dx * dx + dy * dy
        v2 = float(u[a]) * float(u[a]) + float(v[a]) * float(v[a])
        if three:
            za = wrap(z[a], z0, lz)
            inside = inside and za >= z0 and za < z1
            dz = nearest_image(za - zr[a], lz)
            d2 += dz * dz
            v2 += float(w[a]) * float(w[a])
        if not inside:
            out[2] = 1.0
        if not (d2 >= 0.0):
            d2 = math.inf
        if not (v2 >= 0.0):
            v2 = math.inf
    sd[t] = d2
    sv[t] = v2
    tree_reduce(sd, sv, t, MAX, MAX)
    if t == 0:
        cuda.atomic.max(out, 0, sd[0])
        cuda.atomic.max(out, 1, sv[0])


@cuda.jit
def prescribe_patch(x, y, z, u, v, w, patch, x0, y0, z0, which, ox, oy, oz, uu, vv, ww,
                    three):
    """Particles of wall entry ``which``: r = r0 + d(t), v = d'(t) (z, w where ``three``;
    else ``z``, ``w``, ``z0`` are not read)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    if patch[a] == which:
        x[a] = x0[a] + ox
        y[a] = y0[a] + oy
        u[a] = uu
        v[a] = vv
        if three:
            z[a] = z0[a] + oz
            w[a] = ww


# --- the health checks (sphfoam.engine.health.scan on the device) ---------------------------
@cuda.jit
def health_reduce(x, y, z, u, v, w, rho, m, kind, three, rho_lo, rho_hi, speed2_max,
                  acc, partial):
    """The per-step checks of :func:`sphfoam.engine.health.scan`, ghosts skipped: into
    ``acc[0:4]`` the counts of non-finite particles, of fluid densities out of range, of
    fluid too fast and of finite fluid (atomic adds of 1.0: exact), ``acc[4]`` the largest
    fluid speed^2 (an exact atomic maximum), and ``partial[block]`` the block's kinetic
    energy and mass in a fixed order (:func:`sum_partials` adds the blocks into ``acc[5:7]``,
    so the sums do not depend on the scheduling). ``three``: z and w are read (else they
    stand for y and v and are not)."""
    ske = cuda.shared.array(THREADS, dtype=np.float64)
    sm = cuda.shared.array(THREADS, dtype=np.float64)
    a = cuda.grid(1)
    t = cuda.threadIdx.x
    ke = 0.0
    mass = 0.0
    if a < x.shape[0] and kind[a] != 2:
        s2 = float(u[a]) * float(u[a]) + float(v[a]) * float(v[a])
        finite = math.isfinite(x[a]) and math.isfinite(y[a]) and math.isfinite(u[a]) \
            and math.isfinite(v[a]) and math.isfinite(rho[a])
        if three:
            s2 += float(w[a]) * float(w[a])
            finite = finite and math.isfinite(z[a]) and math.isfinite(w[a])
        if not finite:
            cuda.atomic.add(acc, 0, 1.0)
        elif kind[a] == 0:
            cuda.atomic.add(acc, 3, 1.0)
            if not (rho[a] >= rho_lo and rho[a] <= rho_hi):
                cuda.atomic.add(acc, 1, 1.0)
            if s2 > speed2_max:
                cuda.atomic.add(acc, 2, 1.0)
            cuda.atomic.max(acc, 4, s2)
            ke = 0.5 * float(m[a]) * s2
            mass = float(m[a])
    ske[t] = ke
    sm[t] = mass
    tree_reduce(ske, sm, t, SUM, SUM)
    if t == 0:
        partial[cuda.blockIdx.x, 0] = ske[0]
        partial[cuda.blockIdx.x, 1] = sm[0]


@cuda.jit
def sum_partials(partial, out):
    """out[5 + j] = sum over the blocks of partial[:, j] (one block: each thread a fixed
    stride, then a fixed tree)."""
    s0 = cuda.shared.array(THREADS, dtype=np.float64)
    s1 = cuda.shared.array(THREADS, dtype=np.float64)
    t = cuda.threadIdx.x
    a0 = 0.0
    a1 = 0.0
    for i in range(t, partial.shape[0], THREADS):
        a0 += partial[i, 0]
        a1 += partial[i, 1]
    s0[t] = a0
    s1[t] = a1
    tree_reduce(s0, s1, t, SUM, SUM)
    if t == 0:
        out[5] = s0[0]
        out[6] = s1[0]


@cuda.jit
def fill(a, value):
    """a[:] = value (a 1-D array: no host array copied in to clear it)."""
    i = cuda.grid(1)
    if i < a.shape[0]:
        a[i] = value


@cuda.jit
def fill_rows(a, value):
    """a[:, :] = value (a 2-D array, one thread per column)."""
    i = cuda.grid(1)
    if i < a.shape[1]:
        for r in range(a.shape[0]):
            a[r, i] = value
