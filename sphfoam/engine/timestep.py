"""Variable time step of Monaghan & Kos (1999), T(3.88)-(3.90)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphfoam.engine.neighbours import REDUCTION_CHUNKS


def stable_time_step(h, c, sigma, ax, ay, kind, beta, force_condition, az=None):
    """:func:`stable_time_step_into` with scratch of its own."""
    return stable_time_step_into(h, c, sigma, ax, ay, kind, beta, force_condition,
                                 np.empty((2, REDUCTION_CHUNKS)),
                                 ax[:0] if az is None else az)


@njit(cache=True, fastmath=False, parallel=True)
def stable_time_step_into(h, c, sigma, ax, ay, kind, beta, force_condition, scratch, az):
    """beta * min over fluid particles of h / (c_a + sigma_a), T(3.88)-(3.89), and, when
    ``force_condition``, of sqrt(h / |F_a|), T(3.90). Returns +inf for an empty set.
    Parallel over ``REDUCTION_CHUNKS`` ranges of particles (min and max are exact, so the
    result does not depend on the thread count). ``scratch``: a (2, REDUCTION_CHUNKS) float
    array the caller keeps, so that a step allocates nothing. ``az``: dv/dt along z in three
    dimensions, empty in two."""
    three = az.shape[0] > 0
    n = c.shape[0]
    nc = REDUCTION_CHUNKS
    dtc = scratch[0]
    fc = scratch[1]
    for ci in prange(nc):
        dt = math.inf
        fmax = 0.0
        for a in range(ci * n // nc, (ci + 1) * n // nc):
            if kind[a] != 0:
                continue
            d = h / (c[a] + sigma[a])
            if d < dt:
                dt = d
            f2 = ax[a] * ax[a] + ay[a] * ay[a]
            if three:
                f2 += az[a] * az[a]
            if f2 > fmax:
                fmax = f2
        dtc[ci] = dt
        fc[ci] = fmax
    dt = math.inf
    fmax = 0.0
    for ci in range(nc):
        if dtc[ci] < dt:
            dt = dtc[ci]
        if fc[ci] > fmax:
            fmax = fc[ci]
    if force_condition and fmax > 0.0:
        df = math.sqrt(h / math.sqrt(fmax))
        if df < dt:
            dt = df
    return beta * dt
