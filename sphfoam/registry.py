"""Run-time selectable models, the OpenFOAM way: ``family { type name; coeffs... }``.

Every concrete model lives in ``sphfoam/models/<family module>.py`` (function objects in
``sphfoam/sampling/``, study metrics in ``sphfoam/study/``) and registers itself with
:func:`register`.  The engine only ever asks the registry for a family and a name; it never
imports a concrete model.  Each entry carries

* ``name``   the word a user writes after ``type``,
* ``doc``    a one-line description citing the equation it implements (T = thesis, P = paper),
* ``Coeffs`` a pydantic model validating the coefficients written beside ``type``.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict

#: Families a case can select from, with what each is for (``sphfoam models`` prints these).
FAMILIES: dict[str, str] = {
    "kernel": "smoothing kernel W(q) and its gradient",
    "equationOfState": "pressure from density",
    "continuity": "SPH form of the continuity equation (rate of change of density)",
    "momentum": "SPH form of the pressure-gradient term of the momentum equation",
    "viscosity": "viscous term of the momentum equation",
    "turbulence": "sub-particle-scale turbulence closure",
    "boundary": "solid-wall representation",
    "densityFilter": "periodic smoothing/re-initialisation of the density field",
    "velocityCorrection": "correction of the advection velocity (e.g. XSPH)",
    "kernelCorrection": "corrected kernels and gradients (e.g. C-SPH)",
    "particleShifting": "particle shifting: positions move with v + delta_u towards a uniform "
                        "distribution (beside or instead of a velocityCorrection)",
    "integrator": "time-marching scheme",
    "motion": "prescribed motion of a wall (particleDict walls.<name>.motion)",
    "waveMaker": "paddle trajectory X(t) of a wave maker (pistonPaddle waveMaker)",
    "waveTheory": "solitary-wave theory: surface, velocity, pressure and celerity",
    "functionObject": "in-run and post-processing sampling",
    "metric": "error metric of a finished run against its reference (sphfoam study)",
}


class Coeffs(BaseModel):
    """Base of every model's coefficient schema: unknown keys are errors, and so are
    non-finite numbers (inf, nan, 1e400)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Model:
    """Base class of a registered model. Subclasses set the class attributes below."""

    family: ClassVar[str]
    name: ClassVar[str]
    doc: ClassVar[str]
    #: former names a case may still write (the registered ``name`` is the one to use)
    aliases: ClassVar[tuple[str, ...]] = ()
    Coeffs: ClassVar[type[BaseModel]] = Coeffs

    def __init__(self, coeffs: BaseModel | None = None):
        self.coeffs = coeffs if coeffs is not None else self.Coeffs()

    def __repr__(self) -> str:
        return f"{self.family}:{self.name}({self.coeffs!r})"


_REGISTRY: dict[str, dict[str, type[Model]]] = {f: {} for f in FAMILIES}
#: former names still accepted: family -> {old word: registered name}
_ALIASES: dict[str, dict[str, str]] = {f: {} for f in FAMILIES}

#: the modules that register the built-in models, imported by the registry itself on first use
MODEL_MODULES = (
    "sphfoam.models.kernels", "sphfoam.models.eos", "sphfoam.models.equations",
    "sphfoam.models.viscosity", "sphfoam.models.turbulence", "sphfoam.models.boundaries",
    "sphfoam.models.filters", "sphfoam.models.corrections", "sphfoam.models.noop",
    "sphfoam.models.riemann", "sphfoam.models.adami", "sphfoam.models.mdbc",
    "sphfoam.models.integrators", "sphfoam.models.motion", "sphfoam.models.wavemakers",
    "sphfoam.models.goring", "sphfoam.models.wavetheory", "sphfoam.study.metrics",
    "sphfoam.sampling.damBreak", "sphfoam.sampling.profiles", "sphfoam.sampling.waves",
    "sphfoam.models.diffusion", "sphfoam.models.shifting", "sphfoam.sampling.beach",
    "sphfoam.study.beach_metrics", "sphfoam.sampling.loads", "sphfoam.sampling.slices",
    "sphfoam.study.measured_metrics",
)


def register(cls: type[Model]) -> type[Model]:
    """Class decorator adding a model to its family (and its ``aliases``, former names)."""
    if cls.family not in _REGISTRY:
        raise KeyError(f"unknown model family {cls.family!r}")
    if cls.name in _REGISTRY[cls.family] or cls.name in _ALIASES[cls.family]:
        raise KeyError(f"{cls.family} {cls.name!r} registered twice")
    if not getattr(cls, "doc", ""):
        raise ValueError(f"{cls.family} {cls.name!r} needs a one-line doc")
    _REGISTRY[cls.family][cls.name] = cls
    for old in getattr(cls, "aliases", ()):
        _ALIASES[cls.family][old] = cls.name
    return cls


def unregister(cls: type[Model]) -> None:
    """Remove a model registered with :func:`register` (models defined outside the package,
    e.g. in a test, that must not outlive it)."""
    if _REGISTRY[cls.family].get(cls.name) is cls:
        del _REGISTRY[cls.family][cls.name]
    for old in getattr(cls, "aliases", ()):
        _ALIASES[cls.family].pop(old, None)


@dataclass
class UnknownModel(LookupError):
    family: str
    name: str
    choices: list[str]

    @property
    def suggestion(self) -> str | None:
        close = difflib.get_close_matches(self.name, self.choices, n=1, cutoff=0.5)
        return close[0] if close else None

    def __str__(self) -> str:
        msg = f"{self.name!r} is not a registered {self.family}"
        if self.suggestion:
            msg += f"; did you mean {self.suggestion!r}?"
        return msg + f" registered: {', '.join(self.choices) or '(none)'}"


_loaded = False


def _load_models() -> None:
    """Import the modules of :data:`MODEL_MODULES` (each registers its models)."""
    global _loaded
    if _loaded:
        return
    import importlib

    for mod in MODEL_MODULES:
        importlib.import_module(mod)
    _loaded = True


def _ordered(family: str) -> dict[str, type[Model]]:
    """The family's models in a fixed order, whatever order their modules were imported
    in: by module (the order of :data:`MODEL_MODULES`; others after), then by their place
    in the module's source."""
    import inspect

    def key(item):
        cls = item[1]
        mod = cls.__module__
        rank = MODEL_MODULES.index(mod) if mod in MODEL_MODULES else len(MODEL_MODULES)
        try:
            line = inspect.getsourcelines(cls)[1]
        except (OSError, TypeError):
            line = 0
        return rank, mod, line

    return dict(sorted(_REGISTRY[family].items(), key=key))


def names(family: str) -> list[str]:
    _load_models()
    return list(_ordered(family))


def get(family: str, name: str) -> type[Model]:
    _load_models()
    try:
        return _REGISTRY[family][_ALIASES[family].get(name, name)]
    except KeyError:
        raise UnknownModel(family, name, list(_REGISTRY[family])) from None


def families() -> dict[str, dict[str, type[Model]]]:
    _load_models()
    return {f: _ordered(f) for f in _REGISTRY}


def build(family: str, spec: dict[str, Any], context: dict | None = None) -> Model:
    """Instantiate ``spec['type']`` of ``family`` with the remaining keys as coefficients
    (validated with ``context``, e.g. ``{"dim": 3}``: the case's dimension).

    Raises :class:`UnknownModel` or pydantic's ``ValidationError`` (the case layer turns both
    into one-screen messages naming the file and key path).
    """
    spec = dict(spec)
    cls = get(family, str(spec.pop("type")))
    return cls(cls.Coeffs.model_validate(spec, context=context))
