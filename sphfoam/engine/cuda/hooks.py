"""The declared forms of the selected models' run-time hooks (:mod:`sphfoam.engine.hookforms`)
on the device: what :class:`~sphfoam.engine.cuda.runtime.CudaSimulation` runs where the CPU
runs the hooks, at the same points of a step and in selection order, over device arrays.

Imported only once numba.cuda can run (:func:`sphfoam.engine.cuda.cuda_module`).
"""

from __future__ import annotations

import types

import numpy as np
from numba import cuda

from sphfoam.engine.cuda.device import THREADS, blocks, device_function
from sphfoam.engine.hookforms import AdvectionCorrection, AuxAddition, WallField, device_forms
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


def _wall_field(x, y, seg, out):
    """out[a] = wall_function(x[a], y[a], seg), ``wall_function`` bound by
    :func:`wall_field_kernel`."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    out[a] = wall_function(x[a], y[a], seg)  # noqa: F821  (bound per function)


_FIELD_KERNELS: dict[int, object] = {}


def wall_field_kernel(function):
    """The kernel out[a] = ``function(x[a], y[a], seg)`` (``function`` a jitted scalar
    function, compiled as a device function: the host loop's arithmetic), bound as a global
    of its own copy of :func:`_wall_field` (as ``device_function`` binds helpers)."""
    key = id(function)
    if key not in _FIELD_KERNELS:
        glb = dict(_wall_field.__globals__, wall_function=device_function(function))
        _FIELD_KERNELS[key] = cuda.jit(types.FunctionType(_wall_field.__code__, glb,
                                                          "wall_field"))
    return _FIELD_KERNELS[key]


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
        self._pU = None
        self._offsets = None
        self._seg = None
        if self.fields:
            from sphfoam.case.errors import CaseError

            for f in self.fields:
                if f.needs_walls and not sim.segments:
                    raise CaseError.single("system/particleDict", "walls", f.needs_walls)
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
        """The additions declared for ``hook`` (``after_step``: ``scale`` the step taken)."""
        sim = self.sim
        for targets, rows, fluid_only in self.additions.get(hook, ()):
            for t, row in zip(targets, rows):
                self._launch(add_aux, sim.d[t], sim.d_aux, row, float(scale), sim.d["kind"],
                             fluid_only)

    def walls_moved(self, offsets, velocities):
        """The walls' segments where the wall entries' motions put them."""
        if self.fields:
            from sphfoam.models.mirror import segment_array

            seg = segment_array(self.sim.segments, offsets, velocities)
            self._seg = self.sim._to(seg.reshape(-1, 9), np.float64)

    def before_neighbours(self):
        """Every declared wall field of every particle, before the list is built."""
        sim = self.sim
        for f in self.fields:
            self._launch(wall_field_kernel(f.function), sim.d["x"], sim.d["y"], self._seg,
                         sim._extra(f.field))
            sim._dirty = True
