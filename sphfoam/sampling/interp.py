"""SPH interpolation at arbitrary points in two or three dimensions, over a cell list.

The function objects that read the fluid at points (3-D ``probes``, ``pressureSensors``,
``slices``) and the pair sums of ``forces`` share this: the particles are binned in cubic
cells of the kernel's support (``bin_particles``), and each compiled loop visits the 3 x 3
(x 3) cells around a point. A 2-D case is the 3-D one with z = 0 and one layer of cells.

The interpolant is Shepard-normalised, as DualSPHysics' MeasureTool computes it:

    A(r) = sum_b A_b V_b W(r - r_b) / sum_b V_b W(r - r_b),   V_b = m_b / rho_b

over the fluid particles, with the case's kernel W (its alpha_d / h^d, so that the kernel
sum sum_b V_b W(r - r_b) is about 1 inside the water, 1/2 on a flat free surface or wall).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


class Cells:
    """Particles binned in cubic cells of side ``size`` (>= the kernel's support)."""

    def __init__(self, pos: np.ndarray, size: float):
        pos = np.asarray(pos, dtype=float)
        if pos.ndim != 2 or pos.shape[1] not in (2, 3):
            raise ValueError("positions must be (n, 2) or (n, 3)")
        if pos.shape[1] == 2:
            pos = np.column_stack([pos, np.zeros(len(pos))])
        self.size = float(size)
        if len(pos):
            self.lo = pos.min(axis=0) - 1e-9 * max(1.0, float(np.abs(pos).max()))
            hi = pos.max(axis=0)
        else:
            self.lo = np.zeros(3)
            hi = np.zeros(3)
        self.n = np.maximum(np.floor((hi - self.lo) / self.size).astype(np.int64) + 1, 1)
        ijk = np.floor((pos - self.lo) / self.size).astype(np.int64)
        ijk = np.clip(ijk, 0, self.n - 1)
        key = (ijk[:, 0] * self.n[1] + ijk[:, 1]) * self.n[2] + ijk[:, 2]
        self.order = np.argsort(key, kind="stable")
        skey = key[self.order]
        self.starts = np.searchsorted(skey, np.arange(int(np.prod(self.n)) + 1)).astype(np.int64)
        self.pos = np.ascontiguousarray(pos[self.order])

    def sorted(self, a) -> np.ndarray:
        """A per-particle array in the cells' order."""
        return np.ascontiguousarray(np.asarray(a, dtype=float)[..., self.order])


@njit(cache=True)
def _shepard_cells(pos, vol, vals, starts, lo, ncell, size, q3, inv_h, w0, support,
                   kernel_f):
    """(values (nFields, nPoints), kernel sums (nPoints)) at the points q3 (nPoints, 3)."""
    nf, nq = vals.shape[0], q3.shape[0]
    out = np.empty((nf, nq))
    ksum = np.zeros(nq)
    acc = np.empty(nf)
    reach2 = (support / inv_h) ** 2
    for k in range(nq):
        for j in range(nf):
            acc[j] = 0.0
        wsum = 0.0
        ci = int(math.floor((q3[k, 0] - lo[0]) / size))
        cj = int(math.floor((q3[k, 1] - lo[1]) / size))
        ck = int(math.floor((q3[k, 2] - lo[2]) / size))
        for i in range(ci - 1, ci + 2):
            if i < 0 or i >= ncell[0]:
                continue
            for j2 in range(cj - 1, cj + 2):
                if j2 < 0 or j2 >= ncell[1]:
                    continue
                for k2 in range(ck - 1, ck + 2):
                    if k2 < 0 or k2 >= ncell[2]:
                        continue
                    c = (i * ncell[1] + j2) * ncell[2] + k2
                    for b in range(starts[c], starts[c + 1]):
                        dx = q3[k, 0] - pos[b, 0]
                        dy = q3[k, 1] - pos[b, 1]
                        dz = q3[k, 2] - pos[b, 2]
                        r2 = dx * dx + dy * dy + dz * dz
                        if r2 >= reach2:
                            continue
                        w = kernel_f(math.sqrt(r2) * inv_h) * vol[b]
                        wsum += w
                        for j in range(nf):
                            acc[j] += w * vals[j, b]
        ksum[k] = wsum * w0
        for j in range(nf):
            out[j, k] = acc[j] / wsum if wsum > 0.0 else np.nan
    return out, ksum


def shepard(pos, vol, fields, points, kernel, h, dim) -> tuple[np.ndarray, np.ndarray]:
    """Shepard-normalised SPH interpolation of each row of ``fields`` (nFields, nParticles)
    at ``points`` (nPoints, dim) from particles at ``pos`` (nParticles, dim) of volumes
    ``vol``, with ``kernel`` (the case's kernel model) and smoothing length ``h``; returns
    (values (nFields, nPoints), kernel sums sum_b V_b W (nPoints)). Values are NaN where no
    particle is within the support."""
    reach = kernel.support * h
    cells = Cells(pos, reach)
    pts = np.asarray(points, dtype=float).reshape(-1, dim)
    if dim == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    vals = cells.sorted(np.atleast_2d(np.asarray(fields, dtype=float)))
    return _shepard_cells(cells.pos, cells.sorted(vol), vals, cells.starts, cells.lo,
                          cells.n, cells.size, np.ascontiguousarray(pts), 1.0 / h,
                          kernel.alpha(dim) / h**dim, float(kernel.support), kernel.f_jit)


@njit(cache=True)
def _select(kind, want, x, y, z, lo, hi):
    """Indices of the particles of ``kind`` ``want`` inside the box [lo, hi] (one pass)."""
    out = np.empty(x.shape[0], np.int64)
    k = 0
    for a in range(x.shape[0]):
        if kind[a] != want:
            continue
        if x[a] < lo[0] or x[a] > hi[0] or y[a] < lo[1] or y[a] > hi[1] \
                or z[a] < lo[2] or z[a] > hi[2]:
            continue
        out[k] = a
        k += 1
    return out[:k]


def fluid_arrays(state, dim, near=None, reach: float = 0.0):
    """(indices, positions (n, dim), volumes m/rho) of the fluid particles of ``state``;
    with ``near`` (points (nPoints, dim)), only those inside the points' bounding box grown
    by ``reach`` (the kernel's support: every particle that can reach a point), found in
    one compiled pass, so that sampling a few points costs little in a large case."""
    from sphfoam.engine.state import FLUID

    xyz = list(state.positions[:dim])
    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    if near is not None:
        pts = np.asarray(near, dtype=float).reshape(-1, dim)
        pts = pts[np.isfinite(pts).all(axis=1)]
        if len(pts):
            lo[:dim], hi[:dim] = pts.min(axis=0) - reach, pts.max(axis=0) + reach
    z = xyz[2] if dim == 3 else xyz[1]
    sel = _select(np.ascontiguousarray(state.kind), FLUID, np.ascontiguousarray(xyz[0]),
                  np.ascontiguousarray(xyz[1]), np.ascontiguousarray(z), lo, hi)
    pos = np.column_stack([a[sel] for a in xyz]) if len(sel) else np.zeros((0, dim))
    return sel, pos, state.m[sel] / state.rho[sel]
