"""Solitary waves as initial conditions (P §4): particles up to the local free surface,
velocity and pressure from a wave theory (``constant/waveProperties``)."""

from __future__ import annotations

import numpy as np

from sphfoam.case.schemas import BoxRegion
from sphfoam.case.geometry import lattice_count


def wave_columns(region: BoxRegion, dx: float, waves, g: float):
    """Particles of a box of still water with the waves on it.

    Columns stay dx apart; each holds n = round((d + eta)/dx) particles evenly spaced from
    the bed to the local surface d + eta(x) (P §4: "about the same spacing d along the
    vertical, the exact vertical spacing follows from the local free surface position").
    Returns x, y and the vertical spacing dy of each particle.
    """
    (x0, bed), (x1, top) = region.min, region.max
    d = top - bed
    nx = lattice_count(x1 - x0, dx)
    xc = x0 + dx * (np.arange(nx) + 0.5)
    eta = surface(xc, d, waves, g)
    n = np.maximum(1, np.round((d + eta) / dx).astype(int))
    dy = (d + eta) / n
    col = np.repeat(np.arange(nx), n)
    j = np.arange(col.size) - np.repeat(np.cumsum(n) - n, n)
    return xc[col], bed + (j + 0.5) * dy[col], dy[col]


def _solitary(mdl, w, d, g):
    return mdl.solitary(w.height, d, g=g)


def _frame(w, x):
    """x in the frame of a wave travelling to +x (mirrored about x0 for direction -1)."""
    return x if w.direction == 1 else 2.0 * w.x0 - x


def surface(x, d, waves, g):
    """Sum of the waves' elevations eta(x) (well separated waves superpose)."""
    eta = np.zeros_like(np.asarray(x, float))
    for w, mdl in waves:
        eta += _solitary(mdl, w, d, g).eta(_frame(w, x), x0=w.x0)
    return eta


def fields(x, y, bed, d, waves, g, rho0):
    """(u, v, p) at particles (x, y) of the still-water box [bed, bed + d].

    Velocities add up; the pressure is hydrostatic below the total surface plus each
    theory's dynamic part p_w - rho0 g (d + eta_w - z) (zero for the hydrostatic theories).
    """
    z = y - bed
    u = np.zeros_like(x)
    v = np.zeros_like(x)
    eta = surface(x, d, waves, g)
    p = rho0 * g * np.maximum(d + eta - z, 0.0)
    for w, mdl in waves:
        sw = _solitary(mdl, w, d, g)
        sw.rho = rho0
        xf = _frame(w, x)
        u += w.direction * sw.u(xf, z, x0=w.x0)
        v += sw.w(xf, z, x0=w.x0)
        p += sw.p(xf, z, x0=w.x0) - rho0 * g * (d + sw.eta(xf, x0=w.x0) - z)
    return u, v, np.maximum(p, 0.0)
