"""What the device forms of the models' run-time hooks (:mod:`sphfoam.engine.cuda.forms`)
see of a running :class:`~sphfoam.engine.cuda.runtime.CudaSimulation`: the hooks' view
(:class:`~sphfoam.engine.context.RunContext`: coefficients, cell grid, walls, time, the
neighbour list) with the particles' arrays where they live, on the device, and the means to
launch kernels over them, copy scalars back and append particles.
"""

from __future__ import annotations

from sphfoam.engine.context import RunContext


class DeviceContext(RunContext):
    """The public view of one running CUDA simulation that the device forms receive."""

    __slots__ = ()

    @property
    def cuda(self):
        """``numba.cuda`` (a device, or the simulator)."""
        return self._sim.cuda

    @property
    def arrays(self) -> dict:
        """The particles' device arrays by name (``x``, ``y``, ``u``, ``v``, ``rho``, ``m``,
        ``kind``, ``id``, ``p``, ``c``, ``ax``, ``ay``, ``drho``, ``sigma``). An array a
        device form puts here (one element per particle) is carried by the sort, grown by
        :meth:`append` and cut with the particles that leave."""
        return self._sim.d

    @property
    def n(self) -> int:
        """How many particles (and ghosts) the arrays hold."""
        return self._sim.n

    @property
    def cell_start(self):
        """The first particle of each cell (device array, ``cells.ncells + 1``) of the sort
        just made: valid from ``after_sort`` to the next build."""
        return self._sim.cell_start

    def field(self, name: str):
        """The device array of the per-particle field ``name`` (a set-up field such as
        ``ghostX``), wherever the runtime keeps it."""
        return self._sim._extra(name)

    def launch(self, kernel, n: int, *args) -> None:
        """``kernel`` over ``n`` threads (one per particle)."""
        self._sim._launch(kernel, n, *args)

    def copy_back(self, a):
        """A (small) device array copied to the host, counted in the traffic."""
        return self._sim._get(a)

    def copy_in(self, dst, host) -> None:
        """The host array ``host`` copied into the device array ``dst``, counted (and timed
        with the runtime's copies)."""
        self._sim._put(dst, host)

    def append(self, k: int) -> int:
        """``k`` particles more at the end of every array (zeros); the first's index."""
        return self._sim.append(k)
