"""Mirrored ghost particles in three dimensions, T(3.77)-(3.80) across plane walls.

The walls are the closed faces of ``box`` tanks (axis-aligned planes), passed as a (F, 10)
array: axis k, position c, sign s of the normal into the fluid (the fluid is where
s (x_k - c) > 0), the face's extent along the two other axes k+1, k+2 (mod 3) as
(lo1, hi1, lo2, hi2), and the wall's velocity (Ux, Uy, Uz). A fluid particle closer than
``reach`` to a face (on its fluid side, projecting onto it) is reflected across it; near two
faces of different axes (an edge) it is also reflected across both, near three (a vertex)
across every pair and all three: one ghost per non-empty set of its near faces with
distinct axes, the 2-D corner ghost one dimension up. Each ghost keeps its set as up to three
face indices (``f1``, ``f2``, ``f3``; -1 for none).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphfoam.engine.fastmath import FASTMATH

_JIT = dict(cache=True, fastmath=set(FASTMATH))


def plane_array(planes, offsets=None, velocities=None) -> np.ndarray:
    """The (F, 10) array of :class:`sphfoam.case.geometry.Plane` faces; ``offsets`` and
    ``velocities`` (by wall entry, 3-vectors) move a moving tank's faces with it."""
    out = np.zeros((len(planes), 10))
    for i, p in enumerate(planes):
        off = (offsets or {}).get(p.patch, (0.0, 0.0, 0.0))
        k, k1, k2 = p.axis, (p.axis + 1) % 3, (p.axis + 2) % 3
        lo1, hi1, lo2, hi2 = p.extent
        out[i, :7] = (k, p.position + off[k], p.sign, lo1 + off[k1], hi1 + off[k1],
                      lo2 + off[k2], hi2 + off[k2])
        out[i, 7:] = (velocities or {}).get(p.patch, p.velocity)
    return out


@njit(**_JIT, inline="always")
def _coord(xa, ya, za, k):
    if k == 0:
        return xa
    if k == 1:
        return ya
    return za


@njit(**_JIT, inline="always")
def _near(xa, ya, za, pl, f, reach, margin):
    """Particle a is on the fluid side of face ``f``, closer than ``reach`` and projecting
    onto it (its extent widened by ``margin``)."""
    k = int(pl[f, 0])
    d = pl[f, 2] * (_coord(xa, ya, za, k) - pl[f, 1])
    if not (d > 0.0 and d < reach):
        return False
    t1 = _coord(xa, ya, za, (k + 1) % 3)
    t2 = _coord(xa, ya, za, (k + 2) % 3)
    return (t1 >= pl[f, 3] - margin and t1 <= pl[f, 4] + margin
            and t2 >= pl[f, 5] - margin and t2 <= pl[f, 6] + margin)


@njit(**_JIT, inline="always")
def _near_faces(xa, ya, za, pl, reach, margin, out):
    """The faces particle a is near, into ``out``; returns how many."""
    m = 0
    for f in range(pl.shape[0]):
        if _near(xa, ya, za, pl, f, reach, margin):
            out[m] = f
            m += 1
    return m


@njit(**_JIT, inline="always")
def _distinct(pl, near, mask):
    """The faces ``near[i]`` for the bits i of ``mask`` lie on distinct axes."""
    seen = 0
    for i in range(6):
        if mask & (1 << i):
            bit = 1 << int(pl[near[i], 0])
            if seen & bit:
                return False
            seen |= bit
    return True


@njit(**_JIT, inline="always")
def ghosts_of(xa, ya, za, pl, reach, margin, near):
    """How many ghosts particle a makes: one per non-empty set of its near faces whose axes
    differ (a face: 1; an edge: 3; a vertex: 7). ``near``: scratch for 6 face indices."""
    m = _near_faces(xa, ya, za, pl, reach, margin, near)
    k = 0
    for mask in range(1, 1 << m):
        if _distinct(pl, near, mask):
            k += 1
    return k


@njit(parallel=True, **_JIT)
def count_ghosts(x, y, z, kind, pl, reach, count, margin=0.0):
    for a in prange(x.shape[0]):
        k = 0
        if kind[a] == 0:
            k = ghosts_of(x[a], y[a], z[a], pl, reach, margin, np.empty(6, dtype=np.int64))
        count[a] = k


@njit(**_JIT, inline="always")
def fill_of(a, xa, ya, za, pl, reach, margin, j, src, f1, f2, f3, near):
    """The ghosts of particle a into slots j on: its index and faces (``near``: scratch for
    6 face indices)."""
    m = _near_faces(xa, ya, za, pl, reach, margin, near)
    for mask in range(1, 1 << m):
        if not _distinct(pl, near, mask):
            continue
        src[j] = a
        f1[j] = -1
        f2[j] = -1
        f3[j] = -1
        n = 0
        for i in range(m):
            if mask & (1 << i):
                if n == 0:
                    f1[j] = near[i]
                elif n == 1:
                    f2[j] = near[i]
                else:
                    f3[j] = near[i]
                n += 1
        j += 1


@njit(parallel=True, **_JIT)
def fill_ghosts(x, y, z, kind, pl, reach, offset, src, f1, f2, f3, margin=0.0):
    """Ghost j mirrors particle ``src[j]`` across the faces f1[j] (f2[j], f3[j] >= 0)."""
    for a in prange(x.shape[0]):
        if kind[a] != 0:
            continue
        fill_of(a, x[a], y[a], z[a], pl, reach, margin, offset[a], src, f1, f2, f3,
                np.empty(6, dtype=np.int64))


@njit(**_JIT, inline="always")
def _reflect(p, vel, pl, f, no_slip):
    """T(3.77)-(3.79) across face ``f`` in place: x_G = 2 x_w - x_a; the normal velocity
    u_nG = 2 U_n - u_n (and, no-slip, the tangential ones likewise)."""
    k = int(pl[f, 0])
    p[k] = 2.0 * pl[f, 1] - p[k]
    if not no_slip:
        vel[k] = 2.0 * pl[f, 7 + k] - vel[k]


@njit(**_JIT, inline="always")
def ghost_state(xa, ya, za, ua, va, wa, rhoa, pl, f1, f2, f3, no_slip, hydro, gx, gy, gz,
                rho0, B, gamma, p, vel, mean):
    """(x, y, z, u, v, w, rho) of the ghost of particle a across the faces f1 (f2, f3 >= 0):
    T(3.77)-(3.80). No-slip: u_G = 2 U - u_a with U the mean velocity of the ghost's faces
    (zero relative velocity at the wall, the edge and the vertex alike); free slip: each
    face reflects the normal component. ``hydro``: p_G = p_a + rho_a g.(x_G - x_a), as the
    density the Tait equation gives it. ``p``, ``vel``, ``mean``: scratch for 3 each."""
    p[0], p[1], p[2] = xa, ya, za
    vel[0], vel[1], vel[2] = ua, va, wa
    n = 0
    mean[0] = mean[1] = mean[2] = 0.0
    for f in (f1, f2, f3):
        if f >= 0:
            _reflect(p, vel, pl, f, no_slip)
            mean[0] += pl[f, 7]
            mean[1] += pl[f, 8]
            mean[2] += pl[f, 9]
            n += 1
    if no_slip:
        for k in range(3):
            vel[k] = 2.0 * mean[k] / n - (ua if k == 0 else (va if k == 1 else wa))
    rhog = rhoa
    if hydro:
        pa = B * ((rhoa / rho0) ** gamma - 1.0)
        pg = pa + rhoa * (gx * (p[0] - xa) + gy * (p[1] - ya) + gz * (p[2] - za))
        rhog = rho0 * max(1.0 + pg / B, 1e-6) ** (1.0 / gamma)
    return p[0], p[1], p[2], vel[0], vel[1], vel[2], rhog


@njit(parallel=True, **_JIT)
def refresh_ghosts(x, y, z, u, v, w, rho, m, gidx, src, f1, f2, f3, pl, no_slip, active,
                   hydro=False, gx=0.0, gy=0.0, gz=0.0, rho0=1000.0, B=1.0, gamma=7.0):
    """Every ghost from its particle's current state (:func:`ghost_state`); a dormant one
    (``active[j]`` False) gets mass 0, as in two dimensions (``mirror.refresh_ghosts``)."""
    for j in prange(gidx.shape[0]):
        g = gidx[j]
        a = src[j]
        x[g], y[g], z[g], u[g], v[g], w[g], rho[g] = ghost_state(
            x[a], y[a], z[a], u[a], v[a], w[a], rho[a], pl, f1[j], f2[j], f3[j], no_slip,
            hydro, gx, gy, gz, rho0, B, gamma, np.empty(3), np.empty(3), np.empty(3))
        m[g] = m[a] if active[j] else 0.0


@njit(**_JIT, inline="always")
def ghost_on(xa, ya, za, pl, f1, f2, f3, reach):
    """Whether particle a still makes its ghost across f1 (f2, f3): within ``reach`` of each
    face, projecting onto it."""
    return (_near(xa, ya, za, pl, f1, reach, 0.0)
            and (f2 < 0 or _near(xa, ya, za, pl, f2, reach, 0.0))
            and (f3 < 0 or _near(xa, ya, za, pl, f3, reach, 0.0)))


@njit(parallel=True, **_JIT)
def ghost_activity(x, y, z, src, f1, f2, f3, pl, reach, active):
    """``active[j]``: ghost j's particle meets its faces' criterion now; returns how many."""
    n_on = 0
    for j in prange(src.shape[0]):
        a = src[j]
        on = ghost_on(x[a], y[a], z[a], pl, f1[j], f2[j], f3[j], reach)
        active[j] = on
        if on:
            n_on += 1
    return n_on


@njit(**_JIT, inline="always")
def fluid_within(g, x, y, z, kind, nb_start, nb_idx, support2):
    """How many fluid neighbours of particle g are within the support."""
    k = 0
    for i in range(nb_start[g], nb_start[g + 1]):
        b = nb_idx[i]
        if kind[b] == 0:
            dx = x[g] - x[b]
            dy = y[g] - y[b]
            dz = z[g] - z[b]
            if dx * dx + dy * dy + dz * dz < support2:
                k += 1
    return k


@njit(parallel=True, **_JIT)
def dormant_ghost_near_fluid(x, y, z, kind, gidx, active, nb_start, nb_idx, support2):
    """Whether a dormant ghost has a fluid neighbour within the support."""
    bad = 0
    for j in prange(gidx.shape[0]):
        if active[j]:
            continue
        bad += fluid_within(gidx[j], x, y, z, kind, nb_start, nb_idx, support2)
    return bad > 0


@njit(**_JIT, inline="always")
def push_back_of(xa, ya, za, ua, va, wa, pl, f, reach):
    """Particle a after face ``f``'s push-back: if it crossed the face (within ``reach``
    behind it, projecting onto it) it is reflected back, its normal velocity relative to the
    wall reversed where it points out of the fluid: (x, y, z, u, v, w, 1), else unchanged
    with 0."""
    k = int(pl[f, 0])
    s = pl[f, 2]
    if k == 0:
        q, un = xa, ua
    elif k == 1:
        q, un = ya, va
    else:
        q, un = za, wa
    d = s * (q - pl[f, 1])
    if not (d <= 0.0 and d > -reach):
        return xa, ya, za, ua, va, wa, 0
    t1 = xa if k == 2 else (ya if k == 0 else za)
    t2 = ya if k == 2 else (za if k == 0 else xa)
    if not (t1 >= pl[f, 3] and t1 <= pl[f, 4] and t2 >= pl[f, 5] and t2 <= pl[f, 6]):
        return xa, ya, za, ua, va, wa, 0
    q = q - 2.0 * s * d
    rel = s * (un - pl[f, 7 + k])
    if rel < 0.0:
        un = un - 2.0 * s * rel
    if k == 0:
        return q, ya, za, un, va, wa, 1
    if k == 1:
        return xa, q, za, ua, un, wa, 1
    return xa, ya, q, ua, va, un, 1


@njit(parallel=True, **_JIT)
def push_back(x, y, z, u, v, w, kind, pl, reach):
    """A fluid particle that crossed a face (:func:`push_back_of`, face by face) is put back.
    Returns how many were."""
    count = 0
    for a in prange(x.shape[0]):
        if kind[a] != 0:
            continue
        for f in range(pl.shape[0]):
            x[a], y[a], z[a], u[a], v[a], w[a], k = push_back_of(
                x[a], y[a], z[a], u[a], v[a], w[a], pl, f, reach)
            count += k
    return count
