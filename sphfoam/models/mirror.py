"""Mirrored ghost particles, T(3.77)-(3.80): creation each step, refresh at every stage.

Wall segments are passed as a (S, 9) array: p0x, p0y, tx, ty, nx, ny, L, Ux, Uy (start
point, unit tangent, unit normal into the fluid, length, wall velocity). ``corners`` is a
(K, 2) int array of perpendicular segment pairs sharing a vertex. A fluid particle within
``reach`` of a segment (on its fluid side, projecting onto it) gets one ghost per such
segment, and one more per corner whose two segments both qualify.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from sphfoam.engine.fastmath import FASTMATH
from sphfoam.models.walllaw import LAWS, rough_ustar, smooth_ustar, uplus_ustar

_JIT = dict(cache=True, fastmath=set(FASTMATH))


@njit(**_JIT, inline="always")
def _local(xa, ya, seg, s):
    """(t, d): the position of (xa, ya) along segment ``s`` from its start and its signed
    distance from the wall line, positive on the fluid side."""
    rx = xa - seg[s, 0]
    ry = ya - seg[s, 1]
    return rx * seg[s, 2] + ry * seg[s, 3], rx * seg[s, 4] + ry * seg[s, 5]


@njit(**_JIT, inline="always")
def _near(xa, ya, seg, s, reach, margin=0.0):
    """Particle (xa, ya) is on the fluid side of segment ``s``, closer than ``reach`` and
    projecting onto it (extended by ``margin`` at both ends)."""
    t, d = _local(xa, ya, seg, s)
    return d > 0.0 and d < reach and t >= -margin and t <= seg[s, 6] + margin


@njit(**_JIT, inline="always")
def ghosts_of(xa, ya, seg, corners, reach, margin):
    """How many ghosts particle (xa, ya) makes, T(3.77): one per segment it is near, one more
    per corner whose two segments it is near both."""
    k = 0
    for s in range(seg.shape[0]):
        if _near(xa, ya, seg, s, reach, margin):
            k += 1
    for c in range(corners.shape[0]):
        if _near(xa, ya, seg, corners[c, 0], reach, margin) and \
                _near(xa, ya, seg, corners[c, 1], reach, margin):
            k += 1
    return k


@njit(**_JIT, inline="always")
def fill_of(a, xa, ya, seg, corners, reach, margin, j, src, s1, s2):
    """The ghosts of particle ``a`` at (xa, ya) from slot ``j`` on (:func:`ghosts_of` of
    them): ghost j mirrors ``src[j]`` across segment ``s1[j]`` (and ``s2[j]`` >= 0)."""
    for s in range(seg.shape[0]):
        if _near(xa, ya, seg, s, reach, margin):
            src[j] = a
            s1[j] = s
            s2[j] = -1
            j += 1
    for c in range(corners.shape[0]):
        if _near(xa, ya, seg, corners[c, 0], reach, margin) and \
                _near(xa, ya, seg, corners[c, 1], reach, margin):
            src[j] = a
            s1[j] = corners[c, 0]
            s2[j] = corners[c, 1]
            j += 1
    return j


@njit(parallel=True, **_JIT)
def count_ghosts(x, y, kind, seg, corners, reach, count, margin=0.0):
    for a in prange(x.shape[0]):
        k = 0
        if kind[a] == 0:
            k = ghosts_of(x[a], y[a], seg, corners, reach, margin)
        count[a] = k


@njit(parallel=True, **_JIT)
def fill_ghosts(x, y, kind, seg, corners, reach, offset, src, s1, s2, margin=0.0):
    """Ghost j mirrors particle ``src[j]`` across segment ``s1[j]`` (and ``s2[j]`` >= 0)."""
    for a in prange(x.shape[0]):
        if kind[a] != 0:
            continue
        fill_of(a, x[a], y[a], seg, corners, reach, margin, offset[a], src, s1, s2)


@njit(**_JIT, inline="always")
def push_back_of(xa, ya, ua, va, seg, s, reach):
    """(x, y, u, v, 1) of a fluid particle at (xa, ya) that crossed segment ``s`` within
    ``reach`` behind it, reflected back with its normal velocity relative to the wall
    reversed where it points out of the fluid; (xa, ya, ua, va, 0) otherwise."""
    t, d = _local(xa, ya, seg, s)
    if d <= 0.0 and d > -reach and t >= 0.0 and t <= seg[s, 6]:
        px = xa - 2.0 * d * seg[s, 4]
        py = ya - 2.0 * d * seg[s, 5]
        un = (ua - seg[s, 7]) * seg[s, 4] + (va - seg[s, 8]) * seg[s, 5]
        if un < 0.0:
            return px, py, ua - 2.0 * un * seg[s, 4], va - 2.0 * un * seg[s, 5], 1
        return px, py, float(ua), float(va), 1
    return xa, ya, float(ua), float(va), 0


@njit(parallel=True, **_JIT)
def push_back(x, y, u, v, kind, seg, reach):
    """A fluid particle that has crossed a wall line within ``reach`` behind it (a step too
    long near an impermeable mirror wall, where the particle's own ghost pushes it with a
    kernel gradient that vanishes as it reaches the line) is reflected back with its
    normal velocity relative to the wall reversed. Returns how many were."""
    count = 0
    for a in prange(x.shape[0]):
        if kind[a] != 0:
            continue
        for s in range(seg.shape[0]):
            px, py, pu, pv, k = push_back_of(x[a], y[a], u[a], v[a], seg, s, reach)
            if k:
                x[a] = px
                y[a] = py
                u[a] = pu
                v[a] = pv
                count += 1
    return count


@njit(**_JIT, inline="always")
def _reflect_point(px, py, seg, s):
    """T(3.77): x_G = 2 x_w - x_a, x_w the foot of the normal on the wall line."""
    d = (px - seg[s, 0]) * seg[s, 4] + (py - seg[s, 1]) * seg[s, 5]
    return px - 2.0 * d * seg[s, 4], py - 2.0 * d * seg[s, 5]


@njit(**_JIT, inline="always")
def _reflect_velocity(u, v, seg, s, no_slip):
    """T(3.78)-(3.79): u_nG = 2 U_n - u_n; u_sG = u_s (free slip) or 2 U_s - u_s (no-slip)."""
    if no_slip:
        return 2.0 * seg[s, 7] - u, 2.0 * seg[s, 8] - v
    un = (u - seg[s, 7]) * seg[s, 4] + (v - seg[s, 8]) * seg[s, 5]
    return u - 2.0 * un * seg[s, 4], v - 2.0 * un * seg[s, 5]


@njit(**_JIT, inline="always")
def ghost_state(xa, ya, ua, va, rhoa, seg, s1, s2, no_slip, hydro, gx, gy, rho0, B, gamma):
    """(x_G, y_G, u_G, v_G, rho_G) of the ghost of particle a across segment ``s1`` (and
    ``s2`` >= 0, the corner ghost): T(3.77)-(3.80), or with ``hydro`` the hydrostatic
    pressure (see :func:`refresh_ghosts`)."""
    px, py = _reflect_point(xa, ya, seg, s1)
    gu, gv = _reflect_velocity(ua, va, seg, s1, no_slip)
    if s2 >= 0:
        px, py = _reflect_point(px, py, seg, s2)
        if no_slip:
            # relative to the mean velocity of the two walls: zero relative velocity there
            gu = seg[s1, 7] + seg[s2, 7] - ua
            gv = seg[s1, 8] + seg[s2, 8] - va
        else:
            gu, gv = _reflect_velocity(gu, gv, seg, s2, False)
    rhog = rhoa
    if hydro:
        pa = B * ((rhoa / rho0) ** gamma - 1.0)
        pg = pa + rhoa * (gx * (px - xa) + gy * (py - ya))
        rhog = rho0 * max(1.0 + pg / B, 1e-6) ** (1.0 / gamma)
    return px, py, gu, gv, rhog


@njit(parallel=True, **_JIT)
def refresh_ghosts(x, y, u, v, rho, m, gidx, src, s1, s2, seg, no_slip, active,
                   hydro=False, gx=0.0, gy=0.0, rho0=1000.0, B=1.0, gamma=7.0):
    """Position, velocity, density and mass of every ghost from its particle's current
    state. Density: p_G = p_a, T(3.80); or, with ``hydro``, the pressure of the hydrostatic
    Neumann condition dp/dn = rho g.n (the hydrostatic part of Adami, Hu & Adams 2012,
    eq. (27), for one image), p_G = p_a + rho_a g.(x_G - x_a), as the density the Tait
    equation T(3.27) (rho0, B, gamma) gives that pressure. A ghost with ``active[j]`` False
    is *dormant*: it gets mass 0, so that every mass-weighted sum over it adds exactly 0.0
    (ghosts are kept between rebuilds of the neighbour list: ``keeps_neighbours``)."""
    for j in prange(gidx.shape[0]):
        g = gidx[j]
        a = src[j]
        x[g], y[g], u[g], v[g], rho[g] = ghost_state(x[a], y[a], u[a], v[a], rho[a], seg,
                                                     s1[j], s2[j], no_slip, hydro, gx, gy,
                                                     rho0, B, gamma)
        m[g] = m[a] if active[j] else 0.0


@njit(**_JIT, inline="always")
def ghost_on(xa, ya, seg, s1, s2, reach):
    """Whether particle (xa, ya) still makes its ghost across ``s1`` (and ``s2`` >= 0): within
    ``reach`` of the segment(s), projecting onto them (the criterion of T(3.77))."""
    return _near(xa, ya, seg, s1, reach, 0.0) and \
        (s2 < 0 or _near(xa, ya, seg, s2, reach, 0.0))


@njit(parallel=True, **_JIT)
def ghost_activity(x, y, src, s1, s2, seg, reach, active):
    """``active[j]``: the particle of ghost j is now within ``reach`` of its segment(s),
    projecting onto them (the criterion a ghost is made by, T(3.77)); returns how many are."""
    n_on = 0
    for j in prange(src.shape[0]):
        a = src[j]
        on = ghost_on(x[a], y[a], seg, s1[j], s2[j], reach)
        active[j] = on
        if on:
            n_on += 1
    return n_on


@njit(**_JIT, inline="always")
def fluid_within(g, x, y, kind, nb_start, nb_idx, support2):
    """How many fluid neighbours of particle ``g`` are closer than sqrt(support2)."""
    bad = 0
    for k in range(nb_start[g], nb_start[g + 1]):
        b = nb_idx[k]
        if kind[b] == 0:
            dx = x[g] - x[b]
            dy = y[g] - y[b]
            if dx * dx + dy * dy < support2:
                bad += 1
    return bad


@njit(parallel=True, **_JIT)
def dormant_ghost_near_fluid(x, y, kind, gidx, active, nb_start, nb_idx, support2):
    """Whether a dormant ghost has a fluid neighbour within the support (possible only where
    the walls are not convex: it would enter that particle's sums that are not weighted by
    mass, e.g. T(3.89))."""
    bad = 0
    for j in prange(gidx.shape[0]):
        if active[j]:
            continue
        bad += fluid_within(gidx[j], x, y, kind, nb_start, nb_idx, support2)
    return bad > 0


@njit(cache=True, inline="always")     # no fast-math: it compares with inf
def nearest_line_distance(xa, ya, seg):
    """Signed distance of the point (xa, ya) to the nearest wall line, positive on the fluid
    side: the segment nearest in Euclidean distance (its end points included), then
    n . (x - p0) with its normal n into the fluid; +inf with no segments. ``seg`` is the
    (S, 9) array of :func:`segment_array` (p0x, p0y, tx, ty, nx, ny, L, ...). A scalar
    function: :func:`line_distance` on the host and a device kernel share it."""
    best = math.inf
    sd = math.inf
    for s in range(seg.shape[0]):
        rx = xa - seg[s, 0]
        ry = ya - seg[s, 1]
        t = min(max(rx * seg[s, 2] + ry * seg[s, 3], 0.0), seg[s, 6])
        ex = rx - t * seg[s, 2]
        ey = ry - t * seg[s, 3]
        d = ex * ex + ey * ey
        if d < best:
            best = d
            sd = rx * seg[s, 4] + ry * seg[s, 5]
    return sd


@njit(cache=True)           # no fast-math: it compares with inf
def line_distance(x, y, seg, out):
    """out[i] = :func:`nearest_line_distance` of point i (x[i], y[i])."""
    for i in range(x.shape[0]):
        out[i] = nearest_line_distance(x[i], y[i], seg)


def segment_array(segments, offsets=None, velocities=None) -> np.ndarray:
    """The (S, 9) array of :mod:`sphfoam.models.mirror` from :class:`Segment` s, each moved by
    ``offsets[patch]`` and moving with ``velocities[patch]`` (both optional dicts)."""
    out = np.zeros((len(segments), 9))
    for i, s in enumerate(segments):
        ox, oy = (offsets or {}).get(s.patch, (0.0, 0.0))
        ux, uy = (velocities or {}).get(s.patch, (0.0, 0.0))
        tx, ty = s.tangent
        out[i] = (s.p0[0] + ox, s.p0[1] + oy, tx, ty, s.normal[0], s.normal[1], s.length, ux, uy)
    return out


def corner_pairs(segments, tol: float) -> np.ndarray:
    """Pairs of perpendicular segments that meet (at an end or a T-junction, e.g. a paddle
    standing on the bed) and enclose the fluid: each extends from the meeting point C to
    the fluid side of the other."""
    pairs = []
    for i, a in enumerate(segments):
        for j in range(i + 1, len(segments)):
            b = segments[j]
            if abs(a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1]) > 1e-6:
                continue
            # C: a.p0 + s ta = b.p0 + r tb
            ta, tb = np.array(a.tangent), np.array(b.tangent)
            m = np.array([ta, -tb]).T
            s_, r_ = np.linalg.solve(m, np.array(b.p0) - np.array(a.p0))
            if not (-tol <= s_ <= a.length + tol and -tol <= r_ <= b.length + tol):
                continue
            c = np.array(a.p0) + s_ * ta

            def reaches(seg, normal):
                return max(np.dot(np.array(seg.p0) - c, normal),
                           np.dot(np.array(seg.p1) - c, normal)) > tol

            if reaches(a, np.array(b.normal)) and reaches(b, np.array(a.normal)):
                pairs.append((i, j))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


#: the ``law`` argument of :func:`wall_shear` (its branches) for each law of the wall
WALL_SHEAR_LAWS = {"smooth": 0, "rough": 1, "prescribedUPlus": 2}
assert set(WALL_SHEAR_LAWS) == set(LAWS)


@njit(**_JIT)
def wall_shear_of(xa, ya, ua, va, seg, s, reach, phi, law, coef):
    """(fx, fy, 1): the wall shear of segment ``s`` on a fluid particle near it,
    dv_a/dt = -(fx, fy) = -2 Phi(d_a) u*_a^2 t_a (see :func:`wall_shear`); (0, 0, 0) where
    the particle is not near it or does not move along it."""
    t, d = _local(xa, ya, seg, s)
    if not (d > 0.0 and d < reach and t >= 0.0 and t <= seg[s, 6]):
        return 0.0, 0.0, 0
    ur = ua - seg[s, 7]
    vr = va - seg[s, 8]
    un = ur * seg[s, 4] + vr * seg[s, 5]
    tx = ur - un * seg[s, 4]
    ty = vr - un * seg[s, 5]
    ut = math.sqrt(tx * tx + ty * ty)
    if ut <= 0.0:
        return 0.0, 0.0, 0
    if law == 0:
        us = smooth_ustar(ut, d, coef)
    elif law == 1:
        us = rough_ustar(ut, max(d, coef), coef)
    else:
        us = uplus_ustar(ut, coef)
    nphi = phi.shape[0] - 1
    k = d * (nphi / reach)
    i = min(int(k), nphi - 1)
    w = phi[i] + (k - i) * (phi[i + 1] - phi[i])
    f = 2.0 * w * us * us / ut
    return f * tx, f * ty, 1


@njit(parallel=True, **_JIT)
def wall_shear(x, y, u, v, kind, seg, reach, phi, law, coef, ax, ay):
    """Add the wall shear stress of the law of the wall to the acceleration of every fluid
    particle within ``reach`` of a wall segment, projecting onto it (the ghosts' criterion):

        dv_a/dt += -2 Phi(d_a) u*_a^2 t_a,

    d_a the particle's distance from the wall line, t_a the unit tangential velocity of a
    relative to the wall, u*_a from the law at y = d_a with u_t = |v_a - U_w| tangential
    (``law`` 0: smooth T(3.84), ``coef`` nu; 1: rough T(3.85), ``coef`` ks, y at least ks;
    2: prescribed U+, ``coef`` U+), Phi(d) the kernel integrated along the wall line,
    tabulated in ``phi`` at d = k reach/(len(phi) - 1). Returns how many particles felt it."""
    count = 0
    for a in prange(x.shape[0]):
        if kind[a] != 0:
            continue
        for s in range(seg.shape[0]):
            fx, fy, k = wall_shear_of(x[a], y[a], u[a], v[a], seg, s, reach, phi, law, coef)
            if k:
                ax[a] -= fx
                ay[a] -= fy
                count += 1
    return count


def line_kernel(kernel_w, h: float, reach: float, n: int = 257) -> np.ndarray:
    """Phi(d) = int W(sqrt(d^2 + s^2), h) ds over the whole line, at d = k reach/(n - 1), the
    kernel integrated along a wall line at distance d, scaled so that its trapezoidal integral
    over 0 <= d <= reach is exactly 1/2 (the half-plane's share of the kernel): a plane wall
    under a uniform lattice, sum_a V_a Phi(d_a) = 1/2 per unit length, so :func:`wall_shear`
    exerts exactly the wall stress on it. ``kernel_w(r, h)`` the kernel (numpy)."""
    from scipy.integrate import quad

    d = np.linspace(0.0, reach, n)
    out = np.zeros(n)
    for i, di in enumerate(d[:-1]):
        top = math.sqrt(max(reach * reach - di * di, 0.0))
        out[i] = 2.0 * quad(lambda s: float(kernel_w(math.hypot(di, s), h)), 0.0, top,
                            limit=200)[0]
    total = float(np.sum(0.5 * (out[1:] + out[:-1])) * (d[1] - d[0]))
    return out * (0.5 / total)
