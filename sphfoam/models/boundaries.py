"""Solid-wall representations (T §3.8-3.9)."""

from __future__ import annotations

from sphfoam.models.base import PipelineModel
from sphfoam.registry import register


class Boundary(PipelineModel):
    family = "boundary"
    prefix = "bnd_"
    #: lines run for a wall particle a inside its pair loop (rates of wall particles)
    wall_pair_code: str = ""
    #: True when wall particles take part in the continuity equation (their density evolves)
    wall_density_evolves: bool = False


@register
class StationaryGhosts(Boundary):
    """Violeau & Issa (2007): fixed rows of wall particles with evolving density.

    The wall particles never move; their density obeys the same continuity equation as the
    fluid, by symmetry of the pairs they form with fluid particles (T §3.8), their pressure
    follows from the equation of state, and fluid particles feel them through the ordinary
    pressure and viscous terms. Zero wall velocity gives a no-slip wall.
    """

    name = "stationaryGhosts"
    doc = "fixed wall-particle rows whose density evolves by pairing with fluid, T §3.8"
    wall_density_evolves = True
