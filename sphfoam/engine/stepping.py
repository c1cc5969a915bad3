"""The contract between an integrator and the engine: a step as stages and particle updates.

An integrator (``family = "integrator"``) declares

* ``updates``: its per-particle updates, :class:`ParticleUpdate` objects, code for one
  particle ``a`` over named arrays, written once with ``@`` for the components (as the terms
  are, :mod:`sphfoam.engine.terms`): ``X@`` the position, ``U@`` the velocity, ``pU@`` the
  velocity positions move with (:meth:`StepContext.advect`), ``a@`` dv/dt, ``rho``,
  ``drho`` (drho/dt), ``kind``; the arrays it keeps through a step (``kept``) and the
  persistent particle fields it keeps between steps (``history``);
* ``step(run, dt_remaining)``: the order of the stages, in Python, once per step, through
  a :class:`StepContext`: ``run.evaluate()`` (the equation of state and the rates),
  ``run.evaluate_density()``, ``run.time_step()``, ``run.advect()``,
  ``run.update(name, **scalars)``, ``run.move_walls(t)``; it returns the time it advanced.

The backend compiles the updates (:func:`sphfoam.engine.emit_cpu.generate_updates` on the
CPU) and runs them where its arrays live; the simulation alone keeps the time and the step
(``Simulation.last_dt`` is what ``step`` returned).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from sphfoam.engine import terms as T
from sphfoam.engine.context import RunContext

#: the state arrays an update may name (in the vocabulary of the contract)
STATE_ARRAYS = {
    "X@": "the position",
    "U@": "the velocity",
    "pU@": "the velocity positions move with (run.advect(): U@, or XSPH's or a shifting's)",
    "a@": "dv/dt of the last evaluation",
    "rho": "the density",
    "drho": "drho/dt of the last evaluation",
    "kind": "the particle kind (FLUID, WALL, GHOST)",
}
#: where the kept arrays of an integrator are held: the state's working precision, or double
KEPT_PRECISION = ("working", "double")


@dataclass(frozen=True)
class ParticleUpdate:
    """One per-particle update: ``setup`` once per call from the ``scalars`` (e.g.
    ``hdt = 0.5 * dt``), then ``code`` for every particle ``a``."""

    name: str
    code: str
    scalars: tuple[str, ...] = ("dt",)
    setup: str = ""


def expand(code: str, dim: int = 2) -> str:
    """``code`` with its components written out: ``X@`` is the coordinate itself (x, y, z),
    then the terms' expansion (``U@`` u, v, w; any other ``@`` x, y, z)."""
    code = re.sub(r"\bX@", "@", code)
    return T.expand_components(code, _dims(dim)) if code else ""


def components(name: str, dim: int = 2) -> list[str]:
    """The array names ``name`` stands for (one per component where it holds ``@``)."""
    if "@" not in name:
        return [name]
    return expand(f"{name}[a] = 0", dim).replace("[a] = 0", "").split("\n")


def field_components(template: str, dim: int = 2) -> list[str]:
    """A persistent field's names per component: ``U{axis}_0`` -> Ux_0, Uy_0 (, Uz_0)."""
    if "{axis}" not in template:
        return [template]
    return [template.format(axis=ax) for ax, _ in _dims(dim)]


def _dims(dim: int):
    if dim not in (2, 3):
        raise ValueError(f"dimension {dim}: valid are 2, 3")
    return (("x", "u"), ("y", "v"), ("z", "w"))[:dim]


_ARRAY = re.compile(r"\b([A-Za-z_]\w*)\[a\]")


def arrays_of(update: ParticleUpdate, dim: int = 2) -> list[str]:
    """The arrays the expanded code of ``update`` indexes, in order of first use."""
    out: list[str] = []
    for name in _ARRAY.findall(expand(update.code, dim)):
        if name not in out:
            out.append(name)
    return out


class StepContext(RunContext):
    """What an integrator's ``step`` sees of the simulation it advances: the hooks' view
    (:class:`~sphfoam.engine.context.RunContext`) and the stages of a step."""

    __slots__ = ()

    @property
    def filtered(self) -> bool:
        """Whether a density-filter pass ran before this step."""
        return self._sim.filtered

    @property
    def adjust_time_step(self) -> bool:
        return self._sim.adjust_time_step

    def evaluate(self) -> None:
        """The equation of state, then the rates (dv/dt, drho/dt, and sigma where the time
        step is taken from this evaluation)."""
        self._sim.eos()
        self._sim.rates()

    def evaluate_density(self) -> None:
        """drho/dt alone (e.g. the last stage of Monaghan's 2007 scheme, T(3.96))."""
        self._sim.density_rate()

    def time_step(self) -> float:
        """The stable time step of the last evaluation, T(3.88)-(3.90) (or the fixed one)."""
        return self._sim.time_step()

    def advect(self) -> None:
        """The velocity positions move with (``pU@``), from the velocity now."""
        self._sim.advect()

    def update(self, name: str, **scalars) -> None:
        """Run the integrator's update ``name`` for every particle."""
        self._sim.run_update(name, scalars)

    def move_walls(self, t: float) -> None:
        """Walls with a prescribed motion to where they are at time ``t``."""
        self._sim.move_walls(t)


def advance(sim, dt_remaining: float) -> float:
    """One step of a backend's simulation: walls to where they are at the step's start, the
    neighbour update, the per-step pass, the density filter when due, then the integrator's
    step; the simulation keeps the time and the step (``last_dt``). Returns dt."""
    sim.move_walls(sim.time)
    sim.neighbour_update()
    sim.step_pass()
    sim.filtered = bool(sim.filter_schedule and
                        sim.filter_schedule.due_before_step(sim.step_index))
    if sim.filtered:
        sim.filter_density()
    sim._prepassed = False
    sim._evaluations = 0
    try:
        dt = sim.integrator.step(sim._stepping, dt_remaining)
    finally:
        sim._prepassed = None
        sim._evaluations = None
        sim._pU = None
    sim.last_dt = dt
    sim.time += dt
    sim.step_index += 1
    return dt
