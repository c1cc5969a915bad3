"""Declared forms of the models' run-time hooks, for a backend whose arrays live elsewhere.

A model's run-time hooks (``sphfoam.models.base``) are Python over host arrays. Where a hook
is one of a few simple shapes, the model also declares it as data (``device_forms()``), and
a backend that keeps the arrays on a device (``sphfoam.engine.cuda``) runs the declaration
there instead of the hook; a hook with no declared form keeps the model off that backend
(refused by name, :func:`uncovered`). The shapes:

* :class:`AdvectionCorrection`: ``advection_velocity``, positions move with U + dU, dU an
  auxiliary field of the last pre-pass (a velocity correction or shift), fluid only;
* :class:`AuxAddition`: ``after_rates``, ``after_density_rate`` or ``after_step``, a state
  array plus an auxiliary field (times the step just taken, for ``after_step``);
* :class:`WallField`: ``attach``, ``before_neighbours``, ``walls_moved`` and
  ``keeps_neighbours``, a particle field that is a function of the position and the walls'
  segments, at every build of the neighbour list (e.g. the distance from the wall lines);
* :class:`WallVelocity`: ``attach``, ``walls_moved``, ``before_evaluation``,
  ``after_rates``, ``after_density_rate`` and ``after_step``, the wall particles'
  prescribed velocity put back (a boundary whose prepass overwrites it).

Names hold ``@`` for the components as the terms write them (``p_dU@``: p_du, p_dv
(, p_dw); ``a@``: ax, ay (, az)); :func:`sphfoam.engine.stepping.components`
writes them out for a dimension.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class AdvectionCorrection:
    """``advection_velocity``: U@ + aux ``aux`` for the fluid particles, U@ for the others;
    applied in selection order, each to the previous one's result."""

    aux: str

    hooks = ("advection_velocity",)


#: the hooks an :class:`AuxAddition` may stand for
ADDITION_HOOKS = ("after_rates", "after_density_rate", "after_step")


@dataclass(frozen=True)
class AuxAddition:
    """``hook``: ``target``[a] += aux ``aux``[a] (``after_step``: += dt aux[a], dt the step
    just taken); every particle, or with ``fluid_only`` the fluid ones. ``target`` a state
    array: ``a@`` (dv/dt), ``drho``, ``m``."""

    hook: str
    target: str
    aux: str
    fluid_only: bool = False

    def __post_init__(self):
        if self.hook not in ADDITION_HOOKS:
            raise ValueError(f"AuxAddition for hook {self.hook!r}: valid are "
                             f"{', '.join(ADDITION_HOOKS)}")

    @property
    def hooks(self) -> tuple[str, ...]:
        return (self.hook,)


@dataclass(frozen=True)
class WallField:
    """Particle field ``field`` = ``function(x_a, y_a, seg)`` for every particle, when the
    simulation is built and before every build of the neighbour list (between builds no
    particle moves more than half the list's skin, so the list is kept: ``keeps_neighbours``
    True); ``seg`` the array ``segments`` makes of the walls where the last ``walls_moved``
    put them. ``function`` a jitted scalar function
    (``sphfoam.engine.cuda.device.device_function`` compiles it for the device)."""

    field: str
    function: Callable
    #: (segments, offsets, velocities) -> ``seg``: the walls' segments moved by the wall
    #: entries' offsets (``sphfoam.models.mirror.segment_array``)
    segments: Callable
    #: called with the walls' segments when the simulation is built: raises where the model
    #: cannot work with them (e.g. none), or None
    check: Callable | None = None

    hooks = ("attach", "before_neighbours", "walls_moved", "keeps_neighbours")


@dataclass(frozen=True)
class WallVelocity:
    """The wall particles' prescribed velocity put back before and after every evaluation
    and after every step (for a boundary whose prepass overwrites it with an extrapolated
    one, so that the integrators move wall particles with the prescribed velocity): each
    wall particle's velocity as set up, recorded by particle id when the simulation is
    built, or, once walls have moved, its wall entry's velocity (``walls_moved``)."""

    hooks = ("attach", "walls_moved", "before_evaluation", "after_rates",
             "after_density_rate", "after_step")


def device_forms(model) -> tuple:
    """The declared forms of ``model``'s hooks (none where it declares none)."""
    forms = getattr(model, "device_forms", None)
    return tuple(forms()) if callable(forms) else ()


def uncovered(model, hook_names) -> list[str]:
    """The hooks of ``hook_names`` that ``model`` implements and declares no form of."""
    covered = {h for f in device_forms(model) for h in f.hooks}
    return [h for h in hook_names if model.implements(h) and h not in covered]
