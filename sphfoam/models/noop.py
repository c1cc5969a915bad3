"""The ``none`` entry of the optional families (turbulence, densityFilter,
velocityCorrection, kernelCorrection, particleShifting).

Selecting ``none`` contributes no term to the generated pipeline: it costs nothing.
"""

from __future__ import annotations

from sphfoam.models.base import PipelineModel
from sphfoam.registry import register


def _none(family_name: str, what: str):
    cls = type(f"No_{family_name}", (PipelineModel,), {
        "family": family_name, "name": "none", "doc": f"no {what} (adds nothing to the pipeline)",
        "__doc__": f"No {what}."})
    return register(cls)


NoTurbulence = _none("turbulence", "turbulence model: the laminar equations")
NoDensityFilter = _none("densityFilter", "density filter")
NoVelocityCorrection = _none("velocityCorrection", "velocity correction")
NoKernelCorrection = _none("kernelCorrection", "kernel correction")
NoParticleShifting = _none("particleShifting", "particle shifting")
