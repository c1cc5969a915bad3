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

    Velocities add up (each wave's from :func:`velocity`); the pressure is hydrostatic below
    the total surface plus each theory's dynamic part p_w - rho0 g (d + eta_w - z) (zero for
    the hydrostatic theories).
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
        uw, vw = velocity(sw, xf, z, w.x0, getattr(w, "velocity", "theory"))
        u += w.direction * uw
        v += vw
        p += sw.p(xf, z, x0=w.x0) - rho0 * g * (d + sw.eta(xf, x0=w.x0) - z)
    return u, v, np.maximum(p, 0.0)


# --- a kinematically consistent velocity (issue 35, a quiet start) -------------------------
#: Gauss-Legendre rule of the vertical integrals of u (the profiles are smooth in z)
_GAUSS = np.polynomial.legendre.leggauss(24)
#: a theory is kinematically consistent when its flux is c eta and div u = 0 to this
#: (relative; the exact wave 1e-9, Fenton's ninth order 1e-4, KdV2 3e-2, KdV1 1.2e-1)
KINEMATIC_TOL = 1e-3


def _u_integral(sw, x, z, x0):
    """int_0^z u(x, z') dz' at each (x, z), z measured from the bed."""
    t, wt = _GAUSS
    zz = 0.5 * z[:, None] * (t[None, :] + 1.0)
    return 0.5 * z * (sw.u(np.broadcast_to(x[:, None], zz.shape), zz, x0=x0)
                      * wt[None, :]).sum(axis=1)


def flux_scale(sw, x, x0):
    """s = c eta / Q with Q = int_0^(d + eta) u dz the theory's flux through the column at x:
    1 where the theory conserves mass as a wave of permanent form (d/dx Q = c d/dx eta, the
    kinematic surface condition integrated over the column), 1 in still water."""
    x = np.asarray(x, float)
    eta = sw.eta(x, x0=x0)
    Q = _u_integral(sw, x, sw.d + eta, x0)
    ok = np.abs(Q) > 1e-12 * sw.c * sw.A
    return np.where(ok, sw.c * eta / np.where(ok, Q, 1.0), 1.0)


def is_kinematic(sw, tol: float = KINEMATIC_TOL) -> bool:
    """Whether the theory's (u, w) is divergence-free and carries the flux c eta (to ``tol``)
    over its wave: checked on a few columns within two half-widths of the crest."""
    L = 2.0 / sw.decay * np.log(4.0)                     # eta > A/16 or so
    x = np.linspace(-L, L, 9)
    if np.max(np.abs(flux_scale(sw, x, 0.0) - 1.0)) > tol:
        return False
    X, F = np.meshgrid(x, [0.1, 0.5, 0.9])
    X = X.ravel()
    z = F.ravel() * (sw.d + sw.eta(X))
    e = 1e-6 * sw.d
    div = ((sw.u(X + e, z) - sw.u(X - e, z)) + (sw.w(X, z + e) - sw.w(X, z - e))) / (2 * e)
    dudx = (sw.u(X + e, z) - sw.u(X - e, z)) / (2 * e)
    return float(np.max(np.abs(div))) <= tol * float(np.max(np.abs(dudx)))


def continuity_velocity(sw, x, z, x0):
    """(u, w) of a wave of permanent form made from a theory's u: u' = s(x) u with s = c eta/Q
    (:func:`flux_scale`), so its flux is c eta, and w' = -d/dx int_0^z u' dz' from continuity
    (w' = 0 on the bed). div u' = 0 exactly and, with the flux c eta, the kinematic surface
    condition w' = (u' - c) d eta/dx holds at z = d + eta (T(4.6)'s streamline): the start is
    solenoidal. The approximate theories' own fields are not: P's KdV2 (P(13)-(17)) has
    |div u| up to 12 % of |du/dx| at A/d = 0.3 and a surface flux 3 % off c eta, which SPH's
    continuity turns into pressure at t = 0 (interior drho/dt error 2.6 kg/m^3/s against
    0.2 for the exact wave at d/dx = 16) and its crest into a 3 % rise within 1.2 s."""
    x, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(z, float))
    e = 1e-5 * sw.d
    u = flux_scale(sw, x, x0) * sw.u(x, z, x0=x0)
    iplus = flux_scale(sw, x + e, x0) * _u_integral(sw, x + e, z, x0)
    iminus = flux_scale(sw, x - e, x0) * _u_integral(sw, x - e, z, x0)
    return u, -(iplus - iminus) / (2.0 * e)


def velocity(sw, x, z, x0, mode: str = "continuity"):
    """(u, w) of wave ``sw`` for waveProperties ``velocity``: ``theory``, the theory's own;
    ``continuity``, the same for a kinematically consistent theory (:func:`is_kinematic`:
    the exact wave, McCowan, Boussinesq, Fenton) and :func:`continuity_velocity` else."""
    if mode == "theory" or is_kinematic(sw):
        return sw.u(x, z, x0=x0), sw.w(x, z, x0=x0)
    return continuity_velocity(sw, x, z, x0)
