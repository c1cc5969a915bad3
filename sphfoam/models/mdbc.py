"""The modified dynamic boundary condition (mDBC) of English, Domínguez, Vacondio, Crespo,
Stansby, Lind, Chiapponi & Gómez-Gesteira (2022, Comput. Part. Mech. 9, 911-925).

Rows of wall particles behind the wall as for ``stationaryGhosts`` (the first dx/2 behind
the wall surface), but their density does not evolve by pairing with the fluid: before every
evaluation each wall particle w takes the density of the fluid at its *ghost node*, its
mirror image across the wall surface, x_g = x_w + g_w (the set-up's ``ghostX``, ``ghostY``,
``ghostZ``: twice the vector from the particle to the nearest point of the wall surface, so
that the node lies as far in front of the wall as the particle lies behind it; behind a
concave corner or edge, the mirror image across the corner). At the node the fluid's density
and its gradient come from a first-order (linear) fit over the fluid particles f within the
kernel's support, and are extrapolated back to the particle:

    rho_w = rho_g + (x_w - x_g) . grad rho_g                       (English et al. 2022, eq. 10)

The fit is the kernel-weighted least-squares one, with the weights V_f W(x_f - x_g),
V_f = m_f / rho_f: the same first-order consistency as the corrected kernel gradient of Liu
& Liu (2006) that English et al. write (eqs. 8-9), in its symmetric form. Where the fit is
ill-conditioned (the determinant of the moment matrix, normalised by the kernel sum and h,
below ``MIN_DETERMINANT`` times a full support's: a node at the edge of the water, in a
corner under the free surface or above it) English et al. take the zeroth order, the
Shepard mean of the densities; here it is the zeroth order of the pressure continued
hydrostatically to the particle (Adami, Hu & Adams 2012, eq. 27, weighted at the node),
p_w = sum_f (p_f + rho_f g . (x_w - x_f)) V_f W / sum_f V_f W, exact for water at rest, where
the Shepard mean under a free surface is that of deeper water. A node with no fluid within
the support leaves the particle at rho0, and the particle's density is held at rho0 at
least: a wall never pulls the water, which would draw it into the wall (DualSPHysics holds
its boundary particles so). Pressure and sound speed follow from the equation of state
(Tait, T(3.27)).

Wall velocities: with ``noSlip yes`` (the default) they stay as set up (zero: no slip for
the viscous term, as the original DBC). With ``noSlip no`` (free slip; English et al. 2022
use the no-slip form) each wall particle takes, for the pair passes, the tangential part of
the fluid's velocity at its ghost node (from the same linear fit), and a normal part that
pushes as the water's mirror image and pulls no more than a wall at rest:

    u_w = u_g - c ((u_g - U_w) . n) n,    n = g_w / |g_w|,
    c = 2 where (u_g - U_w) . n < 0 (the water approaches: the mirror image's normal
    velocity, as for mirrored ghosts, T(3.78)), else 1 (it leaves: the wall's own)

so that no pair with a wall particle sees a tangential velocity difference (no friction),
water running at the wall is compressed and damped as by its mirror image, and water
drawing away is not held back harder than by a wall at rest. mDBC's wall pressure is the
water's own continued into the wall, near zero under a thin fast front: once the wall's
friction is gone, the approach's compression is what holds such a front off the wall,
while the mirror's expansion on leaving would tear water off convex edges. Behind an edge
or a corner, where the node is the image across two or three planes, each component along
which the offset runs is treated so. The velocity is set before the pair passes of every
evaluation (the ``before_passes`` hook) and the prescribed one put back after them, so
that the integrators move wall particles with it and output shows it. Measured (the 3-D
dam break): docs/user-guide.md.

The fluid sees the wall particles as neighbours of kind ``ghost``: every term treats them as
fluid with the density set here. Compared with ``stationaryGhosts``, whose wall density
rises only where water is compressed against it, the wall's pressure is the water's own
continued through the wall, so the water rests against the wall surface (the dynamic
boundary's gap, of the order of h, closes to about dx/2).

The ghost nodes' neighbours are gathered at each build of the neighbour list, over the cell
grid the list uses, within a cell side (the support and the list's skin) of each node, for
the wall particles that can meet the fluid (less deep behind the wall than the support
radius less dx/4); before each evaluation the fit runs over those lists, in compiled
parallel loops (:func:`node_list` and :func:`fit_wall` per wall particle, which the device
form, ``sphfoam.models.mdbc_cuda``, runs as device functions on backend cuda), each thread
a contiguous run of wall particles with about equal work (``balanced_chunks``). Measured
(cost, the 3-D dam break): docs/user-guide.md and
benchmarks/results/damBreak3D-2026-12-05/README.md.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from pydantic import Field

from sphfoam.engine.state import FLUID, WALL
from sphfoam.models.base import CaseContext
from sphfoam.models.boundaries import Boundary
from sphfoam.registry import Coeffs, register

#: the first-order fit is used where det of the normalised moment matrix is at least this
#: fraction of a full support's (on the lattice of spacing dx)
MIN_DETERMINANT = 0.05

_JIT = dict(cache=True, nogil=True)


@njit(**_JIT)
def _wrap(d, period):
    """The minimum image of a separation along a periodic axis (period 0: not periodic)."""
    if period > 0.0:
        d -= period * math.floor(d / period + 0.5)
    return d


@njit(**_JIT)
def _cell_range(c, n, periodic):
    """The three cells c-1 .. c+1 along an axis: (first, count); on a periodic axis every
    cell index is taken modulo n by the caller."""
    if periodic:
        return c - 1, min(3, n)
    lo = max(c - 1, 0)
    hi = min(c + 1, n - 1)
    return lo, hi - lo + 1


@njit(**_JIT)
def node_list(px, py, pz, three, x, y, kind, z, cell_start, x0, y0, z0, inv_cell, ncx, ncy,
              ncz, lx, ly, lz, reach2, fill, out_idx, start):
    """The fluid particles within sqrt(reach2) of the node (px, py, pz), over the 3 (x 3) x 3
    cells about it in the order of the cell walk: how many, and with ``fill`` their indices
    into ``out_idx`` from ``start`` (2-D: ``three`` False, z and pz unread, ncz 1)."""
    cx = int(math.floor((px - x0) * inv_cell))
    cy = int(math.floor((py - y0) * inv_cell))
    cz = int(math.floor((pz - z0) * inv_cell)) if three else 0
    ix0, nx_ = _cell_range(cx, ncx, lx > 0.0)
    iy0, ny_ = _cell_range(cy, ncy, ly > 0.0)
    iz0, nz_ = _cell_range(cz, ncz, lz > 0.0) if three else (0, 1)
    n = 0
    for kz in range(iz0, iz0 + nz_):
        jz = kz % ncz
        for ky in range(iy0, iy0 + ny_):
            jy = ky % ncy
            for kx in range(ix0, ix0 + nx_):
                c = (jz * ncy + jy) * ncx + kx % ncx
                for b in range(cell_start[c], cell_start[c + 1]):
                    if kind[b] != FLUID:
                        continue
                    dx_ = _wrap(x[b] - px, lx)
                    dy_ = _wrap(y[b] - py, ly)
                    r2 = dx_ * dx_ + dy_ * dy_
                    if three:
                        dz_ = _wrap(z[b] - pz, lz)
                        r2 += dz_ * dz_
                    if r2 < reach2:
                        if fill:
                            out_idx[start + n] = b
                        n += 1
    return n


@njit(parallel=True, **_JIT)
def ghost_lists(walls, gx, gy, gz, x, y, z, kind, cell_start, x0, y0, z0, inv_cell, ncx,
                ncy, ncz, lx, ly, lz, reach2, counts, fill, out_idx, chunks):
    """Two passes over the wall particles ``walls`` (indices), in parallel over the runs
    ``chunks`` (:func:`balanced_chunks`): ``fill`` False counts into ``counts[k]`` the fluid
    particles within sqrt(reach2) of wall k's ghost node (gx, gy, gz: the nodes' positions);
    ``fill`` True writes them into ``out_idx`` from ``counts[k]`` (the running sum's start).
    2-D: z and gz empty and ncz 1 (:func:`node_list`)."""
    three = z.shape[0] > 0
    for ch in prange(chunks.shape[0] - 1):
        for k in range(chunks[ch], chunks[ch + 1]):
            pz = gz[k] if three else 0.0
            n = node_list(gx[k], gy[k], pz, three, x, y, kind, z, cell_start, x0, y0, z0,
                          inv_cell, ncx, ncy, ncz, lx, ly, lz, reach2, fill, out_idx,
                          counts[k])
            if not fill:
                counts[k] = n


@njit(**_JIT)
def _solve(a, m, nr):
    """Solve the m x m system in a[:m, :m] with the ``nr`` right-hand sides a[:m, m:m + nr]
    in place (Gaussian elimination with partial pivoting); returns the matrix's determinant
    (0.0 for a singular one, the system then unsolved)."""
    det = 1.0
    mc = m + nr
    for i in range(m):
        piv = i
        for r in range(i + 1, m):
            if abs(a[r, i]) > abs(a[piv, i]):
                piv = r
        if a[piv, i] == 0.0:
            return 0.0
        if piv != i:
            for c in range(mc):
                t = a[i, c]
                a[i, c] = a[piv, c]
                a[piv, c] = t
            det = -det
        det *= a[i, i]
        for r in range(i + 1, m):
            f = a[r, i] / a[i, i]
            for c in range(i, mc):
                a[r, c] -= f * a[i, c]
    for k in range(m, mc):
        for i in range(m - 1, -1, -1):
            t = a[i, k]
            for c in range(i + 1, m):
                t -= a[i, c] * a[c, k]
            a[i, k] = t / a[i, i]
    return det


@njit(**_JIT)
def _normal(ug, U, g, tiny):
    """A component of a free-slip wall particle's velocity behind an edge or a corner: the
    node's (u_g) where the offset g has no part along it; along the offset, the node's
    mirrored about the wall's (2 U - u_g) where the water there moves towards the wall,
    else the wall's (U)."""
    if abs(g) <= tiny:
        return ug
    if (ug - U) * g < 0.0:
        return 2.0 * U - ug
    return U


@njit(**_JIT)
def fit_wall(a, gox, goy, goz, lo, hi, idx, three, x, y, z, m, rho, lx, ly, lz, h, support,
             kernel_f, det_min, rho0, B, gamma, c0, gx, gy, gz, wk, slip, u, v, w, corner,
             U0x, U0y, U0z):
    """English et al. (2022) eq. (10) for the wall particle ``a``: the linear fit of the
    fluid's density at its ghost node (offset gox, goy, goz from it) over the node's list
    ``idx[lo:hi]``, extrapolated to the particle; where the fit is ill-conditioned, the
    node's zeroth order with the hydrostatic continuation to the particle (AHA12 eq. (27)
    with the node's weights); its p and c by Tait's equation: (rho, p, c, u_w). ``wk``
    (4 x 8) is scratch.

    ``slip`` (free slip; otherwise u, v, w are not read): also the fluid's velocity u_g at
    the node, from the same fit (the Shepard mean where it is ill-conditioned, the
    prescribed (U0x, U0y, U0z) where no fluid is near), and u_w its tangential part with its
    normal part about the wall's mirrored where the water approaches the wall and the wall's
    where it leaves: u_w = u_g - c ((u_g - U0) . n) n, n = the unit offset to the node, c = 2
    for (u_g - U0) . n < 0, else 1; behind an edge or a corner (``corner`` > 0), where the
    node is the image across two or three planes, each component along which the offset runs
    likewise (``_normal``). One wall particle's arithmetic, for the CPU's loop
    (:func:`wall_density`) and the device's (``sphfoam.models.mdbc_cuda``)."""
    mm = 4 if three else 3
    nv = (3 if three else 2) if slip else 0
    inv_h = 1.0 / h
    q2max = support * support
    px = x[a] + gox
    py = y[a] + goy
    pz = z[a] + goz if three else 0.0
    s00 = s01 = s02 = s03 = s11 = s12 = s13 = s22 = s23 = s33 = 0.0
    b0 = b1 = b2 = b3 = 0.0             # rho
    u0 = u1 = u2 = u3 = 0.0             # free slip: u, v, w
    v0 = v1 = v2 = v3 = 0.0
    w0 = w1 = w2 = w3 = 0.0
    for n in range(lo, hi):
        b = idx[n]
        rx = _wrap(x[b] - px, lx) * inv_h
        ry = _wrap(y[b] - py, ly) * inv_h
        rz = _wrap(z[b] - pz, lz) * inv_h if three else 0.0
        q2 = rx * rx + ry * ry + rz * rz
        if q2 >= q2max:
            continue
        vw = m[b] / rho[b] * kernel_f(math.sqrt(q2))
        vr = vw * rho[b]
        s00 += vw
        s01 += vw * rx
        s02 += vw * ry
        s03 += vw * rz
        s11 += vw * rx * rx
        s12 += vw * rx * ry
        s13 += vw * rx * rz
        s22 += vw * ry * ry
        s23 += vw * ry * rz
        s33 += vw * rz * rz
        b0 += vr
        b1 += vr * rx
        b2 += vr * ry
        b3 += vr * rz
        if slip:
            vu = vw * u[b]
            vv = vw * v[b]
            u0 += vu
            u1 += vu * rx
            u2 += vu * ry
            u3 += vu * rz
            v0 += vv
            v1 += vv * rx
            v2 += vv * ry
            v3 += vv * rz
            if three:
                vz = vw * w[b]
                w0 += vz
                w1 += vz * rx
                w2 += vz * ry
                w3 += vz * rz
    wk[0, 0], wk[0, 1], wk[0, 2], wk[1, 1], wk[1, 2], wk[2, 2] = s00, s01, s02, s11, s12, s22
    wk[0, mm], wk[1, mm], wk[2, mm] = b0, b1, b2
    if three:
        wk[0, 3], wk[1, 3], wk[2, 3], wk[3, 3], wk[3, mm] = s03, s13, s23, s33, b3
    if slip:
        wk[0, mm + 1], wk[1, mm + 1], wk[2, mm + 1] = u0, u1, u2
        wk[0, mm + 2], wk[1, mm + 2], wk[2, mm + 2] = v0, v1, v2
        if three:
            wk[3, mm + 1], wk[3, mm + 2] = u3, v3
            wk[0, mm + 3], wk[1, mm + 3], wk[2, mm + 3], wk[3, mm + 3] = w0, w1, w2, w3
    s = wk[0, 0]
    # the zeroth order (Shepard) of the velocity at the node, before the solve
    ug0 = wk[0, mm + 1] / s if slip and s > 0.0 else 0.0
    ug1 = wk[0, mm + 2] / s if slip and s > 0.0 else 0.0
    ug2 = wk[0, mm + 3] / s if slip and three and s > 0.0 else 0.0
    fit = False
    if s > 0.0:
        for i in range(mm):
            for j in range(i):
                wk[i, j] = wk[j, i]
        # the determinant of the moment matrix normalised by the kernel sum
        fit = _solve(wk, mm, 1 + nv) / s ** mm >= det_min
    if fit:
        r = wk[0, mm] - (gox * wk[1, mm] + goy * wk[2, mm]
                         + (goz * wk[3, mm] if three else 0.0)) * inv_h
        if slip:
            ug0 = wk[0, mm + 1]
            ug1 = wk[0, mm + 2]
            ug2 = wk[0, mm + 3] if three else 0.0
    elif s > 0.0:
        # the fluid's pressure continued hydrostatically to the particle, weighted at the
        # node: p_w = sum_f (p_f + rho_f g . (x_w - x_f)) V_f W / sum_f V_f W
        sp = 0.0
        for n in range(lo, hi):
            b = idx[n]
            rx = _wrap(x[b] - px, lx)
            ry = _wrap(y[b] - py, ly)
            rz = _wrap(z[b] - pz, lz) if three else 0.0
            q2 = (rx * rx + ry * ry + rz * rz) * inv_h * inv_h
            if q2 >= q2max:
                continue
            vw = m[b] / rho[b] * kernel_f(math.sqrt(q2))
            pb = B * ((rho[b] / rho0) ** gamma - 1.0)
            # x_w - x_f = -(offset + r)
            sp += vw * (pb - rho[b] * (gx * (gox + rx) + gy * (goy + ry)
                                       + gz * (goz + rz)))
        r = rho0 * max(1.0 + sp / s / B, 1e-6) ** (1.0 / gamma)
    else:
        r = rho0
    # never below rho0: a wall that pulled would absorb the water (DualSPHysics' rule for
    # its boundary particles)
    r = max(r, rho0)
    ratio = r / rho0
    pw = B * (ratio ** gamma - 1.0)
    cw = c0 * ratio ** (0.5 * (gamma - 1.0))
    if not slip:
        return r, pw, cw, 0.0, 0.0, 0.0
    if s <= 0.0:
        ug0, ug1, ug2 = U0x, U0y, U0z
    if corner > 0.5:
        tiny = 1e-9 * math.sqrt(gox * gox + goy * goy + goz * goz)
        return (r, pw, cw, _normal(ug0, U0x, gox, tiny), _normal(ug1, U0y, goy, tiny),
                _normal(ug2, U0z, goz, tiny) if three else 0.0)
    inv = 1.0 / math.sqrt(gox * gox + goy * goy + goz * goz)
    nx, ny, nz = gox * inv, goy * inv, goz * inv
    dn = (ug0 - U0x) * nx + (ug1 - U0y) * ny + (ug2 - U0z) * nz
    if dn < 0.0:
        dn *= 2.0
    return r, pw, cw, ug0 - dn * nx, ug1 - dn * ny, (ug2 - dn * nz) if three else 0.0


def balanced_chunks(starts, parts: int = 64, per_wall: int = 8) -> np.ndarray:
    """Bounds of ``parts`` contiguous runs of the wall particles with about equal work (the
    list entries plus ``per_wall`` for each particle): the threads of a parallel loop over
    them get equal shares. Wet walls lie together in the sorted order, so equal counts of
    wall particles (prange's own split) left one of two threads most of the fit."""
    n = len(starts) - 1
    weight = starts + per_wall * np.arange(n + 1)
    out = np.searchsorted(weight, np.linspace(0, weight[-1], parts + 1)).astype(np.int64)
    out[0], out[-1] = 0, n
    return np.maximum.accumulate(out)


@njit(parallel=True, **_JIT)
def wall_density(walls, ox, oy, oz, starts, idx, x, y, z, m, rho, p, c, lx, ly, lz, h,
                 support, kernel_f, det_min, rho0, B, gamma, c0, gx, gy, gz, work, slip, u,
                 v, w, corner, U0, out_u, chunks):
    """:func:`fit_wall` for each wall particle ``walls[k]``, over its node's list
    ``idx[starts[k]:starts[k + 1]]``, with the scratch ``work[k]`` (len(walls), 4, 8): its
    rho, p and c set, and with ``slip`` its pair passes' velocity into ``out_u`` (dim,
    len(walls); U0 the prescribed, (dim, len(walls))); in the runs ``chunks`` of equal work
    (:func:`balanced_chunks`), in parallel. 2-D: z and oz empty; no slip: u, v, w, corner,
    U0 and out_u may be empty."""
    three = z.shape[0] > 0
    for ch in prange(chunks.shape[0] - 1):
        for k in range(chunks[ch], chunks[ch + 1]):
            a = walls[k]
            goz = oz[k] if three else 0.0
            cor = U0x = U0y = U0z = 0.0
            if slip:
                cor, U0x, U0y = corner[k], U0[0, k], U0[1, k]
                if three:
                    U0z = U0[2, k]
            r, pw, cw, ux, uy, uz = fit_wall(
                a, ox[k], oy[k], goz, starts[k], starts[k + 1], idx, three, x, y, z, m, rho,
                lx, ly, lz, h, support, kernel_f, det_min, rho0, B, gamma, c0, gx, gy, gz,
                work[k], slip, u, v, w, cor, U0x, U0y, U0z)
            rho[a] = r
            p[a] = pw
            c[a] = cw
            if slip:
                out_u[0, k] = ux
                out_u[1, k] = uy
                if three:
                    out_u[2, k] = uz


@njit(parallel=True, **_JIT)
def state_sum(x, y, z, rho, kind, u, v, w):
    """A sum of the positions and the fluid's densities (and, where u is not empty, the
    fluid's velocities): unchanged, nothing the wall state depends on has changed since it
    was computed (the equation of state and the rates pass of one evaluation both call the
    hooks)."""
    s = 0.0
    three = z.shape[0] > 0
    vel = u.shape[0] > 0
    for a in prange(x.shape[0]):
        t = x[a] + 3.0 * y[a]
        if three:
            t += 7.0 * z[a]
        if kind[a] == FLUID:
            t += 11.0 * rho[a]
            if vel:
                t += 13.0 * u[a] + 17.0 * v[a]
                if three:
                    t += 19.0 * w[a]
        s += t
    return s


def full_support_determinant(kernel, hdx: float, dim: int) -> float:
    """The determinant of the normalised moment matrix (r in units of h) of a node on a full
    lattice of spacing dx = h / hdx: the scale of ``MIN_DETERMINANT``."""
    reach = kernel.support * hdx
    n = int(math.ceil(reach)) + 1
    axes = [np.arange(-n, n + 1, dtype=float)] * dim
    r = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim) / hdx
    q = np.linalg.norm(r, axis=1)
    w = np.array([kernel.f_jit(float(v)) if v < kernel.support else 0.0 for v in q])
    basis = np.column_stack([np.ones(len(r)), r])
    mat = (basis * w[:, None]).T @ basis / w.sum()
    return float(np.linalg.det(mat))


@register
class ModifiedDynamic(Boundary):
    """English et al. (2022): wall particles whose density is the fluid's at their ghost
    node, extrapolated (see the module docstring)."""

    name = "mDBC"
    doc = ("modified dynamic boundary, English et al. (2022): wall-particle rows whose "
           "density is the fluid's linear fit at the ghost node (the mirror image across the "
           "wall), extrapolated to the particle (eq. 10); p by the EOS; no-slip (the wall's "
           "velocity) or free slip (the node's tangential velocity, its normal one mirrored on "
           "approach)")
    #: the hooks handle z in 3-D
    hook_dims = (2, 3)
    #: the hooks on the device (sphfoam.models.mdbc_cuda), in both dimensions
    device_form = "sphfoam.models.mdbc_cuda:ModifiedDynamicDevice"
    device_hooks = ("attach", "after_sort", "before_evaluation", "before_passes",
                    "after_rates", "after_density_rate")

    class Coeffs(Coeffs):
        noSlip: bool = Field(True, description=(
            "the wall particles keep their prescribed velocity (zero: no slip, as the "
            "original DBC); no: free slip, the fluid's tangential velocity at the ghost node, "
            "its normal one mirrored where the water approaches the wall"))

    @property
    def keeps_wall_velocity(self) -> bool:
        """No slip: the wall particles' velocities stay as set up; free slip sets them."""
        return bool(self.coeffs.noSlip)

    @property
    def wall_fields(self) -> tuple[str, ...]:
        """The vector from each wall particle to its ghost node (set-up); free slip also
        reads the corner flag (a node across an edge or a corner)."""
        return ("ghostX", "ghostY", "ghostZ") + (() if self.coeffs.noSlip else ("corner",))

    def params(self, ctx: CaseContext):
        return {}

    def neighbour_kinds(self):
        """Every wall particle is a ghost: fluid to every term, with the density (and, free
        slip, the velocity) set here; its own density does not evolve."""
        return {"ghost": "else"}

    # --- run-time hooks (sphfoam.models.base) ---------------------------------------------
    def attach(self, run):
        st = run.state
        missing = [k for k in self.fields_in(st.dim) if k not in st.extra]
        if missing and (st.kind == WALL).any():
            raise ValueError(f"boundary mDBC reads the wall fields {', '.join(missing)}, "
                             "which this case's particles lack: run sphfoam setup again")
        kernel = run.kernel
        prm = run.coefficients()
        self._kernel_f = kernel.f_jit
        self._support = float(kernel.support)
        self._det_min = MIN_DETERMINANT * full_support_determinant(
            kernel, float(kernel.coeffs.hdx), st.dim)
        self._eos = (prm["eos_rho0"], prm["eos_B"], prm["eos_gamma"], prm["eos_c0"])
        self._dx = run.h / float(kernel.coeffs.hdx)
        self._g = (prm["gx"], prm["gy"], prm.get("gz", 0.0))
        self._lists = None
        self._sum = None
        self._slip = not self.coeffs.noSlip
        self._uw = self._U0 = None

    def after_sort(self, run, order):
        """The ghost nodes' lists of fluid particles, over the cell grid just sorted."""
        st = run.state
        cells = run.cells
        three = st.dim == 3
        ox, oy = st.extra["ghostX"], st.extra["ghostY"]
        oz = st.extra["ghostZ"] if three else ox[:0]
        off2 = ox * ox + oy * oy + (oz * oz if three else 0.0)
        reach = run.support_radius
        # a particle deeper behind the wall than the support less dx/4 meets no fluid (the
        # fluid keeps about dx/2 in front of the wall surface): half the offset is its depth
        deepest = 2.0 * (reach - 0.25 * self._dx)
        walls = np.flatnonzero((st.kind == WALL) & (off2 < deepest * deepest))
        gx = st.x[walls] + ox[walls]
        gy = st.y[walls] + oy[walls]
        gz = st.z[walls] + oz[walls] if three else gx[:0]
        z = st.z if three else st.x[:0]
        grid = (cells.x0, cells.y0, cells.z0, 1.0 / cells.cell_size, cells.ncx, cells.ncy,
                cells.ncz if three else 1, cells.lx, cells.ly, cells.lz if three else 0.0,
                cells.cell_size ** 2)
        # the counting pass's shares: by the last build's lists where the same wall
        # particles are fitted (walls stay in their cells, so their order in the sort
        # holds), else equal numbers of them; each walks its node's cells (the wall
        # particles there too), so more work per wall particle than the fit's
        same = self._lists is not None and len(self._lists[0]) == len(walls)
        starts = self._lists[4] if same else np.zeros(len(walls) + 1, dtype=np.int64)
        chunks = balanced_chunks(starts, per_wall=48)
        starts = np.zeros(len(walls) + 1, dtype=np.int64)      # the counts, then their sum
        ghost_lists(walls, gx, gy, gz, st.x, st.y, z, st.kind, cells.cell_start, *grid,
                    starts[1:], False, starts[:0], chunks)
        np.cumsum(starts, out=starts)
        idx = np.empty(int(starts[-1]), dtype=np.int64)
        chunks = balanced_chunks(starts)
        ghost_lists(walls, gx, gy, gz, st.x, st.y, z, st.kind, cells.cell_start, *grid,
                    starts[:-1].copy(), True, idx, chunks)
        # the fit's scratch, kept while the number of fitted wall particles stays
        work = self._lists[7] if same else np.zeros((len(walls), 4, 8))
        corner = np.ascontiguousarray(st.extra["corner"][walls]) if self._slip else ox[:0]
        self._lists = (walls, np.ascontiguousarray(ox[walls]), np.ascontiguousarray(oy[walls]),
                       np.ascontiguousarray(oz[walls]) if three else ox[:0], starts, idx,
                       corner, work, chunks)
        self._sum = None
        self._uw = self._U0 = None          # indexed by the old order: made again before use

    def before_evaluation(self, run):
        """The wall particles' density, pressure and sound speed from their ghost nodes
        (free slip: and the velocity the passes give them, ``before_passes``)."""
        if self._lists is None:
            return
        st = run.state
        three = st.dim == 3
        z = st.z if three else st.x[:0]
        walls, ox, oy, oz, starts, idx, corner, work, chunks = self._lists
        if self._slip:
            u, v = st.velocities[:2]
            w = st.velocities[2] if three else st.x[:0]
        else:
            u = v = w = st.x[:0]
        now = state_sum(st.x, st.y, z, st.rho, st.kind, u, v, w)
        if now == self._sum:
            return
        cells = run.cells
        rho0, B, gamma, c0 = self._eos
        if self._slip:
            # the prescribed velocities (zero, a wall's constant one or its motion's now)
            U0 = np.array([uu[walls] for uu in st.velocities])
            uw = np.empty_like(U0)
        else:
            U0 = uw = np.zeros((3, 0))
        wall_density(walls, ox, oy, oz, starts, idx, st.x, st.y, z, st.m, st.rho, st.p, st.c,
                     cells.lx, cells.ly, cells.lz if three else 0.0, run.h,
                     self._support, self._kernel_f, self._det_min, rho0, B, gamma, c0,
                     *self._g, work, self._slip, u, v, w, corner, U0, uw, chunks)
        self._U0, self._uw = U0, uw
        self._sum = now

    # the free-slip form's hooks (None with no slip): the velocities made from the nodes are
    # the wall particles' for the pair passes only; the prescribed ones are put back after them,
    # before the integrator moves the walls and before anything is written or sampled
    def _set_velocity(self, run, which):
        if self._lists is not None and which is not None:
            walls = self._lists[0]
            for u, uw in zip(run.state.velocities, which):
                u[walls] = uw

    @property
    def before_passes(self):
        if self.coeffs.noSlip:
            return None
        return lambda run: self._set_velocity(run, self._uw)

    @property
    def after_rates(self):
        if self.coeffs.noSlip:
            return None
        return lambda run: self._set_velocity(run, self._U0)

    after_density_rate = after_rates
