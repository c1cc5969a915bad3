"""The declared forms of the selected models' run-time hooks (:mod:`sphfoam.engine.hookforms`)
on the device: what :class:`~sphfoam.engine.cuda.runtime.CudaSimulation` runs where the CPU
runs the hooks, at the same points of a step and in selection order, over device arrays.

Imported only once numba.cuda can run (:func:`sphfoam.engine.cuda.cuda_module`).
"""

from __future__ import annotations


import numpy as np
from numba import cuda

from sphfoam.engine.cuda.device import THREADS, blocks, kernel_with
from sphfoam.engine.hookforms import (AdvectionCorrection, AuxAddition, WallField,
                                      WallVelocity, device_forms)
from sphfoam.engine.state import WALL
from sphfoam.engine.stepping import components


@cuda.jit
def corrected_velocity(u, aux, row, kind, out):
    """out = u + aux[row] for the fluid particles, u for the others (``out`` may be ``u``)."""
    a = cuda.grid(1)
    if a >= u.shape[0]:
        return
    if kind[a] == 0:
        out[a] = u[a] + aux[row, a]
    else:
        out[a] = u[a]


@cuda.jit
def add_aux(target, aux, row, scale, kind, fluid_only):
    """target += scale aux[row] (every particle, or the fluid ones with ``fluid_only``)."""
    a = cuda.grid(1)
    if a >= target.shape[0]:
        return
    if not fluid_only or kind[a] == 0:
        target[a] += scale * aux[row, a]


@cuda.jit
def wall_velocity(u, u0, pid, kind):
    """u = u0[id] of every wall particle (its velocity as set up, by particle id)."""
    a = cuda.grid(1)
    if a >= u.shape[0]:
        return
    if kind[a] == WALL:
        u[a] = u0[pid[a]]


@cuda.jit
def patch_velocity(u, patch, kind, which, uu):
    """u = uu of the wall particles of wall entry ``which``."""
    a = cuda.grid(1)
    if a >= u.shape[0]:
        return
    if kind[a] == WALL and patch[a] == which:
        u[a] = uu


def _wall_field(x, y, seg, out):
    """out[a] = wall_function(x[a], y[a], seg), ``wall_function`` bound by
    :func:`wall_field_kernel`."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    out[a] = wall_function(x[a], y[a], seg)  # noqa: F821  (bound per function)


def wall_field_kernel(function):
    """The kernel out[a] = ``function(x[a], y[a], seg)`` (``function`` a jitted scalar
    function, compiled as a device function: the host loop's arithmetic), bound as a global
    of its own copy of :func:`_wall_field`."""
    return kernel_with(_wall_field, "wall_field", "wall_function", function,
                       (__name__, "wall_field_kernel"))


class DeviceHooks:
    """The selected models' declared hook forms, run over the device arrays of ``sim``."""

    def __init__(self, sim):
        self.sim = sim
        dim = sim.selection.dim
        forms = [f for m in sim.selection.models() for f in device_forms(m)]
        aux = list(sim.module.AUX)
        #: (aux rows) per advection correction, in selection order
        self.advection = [[aux.index(k) for k in components(f.aux, dim)]
                          for f in forms if isinstance(f, AdvectionCorrection)]
        #: hook -> [(state arrays, aux rows, fluid only)]
        self.additions = {}
        for f in forms:
            if isinstance(f, AuxAddition):
                self.additions.setdefault(f.hook, []).append(
                    (components(f.target, dim), [aux.index(k) for k in components(f.aux, dim)],
                     f.fluid_only))
        self.fields = [f for f in forms if isinstance(f, WallField)]
        #: the walls' velocities as set up by particle id, per component (WallVelocity)
        self.wall_u0 = None
        if any(isinstance(f, WallVelocity) for f in forms):
            st = sim._host
            wall = st.kind == WALL
            n_id = int(st.id[wall].max()) + 1 if wall.any() else 0
            self.wall_u0 = []
            for k in components("U@", dim):
                u0 = np.zeros(max(n_id, 1))
                u0[st.id[wall]] = getattr(st, k)[wall]
                self.wall_u0.append(sim._to(u0, np.float64))
        self._wall_velocities = {}
        self._pU = None
        self._seg = []
        if self.fields:
            for f in self.fields:
                if f.check is not None:
                    f.check(sim.segments)
            self.walls_moved(None, None)
            self.before_neighbours()

    def _launch(self, kernel, *args):
        kernel[blocks(self.sim.n), THREADS](*args)

    def advection_velocity(self, U):
        """The velocity positions move with: ``U`` plus each correction in turn (fluid)."""
        if not self.advection:
            return U
        sim = self.sim
        if self._pU is None or self._pU[0].shape[0] != sim.n:
            self._pU = tuple(cuda.device_array(sim.n, dtype=sim.dtype) for _ in U)
        kind = sim.d["kind"]
        for rows in self.advection:
            for u, row, out in zip(U, rows, self._pU):
                self._launch(corrected_velocity, u, sim.d_aux, row, kind, out)
            U = self._pU
        return U

    def run(self, hook: str, scale: float = 1.0):
        """The additions declared for ``hook`` (``after_step``: ``scale`` the step taken);
        after every evaluation and step, the walls' prescribed velocity (WallVelocity)."""
        sim = self.sim
        if hook in ("after_rates", "after_density_rate", "after_step"):
            self._put_back_wall_velocity()
        for targets, rows, fluid_only in self.additions.get(hook, ()):
            for t, row in zip(targets, rows):
                self._launch(add_aux, sim.d[t], sim.d_aux, row, float(scale), sim.d["kind"],
                             fluid_only)

    def before_evaluation(self):
        """What the models do before every evaluation (and when walls move)."""
        self._put_back_wall_velocity()

    def _put_back_wall_velocity(self):
        """The prescribed velocity back on the wall particles (WallVelocity): as set up,
        or their wall entry's where walls have moved."""
        if self.wall_u0 is None:
            return
        sim = self.sim
        dim = sim.selection.dim
        kind = sim.d["kind"]
        for k, u0 in zip(components("U@", dim), self.wall_u0):
            self._launch(wall_velocity, sim.d[k], u0, sim.d["id"], kind)
        if self._wall_velocities and ("patch" in sim.d_extra or
                                      "patch" in sim.module.FIELDS):
            patch = sim._extra("patch")
            for which, vel in self._wall_velocities.items():
                for k, uu in zip(components("U@", dim), vel):
                    self._launch(patch_velocity, sim.d[k], patch, kind, float(which),
                                 float(uu))

    def walls_moved(self, offsets, velocities):
        """The walls' segments where the wall entries' motions put them; their
        velocities."""
        self._wall_velocities = dict(velocities or {})
        self._seg = [self.sim._to(f.segments(self.sim.segments, offsets, velocities),
                                  np.float64) for f in self.fields]

    def before_neighbours(self):
        """Every declared wall field of every particle, before the list is built."""
        sim = self.sim
        for f, seg in zip(self.fields, self._seg):
            self._launch(wall_field_kernel(f.function), sim.d["x"], sim.d["y"], seg,
                         sim._extra(f.field))
            sim._dirty = True
