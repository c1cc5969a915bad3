"""The device form of the ``mDBC`` boundary (:class:`sphfoam.models.mdbc.ModifiedDynamic`,
``device_form``): the wall particles' density from the fluid at their ghost nodes (English et
al. 2022, eq. 10) and, with free slip, the velocity the pair passes see, on the CUDA
backend's device arrays (:mod:`sphfoam.engine.cuda.forms`; imported only there, once
numba.cuda can run).

The same sequence as the model's hooks on the CPU, with the same per-particle arithmetic:
the kernels call the CPU's scalar functions (:func:`sphfoam.models.mdbc.node_list`,
:func:`~sphfoam.models.mdbc.fit_wall`) as device functions, so each equation is written once.

* After each sort by cell (``after_sort``): every wall particle that can meet the fluid
  (less deep behind the wall than the support less dx/4) counts the fluid particles within
  a cell side of its ghost node, in the cell walk's order; an exclusive scan gives each its
  first slot and a second pass writes the lists. The lists are per particle, indexed by the
  order just sorted, and kept until the next build (the cell side holds the list's skin).
* Before each evaluation: one thread per wall particle fits the node and sets its density,
  pressure and sound speed; with free slip it also keeps the particle's prescribed velocity
  and the velocity for the passes. The fit reads the fluid only and writes the walls only,
  so it is made again at every evaluation (the CPU skips an unchanged state).
* Free slip: the passes' velocity on the wall particles before the pair passes
  (``before_passes``), the prescribed one back after them (``after_rates``,
  ``after_density_rate``).

The configuration (the kernel, the fit's determinant threshold, Tait's coefficients,
gravity, dx) is the model's own ``attach``, run on a copy of it.
"""

from __future__ import annotations

import copy

import numpy as np
from numba import cuda, float64

from sphfoam.engine.cuda.device import device_function, exclusive_scan, kernel_with
from sphfoam.engine.state import WALL
from sphfoam.models import mdbc

_node_list = device_function(mdbc.node_list)
_fit_wall = device_function(mdbc.fit_wall)


@cuda.jit
def count_lists(x, y, z, three, kind, ox, oy, oz, deepest2, cell_start, x0, y0, z0,
                inv_cell, ncx, ncy, ncz, lx, ly, lz, reach2, fitted, count, none):
    """How many fluid particles are within sqrt(reach2) of each fitted wall particle's node
    (``fitted[a]``: a wall particle less deep than sqrt(deepest2) / 2; 0 for the others)."""
    a = cuda.grid(1)
    if a >= x.shape[0]:
        return
    k = 0
    fitted[a] = 0
    if kind[a] == WALL:
        goz = oz[a] if three else 0.0
        if ox[a] * ox[a] + oy[a] * oy[a] + goz * goz < deepest2:
            fitted[a] = 1
            pz = z[a] + goz if three else 0.0
            k = _node_list(x[a] + ox[a], y[a] + oy[a], pz, three, x, y, kind, z,
                           cell_start, x0, y0, z0, inv_cell, ncx, ncy, ncz, lx, ly, lz,
                           reach2, False, none, 0)
    count[a] = k


@cuda.jit
def fill_lists(x, y, z, three, kind, ox, oy, oz, cell_start, x0, y0, z0, inv_cell, ncx,
               ncy, ncz, lx, ly, lz, reach2, fitted, starts, idx):
    """The fitted wall particle a's list into idx[starts[a]:starts[a + 1]]."""
    a = cuda.grid(1)
    if a >= x.shape[0] or fitted[a] == 0:
        return
    goz = oz[a] if three else 0.0
    pz = z[a] + goz if three else 0.0
    _node_list(x[a] + ox[a], y[a] + oy[a], pz, three, x, y, kind, z, cell_start, x0, y0,
               z0, inv_cell, ncx, ncy, ncz, lx, ly, lz, reach2, True, idx, starts[a])


def _fit(x, y, z, three, m, rho, p, c, u, v, w, ox, oy, oz, corner, fitted, starts, idx,
         lx, ly, lz, h, support, det_min, rho0, B, gamma, c0, gx, gy, gz, slip, U0, uw):
    """Each fitted wall particle's density, pressure and sound speed from its node
    (:func:`sphfoam.models.mdbc.fit_wall`, ``kernel_f`` bound by :func:`fit_kernel`); with
    ``slip`` its prescribed velocity into U0 and the passes' into uw (dim x n)."""
    a = cuda.grid(1)
    if a >= x.shape[0] or fitted[a] == 0:
        return
    wk = cuda.local.array((4, 8), float64)
    goz = oz[a] if three else 0.0
    cor = U0x = U0y = U0z = 0.0
    if slip:
        cor = corner[a]
        U0x = u[a]
        U0y = v[a]
        if three:
            U0z = w[a]
    r, pw, cw, ux, uy, uz = _fit_wall(
        a, ox[a], oy[a], goz, starts[a], starts[a + 1], idx, three, x, y, z, m, rho, lx, ly,
        lz, h, support, kernel_f, det_min, rho0, B, gamma, c0, gx, gy, gz,  # noqa: F821
        wk, slip, u, v, w, cor, U0x, U0y, U0z)
    rho[a] = r
    p[a] = pw
    c[a] = cw
    if slip:
        U0[0, a] = U0x
        U0[1, a] = U0y
        uw[0, a] = ux
        uw[1, a] = uy
        if three:
            U0[2, a] = U0z
            uw[2, a] = uz


def fit_kernel(kernel_f):
    """The fit's kernel with the smoothing kernel's ``kernel_f`` (a jitted f(q)) bound as a
    device function: a copy of :func:`_fit` per kernel."""
    return kernel_with(_fit, "fit_walls", "kernel_f", kernel_f, (__name__, "fit_kernel"))


@cuda.jit
def set_velocity(u, src, row, fitted):
    """u = src[row] on the fitted wall particles."""
    a = cuda.grid(1)
    if a >= u.shape[0] or fitted[a] == 0:
        return
    u[a] = src[row, a]


class ModifiedDynamicDevice:
    """``mDBC`` on the device (see the module docstring)."""

    def __init__(self, model):
        self.model = model
        self.slip = not model.coeffs.noSlip
        self.lists = None

    def attach(self, run):
        host = copy.copy(self.model)
        host.attach(run)
        self.host = host
        self.three = run.selection.dim == 3
        self.fit = fit_kernel(host._kernel_f)
        self._scratch = None
        self._velocities = None
        self._none = run.cuda.device_array(0, dtype=np.int64)
        #: no slip: the velocities' (unread) stand-ins, of the type the kernel compiles
        #: for (a device compiles the free-slip branch too)
        self._no_velocities = run.cuda.device_array((3, 0), dtype=np.float64)

    def _fields(self, run):
        f = run.field
        ox, oy = f("ghostX"), f("ghostY")
        return ox, oy, f("ghostZ") if self.three else ox

    def after_sort(self, run, order):
        """The ghost nodes' lists of fluid particles, over the cell grid just sorted."""
        cu, cl, d, n = run.cuda, run.cells, run.arrays, run.n
        ox, oy, oz = self._fields(run)
        z = d["z"] if self.three else d["x"]
        deepest = 2.0 * (run.support_radius - 0.25 * self.host._dx)
        grid = (run.cell_start, cl.x0, cl.y0, cl.z0, 1.0 / cl.cell_size, cl.ncx, cl.ncy,
                cl.ncz if self.three else 1, cl.lx, cl.ly, cl.lz if self.three else 0.0,
                cl.cell_size ** 2)
        fitted = cu.device_array(n, dtype=np.uint8)
        count = cu.device_array(n, dtype=np.int64)
        run.launch(count_lists, n, d["x"], d["y"], z, self.three, d["kind"], ox, oy, oz,
                   deepest * deepest, *grid, fitted, count, self._none)
        starts = cu.device_array(n + 1, dtype=np.int64)
        self._scratch = exclusive_scan(count, starts, self._scratch)
        total = int(run.copy_back(starts[n:])[0])
        idx = cu.device_array(max(total, 1), dtype=np.int64)
        run.launch(fill_lists, n, d["x"], d["y"], z, self.three, d["kind"], ox, oy, oz,
                   *grid, fitted, starts, idx)
        self.lists = (fitted, starts, idx)
        if self.slip:
            dim = 3 if self.three else 2
            self._velocities = (cu.device_array((dim, n), dtype=np.float64),
                                cu.device_array((dim, n), dtype=np.float64))

    def before_evaluation(self, run):
        """The wall particles' density, pressure and sound speed from their ghost nodes
        (free slip: and their prescribed velocity and the passes')."""
        if self.lists is None:
            return
        d = run.arrays
        fitted, starts, idx = self.lists
        ox, oy, oz = self._fields(run)
        three = self.three
        z, w = (d["z"], d["w"]) if three else (d["x"], d["x"])
        corner = run.field("corner") if self.slip else ox
        U0, uw = self._velocities if self.slip else (self._no_velocities,) * 2
        h = self.host
        rho0, B, gamma, c0 = h._eos
        run.launch(self.fit, run.n, d["x"], d["y"], z, three, d["m"], d["rho"], d["p"],
                   d["c"], d["u"], d["v"], w, ox, oy, oz, corner, fitted, starts, idx,
                   run.cells.lx, run.cells.ly, run.cells.lz if three else 0.0, run.h,
                   h._support, h._det_min, rho0, B, gamma, c0, *h._g, self.slip, U0, uw)

    # the free-slip form's hooks (None with no slip, as the model's)
    def _set_velocity(self, run, which):
        fitted = self.lists[0]
        d = run.arrays
        for row, k in enumerate(("u", "v", "w")[:3 if self.three else 2]):
            run.launch(set_velocity, run.n, d[k], self._velocities[which], row, fitted)

    @property
    def before_passes(self):
        if not self.slip:
            return None
        return lambda run: self._set_velocity(run, 1) if self.lists is not None else None

    @property
    def after_rates(self):
        if not self.slip:
            return None
        return lambda run: self._set_velocity(run, 0) if self.lists is not None else None

    after_density_rate = after_rates
