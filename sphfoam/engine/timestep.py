"""Variable time step of Monaghan & Kos (1999), T(3.88)-(3.90)."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, fastmath=False)
def stable_time_step(h, c, sigma, ax, ay, kind, beta, force_condition):
    """beta * min over fluid particles of h / (c_a + sigma_a), T(3.88)-(3.89), and, when
    ``force_condition``, of sqrt(h / |F_a|), T(3.90). Returns +inf for an empty set."""
    dt = math.inf
    fmax = 0.0
    for a in range(c.shape[0]):
        if kind[a] != 0:
            continue
        d = h / (c[a] + sigma[a])
        if d < dt:
            dt = d
        f2 = ax[a] * ax[a] + ay[a] * ay[a]
        if f2 > fmax:
            fmax = f2
    if force_condition and fmax > 0.0:
        df = math.sqrt(h / math.sqrt(fmax))
        if df < dt:
            dt = df
    return beta * dt
