"""A case directory: reading, validating and assembling everything a run needs.

Layout (OpenFOAM conventions)::

    constant/transportProperties   rho0, nu
    constant/g                     gravity vector
    constant/sphProperties         kernel, equationOfState, continuity, momentum, viscosity,
                                   boundary, turbulence, densityFilter, velocityCorrection,
                                   kernelCorrection, particleShifting
                                   -- each ``{ type name; coeffs }``
    system/controlDict             time control, writing, function objects
    system/sphSchemes              integrator, time-step control, neighbour search
    system/particleDict            spacing, fluid blocks, walls, domain (for ``sphfoam setup``)
    0/ 0.5/ 1/ ...                 time directories (particles in lagrangian/particles/)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from pydantic import ValidationError

import sphfoam.registry as registry
from sphfoam.case import foamdict
from sphfoam.case.errors import CaseError, Problem, did_you_mean, from_validation
from sphfoam.case.schemas import (SPH_FAMILIES, ControlDict, Gravity, MeshRegion, MeshWalls,
                                  ParticleDict, SphSchemes, TransportProperties,
                                  WaveProperties)
from sphfoam.context import CaseContext

FILES = {
    "controlDict": ("system/controlDict", ControlDict),
    "sphSchemes": ("system/sphSchemes", SphSchemes),
    "particleDict": ("system/particleDict", ParticleDict),
    "transportProperties": ("constant/transportProperties", TransportProperties),
    "g": ("constant/g", Gravity),
    "waveProperties": ("constant/waveProperties", WaveProperties),
}
SPH_PROPERTIES = "constant/sphProperties"


def _strip_header(d: dict) -> dict:
    return {k: v for k, v in d.items() if k != "FoamFile"}


@dataclass
class Models:
    """The models a case selects, instantiated and validated."""

    sph: dict[str, registry.Model]
    integrator: registry.Model
    functions: dict[str, registry.Model]
    #: prescribed wall motions by wall-entry index (system/particleDict walls.<name>.motion)
    motions: dict[int, registry.Model]


class Case:
    """A case directory. Properties read and validate lazily; :meth:`validate` reads all."""

    def __init__(self, path):
        self.path = Path(path).resolve()
        self.name = self.path.name

    # --- raw dictionaries ----------------------------------------------------------------
    def read_dict(self, rel: str, required: bool = True) -> dict:
        f = self.path / rel
        if not f.exists():  # a directory, FIFO or device of that name is refused by read
            if not required:
                return {}
            raise CaseError.single(rel, "", f"file not found in case {self.path}")
        try:
            return _strip_header(foamdict.read(f, filename=rel, case_dir=self.path))
        except foamdict.FoamDictError as e:
            raise CaseError([Problem(rel, "", f"syntax error: {e}")]) from None
        except UnicodeDecodeError as e:
            raise CaseError([Problem(rel, "", f"not a text dictionary: byte {e.object[e.start]:#04x} "
                                     f"at offset {e.start} is not UTF-8")]) from None

    def _validated(self, key: str):
        rel, schema = FILES[key]
        raw = self.read_dict(rel)
        try:
            return schema.model_validate(raw, context={"dim": self.dimension})
        except ValidationError as e:
            raise from_validation(e, rel, schema) from None

    @cached_property
    def dimension(self) -> int:
        """2 or 3: ``system/particleDict``'s ``dimension`` (the one switch of a 3-D case;
        every point and vector of the case then has as many components). A missing or
        unreadable particleDict reads as 2 here and is reported when it is validated."""
        try:
            raw = self.read_dict(FILES["particleDict"][0], required=False)
        except CaseError:
            return 2
        d = raw.get("dimension", 2)
        return d if d in (2, 3) and not isinstance(d, bool) else 2

    @cached_property
    def control(self) -> ControlDict:
        return self._validated("controlDict")

    @cached_property
    def schemes(self) -> SphSchemes:
        rel = FILES["sphSchemes"][0]
        if not (self.path / rel).is_file():
            return SphSchemes()
        return self._validated("sphSchemes")

    @cached_property
    def particles(self) -> ParticleDict:
        pd = self._validated("particleDict")
        problems = []
        entries = [("fluid", n, r) for n, r in pd.fluid.items()] + \
            [("walls", n, w) for n, w in pd.walls.items()]
        for group, name, entry in entries:       # read the file of a `type mesh` entry
            if isinstance(entry, (MeshWalls, MeshRegion)):
                from sphfoam.case.meshwalls import MeshWallError

                try:
                    entry.load(self.path)
                except MeshWallError as e:
                    problems.append(Problem(FILES["particleDict"][0], f"{group}.{name}.file",
                                            str(e)))
        if problems:
            raise CaseError(problems)
        return pd

    @cached_property
    def transport(self) -> TransportProperties:
        return self._validated("transportProperties")

    @cached_property
    def gravity(self) -> tuple[float, ...]:
        return self._validated("g").value

    @cached_property
    def waves(self) -> dict:
        """Initial solitary waves of ``constant/waveProperties`` (optional): name ->
        (InitialWave, theory model)."""
        rel = FILES["waveProperties"][0]
        if not (self.path / rel).is_file():
            return {}
        props = self._validated("waveProperties")
        out, problems = {}, []
        for name, w in props.waves.items():
            mdl = build_model("waveTheory", {"type": w.theory}, rel, f"waves.{name}.theory",
                              problems)
            if mdl is not None:
                out[name] = (w, mdl)
        if problems:
            # the theory key is a word, not a sub-dictionary: report it as such
            raise CaseError([Problem(p.file, p.key.removesuffix(".type"), p.message)
                             for p in problems])
        return out

    # --- models --------------------------------------------------------------------------
    @cached_property
    def models(self) -> Models:
        raw = self.read_dict(SPH_PROPERTIES)
        problems: list[Problem] = []
        unknown = [k for k in raw if k not in SPH_FAMILIES]
        for k in unknown:
            problems.append(Problem(SPH_PROPERTIES, k, f"unknown key '{k}'"
                                    f"{did_you_mean(k, SPH_FAMILIES)} valid keys: "
                                    f"{', '.join(SPH_FAMILIES)}"))
        sph = {}
        for family, default in SPH_FAMILIES.items():
            spec = raw.get(family, None if default is None else {"type": default})
            if spec is None:
                problems.append(Problem(SPH_PROPERTIES, family,
                                        f"required; choose a type from: "
                                        f"{', '.join(registry.names(family))}"))
                continue
            mdl = build_model(family, spec, SPH_PROPERTIES, family, problems)
            if mdl is not None:
                sph[family] = mdl
        if self.dimension == 3:       # a model without a 3-D form is refused by name
            from sphfoam.engine.plan import missing_dimension

            for family, mdl in sph.items():
                why = missing_dimension(mdl, 3)
                if why is not None:
                    problems.append(Problem(SPH_PROPERTIES, f"{family}.type", why))
        # a model that works only with some choices of another family says so
        for family, mdl in sph.items():
            check = getattr(mdl, "selection_problems", None)
            for key, message in (check(sph) if check is not None else ()):
                problems.append(Problem(SPH_PROPERTIES, f"{family}.{key}", message))
        integ = build_model("integrator", self.schemes.integrator.model_dump(),
                            FILES["sphSchemes"][0], "integrator", problems)
        functions = {}
        for name, spec in self.control.functions.items():
            fo = build_model("functionObject", spec, FILES["controlDict"][0],
                             f"functions.{name}", problems, {"dim": self.dimension})
            if fo is not None and self.dimension not in getattr(fo, "dims", (2,)):
                problems.append(Problem(FILES["controlDict"][0], f"functions.{name}.type",
                                        f"functionObject {fo.name!r} has no "
                                        f"{self.dimension}-D form"))
            elif fo is not None:
                fo.object_name = name
                functions[name] = fo
        motions = {}
        pd_file = FILES["particleDict"][0]
        try:
            walls = self.particles.walls
        except CaseError as e:
            problems.extend(e.problems)
            walls = {}
        for i, (name, wall) in enumerate(walls.items()):
            if wall.motion is None:
                continue
            mot = build_model("motion", wall.motion, pd_file, f"walls.{name}.motion", problems)
            if mot is None:
                continue
            if self.dimension not in getattr(mot, "dims", (2,)):
                problems.append(Problem(pd_file, f"walls.{name}.motion.type",
                                        f"motion {mot.name!r} has no {self.dimension}-D form"))
                continue
            try:
                mot.resolve(self.path)
            except (OSError, ValueError) as e:
                problems.append(Problem(pd_file, f"walls.{name}.motion.file", str(e)))
                continue
            n = mot.components
            if n is not None and n != self.dimension:
                problems.append(Problem(
                    pd_file, f"walls.{name}.motion.{mot.components_key}",
                    f"motion {mot.name!r} gives {n} components; a {self.dimension}-D case "
                    f"needs {('(x y)', '(x y z)')[self.dimension - 2]}"))
                continue
            motions[i] = mot
        if problems:
            raise CaseError(problems)
        return Models(sph, integ, functions, motions)

    # --- derived -------------------------------------------------------------------------
    @cached_property
    def context(self) -> CaseContext:
        pd = self.particles
        kernel = self.models.sph["kernel"]
        h = kernel.h(pd.dx)
        from sphfoam.case.geometry import vertical_extent

        ctx = CaseContext(dx=pd.dx, h=h, rho0=self.transport.rho0, nu=self.transport.nu,
                          g=self.gravity, fluid_height=max(vertical_extent(r, pd.dimension)
                                                           for r in pd.fluid.values()),
                          support=kernel.support_radius(h), dim=pd.dimension)
        c0 = self.models.sph["equationOfState"].c0(ctx)
        return CaseContext(**{**ctx.__dict__, "c0": c0})

    def validate(self) -> None:
        """Read and validate every dictionary, collecting all problems into one error."""
        problems: list[Problem] = []
        for attr in ("control", "schemes", "particles", "transport", "gravity", "models",
                     "waves"):
            try:
                getattr(self, attr)
            except CaseError as e:
                problems.extend(p for p in e.problems if str(p) not in map(str, problems))
        if problems:
            raise CaseError(problems)
        if not math.isfinite(self.context.c0) or self.context.c0 <= 0:
            raise CaseError.single(SPH_PROPERTIES, "equationOfState",
                                   "speed of sound is not positive; set vmax or speedOfSound")


def build_model(family, spec, file, key, problems, context=None):
    """Build ``spec`` (``{type name; coeffs}``) of ``family`` from ``file`` at ``key``; problems
    (not a sub-dictionary, unknown type, bad coefficients) are appended to ``problems`` and
    give None."""
    if not isinstance(spec, dict) or "type" not in spec:
        problems.append(Problem(file, key, f"expected a sub-dictionary with a 'type' entry; "
                                f"registered: {', '.join(registry.names(family))}"))
        return None
    try:
        return registry.build(family, spec, context)
    except registry.UnknownModel as e:
        problems.append(Problem(file, f"{key}.type", str(e)))
    except ValidationError as e:
        cls = registry.get(family, str(spec["type"]))
        problems.extend(from_validation(e, file, cls.Coeffs, prefix=key).problems)
    return None
