"""Cell-linked-list neighbour search with particles kept sorted by cell (T §3.12), and the
Verlet neighbour list every pair loop reads.

When the list is (re)built the particles are binned into square cells of side >= kappa h
(the support) and reordered (a stable counting sort), so that the particles of one cell are
contiguous in memory; one walk of the 3 x 3 block of cells around each particle
(``cell_start[c] : cell_start[c + 1]`` is the range of cell ``c``) lists its neighbours within
the cell side R. The list serves every pair loop until some particle has moved (skin/2 minus the
next step's motion) since, skin = R - kappa h (Verlet 1967): no pair can then have come
within the support without being listed.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from sphfoam.engine.fastmath import FASTMATH

_JIT = dict(cache=True, fastmath=set(FASTMATH))


@njit(cache=True)   # no fastmath: a NaN or infinite position must fail the range test
def bin_particles(x, y, z, x0, y0, z0, inv_cell, ncx, ncy, ncz, cell, lx, ly, lz):
    """Cell index (iz ncy + iy) ncx + ix of every particle; -1 marks a particle outside the
    domain box (or with a non-finite position: the range test is done on the float, before
    any conversion to int). ``z`` is empty in two dimensions (then iz = 0, ncz = 1).

    ``lx`` (``ly``, ``lz``) > 0 makes the axis periodic: positions are wrapped into the box
    first.
    """
    n = x.shape[0]
    three = z.shape[0] > 0
    outside = 0
    for a in range(n):
        if lx > 0.0:
            x[a] = x0 + (x[a] - x0) % lx
        if ly > 0.0:
            y[a] = y0 + (y[a] - y0) % ly
        fx = (x[a] - x0) * inv_cell
        fy = (y[a] - y0) * inv_cell
        inside = fx >= 0.0 and fx < ncx and fy >= 0.0 and fy < ncy
        iz = 0
        if three:
            if lz > 0.0:
                z[a] = z0 + (z[a] - z0) % lz
            fz = (z[a] - z0) * inv_cell
            inside = inside and fz >= 0.0 and fz < ncz
            if inside:
                iz = int(fz)
        if inside:
            cell[a] = (iz * ncy + int(fy)) * ncx + int(fx)
        else:
            cell[a] = -1
            outside += 1
    return outside


#: the particle ranges the whole-state reductions split into (a fixed number, so that what
#: each range holds does not depend on the thread count; max and min are exact anyway)
REDUCTION_CHUNKS = 64


@njit(parallel=True, cache=True)   # no fastmath: a NaN position must not pass for a small displacement
def displacement_check(x, y, xr, yr, u, v, x0, y0, x1, y1, lx, ly, scratch, z, zr, w, z0, z1,
                       lz):
    """(largest displacement^2 since (xr, yr), largest speed^2, a particle outside the box
    [x0, x1) x [y0, y1) or not finite). On a periodic axis (``lx``/``ly`` > 0, the period)
    positions are wrapped into the box as binning does and displacements are taken to the
    nearest image, so crossing the period is no reason to rebuild the list (its pairs use the
    nearest image too). A NaN counts as an infinite displacement or speed. Parallel over
    ``REDUCTION_CHUNKS`` ranges of particles, then the maxima of the ranges; ``scratch``: a
    (3, REDUCTION_CHUNKS) float array the caller keeps (no allocation per step). ``z``,
    ``zr``, ``w`` (empty in two dimensions), ``z0``, ``z1``, ``lz``: the third axis."""
    n = x.shape[0]
    nc = REDUCTION_CHUNKS
    three = z.shape[0] > 0
    d2c = scratch[0]
    v2c = scratch[1]
    outc = scratch[2]
    for ci in prange(nc):
        d2max = 0.0
        v2max = 0.0
        out = False
        for a in range(ci * n // nc, (ci + 1) * n // nc):
            if lx > 0.0:
                x[a] = x0 + (x[a] - x0) % lx
            if ly > 0.0:
                y[a] = y0 + (y[a] - y0) % ly
            dx = x[a] - xr[a]
            dy = y[a] - yr[a]
            if lx > 0.0:
                dx -= lx * np.floor(dx / lx + 0.5)
            if ly > 0.0:
                dy -= ly * np.floor(dy / ly + 0.5)
            d2 = dx * dx + dy * dy
            s2 = u[a] * u[a] + v[a] * v[a]
            inside = x[a] >= x0 and x[a] < x1 and y[a] >= y0 and y[a] < y1
            if three:
                if lz > 0.0:
                    z[a] = z0 + (z[a] - z0) % lz
                dz = z[a] - zr[a]
                if lz > 0.0:
                    dz -= lz * np.floor(dz / lz + 0.5)
                d2 += dz * dz
                s2 += w[a] * w[a]
                inside = inside and z[a] >= z0 and z[a] < z1
            if not d2 <= d2max:
                d2max = d2 if d2 == d2 else np.inf
            if not s2 <= v2max:
                v2max = s2 if s2 == s2 else np.inf
            if not inside:
                out = True
        d2c[ci] = d2max
        v2c[ci] = v2max
        outc[ci] = 1.0 if out else 0.0
    return d2c.max(), v2c.max(), outc.max() > 0.0


@njit(**_JIT)
def counting_sort(cell, ncells, order, cell_start):
    """Stable counting sort of particle indices by cell: fills ``order`` and ``cell_start``."""
    cell_start[:] = 0
    for a in range(cell.shape[0]):
        cell_start[cell[a] + 1] += 1
    for c in range(ncells):
        cell_start[c + 1] += cell_start[c]
    fill = cell_start[:-1].copy()
    for a in range(cell.shape[0]):
        c = cell[a]
        order[fill[c]] = a
        fill[c] += 1


@njit(parallel=True, **_JIT)
def permute(order, f8, i8):
    """Reorder the rows of a (k, n) float array and a (j, n) int array by ``order`` in one
    parallel pass (one call per step instead of one per field)."""
    out_f = np.empty_like(f8)
    out_i = np.empty_like(i8)
    for i in prange(order.shape[0]):
        o = order[i]
        for k in range(f8.shape[0]):
            out_f[k, i] = f8[k, o]
        for k in range(i8.shape[0]):
            out_i[k, i] = i8[k, o]
    return out_f, out_i


class CellList:
    """A fixed grid over the domain box; rebuilt (re-sorted) once per step.

    On a periodic axis the cells tile the period exactly (their side is the period divided
    by a whole number >= 3, and no smaller than ``cell_size``). ``lo`` and ``hi`` have two
    or three components: the grid's dimension (cells numbered (iz ncy + iy) ncx + ix).
    """

    def __init__(self, lo, hi, cell_size, periodic_x=False, periodic_y=False,
                 periodic_z=False):
        self.dim = 3 if len(lo) > 2 and len(hi) > 2 else 2
        self.x0, self.y0 = float(lo[0]), float(lo[1])
        self.z0 = float(lo[2]) if self.dim == 3 else 0.0
        self.lx = float(hi[0] - lo[0]) if periodic_x else 0.0
        self.ly = float(hi[1] - lo[1]) if periodic_y else 0.0
        self.lz = float(hi[2] - lo[2]) if periodic_z and self.dim == 3 else 0.0
        periods = [p for p in (self.lx, self.ly, self.lz) if p]
        if periods:
            period = periods[0]
            n = int(np.floor(period / cell_size))
            if n < 3:
                raise ValueError(f"periodic length {period:g} must be at least 3 kernel supports "
                                 f"({3 * cell_size:g})")
            cell_size = period / n
            if any(abs(p / cell_size - round(p / cell_size)) > 1e-9 for p in periods[1:]):
                raise ValueError("with several axes periodic, the lengths must share a cell "
                                 "size")
        self.cell_size = float(cell_size)
        self.ncx = max(1, int(np.ceil((hi[0] - lo[0]) / cell_size - 1e-9)))
        self.ncy = max(1, int(np.ceil((hi[1] - lo[1]) / cell_size - 1e-9)))
        self.ncz = max(1, int(np.ceil((hi[2] - lo[2]) / cell_size - 1e-9))) \
            if self.dim == 3 else 1
        if self.ncx * self.ncy * self.ncz > 200_000_000:
            shape = " x ".join(str(k) for k in (self.ncx, self.ncy, self.ncz)[:self.dim])
            raise ValueError(f"domain box too large for the cell grid ({shape} cells); give "
                             "a smaller domain")
        self.ncells = self.ncx * self.ncy * self.ncz
        self.cell_start = np.zeros(self.ncells + 1, dtype=np.int64)

    def bin(self, x, y, z=None):
        cell = np.empty(x.shape[0], dtype=np.int64)
        outside = bin_particles(x, y, x[:0] if z is None else z, self.x0, self.y0, self.z0,
                                1.0 / self.cell_size, self.ncx, self.ncy, self.ncz, cell,
                                self.lx, self.ly, self.lz)
        return cell, outside

    def grid(self) -> tuple:
        """The grid arguments of the generated neighbour search: origin, 1/side, counts."""
        if self.dim == 3:
            return (self.x0, self.y0, self.z0, 1.0 / self.cell_size, self.ncx, self.ncy,
                    self.ncz)
        return (self.x0, self.y0, 1.0 / self.cell_size, self.ncx, self.ncy)

    def sort(self, cell):
        """Return the permutation that sorts particles by cell; fills ``cell_start``."""
        order = np.empty(cell.shape[0], dtype=np.int64)
        counting_sort(cell, self.ncells, order, self.cell_start)
        return order


@njit(cache=True)
def deal_bands(half, n, threads):
    """The order the half-list loops run each colour's bands in: ``half`` is [nb_mid (n) |
    band starts (nb + 1) | the dealt order (nb) | nb]. prange hands thread t a contiguous
    share of a colour's bands (the first shares one longer where they do not divide
    evenly), so the order lists the colour's bands t, t + T, t + 2T, ... for t = 0 .. T-1:
    each thread runs every T-th band of the colour, rows of water and rows above alike,
    not the bottom or top half of the tank. The bands of a colour write disjoint particles,
    so the order changes no sum."""
    nb = int(half[half.shape[0] - 1])
    k = n + nb + 1
    t_count = max(threads, 1)
    for colour in range(2):
        n_colour = (nb + 1 - colour) // 2
        for t in range(t_count):
            for p in range(t, n_colour, t_count):
                half[k] = 2 * p + colour
                k += 1


@njit(parallel=True, cache=True)
def half_starts(nb_start, nb_idx, cell_start, ncx, ncy, ncz, split, nb_mid):
    """``nb_mid[a]``: where the neighbours b > a of particle a start in its list, for cells
    in ``ncz`` layers of ``ncy`` rows of ``ncx`` cells (2-D: layers of one row). True if, as
    the cell walk of particles sorted by cell makes them, every list holds its b < a before
    its b > a and every b > a lies in a's layer or the next; with ``split`` (y not
    periodic), in a's row or the next of its layer or in the three rows around a's in the
    next layer. The particles are split into ``REDUCTION_CHUNKS`` ranges run in parallel
    (each finds the row of its first particle by bisection)."""
    n = nb_start.shape[0] - 1
    rows = ncy * ncz
    if cell_start[rows * ncx] != n:
        return False
    nc = REDUCTION_CHUNKS
    bad = np.zeros(nc, dtype=np.bool_)
    for ci in prange(nc):
        a0 = ci * n // nc
        a1 = (ci + 1) * n // nc
        if a1 <= a0:
            continue
        r_lo = 0                      # the last row starting at or before a0
        r_hi = rows
        while r_hi - r_lo > 1:
            mid = (r_lo + r_hi) // 2
            if cell_start[mid * ncx] <= a0:
                r_lo = mid
            else:
                r_hi = mid
        r = r_lo - 1
        row_end = 0
        hi1 = lo2 = hi2 = 0
        for a in range(a0, a1):
            while a >= row_end:
                r += 1
                row_end = cell_start[(r + 1) * ncx]
                lay = r // ncy
                iy = r - lay * ncy
                nxt = (lay + 1) * ncy
                lo2 = n
                hi2 = n
                if not split:         # a's layer or the next (a periodic y wraps rows)
                    hi1 = cell_start[min(nxt + ncy, rows) * ncx]
                else:
                    hi1 = cell_start[min(r + 2, nxt) * ncx]
                    if lay + 1 < ncz:
                        lo2 = cell_start[(nxt + max(iy - 1, 0)) * ncx]
                        hi2 = cell_start[(nxt + min(iy + 2, ncy)) * ncx]
            k = nb_start[a]
            k1 = nb_start[a + 1]
            while k < k1 and nb_idx[k] < a:
                k += 1
            nb_mid[a] = k
            while k < k1:
                b = nb_idx[k]
                if b <= a or (b >= hi1 and (b < lo2 or b >= hi2)):
                    bad[ci] = True
                k += 1
    return not bad.any()


@njit(cache=True)
def half_lists(nb_start, nb_idx, cell_start, ncx, ncy, bands, nb_mid, band_start):
    """Split the neighbour list for the half-list loops: ``nb_mid[a]`` is where the
    neighbours b > a of particle a start in its list; the cell rows (``ncy`` rows of ``ncx``
    cells) are grouped into about
    ``bands`` bands of consecutive rows holding about as many particles each, and
    ``band_start[i]`` is the first particle of band i (``band_start[nb]`` = n). Returns the
    number of bands nb; 0 unless, as the cell walk of particles sorted by cell makes them,
    every list holds its b < a before its b > a and every b > a lies in a's cell row or the
    next (so in a's band or the next): the loops then gather over the full lists
    (``half_starts``)."""
    n = nb_start.shape[0] - 1
    if not half_starts(nb_start, nb_idx, cell_start, ncx, 1, ncy, False, nb_mid):
        return 0
    target = max(n // max(bands, 1), 1)
    nb = 0
    band_start[0] = 0
    for r in range(1, ncy + 1):
        first = cell_start[r * ncx]
        if first - band_start[nb] >= target or r == ncy:
            nb += 1
            band_start[nb] = first
    return nb


#: the colours of the 3-D half-list blocks: (parity of the slab of layers, parity of the
#: block of rows within it)
BLOCK_COLOURS = 4


@njit(cache=True)
def deal_blocks(half, n, threads, nb_start):
    """``deal_bands`` for the 3-D layout of ``half_blocks``, [nb_mid (n) | block starts
    (nb + 1) | the dealt order (nb) | colour starts (5) | nb], balanced by work: prange hands
    thread t a contiguous share of a colour's segment (the first shares one longer where they
    do not divide evenly), so each colour's blocks, largest first, go to the share with the
    least work (a block's listed pairs b > a, plus one per particle) that has room left, and
    the segment lists share after share. The blocks of a colour write disjoint particles, so
    the order changes no sum."""
    nb = int(half[half.shape[0] - 1])
    k0 = n + nb + 1
    cs = k0 + nb
    t_count = max(threads, 1)
    work = np.zeros(nb, dtype=np.int64)
    for b in range(nb):
        for a in range(int(half[n + b]), int(half[n + b + 1])):
            work[b] += nb_start[a + 1] - half[a] + 1
    load = np.zeros(t_count, dtype=np.int64)
    room = np.zeros(t_count, dtype=np.int64)
    owner = np.zeros(nb, dtype=np.int64)
    for colour in range(BLOCK_COLOURS):
        c0 = int(half[cs + colour])
        c1 = int(half[cs + colour + 1])
        m = c1 - c0
        seg = np.sort(half[k0 + c0:k0 + c1].astype(np.int64))
        for t in range(t_count):
            load[t] = 0
            room[t] = m // t_count + (1 if t < m % t_count else 0)
        w = np.empty(m, dtype=np.int64)
        for i in range(m):
            w[i] = -work[seg[i]]
        for i in np.argsort(w, kind="mergesort"):
            best = -1
            for t in range(t_count):
                if room[t] > 0 and (best < 0 or load[t] < load[best]):
                    best = t
            owner[seg[i]] = best
            load[best] += work[seg[i]]
            room[best] -= 1
        k = k0 + c0
        for t in range(t_count):
            for i in range(m):
                if owner[seg[i]] == t:
                    half[k] = seg[i]
                    k += 1


@njit(cache=True)
def half_blocks(nb_start, nb_idx, cell_start, ncx, ncy, ncz, split, blocks, nb_mid, half):
    """The half lists of a 3-D list in blocks of rows: ``nb_mid[a]`` as in ``half_lists``;
    the layers of cells (one z, ``ncy`` rows of ``ncx`` cells each) are grouped into slabs of
    consecutive layers holding about n / ``blocks`` particles or more, and a slab of one layer
    is cut (``split``: y is not periodic) into blocks of at least two rows of about that many
    particles. The cell walk lists a particle's b > a in its row or the next of its layer and
    in the three rows around its own in the next layer, so a block writes its own particles,
    the next block's first row and the next slab: the blocks of one colour, 2 (slab parity)
    + (block parity within its slab), write disjoint particles. ``half`` receives [block
    starts (nb + 1) | the order, by colour (nb) | colour starts (5)], the order not yet dealt.
    Returns nb; 0 unless every listed b > a lies where the walk puts it (then the loops
    gather over the full lists)."""
    n = nb_start.shape[0] - 1
    rows = ncy * ncz
    if not half_starts(nb_start, nb_idx, cell_start, ncx, ncy, ncz, split, nb_mid):
        return 0
    target = max(n // max(blocks, 1), 1)
    colour = np.empty(rows + 1, dtype=np.int64)
    nb = 0
    half[0] = 0
    slab = 0
    first = 0                         # the first layer of the open slab
    for lay in range(ncz):
        end = cell_start[(lay + 1) * ncy * ncx]
        if end - half[nb] < target and lay < ncz - 1:
            continue                  # the slab takes the next layer too
        if split and lay == first and ncy >= 4:
            j = 0
            r0 = lay * ncy            # the open block's first row
            for r in range(lay * ncy + 1, (lay + 1) * ncy):
                at = cell_start[r * ncx]
                if at - half[nb] >= target and r - r0 >= 2 and (lay + 1) * ncy - r >= 2:
                    colour[nb] = 2 * (slab % 2) + j % 2
                    nb += 1
                    half[nb] = at
                    j += 1
                    r0 = r
            colour[nb] = 2 * (slab % 2) + j % 2
        else:
            colour[nb] = 2 * (slab % 2)
        nb += 1
        half[nb] = end
        slab += 1
        first = lay + 1
    k = nb + 1
    cs = k + nb
    for c in range(BLOCK_COLOURS):
        half[cs + c] = k - (nb + 1)
        for i in range(nb):
            if colour[i] == c:
                half[k] = i
                k += 1
    half[cs + BLOCK_COLOURS] = nb
    return nb
