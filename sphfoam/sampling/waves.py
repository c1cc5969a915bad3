"""Free-surface wave sampling: gauges, probes, u(z) lines, run-up and crest tracking (T ch. 4).

Every object reads the fluid particles only (``kind == FLUID``: wall particles and the
ghosts mirrored across walls are ignored) and writes, as every function object does,
``postProcessing/<name>/<startTime>/<name>.dat`` with a ``#`` header whose last line names
the columns.

Surface convention (shared with ``damBreakFront``): a particle stands for a dx x dx cell, so
the free surface is the top of the highest particle's cell, its y **plus dx/2**. Water at rest
on a lattice whose particles sit at cell centres (as the set-up places them) then reads its
true level, e.g. 0 above a still level ``still`` equal to the depth.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numba import njit
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, \
    model_validator

from sphfoam.case.schemas import Vector, Vector2, case_dimension
from sphfoam.engine.state import FLUID
from sphfoam.registry import register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs

#: half-width of a wave gauge's search windows in units of dx, delta x = 2.5 dx (T §4.3.2)
GAUGE_WINDOW = 2.5


def _as_list(v):
    return [v] if isinstance(v, (int, float)) else v


def _label(v: float) -> str:
    return f"{v:g}"


def _dim(ctx) -> int:
    """The case's dimension (2 for a context that does not say)."""
    return int(getattr(ctx, "dim", 2))


def _fluid(sim):
    st = sim.state
    f = st.kind == FLUID
    return st, f


# --- free-surface gauge, T §4.3.2 --------------------------------------------------------------
@njit(cache=True)
def _gauge_tops(xs, ys, gx, lo, mid, hi):
    """Highest particle in [lo, mid) and in [mid, hi) of x-sorted particles for each gauge
    (ties: the one nearest the gauge); linear interpolation between them to the gauge."""
    n = gx.size
    out = np.empty(n)
    for g in range(n):
        xg = gx[g]
        yl, xl, il = -np.inf, 0.0, -1
        for i in range(lo[g], mid[g]):
            if ys[i] > yl or (ys[i] == yl and xs[i] > xl):
                yl, xl, il = ys[i], xs[i], i
        yr, xr, ir = -np.inf, 0.0, -1
        for i in range(mid[g], hi[g]):
            if ys[i] > yr or (ys[i] == yr and xs[i] < xr):
                yr, xr, ir = ys[i], xs[i], i
        if il >= 0 and ir >= 0:
            out[g] = yl + (yr - yl) * (xg - xl) / (xr - xl) if xr > xl else max(yl, yr)
        elif il >= 0:
            out[g] = yl
        elif ir >= 0:
            out[g] = yr
        else:
            out[g] = np.nan
    return out


def surface_elevation(x_particles, y_particles, gauges_x, dx, *, still: float = 0.0,
                      window: float = GAUGE_WINDOW, presorted: bool = False) -> np.ndarray:
    """Free-surface elevation at ``gauges_x`` by the SPH wave gauge of T §4.3.2 (Fig 4.1).

    For each gauge x_g: the highest particle with x_g - delta x <= x < x_g and the highest with
    x_g <= x <= x_g + delta x (delta x = ``window`` dx, 2.5 dx in the thesis; ties go to the
    particle nearest the gauge), joined by a straight line evaluated at x_g; plus dx/2 (the top
    of that particle's cell, so a lattice at rest reads its true surface), minus ``still``.
    With particles on one side only, that particle's height is used; with none, NaN.
    Pass the fluid particles only; ``presorted`` says x is already ascending.
    """
    x = np.asarray(x_particles, dtype=float)
    y = np.asarray(y_particles, dtype=float)
    g = np.atleast_1d(np.asarray(gauges_x, dtype=float))
    if not presorted:
        order = np.argsort(x, kind="stable")
        x, y = x[order], y[order]
    half = window * dx
    lo = np.searchsorted(x, g - half, side="left")
    mid = np.searchsorted(x, g, side="left")
    hi = np.searchsorted(x, g + half, side="right")
    top = _gauge_tops(np.ascontiguousarray(x), np.ascontiguousarray(y), np.ascontiguousarray(g),
                      lo, mid, hi)
    return top + 0.5 * dx - still


# --- the free-surface gauge in 3-D: T §4.3.2 on four quadrants ---------------------------------
@njit(cache=True)
def _quadrant_tops(xs, ys, zs, gx, gy, lo, hi, half):
    """For each gauge (gx, gy), the highest of the x-sorted particles lo..hi in each of the
    four quadrants of the square |x - gx| <= half, |y - gy| <= half split at the gauge as
    the 2-D gauge splits its window ([g - half, g) and [g, g + half] along x and along y);
    ties go to the particle nearest the gauge. Returns (z, x, y) of each (nGauges, 4); z is
    -inf for an empty quadrant."""
    n = gx.size
    tz = np.full((n, 4), -np.inf)
    tx = np.zeros((n, 4))
    ty = np.zeros((n, 4))
    for g in range(n):
        for i in range(lo[g], hi[g]):
            ddy = ys[i] - gy[g]
            if ddy < -half or ddy > half:
                continue
            ddx = xs[i] - gx[g]
            q = (1 if ddx >= 0.0 else 0) + (2 if ddy >= 0.0 else 0)
            d2 = ddx * ddx + ddy * ddy
            if zs[i] > tz[g, q]:
                take = True
            elif zs[i] == tz[g, q]:
                ex = tx[g, q] - gx[g]
                ey = ty[g, q] - gy[g]
                take = d2 < ex * ex + ey * ey
            else:
                take = False
            if take:
                tz[g, q] = zs[i]
                tx[g, q] = xs[i]
                ty[g, q] = ys[i]
    return tz, tx, ty


def _plane_at(px, py, pz, gx, gy) -> float:
    """The height at (gx, gy) of the least-squares plane through the points (px, py, pz)
    (the 2-D gauge's straight line, one dimension up): one point gives its height; points
    on one line (two points, or more in a row) the straight line through them along that
    line, evaluated at the gauge's projection on it (the highest of them if they stand at
    one place)."""
    if px.size == 1:
        return float(pz[0])
    dx, dy = px - gx, py - gy
    a = np.column_stack([np.ones(px.size), dx, dy])
    cx, cy = dx - dx.mean(), dy - dy.mean()
    spread = np.column_stack([cx, cy])
    sv = np.linalg.svd(spread, compute_uv=False)
    scale = max(float(np.abs(spread).max()), 1e-300)
    if px.size >= 3 and sv[-1] > 1e-9 * scale:
        coef = np.linalg.lstsq(a, pz, rcond=None)[0]
        return float(coef[0])
    # collinear: the straight line along their common direction
    _, _, vt = np.linalg.svd(spread)
    d = vt[0]
    t = dx * d[0] + dy * d[1]
    if np.ptp(t) <= 1e-12 * scale:
        return float(pz.max())
    _, c = np.polyfit(t, pz, 1)
    return float(c)


def surface_elevation_3d(x, y, z, gauges, dx, *, still: float = 0.0,
                         window: float = GAUGE_WINDOW) -> np.ndarray:
    """Free-surface elevation at the horizontal points ``gauges`` ((x y) rows) of a 3-D case
    (z up), the gauge of T §4.3.2 extended to a horizontal plane: the 2-D gauge's window
    [x_g - delta, x_g) | [x_g, x_g + delta] becomes the four quadrants of the square
    |x - x_g| <= delta, |y - y_g| <= delta (delta = ``window`` dx, 2.5 dx) split at the
    gauge; the highest fluid particle of each (ties: the one nearest the gauge); the
    least-squares plane through those tops evaluated at the gauge (with tops on one line,
    the straight line through them, as the 2-D gauge joins its two); plus dx/2 (the top of
    that particle's cell), minus ``still``. An extruded 2-D case (uniform across y) reads
    what the 2-D gauge reads. NaN with no particle in the square."""
    x = np.asarray(x, dtype=float)
    g = np.atleast_2d(np.asarray(gauges, dtype=float))
    order = np.argsort(x, kind="stable")
    xs = np.ascontiguousarray(x[order])
    ys = np.ascontiguousarray(np.asarray(y, dtype=float)[order])
    zs = np.ascontiguousarray(np.asarray(z, dtype=float)[order])
    half = window * dx
    gx, gy = np.ascontiguousarray(g[:, 0]), np.ascontiguousarray(g[:, 1])
    lo = np.searchsorted(xs, gx - half, side="left")
    hi = np.searchsorted(xs, gx + half, side="right")
    tz, tx, ty = _quadrant_tops(xs, ys, zs, gx, gy, lo, hi, half)
    out = np.full(len(g), np.nan)
    for k in range(len(g)):
        ok = np.isfinite(tz[k])
        if ok.any():
            out[k] = _plane_at(tx[k, ok], ty[k, ok], tz[k, ok], gx[k], gy[k])
    return out + 0.5 * dx - still


@njit(cache=True)
def _phi3(xq, yq, zq, cx, cy, cz, cv, inv_h, w0, support, kernel_f):
    s = 0.0
    for i in range(cx.size):
        a = xq - cx[i]
        b = yq - cy[i]
        c = zq - cz[i]
        q = math.sqrt(a * a + b * b + c * c) * inv_h
        if q < support:
            s += cv[i] * kernel_f(q)
    return s * w0


@njit(cache=True)
def _column_crossing(cx, cy, cz, cv, gx, gy, z0, length, step, inv_h, w0, support, kernel_f,
                     level):
    """The first depth t below z0 (0 <= t <= length) on the vertical through (gx, gy) where
    the fluid fraction of the column's particles reaches ``level`` (marching by ``step``,
    then bisection); NaN if never."""
    if _phi3(gx, gy, z0, cx, cy, cz, cv, inv_h, w0, support, kernel_f) >= level:
        return 0.0
    a = 0.0
    while a < length:
        b = min(a + step, length)
        if _phi3(gx, gy, z0 - b, cx, cy, cz, cv, inv_h, w0, support, kernel_f) >= level:
            for _ in range(60):
                m = 0.5 * (a + b)
                if _phi3(gx, gy, z0 - m, cx, cy, cz, cv, inv_h, w0, support,
                         kernel_f) >= level:
                    b = m
                else:
                    a = m
                if b - a <= 1e-12 * step:
                    break
            return 0.5 * (a + b)
        a = b
    return np.nan


def fraction_surface_3d(x, y, z, vol, gauges, kernel, h, dx, *, still: float = 0.0,
                        level: float = 0.5) -> np.ndarray:
    """Sub-particle free-surface elevation of a 3-D case at the horizontal points
    ``gauges``: the highest z on the vertical through (x_g, y_g) where the SPH fluid
    fraction sum_b V_b W(r - r_b) (the 3-D kernel, alpha_3d / h^3) reaches 1/2, searched
    down from one support above the highest particle within a horizontal support of the
    gauge (dx/4 steps, then bisection), minus ``still``; NaN with no fluid within reach.
    The 2-D ``fraction_surface`` on a vertical line instead of a vertical plane's line."""
    x, y, z, vol = (np.asarray(a, dtype=float) for a in (x, y, z, vol))
    g = np.atleast_2d(np.asarray(gauges, dtype=float))
    out = np.full(len(g), np.nan)
    reach = float(kernel.support) * h
    for k, (gx, gy) in enumerate(g):
        near = (x - gx) ** 2 + (y - gy) ** 2 < reach * reach
        if not near.any():
            continue
        cx, cy, cz, cv = (np.ascontiguousarray(a[near]) for a in (x, y, z, vol))
        z0 = float(cz.max()) + reach
        t = _column_crossing(cx, cy, cz, cv, float(gx), float(gy), z0,
                             z0 - (float(cz.min()) - reach), 0.25 * dx, 1.0 / h,
                             kernel.alpha(3) / h**3, float(kernel.support), kernel.f_jit,
                             float(level))
        out[k] = z0 - t
    return out - still


# --- sub-particle surface: the SPH fluid fraction crosses 1/2 (issue 13) ------------------------
#: a surface mode: ``particle`` (the thesis's highest particle, T §4.3.2) or ``fraction``
SurfaceMode = Literal["particle", "fraction"]
#: the gauges' modes (``waveGauges``, ``crestTracker``): those two, ``volume`` or ``wire``
GaugeSurfaceMode = Literal["particle", "fraction", "volume", "wire"]


@njit(cache=True)
def _phi(xq, yq, xs, ys, vs, lo, hi, inv_h, w0, support, kernel_f):
    """Fluid fraction phi(r) = sum_b V_b W(r - r_b) at one point (particles lo..hi)."""
    s = 0.0
    for i in range(lo, hi):
        dxq = xq - xs[i]
        dyq = yq - ys[i]
        q = math.sqrt(dxq * dxq + dyq * dyq) * inv_h
        if q < support:
            s += vs[i] * kernel_f(q)
    return s * w0


@njit(cache=True)
def _fraction_crossings(xs, ys, vs, lo, hi, px, py, ux, uy, length, step, inv_h, w0, support,
                        kernel_f, level):
    """For each line r = p + t u, 0 <= t <= length, the first t where the fluid fraction reaches
    ``level`` (marching by ``step``, then bisection to 1e-12 of the step); NaN if never."""
    n = px.size
    out = np.full(n, np.nan)
    for g in range(n):
        a = 0.0
        if _phi(px[g], py[g], xs, ys, vs, lo[g], hi[g], inv_h, w0, support, kernel_f) >= level:
            out[g] = 0.0
            continue
        while a < length[g]:
            b = min(a + step, length[g])
            if _phi(px[g] + b * ux[g], py[g] + b * uy[g], xs, ys, vs, lo[g], hi[g], inv_h, w0,
                    support, kernel_f) >= level:
                for _ in range(60):
                    m = 0.5 * (a + b)
                    if _phi(px[g] + m * ux[g], py[g] + m * uy[g], xs, ys, vs, lo[g], hi[g],
                            inv_h, w0, support, kernel_f) >= level:
                        b = m
                    else:
                        a = m
                    if b - a <= 1e-12 * step:
                        break
                out[g] = 0.5 * (a + b)
                break
            a = b
    return out


def _kernel_parts(kernel):
    return kernel.f_jit, float(kernel.support), float(kernel.alpha_2d)


def fraction_crossings(x, y, vol, start, direction, length, kernel, h, dx, *, level=0.5):
    """Distance t along each line start + t direction (unit vectors, 0 <= t <= length) at
    which the SPH fluid fraction phi = sum_b V_b W(r - r_b) (T(3.8) of the constant 1, without
    Shepard's normalisation) first reaches ``level`` (1/2: the kernel-smoothed indicator of the
    water crosses half-way, the sub-particle free surface).  Marched by dx/4 and refined by
    bisection; NaN where the line never reaches it."""
    f, support, alpha = _kernel_parts(kernel)
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    xs = np.ascontiguousarray(x[order])
    ys = np.ascontiguousarray(np.asarray(y, dtype=float)[order])
    vs = np.ascontiguousarray(np.asarray(vol, dtype=float)[order])
    p = np.atleast_2d(np.asarray(start, dtype=float))
    u = np.atleast_2d(np.asarray(direction, dtype=float))
    u = np.broadcast_to(u, p.shape)
    L = np.broadcast_to(np.asarray(length, dtype=float), p.shape[:1]).copy()
    reach = support * h
    xa = np.minimum(p[:, 0], p[:, 0] + L * u[:, 0]) - reach
    xb = np.maximum(p[:, 0], p[:, 0] + L * u[:, 0]) + reach
    lo = np.searchsorted(xs, xa, side="left")
    hi = np.searchsorted(xs, xb, side="right")
    return _fraction_crossings(xs, ys, vs, lo, hi, np.ascontiguousarray(p[:, 0]),
                               np.ascontiguousarray(p[:, 1]), np.ascontiguousarray(u[:, 0]),
                               np.ascontiguousarray(u[:, 1]), L, 0.25 * dx, 1.0 / h,
                               alpha / h**2, support, f, float(level))


def fraction_surface(x, y, vol, gauges_x, kernel, h, dx, *, still: float = 0.0,
                     level: float = 0.5) -> np.ndarray:
    """Sub-particle free-surface elevation at ``gauges_x``: the highest y on the vertical
    x = x_g where the SPH fluid fraction sum_b V_b W(r - r_b) reaches 1/2 (searched down from
    above the highest particle within the kernel support), minus ``still``; NaN with no fluid
    within reach.  Pass the fluid particles and their volumes V_b = m_b/rho_b."""
    g = np.atleast_1d(np.asarray(gauges_x, dtype=float))
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size == 0:
        return np.full(g.size, np.nan)
    reach = _kernel_parts(kernel)[1] * h
    order = np.argsort(x, kind="stable")
    xs, ys = x[order], y[order]
    lo = np.searchsorted(xs, g - reach, side="left")
    hi = np.searchsorted(xs, g + reach, side="right")
    top = np.array([ys[a:b].max() if b > a else np.nan for a, b in zip(lo, hi)])
    bottom = float(y.min()) - reach
    ok = np.isfinite(top)
    out = np.full(g.size, np.nan)
    if ok.any():
        y0 = top[ok] + reach
        t = fraction_crossings(x, y, vol, np.column_stack([g[ok], y0]), (0.0, -1.0),
                               y0 - bottom, kernel, h, dx, level=level)
        out[ok] = y0 - t
    return out - still


def _mirror(x, y, vol, point, normal, reach):
    """Fluid particles within ``reach`` of the line through ``point`` with unit ``normal``,
    reflected across it and added (the wall as a plane of symmetry, so that the kernel sum
    at the wall sees a whole support)."""
    dn = (x - point[0]) * normal[0] + (y - point[1]) * normal[1]
    near = np.abs(dn) < reach
    xr = x[near] - 2.0 * dn[near] * normal[0]
    yr = y[near] - 2.0 * dn[near] * normal[1]
    return (np.concatenate([x, xr]), np.concatenate([y, yr]), np.concatenate([vol, vol[near]]))


def fraction_wall_run_up(x, y, vol, wall_x, kernel, h, dx, *, still=0.0) -> float:
    """Run-up on the vertical wall x = wall_x: the highest point of the wall where the fluid
    fraction, with the fluid mirrored across the wall, reaches 1/2, minus ``still``."""
    x, y, vol = (np.asarray(a, dtype=float) for a in (x, y, vol))
    reach = _kernel_parts(kernel)[1] * h
    if not (np.abs(x - wall_x) < reach).any():
        return float("nan")
    xm, ym, vm = _mirror(x, y, vol, (wall_x, 0.0), (1.0, 0.0), reach)
    return float(fraction_surface(xm, ym, vm, [wall_x], kernel, h, dx)[0]) - still


def fraction_wall_run_up_3d(x, y, z, vol, wall_x, wall_y, kernel, h, dx, *,
                            still=0.0) -> float:
    """Run-up on the vertical wall plane x = wall_x of a 3-D case at its point y = wall_y:
    the highest z there where the fluid fraction, with the fluid mirrored across the plane,
    reaches 1/2 (:func:`fraction_surface_3d` on the wall), minus ``still``."""
    x, y, z, vol = (np.asarray(a, dtype=float) for a in (x, y, z, vol))
    reach = float(kernel.support) * h
    near = np.abs(x - wall_x) < reach
    if not near.any():
        return float("nan")
    xm = np.concatenate([x, 2.0 * wall_x - x[near]])
    ym, zm = np.concatenate([y, y[near]]), np.concatenate([z, z[near]])
    vm = np.concatenate([vol, vol[near]])
    return float(fraction_surface_3d(xm, ym, zm, vm, [(wall_x, wall_y)], kernel, h, dx)[0]) \
        - still


def wall_run_up_3d(xf, yf, zf, wall_x, dx, *, wall_y=None, still=0.0, band=1.5) -> float:
    """Highest fluid particle within ``band`` dx of the vertical wall plane x = ``wall_x``
    (and of its point y = ``wall_y``, if given), + dx/2, above ``still`` (NaN with no fluid
    there): :func:`wall_run_up` in 3-D, z up."""
    near = np.abs(np.asarray(xf) - wall_x) <= band * dx
    if wall_y is not None:
        near &= np.abs(np.asarray(yf) - wall_y) <= band * dx
    if not near.any():
        return float("nan")
    return float(np.asarray(zf)[near].max()) + 0.5 * dx - still


# --- the wire gauge: the wetted length of a vertical wire ---------------------------------------
@njit(cache=True)
def _wetted(cx, cy, cz, cv, gx, gy, z_bot, z_top, step, inv_h, w0, support, kernel_f, level):
    """Up the vertical through (gx, gy) from z_bot to z_top: the lowest height where the fluid
    fraction of the particles (cx, cy, cz, cv) reaches ``level`` and the total length of the
    stretches where it is at least ``level`` (marched by ``step``, every crossing refined by
    bisection). (NaN, 0) if the vertical is never wet."""
    lowest = np.nan
    wet_len = 0.0
    a = z_bot
    wet = _phi3(gx, gy, a, cx, cy, cz, cv, inv_h, w0, support, kernel_f) >= level
    enter = a
    if wet:
        lowest = a
    while a < z_top:
        b = min(a + step, z_top)
        now = _phi3(gx, gy, b, cx, cy, cz, cv, inv_h, w0, support, kernel_f) >= level
        if now != wet:
            lo, hi = a, b                           # phi crosses level in [lo, hi]
            for _ in range(60):
                m = 0.5 * (lo + hi)
                if (_phi3(gx, gy, m, cx, cy, cz, cv, inv_h, w0, support, kernel_f)
                        >= level) == wet:
                    lo = m
                else:
                    hi = m
                if hi - lo <= 1e-12 * step:
                    break
            z = 0.5 * (lo + hi)
            if now:
                enter = z
                if math.isnan(lowest):
                    lowest = z
            else:
                wet_len += z - enter
            wet = now
        a = b
    if wet:
        wet_len += z_top - enter
    return lowest, wet_len


def wire_surface_3d(x, y, z, vol, gauges, kernel, h, dx, *, still: float = 0.0,
                    level: float = 0.5, dim: int = 3) -> np.ndarray:
    """The free surface a wire wave gauge (resistance or capacitance) reads at the horizontal
    points ``gauges``: the wire's wetted length, here the total length of the vertical through
    (x_g, y_g) where the SPH fluid fraction sum_b V_b W(r - r_b) is at least 1/2, added to the
    lowest wet height, minus ``still``. Where the water is one column it is the fraction
    gauge's surface (:func:`fraction_surface_3d`); a sheet or drop passing above adds its
    own thickness only, where the highest crossing would read its height. NaN with no fluid
    within reach. ``dim`` 2: a 2-D case, (x, z) the plane's coordinates and y unused."""
    x, y, z, vol = (np.asarray(a, dtype=float) for a in (x, y, z, vol))
    g = np.atleast_2d(np.asarray(gauges, dtype=float))
    out = np.full(len(g), np.nan)
    reach = float(kernel.support) * h
    w0 = (kernel.alpha(3) / h**3) if dim == 3 else (float(kernel.alpha_2d) / h**2)
    for k, (gx, gy) in enumerate(g):
        near = (x - gx) ** 2 + (y - gy) ** 2 < reach * reach
        if not near.any():
            continue
        cx, cy, cz, cv = (np.ascontiguousarray(a[near]) for a in (x, y, z, vol))
        lowest, length = _wetted(cx, cy, cz, cv, float(gx), float(gy),
                                 float(cz.min()) - reach, float(cz.max()) + reach, 0.25 * dx,
                                 1.0 / h, w0, float(kernel.support), kernel.f_jit,
                                 float(level))
        out[k] = lowest + length
    return out - still


def wire_surface(x, y, vol, gauges_x, kernel, h, dx, *, still: float = 0.0) -> np.ndarray:
    """:func:`wire_surface_3d` of a 2-D case: the vertical x = x_g of the (x, y) plane."""
    g = np.atleast_1d(np.asarray(gauges_x, dtype=float))
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return np.full(g.size, np.nan)
    return wire_surface_3d(x, np.zeros_like(x), y, vol, np.column_stack([g, np.zeros_like(g)]),
                           kernel, h, dx, still=still, dim=2)


def _fluid_volumes(st, f):
    return st.m[f] / st.rho[f]


# --- the column's water volume: surface volume (issue 13's "equivalent mass criterion") -------
#: the Gaussian window of ``surface volume`` is cut at this many standard deviations (and
#: renormalised: the weight it leaves out, erfc(5/sqrt 2) = 6e-7, would read as much of d)
_COLUMN_CUT = 5.0


@njit(cache=True)
def _column_sums(xs, vs, lo, hi, gx, inv_sigma, cut):
    out = np.zeros(gx.size)
    norm = inv_sigma / (math.sqrt(2.0 * math.pi) * math.erf(cut / math.sqrt(2.0)))
    for g in range(gx.size):
        s = 0.0
        for i in range(lo[g], hi[g]):
            q = (gx[g] - xs[i]) * inv_sigma
            s += vs[i] * math.exp(-0.5 * q * q)
        out[g] = s * norm
    return out


def column_depth(x, vol, gauges_x, width) -> np.ndarray:
    """Water volume per unit width in the vertical column at each x_g: sum_b V_b G(x_g - x_b)
    over the fluid particles, G the Gaussian of standard deviation ``width`` (m) cut at 5
    ``width`` and normalised. It does not depend on the particles' heights, so however the particles
    of a column are arranged (a disordered surface layer included) it reads the column's
    volume; the window smooths the surface by 1/2 width^2 eta'' (0.06 % of H at a solitary
    wave's crest for H/d = 0.3 and width d/20)."""
    g = np.atleast_1d(np.asarray(gauges_x, dtype=float))
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    xs = np.ascontiguousarray(x[order])
    vs = np.ascontiguousarray(np.asarray(vol, dtype=float)[order])
    cut = _COLUMN_CUT * width
    lo = np.searchsorted(xs, g - cut, side="left")
    hi = np.searchsorted(xs, g + cut, side="right")
    return _column_sums(xs, vs, lo, hi, np.ascontiguousarray(g), 1.0 / width, _COLUMN_CUT)


class _GaugeSurfaceCoeffs(FunctionObjectCoeffs):
    """How ``waveGauges`` and ``crestTracker`` read the surface."""

    surface: GaugeSurfaceMode = Field("particle", description=(
        "`particle`: the thesis's highest particle + dx/2 (T §4.3.2); `fraction`: where the "
        "SPH fluid fraction sum_b V_b W(r - r_b) crosses 1/2 along the vertical, "
        "sub-particle (issue 13); `volume`: the bed plus the column's water volume per "
        "unit width, sum_b V_b G(x - x_b), whatever the arrangement of its particles, the "
        "bed calibrated by `fraction` on the case's first time directory (issue 13), 2-D "
        "only; `wire`: what a wire (resistance) gauge reads, the lowest wet height plus the "
        "vertical's whole length where the fluid fraction is at least 1/2, so a sheet or "
        "splash passing above adds its thickness, not its height"))
    volumeWidth: float = Field(1.0, gt=0, description=(
        "surface volume: standard deviation of the Gaussian window G, in dx"))

    @model_validator(mode="after")
    def _width(self):
        """``volumeWidth`` with another mode would be ignored, so it is refused."""
        if "volumeWidth" in self.model_fields_set and self.surface != "volume":
            raise ValueError(f"volumeWidth applies to surface volume only (surface is "
                             f"{self.surface})")
        return self


#: what each surface mode but the thesis's reads, for the output's header line
SURFACE_READS = {
    "fraction": "sub-particle, the highest point of the vertical where the SPH fluid fraction "
                "sum_b V_b W(r - r_b) reaches 1/2",
    "volume": "the bed plus the column's water volume per unit width, sum_b V_b G(x - x_b)",
    "wire": "what a wire gauge reads, the lowest wet height plus the vertical's length where "
            "the fluid fraction is at least 1/2",
}


class _SurfaceHeader:
    """The header line of a gauge object names its ``surface`` mode where it is not the
    thesis's highest particle (which its ``doc`` describes)."""

    @property
    def header_doc(self) -> str:
        mode = self.coeffs.surface
        if mode == "particle":
            return self.doc
        return f"{self.doc.split(':')[0]}; surface {mode}: {SURFACE_READS[mode]}"


class ColumnSurface:
    """``surface volume``: the free surface at x is the bed's elevation b(x) plus the column's
    water volume per unit width (:func:`column_depth`), so the surface moves exactly as much
    water as enters or leaves the column, whatever the arrangement of its particles. The
    fraction gauge reads the surface of a regular lattice to a few 1e-4 dx, but on the
    disordered surface layer of a running simulation its reading drifts (in the flume at
    d/dx = 20 by +1.4 mm with δ+ shifting's anti-clumping term near the surface only, by
    -4.5 mm with it everywhere at Ma 0.03, while the water's volume stays within 0.6 mm of
    the depth: docs/low-dissipation.md).

    b(x) is calibrated once, on the case's first time directory (the set-up's lattice, or
    the settled state): b = the fraction gauge's surface there less the column's volume, on a
    grid of dx/2 over the water there, interpolated between. A restart reads the same first
    directory, so the readings continue; a case without one calibrates on the first state
    sampled. Where that state had no water (a dry beach), or within the window's cut (5
    ``width``) of where its water ended (a paddle, a far wall, a shoreline), b is not known
    and the reading is NaN.
    Overturning water is counted where it lies: under a plunging jet the reading is the
    column's equivalent depth, not the top of the jet."""

    def __init__(self, fo, width_dx: float):
        self.fo = fo
        self.width = width_dx * fo.ctx.dx
        self.grid: np.ndarray | None = None
        self.bed: np.ndarray | None = None
        from sphfoam.case.times import list_times
        from sphfoam.io.fields import has_particles, read_state

        first = next((d for _, d in list_times(fo.case.path) if has_particles(d)), None)
        if first is not None:
            s = read_state(first)
            f = np.asarray(s["type"]) == FLUID
            self._calibrate(s["positions"][f, 0], s["positions"][f, 1],
                            s["mass"][f] / s["rho"][f])

    def _calibrate(self, x, y, vol) -> None:
        dx = self.fo.ctx.dx
        if np.size(x) == 0:
            self.grid, self.bed = np.array([0.0]), np.array([np.nan])
            return
        n = int(math.ceil((float(np.max(x)) - float(np.min(x))) / (0.5 * dx))) + 1
        self.grid = float(np.min(x)) + 0.5 * dx * np.arange(n)
        top = fraction_surface(x, y, vol, self.grid, self.fo.case.models.sph["kernel"],
                               self.fo.ctx.h, dx)
        self.bed = top - column_depth(x, vol, self.grid, self.width)
        # a window that reaches past the water's ends there (a paddle, a far wall, the
        # shoreline) misses water the column has: no calibration within its cut of them
        cut = _COLUMN_CUT * self.width
        self.bed[(self.grid - cut < float(np.min(x))) | (self.grid + cut > float(np.max(x)))] \
            = np.nan

    def surface(self, x, y, vol, gauges_x, still: float = 0.0) -> np.ndarray:
        """Free-surface elevation above ``still`` at ``gauges_x`` (the fluid particles and their
        volumes V_b = m_b/rho_b)."""
        if self.grid is None:
            self._calibrate(x, y, vol)
        g = np.atleast_1d(np.asarray(gauges_x, dtype=float))
        b = np.interp(g, self.grid, self.bed, left=np.nan, right=np.nan)
        return b + column_depth(x, vol, g, self.width) - still


# --- SPH interpolation with Shepard normalisation ----------------------------------------------
@njit(cache=True)
def _shepard(xs, ys, vol, vals, lo, hi, xq, yq, inv_h, support, kernel_f):
    nf, nq = vals.shape[0], xq.size
    out = np.empty((nf, nq))
    acc = np.empty(nf)
    for k in range(nq):
        wsum = 0.0
        for j in range(nf):
            acc[j] = 0.0
        for i in range(lo[k], hi[k]):
            dxq = xq[k] - xs[i]
            dyq = yq[k] - ys[i]
            q = math.sqrt(dxq * dxq + dyq * dyq) * inv_h
            if q >= support:
                continue
            w = kernel_f(q) * vol[i]
            if w == 0.0:
                continue
            wsum += w
            for j in range(nf):
                acc[j] += w * vals[j, i]
        for j in range(nf):
            out[j, k] = acc[j] / wsum if wsum > 0.0 else np.nan
    return out


def sph_interpolate(x, y, vol, fields, xq, yq, kernel, h) -> np.ndarray:
    """Shepard-normalised SPH interpolation A(r) = sum_b A_b V_b W_b / sum_b V_b W_b (T(3.8)
    divided by the kernel sum, as the Shepard filter T(3.69)) of each row of ``fields``
    (shape (nFields, nParticles)) at the points (xq, yq); V_b = m/rho.

    ``kernel`` is the case's kernel model (``sphfoam.models.kernels``): its jitted f(q) and
    support are used (the normalisation alpha_d / h^2 cancels). Points with no particle
    within the kernel support give NaN.
    """
    f = kernel.f_jit
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    xs = np.ascontiguousarray(x[order])
    ys = np.ascontiguousarray(np.asarray(y, dtype=float)[order])
    vs = np.ascontiguousarray(np.asarray(vol, dtype=float)[order])
    vals = np.ascontiguousarray(np.atleast_2d(np.asarray(fields, dtype=float))[:, order])
    xq = np.ascontiguousarray(np.atleast_1d(np.asarray(xq, dtype=float)))
    yq = np.ascontiguousarray(np.atleast_1d(np.asarray(yq, dtype=float)))
    reach = kernel.support * h
    lo = np.searchsorted(xs, xq - reach, side="left")
    hi = np.searchsorted(xs, xq + reach, side="right")
    return _shepard(xs, ys, vs, vals, lo, hi, xq, yq, 1.0 / h, float(kernel.support), f)


def _current_pressure(sim) -> None:
    eos = getattr(sim, "eos", None)
    if callable(eos):
        eos()


def _sample_fluid(sim, case, ctx, xq, yq) -> np.ndarray:
    """(p, Ux, Uy) rows interpolated at the points from the fluid particles of ``sim``."""
    st, f = _fluid(sim)
    vol = st.m[f] / st.rho[f]
    fields = np.stack([st.p[f], st.u[f], st.v[f]])
    return sph_interpolate(st.x[f], st.y[f], vol, fields, xq, yq, case.models.sph["kernel"],
                           ctx.h)


# --- waveGauges --------------------------------------------------------------------------------
def _horizontal(v, info: ValidationInfo):
    """A horizontal position: x in a 2-D case (a number, or (x)), (x y) in a 3-D case."""
    dim = case_dimension(info)
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        v = [v]
    if (isinstance(v, (list, tuple)) and len(v) == dim - 1
            and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in v)):
        return tuple(float(c) for c in v)
    raise ValueError(f"expected a horizontal position ({'x' if dim == 2 else '(x y)'}) in a "
                     f"{dim}-D case, got {v!r}")


class GaugeLine(BaseModel):
    """A line of gauges: ``nPoints`` gauges evenly spaced from ``start`` to ``end`` (both
    included): x in 2-D, (x y) in 3-D."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    start: tuple[float, ...] = Field(description="first gauge: x (2-D) or (x y) (3-D)")
    end: tuple[float, ...] = Field(description="last gauge: x (2-D) or (x y) (3-D)")
    nPoints: int = Field(ge=2, description="gauges on the line, ends included")

    _pos = field_validator("start", "end", mode="before")(_horizontal)

    def positions(self) -> np.ndarray:
        """(nPoints, dim - 1) positions."""
        a, b = np.asarray(self.start), np.asarray(self.end)
        t = np.linspace(0.0, 1.0, self.nPoints)[:, None]
        return a[None, :] + t * (b - a)[None, :]


@register
class WaveGauges(_SurfaceHeader, FunctionObject):
    """Free-surface elevation eta(t) at a set of wave gauges, the SPH wave gauge of T §4.3.2.

    2-D (``x``): at each gauge the highest fluid particle within delta x = 2.5 dx on either
    side ([x_g - delta x, x_g) and [x_g, x_g + delta x]) is found and the two are joined by a
    straight line evaluated at x_g (T Fig 4.1); dx/2 is added (the top of the particle's cell,
    as in ``damBreakFront``) so that water at rest reads its true level, and ``still`` is
    subtracted. A gauge with fluid on one side only reads that particle; with none, NaN.
    With ``surface fraction`` the gauge is sub-particle instead: the highest y on the vertical
    where the SPH fluid fraction sum_b V_b W(r - r_b) reaches 1/2 (``fraction_surface``);
    with ``surface volume`` it is the bed plus the column's water volume (``ColumnSurface``);
    with ``surface wire`` it is what a wire gauge reads, the lowest wet height plus the
    wetted length of the vertical (``wire_surface``: a splash above adds its thickness only).

    3-D (``points``, (x y) with z up): the same gauge on the horizontal plane
    (``surface_elevation_3d``): the highest fluid particle in each quadrant of the square
    |x - x_g|, |y - y_g| <= delta x around the gauge, the least-squares plane through those
    tops evaluated at the gauge (the 2-D straight line, one dimension up; an extruded 2-D
    case reads as the 2-D gauge), + dx/2 - ``still``. ``surface fraction``: the highest z on
    the vertical through the gauge where the 3-D fluid fraction reaches 1/2
    (``fraction_surface_3d``); ``surface wire`` the wetted length of the vertical
    (``wire_surface_3d``). ``surface volume`` has no 3-D form (refused).

    ``line`` adds a line of evenly spaced gauges (in 2-D from x = start to end, in 3-D from
    (x y) start to end), after those of ``x`` / ``points``. Columns: ``eta(x)`` in 2-D,
    ``eta(x,y)`` in 3-D.
    """

    name = "waveGauges"
    doc = "free-surface elevation eta(t) at wave gauges: highest particle within 2.5 dx either " \
          "side, interpolated linearly, T §4.3.2 (3-D: at (x y) points, four quadrants)"
    dims = (2, 3)

    class Coeffs(_GaugeSurfaceCoeffs):
        x: list[float] = Field(default_factory=list, description=(
            "2-D: gauge positions (m), e.g. `(1 2 4 6 8)` (T §4.3.2 used x = 1, 2 m and then "
            "every 2 m up to 20 m from the paddle)"))
        points: list[tuple[float, float]] = Field(default_factory=list, description=(
            "3-D: gauge positions `((x1 y1) (x2 y2) ...)` (m) on the horizontal plane "
            "(z is up)"))
        line: GaugeLine | None = Field(None, description=(
            "a line of gauges `{ start <x | (x y)>; end <x | (x y)>; nPoints <n>; }`, "
            "added after `x` / `points`"))
        still: float = Field(0.0, description=(
            "still-water level (m): eta = surface height - still (0: eta is the surface "
            "height itself)"))
        window: float = Field(GAUGE_WINDOW, gt=0, description=(
            "half-width delta x of the search windows either side of a gauge, in dx "
            "(2.5 in T §4.3.2)"))

        @field_validator("x", mode="before")
        @classmethod
        def _one(cls, v):
            return _as_list(v)

        @model_validator(mode="after")
        def _gauges(self, info: ValidationInfo):
            dim = case_dimension(info)
            if dim == 2 and self.points:
                raise ValueError("points (x y) are the gauges of a 3-D case: a 2-D case "
                                 "gives x")
            if dim == 3 and self.x:
                raise ValueError("a 3-D case's gauges are points ((x y) ...) on the "
                                 "horizontal plane, not x")
            if dim == 3 and self.surface == "volume":
                raise ValueError("surface volume has no 3-D form: use particle, fraction "
                                 "or wire")
            if not (self.x or self.points or self.line):
                raise ValueError("give the gauges: x (2-D), points (3-D) or a line")
            return self

    def gauges(self) -> np.ndarray:
        """The gauge positions: (n,) x in 2-D, (n, 2) (x y) in 3-D."""
        c = self.coeffs
        three = _dim(self.ctx) == 3
        own = np.asarray(c.points if three else c.x, dtype=float).reshape(-1, 2 if three
                                                                           else 1)
        if c.line is not None:
            own = np.vstack([own, c.line.positions()])
        return own if three else own[:, 0]

    def start(self, case, ctx, start_time_name):
        self.ctx = ctx
        if _dim(ctx) == 3:
            self.columns = ("time",) + tuple(f"eta({_label(x)},{_label(y)})"
                                             for x, y in self.gauges())
        else:
            self.columns = ("time",) + tuple(f"eta({_label(x)})" for x in self.gauges())
        super().start(case, ctx, start_time_name)
        self.column = (ColumnSurface(self, self.coeffs.volumeWidth)
                       if self.coeffs.surface == "volume" else None)

    def execute(self, sim):
        c = self.coeffs
        st, f = _fluid(sim)
        if _dim(self.ctx) == 3:
            self.write_row((sim.time, *self.measure_3d(st, f)))
            return
        gx = c.x if c.line is None else self.gauges()
        if c.surface == "volume":
            eta = self.column.surface(st.x[f], st.y[f], _fluid_volumes(st, f), gx,
                                      still=c.still)
        elif c.surface == "fraction":
            eta = fraction_surface(st.x[f], st.y[f], _fluid_volumes(st, f), gx,
                                   self.case.models.sph["kernel"], self.ctx.h, self.ctx.dx,
                                   still=c.still)
        elif c.surface == "wire":
            eta = wire_surface(st.x[f], st.y[f], _fluid_volumes(st, f), gx,
                               self.case.models.sph["kernel"], self.ctx.h, self.ctx.dx,
                               still=c.still)
        else:
            eta = surface_elevation(st.x[f], st.y[f], gx, self.ctx.dx, still=c.still,
                                    window=c.window)
        self.write_row((sim.time, *eta))

    def measure_3d(self, st, f) -> np.ndarray:
        c, g = self.coeffs, self.gauges()
        if not f.any():
            return np.full(len(g), np.nan)
        if c.surface in ("fraction", "wire"):
            read = fraction_surface_3d if c.surface == "fraction" else wire_surface_3d
            return read(st.x[f], st.y[f], st.z[f], _fluid_volumes(st, f), g,
                        self.case.models.sph["kernel"], self.ctx.h, self.ctx.dx, still=c.still)
        return surface_elevation_3d(st.x[f], st.y[f], st.z[f], g, self.ctx.dx,
                                    still=c.still, window=c.window)


# --- probes ------------------------------------------------------------------------------------
@register
class Probes(FunctionObject):
    """Pressure and velocity at fixed points, SPH-interpolated from the fluid particles.

    A(r) = sum_b A_b (m_b/rho_b) W(r - r_b) / sum_b (m_b/rho_b) W(r - r_b) over the fluid
    particles with the case's kernel and h (the SPH interpolant T(3.8) normalised as the
    Shepard filter T(3.69): constant fields stay exact near the free surface and walls, where
    the kernel support is truncated). The pressure is brought up to date with the equation of
    state first. A point with no fluid particle within the kernel support gives NaN.
    2-D: points (x y), columns p, Ux, Uy per point; 3-D: points (x y z), columns p, Ux, Uy,
    Uz (the same interpolant over the 3-D kernel's sphere, ``sampling.interp.shepard``).
    """

    name = "probes"
    doc = "SPH-interpolated (Shepard-normalised) pressure and velocity at fixed points, " \
          "T(3.8), T(3.69)"
    dims = (2, 3)

    class Coeffs(FunctionObjectCoeffs):
        points: list[Vector] = Field(min_length=1, description=(
            "probe locations `((x1 y1) (x2 y2) ...)` (m); `((x1 y1 z1) ...)` in 3-D"))

    def start(self, case, ctx, start_time_name):
        cols = ["time"]
        comps = ("Ux", "Uy") if _dim(ctx) == 2 else ("Ux", "Uy", "Uz")
        for pt in self.coeffs.points:
            loc = "(" + ",".join(_label(v) for v in pt) + ")"
            cols += [f"p{loc}"] + [f"{q}{loc}" for q in comps]
        self.columns = tuple(cols)
        super().start(case, ctx, start_time_name)

    def execute(self, sim):
        _current_pressure(sim)
        pts = np.asarray(self.coeffs.points, dtype=float)
        if _dim(self.ctx) == 3:
            from sphfoam.sampling.interp import fluid_arrays, shepard

            st = sim.state
            kernel = self.case.models.sph["kernel"]
            f, pos, vol = fluid_arrays(st, 3, pts, kernel.support * self.ctx.h)
            vals, _ = shepard(pos, vol, np.stack([st.p[f], st.u[f], st.v[f], st.w[f]]), pts,
                              kernel, self.ctx.h, 3)
        else:
            vals = _sample_fluid(sim, self.case, self.ctx, pts[:, 0], pts[:, 1])
        self.write_row((sim.time, *vals.T.ravel()))


# --- lines -------------------------------------------------------------------------------------
@register
class Lines(FunctionObject):
    """Velocity and pressure profiles u(z) along vertical lines from the bed to the surface.

    Lines stand at fixed ``x`` or, with ``follow crest``, under the wave crest, the x of the
    highest fluid particle at that instant (T Figs 4.17, 4.21). Each line has ``nPoints``
    points evenly spaced from ``y0`` (the bed) up to the local surface given by the wave gauge
    (T §4.3.2, dx/2 convention); p, Ux, Uy are SPH-interpolated there as in ``probes``. Each
    sample writes ``<time>/line.dat`` (columns y, Ux, Uy, p; with several lines these four
    repeat per line, the header naming each line's x); ``<name>.dat`` holds time and, per
    line, its x and surface y.

    3-D (z up): the lines stand at horizontal ``points`` ((x y) ...) or under the highest
    fluid particle; the surface is the 3-D gauge's, ``y0`` is the bed's height z, and
    ``line.dat`` holds z, Ux, Uy, Uz, p per line (the 3-D interpolant of ``probes``);
    ``<name>.dat`` holds time and, per line, its x, y and surface z.
    """

    name = "lines"
    doc = "u(z) profiles (Ux, Uy, p) from bed to surface at fixed x or under the moving crest, " \
          "T Figs 4.17, 4.21"
    dims = (2, 3)

    class Coeffs(FunctionObjectCoeffs):
        x: list[float] = Field(default_factory=list, description=(
            "x of the vertical lines (m), e.g. `(5 10)`; leave out with `follow crest`"))
        points: list[Vector2] = Field(default_factory=list, description=(
            "3-D: the lines' horizontal positions `((x1 y1) ...)` (m); leave out with "
            "`follow crest`"))
        follow: Literal["none", "crest"] = Field("none", description=(
            "`crest`: one line under the highest fluid particle, moving with the wave "
            "(T Figs 4.17, 4.21); `none`: the fixed lines of `x`"))
        xMin: float = Field(-math.inf, description=(
            "with `follow crest`, only look for the crest at x >= xMin (e.g. beyond the "
            "paddle)"))
        xMax: float = Field(math.inf, description=(
            "with `follow crest`, only look for the crest at x <= xMax"))
        y0: float = Field(0.0, description=(
            "height of the bed (m), the lowest point of each line (y in 2-D, z in 3-D)"))
        nPoints: int = Field(20, ge=2, description=(
            "points per line, evenly spaced from y0 to the local surface"))
        still: float = Field(0.0, description=(
            "still-water level (m), for the surface elevation in the header of line.dat"))

        @field_validator("x", mode="before")
        @classmethod
        def _one(cls, v):
            return _as_list(v)

        @model_validator(mode="after")
        def _check(self, info: ValidationInfo):
            dim = case_dimension(info)
            where = "points" if dim == 3 else "x"
            if dim == 3 and self.x:
                raise ValueError("a 3-D case's lines stand at points ((x y) ...), not x")
            if dim == 2 and self.points:
                raise ValueError("points (x y) are the lines of a 3-D case: a 2-D case "
                                 "gives x")
            given = self.points if dim == 3 else self.x
            if self.follow == "crest" and given:
                raise ValueError(f"give either {where} (fixed lines) or follow crest, not "
                                 "both")
            if self.follow == "none" and not given:
                raise ValueError(f"give the line positions {where}, or follow crest")
            return self

    def start(self, case, ctx, start_time_name):
        c = self.coeffs
        three = _dim(ctx) == 3
        n = 1 if c.follow == "crest" else len(c.points if three else c.x)
        cols = ["time"]
        for k in range(n):
            tag = "" if n == 1 else f"_{k}"
            cols += [f"x{tag}", f"y{tag}", f"surface{tag}"] if three else \
                [f"x{tag}", f"surface{tag}"]
        self.columns = tuple(cols)
        super().start(case, ctx, start_time_name)
        self.precision = int(getattr(getattr(case, "control", None), "timePrecision", 6) or 6)

    def line_positions(self, xf, yf) -> np.ndarray:
        c = self.coeffs
        if c.follow == "crest":
            sel = (xf >= c.xMin) & (xf <= c.xMax)
            if not sel.any():
                return np.array([np.nan])
            i = int(np.argmax(np.where(sel, yf, -np.inf)))
            return np.array([xf[i]])
        return np.asarray(c.x, dtype=float)

    def _positions_3d(self, st, f) -> np.ndarray:
        """(n, 2): the lines' (x y), or that of the highest fluid particle in [xMin, xMax]."""
        c = self.coeffs
        if c.follow == "crest":
            sel = f & (st.x >= c.xMin) & (st.x <= c.xMax)
            if not sel.any():
                return np.full((1, 2), np.nan)
            i = int(np.argmax(np.where(sel, st.z, -np.inf)))
            return np.array([[st.x[i], st.y[i]]])
        return np.asarray(c.points, dtype=float).reshape(-1, 2)

    def _execute_3d(self, sim):
        from sphfoam.sampling.interp import fluid_arrays, shepard

        c, dx = self.coeffs, self.ctx.dx
        _current_pressure(sim)
        st, f = _fluid(sim)
        xy = self._positions_3d(st, f)
        surf = np.full(len(xy), np.nan)
        ok = np.isfinite(xy[:, 0])
        if ok.any() and f.any():
            surf[ok] = surface_elevation_3d(st.x[f], st.y[f], st.z[f], xy[ok], dx)
        frac = np.linspace(0.0, 1.0, c.nPoints)
        zs = c.y0 + (surf[:, None] - c.y0) * frac[None, :]          # (nLines, nPoints)
        pts = np.column_stack([np.repeat(xy[:, 0], c.nPoints), np.repeat(xy[:, 1], c.nPoints),
                               zs.ravel()])
        vals = np.full((4, len(pts)), np.nan)
        good = np.isfinite(pts).all(axis=1)
        if good.any():
            kernel = self.case.models.sph["kernel"]
            ff, pos, vol = fluid_arrays(st, 3, pts[good], kernel.support * self.ctx.h)
            vals[:, good], _ = shepard(pos, vol, np.stack([st.p[ff], st.u[ff], st.v[ff],
                                                           st.w[ff]]), pts[good],
                                       kernel, self.ctx.h, 3)
        p, ux, uy, uz = (v.reshape(len(xy), c.nPoints) for v in vals)
        row = [sim.time]
        for k in range(len(xy)):
            row += [xy[k, 0], xy[k, 1], surf[k]]
        self.write_row(row)
        one = len(xy) == 1
        labels = ["" if one else f"({_label(x)},{_label(y)})" for x, y in xy]
        cols = [f"{q}{lab}" for lab in labels for q in ("z", "Ux", "Uy", "Uz", "p")]
        table = np.column_stack([a for k in range(len(xy))
                                 for a in (zs[k], ux[k], uy[k], uz[k], p[k])])
        where = "; ".join(f"(x y) = ({x:.9g} {y:.9g}), surface z = {sz:.9g}, eta = "
                          f"{sz - c.still:.9g}" for (x, y), sz in zip(xy, surf))
        self._write_line(sim.time, where, cols, table)

    def _write_line(self, time, where, cols, table) -> None:
        """``<time>/line.dat``: the header (where the lines stood) and the profiles."""
        from sphfoam.case.times import time_name

        folder = self.folder / time_name(float(time), self.precision)
        folder.mkdir(parents=True, exist_ok=True)
        with (folder / "line.dat").open("w") as fh:
            fh.write(f"# {self.object_name} ({self.name}) at time {time:.9g}"
                     f"{' under the crest' if self.coeffs.follow == 'crest' else ''}: "
                     f"{where}\n")
            fh.write("# " + "\t".join(cols) + "\n")
            for r in table:
                fh.write("\t".join(f"{v:.9g}" for v in r) + "\n")

    def execute(self, sim):
        if _dim(self.ctx) == 3:
            self._execute_3d(sim)
            return
        c, dx = self.coeffs, self.ctx.dx
        _current_pressure(sim)
        st, f = _fluid(sim)
        xf, yf = st.x[f], st.y[f]
        xl = self.line_positions(xf, yf)
        surf = np.full(xl.size, np.nan)
        ok = np.isfinite(xl)
        if ok.any() and xf.size:
            surf[ok] = surface_elevation(xf, yf, xl[ok], dx)
        frac = np.linspace(0.0, 1.0, c.nPoints)
        ys = c.y0 + (surf[:, None] - c.y0) * frac[None, :]          # (nLines, nPoints)
        xs = np.repeat(xl, c.nPoints)
        vals = np.full((3, xs.size), np.nan)
        good = np.isfinite(ys.ravel()) & np.isfinite(xs)
        if good.any():
            vals[:, good] = _sample_fluid(sim, self.case, self.ctx, xs[good], ys.ravel()[good])
        p, ux, uy = (v.reshape(xl.size, c.nPoints) for v in vals)
        row = [sim.time]
        for k in range(xl.size):
            row += [xl[k], surf[k]]
        self.write_row(row)
        table = np.column_stack([a for k in range(xl.size)
                                 for a in (ys[k], ux[k], uy[k], p[k])])
        one = xl.size == 1
        cols = [f"{q}{'' if one else f'({_label(xl[k])})'}"
                for k in range(xl.size) for q in ("y", "Ux", "Uy", "p")]
        where = "; ".join(f"x = {xl[k]:.9g}, surface y = {surf[k]:.9g}, eta = "
                          f"{surf[k] - c.still:.9g}" for k in range(xl.size))
        self._write_line(sim.time, where, cols, table)


# --- runUp -------------------------------------------------------------------------------------
def wall_run_up(xf, yf, wall_x, dx, *, still=0.0, band=1.5) -> float:
    """Highest fluid particle within ``band`` dx of the vertical wall x = ``wall_x``, + dx/2,
    above ``still`` (NaN with no fluid there)."""
    near = np.abs(np.asarray(xf) - wall_x) <= band * dx
    if not near.any():
        return float("nan")
    return float(np.asarray(yf)[near].max()) + 0.5 * dx - still


def beach_shoreline(xf, yf, start, angle, dx, *, length=math.inf, still=0.0, band=1.5,
                    on_beach: bool = False, gap: float = math.inf) -> tuple[float, float]:
    """(R, x) of the shoreline on a plane beach rising from ``start`` at ``angle`` degrees,
    from the fluid particles within ``band`` dx of the slope line (along it,
    0 <= s <= length); NaN, NaN with no fluid in contact. Default: R is the highest of them
    + dx/2, above ``still``, and x its x. ``on_beach``: the point of the beach line
    s_max + dx/2 along it, s_max the furthest particle up the beach (the leading edge of its
    cell): R its height above ``still`` and x its x, free of the particles' height above
    the slope (up to band dx), which the default adds to a thin run-up tongue.

    ``gap`` (a length; with ``on_beach``): s_max is instead the furthest particle of the
    connected layer: the contact particles in order up the beach, up to the first that is
    more than ``gap`` beyond the one below it. Particles that have come apart from the
    water behind them by more than the kernel's support (the ``connected`` shoreline) feel
    no pressure from it and slide up a frictionless beach on their own."""
    a = math.radians(angle)
    xf, yf = np.asarray(xf), np.asarray(yf)
    rx, ry = xf - start[0], yf - start[1]
    s = rx * math.cos(a) + ry * math.sin(a)
    n = -rx * math.sin(a) + ry * math.cos(a)
    near = np.flatnonzero((np.abs(n) <= band * dx) & (s >= 0.0) & (s <= length))
    if not near.size:
        return float("nan"), float("nan")
    if on_beach:
        along = np.sort(s[near])
        cut = np.flatnonzero(np.diff(along) > gap)
        top = min(float(along[cut[0]] if cut.size else along[-1]) + 0.5 * dx, length)
        return (start[1] + top * math.sin(a) - still, start[0] + top * math.cos(a))
    i = near[np.argmax(yf[near])]
    return float(yf[i]) + 0.5 * dx - still, float(xf[i])


def beach_run_up(xf, yf, start, angle, dx, *, length=math.inf, still=0.0, band=1.5) -> float:
    """Shoreline elevation on a plane beach (see :func:`beach_shoreline`)."""
    return beach_shoreline(xf, yf, start, angle, dx, length=length, still=still, band=band)[0]


@register
class RunUp(FunctionObject):
    """Run-up R(t) on a vertical wall or a plane beach, and its running maximum (T §5.2.1).

    ``mode wall``: the highest fluid particle within ``band`` dx (1.5) of the wall x = ``x``.
    ``mode beach``: the shoreline, the highest fluid particle within ``band`` dx of the beach
    line rising from ``start`` at ``angle`` degrees (as a slope wall of particleDict) over
    ``length``; two more columns give its x and the x at the running maximum. Both add dx/2 (the dx/2 surface convention: still water reads R = 0 when
    ``still`` is its level) and subtract ``still``. NaN while no fluid touches the wall/beach.
    ``surface fraction`` (walls): the highest point of the wall where the SPH fluid fraction,
    with the fluid mirrored across the wall, reaches 1/2 (sub-particle).

    3-D (mode wall, z up): the wall is the plane x = ``x``; ``surface particle`` reads the
    highest fluid particle within ``band`` dx of it (and of y = ``y``, if given), ``surface
    fraction`` the fraction's crossing on the wall's vertical at y = ``y``.
    """

    name = "runUp"
    doc = "run-up on a vertical wall or a plane beach (highest fluid particle in contact + " \
          "dx/2) and its running maximum"
    columns = ("time", "runUp", "maxRunUp")
    dims = (2, 3)

    class Coeffs(FunctionObjectCoeffs):
        mode: Literal["wall", "beach"] = Field(description=(
            "`wall`: a vertical wall at `x`; `beach`: a plane slope given by `start` and "
            "`angle`"))
        x: float | None = Field(None, description="x of the wall (m), mode wall")
        y: float | None = Field(None, description=(
            "3-D, mode wall: the wall's point y (m) to read (`surface fraction` needs it; "
            "`surface particle` without it reads the whole wall)"))
        start: Vector2 | None = Field(None, description=(
            "foot of the beach line `(x y)` (m), mode beach"))
        angle: float | None = Field(None, gt=-90.0, lt=90.0, description=(
            "slope of the beach in degrees above the +x axis, mode beach"))
        length: float = Field(math.inf, gt=0, description=(
            "length of the beach along the slope from `start` (m), mode beach"))
        still: float = Field(0.0, description="still-water level (m) run-up is measured from")
        band: float = Field(1.5, gt=0, description=(
            "contact distance from the wall or beach line, in dx"))
        shoreline: Literal["highestParticle", "onBeach", "connected"] = Field(
            "highestParticle", description=(
                "mode beach: `highestParticle`: the highest fluid particle in contact + dx/2; "
                "`onBeach`: the point of the beach line dx/2 beyond the furthest particle "
                "in contact (a thin tongue's particles sit up to `band` dx above the beach, "
                "which `highestParticle` adds to the run-up); `connected`: as `onBeach`, "
                "from the furthest particle of the layer in contact that is connected to "
                "the water body, each particle within the kernel's support of the one below "
                "it (a particle further apart feels no pressure from the water and slides on "
                "by itself)"))
        surface: SurfaceMode = Field("particle", description=(
            "`particle`: the highest fluid particle in contact + dx/2; `fraction` (mode wall "
            "only): the highest point of the wall where the SPH fluid fraction, the fluid "
            "mirrored across the wall, reaches 1/2, sub-particle (issue 13)"))

        @model_validator(mode="after")
        def _check(self, info: ValidationInfo):
            dim = case_dimension(info)
            if dim == 3 and self.mode == "beach":
                raise ValueError("mode beach has no 3-D form (a beach line is 2-D): use mode "
                                 "wall")
            if dim == 3 and self.surface == "fraction" and self.y is None:
                raise ValueError("surface fraction in 3-D reads the wall on one vertical: "
                                 "give its y")
            if dim == 2 and self.y is not None:
                raise ValueError("y is the wall's point in a 3-D case: a 2-D wall is x")
            if self.mode == "wall" and self.x is None:
                raise ValueError("mode wall needs the wall position x")
            if self.mode == "beach" and (self.start is None or self.angle is None):
                raise ValueError("mode beach needs start (x y) and angle")
            if self.mode == "wall" and self.shoreline != "highestParticle":
                raise ValueError("shoreline is an option of mode beach only")
            if self.mode == "beach" and self.surface == "fraction":
                raise ValueError("surface fraction works with mode wall only: the water "
                                 "layer at a beach's shoreline is thinner than the kernel "
                                 "and never reaches fraction 1/2; use surface particle")
            return self

    def start(self, case, ctx, start_time_name):
        if self.coeffs.mode == "beach":     # the shoreline's x, and x at the running maximum
            self.columns = type(self).columns + ("xShore", "xMaxRunUp")
        super().start(case, ctx, start_time_name)
        self.max = float("nan")
        self.x_max = float("nan")

    def _gap(self) -> float:
        """The largest gap of the ``connected`` shoreline: the kernel's support."""
        if self.coeffs.shoreline != "connected":
            return math.inf
        return self.case.models.sph["kernel"].support * self.ctx.h

    def measure_3d(self, st, f) -> float:
        c, dx = self.coeffs, self.ctx.dx
        if c.surface == "fraction":
            return fraction_wall_run_up_3d(st.x[f], st.y[f], st.z[f], _fluid_volumes(st, f),
                                           c.x, c.y, self.case.models.sph["kernel"],
                                           self.ctx.h, dx, still=c.still)
        return wall_run_up_3d(st.x[f], st.y[f], st.z[f], c.x, dx, wall_y=c.y, still=c.still,
                              band=c.band)

    def measure(self, xf, yf, vf=None) -> float:
        c, dx = self.coeffs, self.ctx.dx
        if c.surface == "fraction":
            return fraction_wall_run_up(xf, yf, vf, c.x, self.case.models.sph["kernel"],
                                        self.ctx.h, dx, still=c.still)
        if c.mode == "wall":
            return wall_run_up(xf, yf, c.x, dx, still=c.still, band=c.band)
        return self.shoreline(xf, yf)[0]

    def shoreline(self, xf, yf) -> tuple[float, float]:
        """(R, x) of the shoreline of mode beach, as ``shoreline`` reads it."""
        c = self.coeffs
        return beach_shoreline(xf, yf, c.start, c.angle, self.ctx.dx, length=c.length,
                               still=c.still, band=c.band,
                               on_beach=c.shoreline in ("onBeach", "connected"),
                               gap=self._gap())

    def execute(self, sim):
        st, f = _fluid(sim)
        c = self.coeffs
        if c.mode == "beach":
            r, xs = self.shoreline(st.x[f], st.y[f])
            if r > self.max or not math.isfinite(self.max):
                self.x_max = xs if math.isfinite(r) else self.x_max
            self.max = float(np.fmax(self.max, r))
            self.write_row((sim.time, r, self.max, xs, self.x_max))
            return
        if _dim(self.ctx) == 3:
            r = self.measure_3d(st, f)
        else:
            r = self.measure(st.x[f], st.y[f], _fluid_volumes(st, f))
        self.max = float(np.fmax(self.max, r))
        self.write_row((sim.time, r, self.max))


# --- crestTracker ------------------------------------------------------------------------------
def crest(gx, eta, fit_above: float = 0.5) -> tuple[float, float]:
    """(x_c, eta_c) of a surface sampled at gauges ``gx`` (ascending): eta_c is the highest
    reading; x_c is the vertex of the least-squares parabola through the contiguous readings
    around it that are at least ``fit_above`` eta_c (the highest gauge's x when fewer than 3
    or the fit is not concave). NaN readings are ignored.

    Where those readings run into the first or last gauge, the crest is only partly sampled
    and a parabola through the cut-off side would pull x_c towards the remaining side (a
    solitary wave's sech^2 is not a parabola: by up to 1.8 m, 3 gauges, for P's A/d = 0.3
    wave within 18 m of the range's end); the fit then keeps the readings symmetric about the
    highest one, as many on each side as the short side has."""
    gx = np.asarray(gx, dtype=float)
    e = np.where(np.isfinite(eta), eta, -np.inf)
    if not np.isfinite(e).any():
        return float("nan"), float("nan")
    j = int(np.argmax(e))
    top = float(e[j])
    if top <= 0.0:
        return float(gx[j]), top
    below = np.flatnonzero(e < fit_above * top)
    a = below[below < j]
    b = below[below > j]
    i0 = a[-1] + 1 if a.size else 0
    i1 = b[0] if b.size else e.size
    if i0 == 0 or i1 == e.size:                 # cut off by the range: symmetric about j
        m = min(j - i0, i1 - 1 - j)
        i0, i1 = j - m, j + m + 1
    if i1 - i0 < 3:
        return float(gx[j]), top
    xs = gx[i0:i1] - gx[j]
    c2, c1, _ = np.polyfit(xs, e[i0:i1], 2)
    if c2 >= 0.0:
        return float(gx[j]), top
    xc = float(np.clip(-c1 / (2.0 * c2), xs[0], xs[-1]))
    return float(gx[j] + xc), top


def fit_celerity(t, xc) -> tuple[float, float, float]:
    """(c, x0, rms) of the least-squares line x_c = x0 + c t (NaN with fewer than 2 points)."""
    t, xc = np.asarray(t, dtype=float), np.asarray(xc, dtype=float)
    if t.size < 2 or np.ptp(t) == 0:
        return float("nan"), float("nan"), float("nan")
    c, x0 = np.polyfit(t, xc, 1)
    rms = float(np.sqrt(np.mean((xc - (x0 + c * t)) ** 2)))
    return float(c), float(x0), rms


@register
class CrestTracker(_SurfaceHeader, FunctionObject):
    """Crest position x_c(t), crest height eta_c(t) and celerity of a travelling wave (T §4.4.2).

    The surface is read by wave gauges (T §4.3.2, dx/2 convention) every ``spacing`` (default
    dx) from ``xMin`` to ``xMax`` (default: the extent of the fluid). eta_c is the highest
    reading; x_c the vertex of the least-squares parabola through the contiguous readings
    around it above ``fitAbove`` eta_c (many gauges, so it is not tied to the gauge grid
    or the particle noise; exact for a symmetric crest; symmetric about the highest reading
    where the range cuts those readings off, see :func:`crest`). Each row's celerity c is the central
    difference of x_c between the neighbouring samples (one-sided at the first and last), so
    rows are written one sample late. At the end c is fitted by least squares to x_c(t) over
    the samples with ``fitFrom`` <= x_c <= ``fitTo`` and eta_c >= ``minHeight`` and written
    to ``celerity.dat`` (the thesis's average wave speed between two gauges, T Table 4.3,
    with every sample in between). ``surface fraction`` reads the gauges by the SPH fluid
    fraction 1/2 (sub-particle) instead of the highest particle, ``surface volume`` by the
    column's water volume (``ColumnSurface``), ``surface wire`` by the wetted length of the
    vertical (``wire_surface``).

    3-D (z up): the gauges lie on the line y = ``y`` from ``xMin`` to ``xMax`` (the 3-D
    gauges, :func:`surface_elevation_3d` or :func:`fraction_surface_3d`); ``surface volume``
    has no 3-D form.
    """

    name = "crestTracker"
    doc = "crest position, height and celerity of a travelling wave (gauges every dx, " \
          "least-squares fits), T §4.3.2"
    columns = ("time", "xCrest", "etaCrest", "c")
    dims = (2, 3)

    class Coeffs(_GaugeSurfaceCoeffs):
        xMin: float | None = Field(None, description=(
            "first gauge (m); default the leftmost fluid particle"))
        y: float | None = Field(None, description=(
            "3-D: the gauges' line y (m), along x (required in 3-D)"))
        xMax: float | None = Field(None, description=(
            "last gauge (m); default the rightmost fluid particle"))
        spacing: float | None = Field(None, gt=0, description="gauge spacing (m); default dx")
        still: float = Field(0.0, description="still-water level (m): eta = surface y - still")
        window: float = Field(GAUGE_WINDOW, gt=0, description=(
            "half-width of each gauge's search windows, in dx (2.5 in T §4.3.2)"))
        fitAbove: float = Field(0.5, gt=0, lt=1, description=(
            "x_c is the vertex of the parabola fitted to the readings above this fraction "
            "of the crest height"))
        fitFrom: float = Field(-math.inf, description=(
            "celerity fit: only samples with the crest at x_c >= fitFrom (m)"))
        fitTo: float = Field(math.inf, description=(
            "celerity fit: only samples with the crest at x_c <= fitTo (m)"))
        minHeight: float = Field(0.0, description=(
            "celerity fit: only samples with eta_c >= minHeight (m), e.g. once the wave has "
            "formed"))

        @model_validator(mode="after")
        def _line(self, info: ValidationInfo):
            dim = case_dimension(info)
            if dim == 3 and self.y is None:
                raise ValueError("a 3-D case's crest tracker reads gauges along x on one line: "
                                 "give its y")
            if dim == 3 and self.surface == "volume":
                raise ValueError("surface volume has no 3-D form: use particle, fraction "
                                 "or wire")
            if dim == 2 and self.y is not None:
                raise ValueError("y is the gauges' line in a 3-D case: a 2-D case has none")
            return self

    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        self.column = (ColumnSurface(self, self.coeffs.volumeWidth)
                       if self.coeffs.surface == "volume" else None)
        self.samples: list[tuple[float, float, float]] = []
        self._written = 0
        self.summary_file = self.folder / "celerity.dat"

    def measure(self, xf, yf, vf=None) -> tuple[float, float]:
        """(x_c, eta_c) from the fluid particles (their volumes ``vf`` for surface fraction)."""
        c, dx = self.coeffs, self.ctx.dx
        if xf.size == 0:
            return float("nan"), float("nan")
        gx = self._gauges(xf)
        if c.surface == "volume":
            eta = self.column.surface(xf, yf, vf, gx, still=c.still)
        elif c.surface in ("fraction", "wire"):
            read = fraction_surface if c.surface == "fraction" else wire_surface
            eta = read(xf, yf, vf, gx, self.case.models.sph["kernel"], self.ctx.h, dx,
                       still=c.still)
        else:
            eta = surface_elevation(xf, yf, gx, dx, still=c.still, window=c.window)
        return crest(gx, eta, c.fitAbove)

    def _gauges(self, xf) -> np.ndarray:
        """The gauges' x: every ``spacing`` from xMin to xMax (the fluid's extent)."""
        c = self.coeffs
        lo = c.xMin if c.xMin is not None else float(xf.min())
        hi = c.xMax if c.xMax is not None else float(xf.max())
        step = c.spacing or self.ctx.dx
        return lo + step * np.arange(int(math.floor((hi - lo) / step + 1e-9)) + 1)

    def measure_3d(self, st, f) -> tuple[float, float]:
        """(x_c, eta_c) of a 3-D case: the gauges along x on the line y = ``y``."""
        c, dx = self.coeffs, self.ctx.dx
        if not f.any():
            return float("nan"), float("nan")
        gx = self._gauges(st.x[f])
        pts = np.column_stack([gx, np.full(gx.size, c.y)])
        if c.surface in ("fraction", "wire"):
            read = fraction_surface_3d if c.surface == "fraction" else wire_surface_3d
            eta = read(st.x[f], st.y[f], st.z[f], _fluid_volumes(st, f), pts,
                       self.case.models.sph["kernel"], self.ctx.h, dx, still=c.still)
        else:
            eta = surface_elevation_3d(st.x[f], st.y[f], st.z[f], pts, dx, still=c.still,
                                       window=c.window)
        return crest(gx, eta, c.fitAbove)

    def execute(self, sim):
        st, f = _fluid(sim)
        if _dim(self.ctx) == 3:
            xc, ec = self.measure_3d(st, f)
        else:
            xc, ec = self.measure(st.x[f], st.y[f], _fluid_volumes(st, f))
        self.samples.append((float(sim.time), xc, ec))
        if len(self.samples) >= 2:
            self._flush(len(self.samples) - 1)

    def _celerity(self, i: int) -> float:
        s = self.samples
        a, b = max(i - 1, 0), min(i + 1, len(s) - 1)
        if b == a or s[b][0] == s[a][0]:
            return float("nan")
        return (s[b][1] - s[a][1]) / (s[b][0] - s[a][0])

    def _flush(self, upto: int) -> None:
        while self._written < upto:
            t, xc, ec = self.samples[self._written]
            self.write_row((t, xc, ec, self._celerity(self._written)))
            self._written += 1

    def end(self):
        self._flush(len(self.samples))
        super().end()
        c = self.coeffs
        s = np.array(self.samples, dtype=float).reshape(-1, 3)
        sel = np.isfinite(s[:, 1]) & (s[:, 1] >= c.fitFrom) & (s[:, 1] <= c.fitTo) & \
            (s[:, 2] >= c.minHeight)
        t, xc, ec = s[sel, 0], s[sel, 1], s[sel, 2]
        cel, x0, rms = fit_celerity(t, xc)
        cols = ("c", "x0", "etaMean", "tFrom", "tTo", "nSamples", "rms")
        row = (cel, x0, float(ec.mean()) if ec.size else float("nan"),
               float(t.min()) if t.size else float("nan"),
               float(t.max()) if t.size else float("nan"), t.size, rms)
        with self.summary_file.open("w") as fh:
            fh.write(f"# {self.object_name} ({self.name}): celerity c from the least-squares "
                     f"line x_c = x0 + c t over the samples with {c.fitFrom:g} <= x_c <= "
                     f"{c.fitTo:g} and eta_c >= {c.minHeight:g}; etaMean: their mean crest "
                     "height; rms: residual of x_c (m)\n")
            fh.write("# " + "\t".join(cols) + "\n")
            fh.write("\t".join(f"{v:.9g}" for v in row) + "\n")
