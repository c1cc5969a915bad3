"""The device form of the ``mirrorGhosts`` boundary (:class:`sphfoam.models.boundaries.
MirrorGhosts`, ``device_form``): mirrored ghost particles, T(3.77)-(3.80), on the CUDA
backend's device arrays (:mod:`sphfoam.engine.cuda.forms`; imported only there, once
numba.cuda can run): across 2-D wall segments, and in 3-D across the faces of box tanks with
their edge and vertex ghosts (the kernels ending in 3, over :mod:`sphfoam.models.mirror3d`'s
scalar functions; the ghost table then holds a third face, ``gs3``).

The same sequence as the model's hooks on the CPU, with the same per-particle arithmetic:
the kernels call the scalar functions of :mod:`sphfoam.models.mirror` (``ghosts_of``,
``fill_of``, ``ghost_state``, ``ghost_on``, ``fluid_within``, ``push_back_of``,
``wall_shear_of``) as device functions, so each equation is written once.

* At a list build (``add_particles``): the ghosts of the last build are sent to the cell of
  those that leave (dropped with them, not reported); every fluid particle inside the box
  counts its ghosts within the list radius (kernel), an exclusive scan gives each its first
  slot, the arrays grow by the ghosts, each ghost gets its particle, segment(s), kind,
  id -1 - id_a and state (T(3.77)-(3.80)), and is binned (a ghost outside the grid is
  dropped with the particles that leave). The ghost table (``gsrc``, ``gs1``, ``gs2``,
  ``gact`` per particle, gsrc -1 for a particle that is no ghost) lives in the state's
  arrays, so the sort carries it; ``after_sort`` maps gsrc through the permutation.
* Per step (``keeps_neighbours``): which ghosts are active (the criterion of T(3.77) within
  the support), how many a build would make, and whether a dormant ghost is within the
  support of a fluid particle: three counts by atomics, one copy back.
* Before each evaluation: every ghost from its particle (dormant ones with mass 0); after the
  rates: the wall shear of ``wallLaw``; after the step: the push-back across a wall; when a
  wall moves: the segments (a few numbers) copied to the device.

The configuration (reach, segments, corners, the wall law's table, the hydrostatic
coefficients, the unweighted terms) is the model's own ``attach``, run on a copy of it.
"""

from __future__ import annotations

import copy

import numpy as np
from numba import cuda

from numba import float64, int64

from sphfoam.engine.cuda import device as D
from sphfoam.engine.cuda.device import device_function, exclusive_scan
from sphfoam.engine.state import GHOST
from sphfoam.models import mirror as gh
from sphfoam.models import mirror3d as m3

_ghosts_of = device_function(gh.ghosts_of)
_fill_of = device_function(gh.fill_of)
_ghost_state = device_function(gh.ghost_state)
_ghost_on = device_function(gh.ghost_on)
_fluid_within = device_function(gh.fluid_within)
_push_back_of = device_function(gh.push_back_of)
_wall_shear_of = device_function(gh.wall_shear_of)
# 3-D: the box tanks' faces (sphfoam.models.mirror3d)
_ghosts_of3 = device_function(m3.ghosts_of)
_fill_of3 = device_function(m3.fill_of)
_ghost_state3 = device_function(m3.ghost_state)
_ghost_on3 = device_function(m3.ghost_on)
_fluid_within3 = device_function(m3.fluid_within)
_push_back_of3 = device_function(m3.push_back_of)


@cuda.jit
def retire_ghosts(kind, gsrc, cell, counts, outside):
    """The ghosts of the last build go to the cell of the particles that leave."""
    a = cuda.grid(1)
    if a >= kind.shape[0] or kind[a] != GHOST:
        return
    cuda.atomic.sub(counts, cell[a], 1)
    cuda.atomic.add(counts, outside, 1)
    cell[a] = outside
    gsrc[a] = -1


@cuda.jit
def count_ghosts(x, y, kind, cell, outside, seg, corners, reach, margin, count):
    """How many ghosts each fluid particle inside the box makes, T(3.77)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    k = 0
    if kind[a] == 0 and cell[a] != outside:
        k = _ghosts_of(x[a], y[a], seg, corners, reach, margin)
    count[a] = k


@cuda.jit
def fill_ghosts(x, y, kind, cell, outside, seg, corners, reach, margin, n0, offset, gsrc,
                gs1, gs2):
    """The ghosts of particle a in slots n0 + offset[a] on: its index and segment(s)."""
    a = cuda.grid(1)
    if a >= offset.shape[0] - 1 or kind[a] != 0 or cell[a] == outside:
        return
    _fill_of(a, x[a], y[a], seg, corners, reach, margin, n0 + offset[a], gsrc, gs1, gs2)


@cuda.jit
def label_ghosts(n0, kind, pid, gsrc, active):
    """The new ghosts: kind GHOST, id -1 - id of their particle, active."""
    j = cuda.grid(1)
    g = n0 + j
    if g >= kind.shape[0]:
        return
    kind[g] = GHOST
    pid[g] = -1 - pid[gsrc[g]]
    active[g] = 1


@cuda.jit
def inverse(order, inv):
    """inv[order[i]] = i: where the sort put each particle."""
    i = cuda.grid(1)
    if i >= order.shape[0]:
        return
    inv[order[i]] = i


@cuda.jit
def remap_sources(gsrc, inv):
    """Each ghost's particle by its index after the sort."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0] or gsrc[g] < 0:
        return
    gsrc[g] = inv[gsrc[g]]


@cuda.jit
def refresh_ghosts(x, y, u, v, rho, m, gsrc, gs1, gs2, seg, no_slip, active, hydro, gx, gy,
                   rho0, B, gamma):
    """Every ghost from its particle's state now, T(3.77)-(3.80) (:func:`sphfoam.models.
    mirror.refresh_ghosts`); a dormant one (``active`` 0) with mass 0."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0]:
        return
    a = gsrc[g]
    if a < 0:
        return
    x[g], y[g], u[g], v[g], rho[g] = _ghost_state(x[a], y[a], u[a], v[a], rho[a], seg,
                                                  gs1[g], gs2[g], no_slip, hydro, gx, gy,
                                                  rho0, B, gamma)
    m[g] = m[a] if active[g] else 0.0


@cuda.jit
def ghost_activity(x, y, gsrc, gs1, gs2, seg, reach, active, out):
    """``active[g]``: ghost g's particle still meets T(3.77)'s criterion; out[0] += how many."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0]:
        return
    a = gsrc[g]
    if a < 0:
        return
    if _ghost_on(x[a], y[a], seg, gs1[g], gs2[g], reach):
        active[g] = 1
        cuda.atomic.add(out, 0, 1)
    else:
        active[g] = 0


@cuda.jit
def count_qualifying(x, y, kind, seg, corners, reach, out):
    """out[1] += the ghosts a build would make now (within the support, no skin)."""
    a = cuda.grid(1)
    if a >= x.shape[0] or kind[a] != 0:
        return
    k = _ghosts_of(x[a], y[a], seg, corners, reach, 0.0)
    if k:
        cuda.atomic.add(out, 1, k)


@cuda.jit
def dormant_near_fluid(x, y, kind, gsrc, active, nb_start, nb_idx, support2, out):
    """out[2] += the fluid neighbours of dormant ghosts within the support."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0] or gsrc[g] < 0 or active[g]:
        return
    k = _fluid_within(g, x, y, kind, nb_start, nb_idx, support2)
    if k:
        cuda.atomic.add(out, 2, k)


@cuda.jit
def push_back(x, y, u, v, kind, seg, reach, total):
    """A fluid particle that crossed a wall line goes back (:func:`sphfoam.models.mirror.
    push_back`); total[0] += the crossings."""
    a = cuda.grid(1)
    if a >= x.shape[0] or kind[a] != 0:
        return
    for s in range(seg.shape[0]):
        px, py, pu, pv, k = _push_back_of(x[a], y[a], u[a], v[a], seg, s, reach)
        if k:
            x[a] = px
            y[a] = py
            u[a] = pu
            v[a] = pv
            cuda.atomic.add(total, 0, 1)


@cuda.jit
def wall_shear(x, y, u, v, kind, seg, reach, phi, law, coef, ax, ay):
    """The wall shear stress of the law of the wall on every fluid particle near a wall
    (:func:`sphfoam.models.mirror.wall_shear`, T(3.84)-(3.85))."""
    a = cuda.grid(1)
    if a >= x.shape[0] or kind[a] != 0:
        return
    for s in range(seg.shape[0]):
        fx, fy, k = _wall_shear_of(x[a], y[a], u[a], v[a], seg, s, reach, phi, law, coef)
        if k:
            ax[a] -= fx
            ay[a] -= fy


# --- 3-D: the same steps across the faces of box tanks (sphfoam.models.mirror3d) ----------------
@cuda.jit
def count_ghosts3(x, y, z, kind, cell, outside, pl, reach, margin, count):
    """How many ghosts each fluid particle inside the box makes: one per set of its near
    faces on distinct axes (a face, an edge, a vertex)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    k = 0
    if kind[a] == 0 and cell[a] != outside:
        near = cuda.local.array(6, int64)
        k = _ghosts_of3(x[a], y[a], z[a], pl, reach, margin, near)
    count[a] = k


@cuda.jit
def fill_ghosts3(x, y, z, kind, cell, outside, pl, reach, margin, n0, offset, gsrc, gs1, gs2,
                 gs3):
    """The ghosts of particle a in slots n0 + offset[a] on: its index and faces."""
    a = cuda.grid(1)
    if a >= offset.shape[0] - 1 or kind[a] != 0 or cell[a] == outside:
        return
    near = cuda.local.array(6, int64)
    _fill_of3(a, x[a], y[a], z[a], pl, reach, margin, n0 + offset[a], gsrc, gs1, gs2, gs3,
              near)


@cuda.jit
def refresh_ghosts3(x, y, z, u, v, w, rho, m, gsrc, gs1, gs2, gs3, pl, no_slip, active,
                    hydro, gx, gy, gz, rho0, B, gamma):
    """Every ghost from its particle's state now (:func:`sphfoam.models.mirror3d.
    ghost_state`); a dormant one with mass 0."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0]:
        return
    a = gsrc[g]
    if a < 0:
        return
    pos = cuda.local.array(3, float64)
    vel = cuda.local.array(3, float64)
    mean = cuda.local.array(3, float64)
    x[g], y[g], z[g], u[g], v[g], w[g], rho[g] = _ghost_state3(
        x[a], y[a], z[a], u[a], v[a], w[a], rho[a], pl, gs1[g], gs2[g], gs3[g], no_slip,
        hydro, gx, gy, gz, rho0, B, gamma, pos, vel, mean)
    m[g] = m[a] if active[g] else 0.0


@cuda.jit
def ghost_activity3(x, y, z, gsrc, gs1, gs2, gs3, pl, reach, active, out):
    """``active[g]``: ghost g's particle still meets its faces' criterion; out[0] += how
    many."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0]:
        return
    a = gsrc[g]
    if a < 0:
        return
    if _ghost_on3(x[a], y[a], z[a], pl, gs1[g], gs2[g], gs3[g], reach):
        active[g] = 1
        cuda.atomic.add(out, 0, 1)
    else:
        active[g] = 0


@cuda.jit
def count_qualifying3(x, y, z, kind, pl, reach, out):
    """out[1] += the ghosts a build would make now (within the support, no skin)."""
    a = cuda.grid(1)
    if a >= x.shape[0] or kind[a] != 0:
        return
    near = cuda.local.array(6, int64)
    k = _ghosts_of3(x[a], y[a], z[a], pl, reach, 0.0, near)
    if k:
        cuda.atomic.add(out, 1, k)


@cuda.jit
def dormant_near_fluid3(x, y, z, kind, gsrc, active, nb_start, nb_idx, support2, out):
    """out[2] += the fluid neighbours of dormant ghosts within the support."""
    g = cuda.grid(1)
    if g >= gsrc.shape[0] or gsrc[g] < 0 or active[g]:
        return
    k = _fluid_within3(g, x, y, z, kind, nb_start, nb_idx, support2)
    if k:
        cuda.atomic.add(out, 2, k)


@cuda.jit
def push_back3(x, y, z, u, v, w, kind, pl, reach, total):
    """A fluid particle that crossed a face goes back, face by face (:func:`sphfoam.models.
    mirror3d.push_back`); total[0] += the crossings."""
    a = cuda.grid(1)
    if a >= x.shape[0] or kind[a] != 0:
        return
    for f in range(pl.shape[0]):
        x[a], y[a], z[a], u[a], v[a], w[a], k = _push_back_of3(
            x[a], y[a], z[a], u[a], v[a], w[a], pl, f, reach)
        if k:
            cuda.atomic.add(total, 0, 1)


#: the ghost table, per particle (carried by the sort with the state); 3-D also "gs3"
TABLE = ("gsrc", "gs1", "gs2", "gact")


#: the activity counters' reset
_ZERO3 = np.zeros(3, dtype=np.int64)


class MirrorGhostsDevice:
    """``mirrorGhosts`` on the device (see the module docstring): across 2-D segments, or
    in 3-D across the faces of box tanks."""

    def __init__(self, model):
        self.model = model

    def attach(self, run):
        host = copy.copy(self.model)
        host.attach(run)
        self.host = host
        cu = run.cuda
        self.three = bool(host.three)
        self.reach = float(host.reach)
        self.build_reach = float(host.build_reach)
        self.margin = float(host.margin)
        self.no_slip = bool(host.coeffs.noSlip)
        self.hydro = tuple(host._hydro)
        if self.three:
            self.d_walls = cu.to_device(np.ascontiguousarray(host.pl))
        else:
            self.d_walls = cu.to_device(np.ascontiguousarray(host.seg))
            self.d_corners = cu.to_device(np.ascontiguousarray(host.corners,
                                                               dtype=np.int64))
        self.shear = None
        if host._shear is not None:
            phi, law, coef = host._shear
            self.shear = (cu.to_device(np.ascontiguousarray(phi)), int(law), float(coef))
        self.unweighted = bool(host.unweighted)
        self.built = False
        self.d_pushed = cu.to_device(np.zeros(1, dtype=np.int64))
        self.d_counts = cu.device_array(3, dtype=np.int64)
        self._scratch = None
        n = run.n
        self.table = TABLE + (("gs3",) if self.three else ())
        for k in self.table:
            run.arrays[k] = cu.to_device(np.full(n, -1, dtype=np.int64) if k != "gact"
                                         else np.zeros(n, dtype=np.uint8))

    def _table(self, run):
        """gsrc, the walls' columns (gs1, gs2; 3-D gs3 too), gact."""
        d = run.arrays
        return (d["gsrc"], d["gs1"], d["gs2"]) + ((d["gs3"],) if self.three else ()) + \
            (d["gact"],)

    def _pos(self, run):
        d = run.arrays
        return (d["x"], d["y"], d["z"]) if self.three else (d["x"], d["y"])

    def _vel(self, run):
        d = run.arrays
        return (d["u"], d["v"], d["w"]) if self.three else (d["u"], d["v"])

    # --- the list build -------------------------------------------------------------------
    def add_particles(self, run, cell, counts):
        """Retire the last build's ghosts; make, state and bin this build's (T(3.77))."""
        cu, cl, d = run.cuda, run.cells, run.arrays
        outside = cl.ncx * cl.ncy * (cl.ncz if self.three else 1)
        n0 = run.n
        gsrc, *walls, gact = self._table(run)
        run.launch(retire_ghosts, n0, d["kind"], gsrc, cell, counts, outside)
        count = cu.device_array(n0, dtype=np.int64)
        pos = self._pos(run)
        if self.three:
            run.launch(count_ghosts3, n0, *pos, d["kind"], cell, outside, self.d_walls,
                       self.build_reach, self.margin, count)
        else:
            run.launch(count_ghosts, n0, *pos, d["kind"], cell, outside, self.d_walls,
                       self.d_corners, self.build_reach, self.margin, count)
        offset = cu.device_array(n0 + 1, dtype=np.int64)
        self._scratch = exclusive_scan(count, offset, self._scratch)
        ng = int(run.copy_back(offset[n0:])[0])          # the ghosts' count (one scalar)
        self.built = True
        if ng == 0:
            return cell
        run.append(ng)
        gsrc, *walls, gact = self._table(run)
        pos = self._pos(run)
        if self.three:
            run.launch(fill_ghosts3, n0, *pos, d["kind"], cell, outside, self.d_walls,
                       self.build_reach, self.margin, n0, offset, gsrc, *walls)
        else:
            run.launch(fill_ghosts, n0, *pos, d["kind"], cell, outside, self.d_walls,
                       self.d_corners, self.build_reach, self.margin, n0, offset, gsrc,
                       *walls)
        run.launch(label_ghosts, ng, n0, d["kind"], d["id"], gsrc, gact)
        self.before_evaluation(run)
        grown = cu.device_array(n0 + ng, dtype=np.int64)
        run.launch(D.extend, n0 + ng, cell, grown)
        x, y = d["x"][n0:], d["y"][n0:]
        z = d["z"][n0:] if self.three else x         # (2-D: x stands for z, unread)
        run.launch(D.bin_particles, ng, x, y, z, cl.x0, cl.y0, cl.z0, 1.0 / cl.cell_size,
                   cl.ncx, cl.ncy, cl.ncz, cl.lx, cl.ly, cl.lz, self.three, grown[n0:],
                   counts)
        return grown

    def after_sort(self, run, order):
        """The ghosts' particles by their new index; which ghosts are active; their state."""
        inv = run.cuda.device_array(order.shape[0], dtype=np.int64)
        gsrc = run.arrays["gsrc"]
        run.launch(inverse, order.shape[0], order, inv)
        run.launch(remap_sources, run.n, gsrc, inv)
        self._activity(run)
        self.before_evaluation(run)

    def _activity(self, run):
        gsrc, *walls, gact = self._table(run)
        run.copy_in(self.d_counts, _ZERO3)
        if self.three:
            run.launch(ghost_activity3, run.n, *self._pos(run), gsrc, *walls, self.d_walls,
                       self.reach, gact, self.d_counts)
        else:
            run.launch(ghost_activity, run.n, *self._pos(run), gsrc, *walls, self.d_walls,
                       self.reach, gact, self.d_counts)

    # --- per step ---------------------------------------------------------------------------
    def keeps_neighbours(self, run) -> bool:
        """Whether the last build's ghosts still serve (``MirrorGhosts.keeps_neighbours``):
        the active ones are those a build would make and, where a selected term is not
        weighted by mass, no dormant one is within the support of a fluid particle."""
        if not self.built:
            return False
        d = run.arrays
        self._activity(run)
        if self.three:
            run.launch(count_qualifying3, run.n, *self._pos(run), d["kind"], self.d_walls,
                       self.reach, self.d_counts)
        else:
            run.launch(count_qualifying, run.n, *self._pos(run), d["kind"], self.d_walls,
                       self.d_corners, self.reach, self.d_counts)
        self.before_evaluation(run)
        if self.unweighted:
            nb_start, nb_idx = run.neighbours
            near = dormant_near_fluid3 if self.three else dormant_near_fluid
            run.launch(near, run.n, *self._pos(run), d["kind"], d["gsrc"], d["gact"],
                       nb_start, nb_idx, self.reach ** 2 * (1.0 + 1e-12), self.d_counts)
        n_on, n_made, near = run.copy_back(self.d_counts)
        return n_on == n_made and near == 0

    def before_evaluation(self, run):
        """Every ghost from its particle's state now (dormant ones with mass 0)."""
        if not self.built:
            return
        d = run.arrays
        gsrc, *walls, gact = self._table(run)
        refresh = refresh_ghosts3 if self.three else refresh_ghosts
        run.launch(refresh, run.n, *self._pos(run), *self._vel(run), d["rho"], d["m"],
                   gsrc, *walls, self.d_walls, self.no_slip, gact, *self.hydro)

    def after_rates(self, run):
        """``wallLaw`` (2-D): the wall's shear stress on the fluid near it."""
        if self.shear is None:
            return
        d = run.arrays
        run.launch(wall_shear, run.n, d["x"], d["y"], d["u"], d["v"], d["kind"], self.d_walls,
                   self.reach, *self.shear, d["ax"], d["ay"])

    def walls_moved(self, run, offsets, velocities):
        """The segments or faces where the walls are now (the host's few numbers, copied
        over)."""
        self.host.walls_moved(run, offsets, velocities)
        walls = self.host.pl if self.three else self.host.seg
        run.copy_in(self.d_walls, np.ascontiguousarray(walls))

    def after_step(self, run):
        """A particle that crossed a mirror wall during the step goes back."""
        d = run.arrays
        if self.three:
            run.launch(push_back3, run.n, *self._pos(run), *self._vel(run), d["kind"],
                       self.d_walls, self.reach, self.d_pushed)
        else:
            run.launch(push_back, run.n, d["x"], d["y"], d["u"], d["v"], d["kind"],
                       self.d_walls, self.reach, self.d_pushed)

    def summary(self) -> str:
        self.host.pushed_back = int(self.d_pushed.copy_to_host()[0])
        return self.host.summary()
