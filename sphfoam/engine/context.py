"""What a model's run-time hooks see of a running simulation.

The hooks of ``sphfoam.models.base`` (``attach``, ``before_neighbours``, ``add_particles``,
``after_rates``, ``advection_velocity``, ...) receive a :class:`RunContext`, never the
:class:`~sphfoam.engine.simulation.Simulation`: the particles' named arrays, the auxiliary
fields by name, the neighbour list, the time, the coefficients by name, the kernel, the cell
grid and the walls. A backend that keeps the arrays elsewhere (a GPU) gives its hooks the same context,
with the arrays where the hook can read them.
"""

from __future__ import annotations


class RunContext:
    """The public view of one running simulation that the models' hooks receive."""

    __slots__ = ("_sim",)

    def __init__(self, sim):
        self._sim = sim

    @property
    def state(self):
        """The particles' named arrays (``x``, ``y``, ``u``, ``v``, ``rho``, ``p``, ``m``,
        ``kind``, ``ax``, ``ay``, ``drho``, the set-up's fields in ``extra``)."""
        return self._sim.state

    def aux(self, name: str):
        """The auxiliary field ``name`` of every particle (what the terms write as
        ``aux.<name>``), as the last evaluation left it."""
        sim = self._sim
        return sim.aux[sim.pipeline.aux_index(name)]

    def coefficients(self) -> dict[str, float]:
        """Every coefficient of the pipeline by name (``h``, ``gx``, ``eos_B``, ...)."""
        pipe = self._sim.pipeline
        return dict(zip(pipe.module.PARAMS, pipe.prm.tolist()))

    @property
    def neighbours(self):
        """(nb_start, nb_idx): the neighbours of particle a are
        ``nb_idx[nb_start[a]:nb_start[a + 1]]`` (the list of this step)."""
        return self._sim._nb

    @property
    def time(self) -> float:
        return self._sim.time

    @property
    def step_index(self) -> int:
        return self._sim.step_index

    @property
    def last_dt(self) -> float:
        """The time step last taken (in ``after_step``: the step just taken)."""
        return self._sim.last_dt

    @property
    def h(self) -> float:
        """The smoothing length."""
        return self._sim.h

    @property
    def support_radius(self) -> float:
        return self._sim.pipeline.support_radius

    @property
    def kernel(self):
        """The selected kernel model (its jitted ``f_jit``, ``support`` in h, ``alpha(dim)``)."""
        return self._sim.pipeline.selection.kernel

    @property
    def cells(self):
        """The cell grid (``bin``, ``cell_size``) the neighbour list is built on."""
        return self._sim.cells

    @property
    def segments(self):
        """The walls' segments of ``system/particleDict``."""
        return self._sim.segments

    @property
    def planes(self):
        """The plane faces of a 3-D case's box tanks (``sphfoam.case.geometry.Plane``)."""
        return getattr(self._sim, "planes", ())

    @property
    def selection(self):
        """The models the case selects (``sphfoam.engine.plan.Selection``)."""
        return self._sim.pipeline.selection
