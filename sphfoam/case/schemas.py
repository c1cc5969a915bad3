"""pydantic schemas of every case dictionary. Unknown keys are errors everywhere.

Dictionary values arrive from :mod:`sphfoam.case.foamdict` as words, numbers, tuples and
lists; OpenFOAM switches (yes/no/on/off/true/false) become bools, dimensioned scalars such as
``nu [0 2 -1 0 0 0 0] 1e-06;`` are checked against their expected dimensions.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Union

from pydantic import (BaseModel, BeforeValidator, ConfigDict, Field, PrivateAttr,
                      ValidationInfo, field_validator, model_validator)

from sphfoam.case.foamdict import DimensionSet


class Strict(BaseModel):
    """Base of every dictionary schema: unknown keys are errors, and so are inf and nan (as
    written, or a literal such as 1e400 that overflows to inf) in any number."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)


def _vector2(v: Any) -> tuple[float, float]:
    """(x y) or (x y z) with z = 0 (a 2-D case)."""
    if isinstance(v, (list, tuple)) and len(v) in (2, 3) and all(
            isinstance(c, (int, float)) for c in v):
        if len(v) == 3 and v[2] != 0:
            raise ValueError("a 2-D case's vectors are (x y), z = 0: a 3-D case sets "
                             "`dimension 3;` in system/particleDict")
        return (float(v[0]), float(v[1]))
    raise ValueError(f"expected a vector (x y), got {v!r}")


Vector2 = Annotated[tuple[float, float], BeforeValidator(_vector2)]


def case_dimension(info: ValidationInfo | None) -> int:
    """The case's dimension a dictionary is validated for (``system/particleDict``
    ``dimension``, passed as the validation context ``{"dim": 2 | 3}``; 2 without one)."""
    ctx = getattr(info, "context", None) or {}
    return int(ctx.get("dim", 2))


def _vector(v: Any, info: ValidationInfo) -> tuple[float, ...]:
    """A point or vector of the case's dimension: (x y) in 2-D (or (x y 0), as OpenFOAM
    writes a 2-D case's vectors), (x y z) in 3-D."""
    dim = case_dimension(info)
    if dim == 2:
        return _vector2(v)
    if isinstance(v, (list, tuple)) and len(v) == 3 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) for c in v):
        return (float(v[0]), float(v[1]), float(v[2]))
    raise ValueError(f"expected a vector (x y z) in a 3-D case (system/particleDict "
                     f"dimension 3), got {v!r}")


#: a point or vector with the case's dimension's components (x y) or (x y z)
Vector = Annotated[tuple[float, ...], BeforeValidator(_vector)]


def dimensioned(dims: tuple[int, ...]):
    """Accept ``value``, ``[dims] value`` or ``name [dims] value``; check the dimensions."""

    def check(v: Any) -> Any:
        if isinstance(v, tuple):
            items = [i for i in v if not isinstance(i, str)]
            dimset = [i for i in items if isinstance(i, DimensionSet)]
            nums = [i for i in items if isinstance(i, (int, float))]
            if len(nums) != 1:
                raise ValueError(f"expected [dimensions] value, got {' '.join(map(str, v))}")
            if dimset:
                got = tuple(int(x) for x in dimset[0])
                if got[:len(dims)] != dims[:len(got)] or any(got[len(dims):]):
                    raise ValueError(f"dimensions {list(got)} do not match the expected "
                                     f"{list(dims)}")
                return nums[0] * dimset[0].factor  # a value in units, e.g. [g/cm^3], to SI
            return nums[0]
        return v

    return BeforeValidator(check)


# --- system/controlDict -------------------------------------------------------------------
class StabilityChecks(Strict):
    """Cheap checks after every step (sphfoam.engine.health): a run that diverges stops with a
    diagnosis in the log and postProcessing/stability/, and its last good state is written as
    a time directory. The defaults never fire on a healthy weakly-compressible run."""

    enabled: bool = Field(True, description=(
        "no: skip the checks (a non-finite or non-positive time step still stops the run, "
        "which would otherwise never end)"))
    densityRatio: tuple[float, float] = Field((0.5, 2.0), description=(
        "(lo hi): a fluid particle with rho/rho0 outside this range has diverged; weakly-"
        "compressible SPH keeps it within a few per cent (densityVariation, T(3.31))"))
    maxSpeed: float = Field(1.0, gt=0, description=(
        "a fluid particle faster than maxSpeed c0 (the artificial speed of sound, 10 vmax) is "
        "escaping"))
    maxEscaped: float = Field(0.05, gt=0, le=1, description=(
        "largest fraction of the fluid particles at the start of the run that may leave the "
        "domain box (not checked when a tank has an open side other than its top: outflow)"))
    minDeltaT: float = Field(1e-3, gt=0, lt=1, description=(
        "smallest time step, as a fraction of the first step of the run, before the step is "
        "said to have collapsed"))
    maxKineticEnergy: float = Field(4.0, gt=0, description=(
        "largest fluid kinetic energy in units of M (c0/10)^2 / 2 (M: fluid mass; c0/10 = vmax "
        "by construction), i.e. an RMS speed above sqrt(maxKineticEnergy) vmax"))

    @field_validator("densityRatio")
    @classmethod
    def _ratio(cls, v):
        lo, hi = v
        if not (0 < lo < 1 < hi and math.isfinite(hi)):
            raise ValueError("densityRatio must be (lo hi) with 0 < lo < 1 < hi")
        return v


class Settling(Strict):
    """An initialisation run with every wall and paddle still (T §5.3.4: "an initialisation
    run, with no paddle motion, ... to allow the particles to settle into position"), made by
    the set-up (``sphfoam setup``, or ``sphfoam run`` on a case without particles): the
    generated layout is kept as ``0.unsettled/``, the state after ``endTime`` seconds of
    settling becomes ``0/`` with its time back to 0 and every fluid velocity zeroed."""

    endTime: float = Field(gt=0, description=(
        "seconds of settling: a few times the time sound takes to cross the tank (length / "
        "c0), long enough for the seam above a slope's toe to even out (T §5.3.4 does not "
        "give its settling time)"))


def _threads(v: Any) -> Any:
    """``auto`` or a whole number >= 1 (a switch word such as ``yes`` is neither)."""
    if isinstance(v, str) and v == "auto":
        return v
    if isinstance(v, int) and not isinstance(v, bool) and v >= 1:
        return v
    raise ValueError(f"expected auto or a whole number of threads >= 1, got {v!r}")


Threads = Annotated[Union[Literal["auto"], int], BeforeValidator(_threads)]


class ControlDict(Strict):
    application: str = "sphfoam"
    startFrom: Literal["startTime", "latestTime"] = "latestTime"
    startTime: float = 0.0
    stopAt: Literal["endTime"] = "endTime"
    endTime: float = Field(gt=0)
    deltaT: float = Field(gt=0, description="the fixed step with adjustTimeStep no; with adjustTimeStep yes "
                          "the step comes from T(3.88)-(3.90) and deltaT is only recorded")
    adjustTimeStep: bool = True
    maxCo: float = Field(0.2, gt=0, le=2.0,
                         description="beta of the time-step conditions T(3.88), T(3.90)")
    maxDeltaT: float = Field(math.inf, gt=0)
    writeControl: Literal["timeStep", "runTime", "adjustableRunTime"] = "adjustableRunTime"
    writeInterval: float = Field(gt=0)
    purgeWrite: int = Field(0, ge=0)
    writeFormat: Literal["binary", "ascii"] = "binary"
    writePrecision: int = Field(6, ge=1, le=17)
    timePrecision: int = Field(6, ge=1, le=17)
    functions: dict[str, dict[str, Any]] = Field(default_factory=dict)
    threads: Threads = Field("auto", description=(
        "numba threads of the run: `auto` chooses between 1 and numba's pool "
        "(`NUMBA_NUM_THREADS`) from the measured wall time per step, moving to fewer threads "
        "when another process makes them slower and back when it stops (see the user guide, "
        "*Threads*); a whole number >= 1 pins the count (at most the pool's; `sphfoam run -j` "
        "overrides either); results do not depend on it"))
    settling: Settling | None = Field(None, description=(
        "{ endTime 0.5; }: settle the set-up particles with every wall still before t = 0 "
        "(T §5.3.4); the layout before settling is kept as 0.unsettled/"))
    stability: StabilityChecks = Field(default_factory=StabilityChecks, description=(
        "blow-up detection after every step: { enabled yes; densityRatio (0.5 2); maxSpeed 1; "
        "maxEscaped 0.05; minDeltaT 1e-3; maxKineticEnergy 4; }"))

    @field_validator("functions")
    @classmethod
    def _names(cls, v):
        from sphfoam.case.paths import check_name

        for name in v:      # each names a folder postProcessing/<name>/
            check_name(name)
        return v

    @model_validator(mode="after")
    def _check(self):
        if self.endTime / self.writeInterval > 1e6 and self.writeControl != "timeStep":
            raise ValueError(f"writeInterval {self.writeInterval:g} would write "
                             f"{self.endTime / self.writeInterval:.3g} time directories "
                             f"before endTime {self.endTime:g} (at most a million)")
        if self.writeControl == "timeStep" and self.writeInterval != int(self.writeInterval):
            raise ValueError("writeInterval must be a whole number of steps with "
                             "writeControl timeStep")
        return self


# --- system/sphSchemes ---------------------------------------------------------------------
class ModelSpec(BaseModel):
    """``{ type name; coeffs... }``: the coefficients are validated by the model itself."""

    model_config = ConfigDict(extra="allow")
    type: str


class TimeStepControl(Strict):
    forceCondition: bool = Field(True, description="also limit by sqrt(h/|F|), T(3.90)")


class NeighbourSearch(Strict):
    type: Literal["cellLinkedList"] = "cellLinkedList"
    cellSizeFactor: float = Field(1.05, ge=1.0, le=2.0, description=(
        "cell side in units of the kernel support; the margin above 1 covers the motion of "
        "particles between the re-sort at the start of a step and its later stages"))


class SphSchemes(Strict):
    integrator: ModelSpec = ModelSpec(type="monaghan2007")
    timeStepControl: TimeStepControl = TimeStepControl()
    neighbourSearch: NeighbourSearch = NeighbourSearch()
    precision: Literal["double", "single"] = Field("double", description=(
        "working precision of velocities, density, pressure and the pair arithmetic: "
        "double, or single (float32; positions stay double, relative positions are formed "
        "in double and then rounded)"))
    backend: Literal["cpu", "cuda"] = Field("cpu", description=(
        "where the pipeline runs: cpu (numba's threads) or cuda (one GPU thread per "
        "particle, numba-cuda: pip install 'sphfoam[gpu]')"))


# --- constant/ -----------------------------------------------------------------------------
class TransportProperties(Strict):
    rho0: Annotated[float, dimensioned((1, -3, 0, 0, 0, 0, 0))] = Field(1000.0, gt=0)
    nu: Annotated[float, dimensioned((0, 2, -1, 0, 0, 0, 0))] = Field(1e-6, ge=0)


class Gravity(Strict):
    dimensions: DimensionSet | None = None
    value: Vector = Field(description="(gx gy) in 2-D, y up; (gx gy gz) in 3-D, z up")

    @field_validator("dimensions", mode="before")
    @classmethod
    def _dims(cls, v):
        if v is not None and not isinstance(v, DimensionSet):
            raise ValueError(f"expected a dimension set [0 1 -2 0 0 0 0], got {v!r}")
        if v is not None and tuple(int(x) for x in v)[:3] != (0, 1, -2):
            raise ValueError(f"g must have dimensions [0 1 -2 0 0 0 0], got {list(v)}")
        if v is not None and v.factor != 1:
            raise ValueError(f"g is read in SI units: [{v.units}] is not m/s^2")
        return v

    model_config = ConfigDict(extra="forbid", arbitrary_types_allowed=True, allow_inf_nan=False)


#: families chosen in constant/sphProperties, with the default a case gets when it is silent
SPH_FAMILIES: dict[str, str | None] = {
    "kernel": None,
    "equationOfState": "tait",
    "continuity": "differenceForm",
    "momentum": "symmetric",
    "viscosity": None,
    "boundary": None,
    "turbulence": "none",
    "densityFilter": "none",
    "velocityCorrection": "none",
    "kernelCorrection": "none",
    "particleShifting": "none",
}


# --- system/particleDict -------------------------------------------------------------------
class Grid(Strict):
    """The lattice a fluid region is filled on (T §5.3.4, Fig 5.2): square, of spacing dx,
    with rows at ``angle`` degrees to the +x axis, its cells anchored at ``origin`` (the cell
    centres sit at origin + (i + 1/2) dx t + (j + 1/2) dx n, t = (cos a, sin a), n = (-sin a,
    cos a)). Anchored at the toe of a slope and at the slope's angle, the first row lies
    dx/2 above the slope, parallel to it, as the first row of the usual grid lies dx/2 above
    a flat bed."""

    origin: Vector2 = Field(description="a corner of the lattice's cells (m), e.g. the toe "
                            "of the slope")
    angle: float = Field(0.0, description="degrees of the rows above the +x axis, "
                         "-45..45 (any square lattice is one of these), e.g. the slope's 5")

    @field_validator("angle")
    @classmethod
    def _angle(cls, v):
        if not -45.0 <= v <= 45.0:
            raise ValueError(f"angle {v:g} is out of range: give -45..45 degrees (a square "
                             "lattice rotated by more is the same as one rotated by "
                             "angle -/+ 90)")
        return v


_CLIP_DOC = ("yes: fill only the part of the region on the fluid side of the walls (at least "
             "dx/2 from them), e.g. a box over a beach filled above the slope; no: the whole "
             "region (fluid closer than dx/2 to a wall is dropped either way)")

_GRID_DOC = ("{ origin (x y); angle a; }: fill the region on a lattice rotated by a degrees "
             "and anchored at origin (particles above a slope, T §5.3.4); default: the usual "
             "grid anchored at the region's lower-left corner")


def _axes(n: int) -> str:
    return "x and y" if n == 2 else "x, y and z"


def _check_order(lo, hi, what: str) -> None:
    if not all(b > a for a, b in zip(lo, hi)):
        raise ValueError(f"{what} max {hi} must exceed min {lo} in {_axes(len(lo))}")


def _two_dimensional(what: str, info: ValidationInfo, instead: str) -> None:
    """Refuse, by name, an entry that has no 3-D form."""
    if case_dimension(info) == 3:
        raise ValueError(f"{what} is two-dimensional: a 3-D case uses {instead}")


def _three_dimensional(what: str, info: ValidationInfo) -> None:
    if case_dimension(info) != 3:
        raise ValueError(f"{what} is a 3-D shape: set `dimension 3;` in system/particleDict "
                         "(and give every point as (x y z))")


class BoxRegion(Strict):
    type: Literal["box"]
    min: Vector
    max: Vector
    grid: Grid | None = Field(None, description=_GRID_DOC + " (2-D only)")
    clipToWalls: bool = Field(False, description=_CLIP_DOC)

    @model_validator(mode="after")
    def _order(self, info: ValidationInfo):
        _check_order(self.min, self.max, "box")
        if self.grid is not None:
            _two_dimensional("a rotated grid", info, "the usual grid")
        return self


class PolygonRegion(Strict):
    type: Literal["polygon"]
    points: list[Vector2] = Field(min_length=3)
    grid: Grid | None = Field(None, description=_GRID_DOC)
    clipToWalls: bool = Field(False, description=_CLIP_DOC)

    @model_validator(mode="after")
    def _plane(self, info: ValidationInfo):
        _two_dimensional("a polygon", info, "box, cylinder, extrude or mesh")
        return self


class CylinderRegion(Strict):
    """3-D: the inside of the cylinder of ``radius`` around the axis ``point1``-``point2``
    (OpenFOAM's cylinderToCell), filled on the lattice anchored at the case's origin."""

    type: Literal["cylinder"]
    point1: Vector = Field(description="centre of one end (m)")
    point2: Vector = Field(description="centre of the other end (m)")
    radius: float = Field(gt=0)
    clipToWalls: bool = Field(False, description=_CLIP_DOC)

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _three_dimensional("a cylinder", info)
        if self.point1 == self.point2:
            raise ValueError("point1 and point2 must differ (the cylinder's axis)")
        return self


class ExtrudeRegion(Strict):
    """3-D: a 2-D section in the vertical x-z plane, ``points`` ((x z) ...), extruded across
    y over ``span`` (y0 y1): a flume's section made a basin's."""

    type: Literal["extrude"]
    points: list[tuple[float, float]] = Field(min_length=3, description="((x z) ...)")
    span: tuple[float, float] = Field(description="(y0 y1), y1 > y0")
    clipToWalls: bool = Field(False, description=_CLIP_DOC)

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _three_dimensional("an extruded section", info)
        if not self.span[1] > self.span[0]:
            raise ValueError(f"span {self.span}: y1 must exceed y0")
        return self


def _resolve(file: str, case_dir):
    from pathlib import Path

    f = Path(file)
    return f if f.is_absolute() else Path(case_dir) / f


class MeshRegion(Strict):
    """3-D: the inside of a closed surface mesh read with meshio (STL, OBJ, VTK, Gmsh, ...;
    sphfoam.case.meshsolids, VTK's point-in-surface test), filled on the lattice anchored at
    the case's origin. The faces' orientation does not matter."""

    type: Literal["mesh"]
    file: str = Field(description="closed surface mesh, relative to the case directory "
                      "(e.g. `\"constant/geometry/water.stl\"`): any format meshio reads")
    scale: float = Field(1.0, gt=0, description="factor on the file's coordinates, e.g. 0.001 "
                         "for a CAD file in mm")
    translate: Vector = Field((0.0, 0.0, 0.0), description="shift (x y z) (m) added after "
                              "scaling")
    _surface: Any = PrivateAttr(None)

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _three_dimensional("a mesh fluid region", info)
        return self

    def load(self, case_dir) -> None:
        """Read the surface (relative to ``case_dir``); raises MeshWallError with the
        reason (not closed, no triangles, ...)."""
        from sphfoam.case.meshsolids import read_surface

        self._surface = read_surface(_resolve(self.file, case_dir), self.scale,
                                     self.translate, closed=True)

    @property
    def surface(self):
        """The closed surface (sphfoam.case.meshsolids.Surface), once :meth:`load` ran."""
        if self._surface is None:
            raise RuntimeError(f"mesh region {self.file}: load(case_dir) has not been called")
        return self._surface


FluidRegion = Annotated[BoxRegion | PolygonRegion | CylinderRegion | ExtrudeRegion
                        | MeshRegion, Field(discriminator="type")]


_MOTION_DOC = ("prescribed motion of this wall, { type <motion>; ... } (sphfoam models "
               "motion): e.g. a piston wave paddle or a displacement table")


class _Wall(Strict):
    motion: dict[str, Any] | None = Field(None, description=_MOTION_DOC)

    @model_validator(mode="after")
    def _one_motion(self):
        if self.motion is not None and any(getattr(self, "velocity", ())):
            raise ValueError("give either a constant velocity or a motion, not both")
        return self


#: a tank's sides: 2-D, y up: bottom/top y, left/right x; 3-D, z up: bottom/top z,
#: left/right x, front/back y
FACES = ("top", "bottom", "left", "right", "front", "back")


class BoxWalls(_Wall):
    """A rectangular tank: wall rows outside ``min``..``max``; ``open`` sides get none."""

    type: Literal["box"]
    min: Vector
    max: Vector
    layers: int = Field(3, ge=1, le=10, description="rows of wall particles")
    velocity: Vector = Field((0.0, 0.0), description="constant wall velocity (m/s), e.g. "
                             "the sliding plate of a Couette flow (2-D)")
    open: list[Literal["top", "bottom", "left", "right", "front", "back"]] = Field(
        default_factory=lambda: ["top"], description=(
            "sides without wall rows: 2-D (y up) top, bottom, left, right; 3-D (z up) also "
            "front (y min) and back (y max)"))

    @field_validator("open", mode="before")
    @classmethod
    def _one(cls, v):
        return [v] if isinstance(v, str) else v

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _check_order(self.min, self.max, "box")
        if case_dimension(info) == 2 and {"front", "back"} & set(self.open):
            raise ValueError("front and back are the y sides of a 3-D tank: a 2-D tank's "
                             "sides are top, bottom, left and right")
        return self


class BlockWalls(_Wall):
    """A solid box (an obstacle): ``layers`` of wall particles inside its faces, fluid
    outside. 2-D or 3-D."""

    type: Literal["block"]
    min: Vector
    max: Vector
    layers: int = Field(3, ge=1, le=10, description="rows of wall particles inside the faces")

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _check_order(self.min, self.max, "block")
        return self


class CylinderWalls(_Wall):
    """3-D: a solid cylinder (a pile, a column) of ``radius`` around ``point1``-``point2``:
    ``layers`` of wall particles inside its surface, fluid outside."""

    type: Literal["cylinder"]
    point1: Vector = Field(description="centre of one end (m)")
    point2: Vector = Field(description="centre of the other end (m)")
    radius: float = Field(gt=0)
    layers: int = Field(3, ge=1, le=10, description="layers of wall particles")

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _three_dimensional("a cylinder", info)
        if self.point1 == self.point2:
            raise ValueError("point1 and point2 must differ (the cylinder's axis)")
        return self


class ExtrudeWalls(_Wall):
    """3-D: a solid 2-D section in the x-z plane, ``points`` ((x z) ...), extruded across y
    over ``span`` (y0 y1) (a beach's slope, a breakwater): ``layers`` of wall particles
    inside its surface, fluid outside."""

    type: Literal["extrude"]
    points: list[tuple[float, float]] = Field(min_length=3, description="((x z) ...)")
    span: tuple[float, float] = Field(description="(y0 y1), y1 > y0")
    layers: int = Field(3, ge=1, le=10, description="layers of wall particles")

    @model_validator(mode="after")
    def _shape(self, info: ValidationInfo):
        _three_dimensional("an extruded section", info)
        if not self.span[1] > self.span[0]:
            raise ValueError(f"span {self.span}: y1 must exceed y0")
        return self


class PolylineWalls(_Wall):
    """Wall rows along a polyline; the solid lies on ``side`` of the direction of travel."""

    type: Literal["polyline"]
    points: list[Vector2] = Field(min_length=2)
    layers: int = Field(3, ge=1, le=10, description="rows of wall particles")
    side: Literal["left", "right"] = Field("right", description="side of the direction of "
                                           "travel the solid lies on")
    velocity: Vector2 = Field((0.0, 0.0), description="constant wall velocity (m/s)")

    @model_validator(mode="after")
    def _plane(self, info: ValidationInfo):
        _two_dimensional("a polyline", info, "box, block, cylinder, extrude or mesh walls")
        return self


class SlopeWalls(_Wall):
    """A plane slope (e.g. the 5 degree beach of T ch. 5) rising from ``start`` at ``angle``
    degrees to the horizontal over ``length`` metres along the slope; the solid lies below."""

    type: Literal["slope"]
    start: Vector2
    angle: float = Field(gt=-90.0, lt=90.0, description="degrees above the +x axis")
    length: float = Field(gt=0, description="length along the slope (m)")
    layers: int = Field(3, ge=1, le=10, description="rows of wall particles")
    velocity: Vector2 = Field((0.0, 0.0), description="constant wall velocity (m/s)")

    @model_validator(mode="after")
    def _plane(self, info: ValidationInfo):
        _two_dimensional("a slope", info, "extrude walls (the slope's section across y)")
        return self


class MeshWalls(_Wall):
    """Walls from a mesh file read with meshio. 2-D (sphfoam.case.meshwalls): wall rows along
    its line cells, the section of its surface (STL, OBJ, VTK, Gmsh triangles or quads) by the
    plane z = ``z``, or the boundary of a flat surface mesh; the solid lies behind the faces
    (their normals point into the fluid) or on ``side`` of the line cells. 3-D
    (sphfoam.case.meshsolids, VTK's distance and point-in-surface filters): a closed surface
    is a solid with ``layers`` of wall particles inside it and the fluid outside (``side
    left``: a container, the layers outside it and the fluid inside); an open surface (a
    terrain, a sheet of sea wall) has its layers behind its faces, opposite their normals
    (``side left``: in front)."""

    type: Literal["mesh"]
    file: str = Field(description="mesh file, relative to the case directory (e.g. "
                      "`\"constant/geometry/obstacle.stl\"`): any format meshio reads")
    layers: int = Field(3, ge=1, le=10, description="rows of wall particles")
    side: Literal["left", "right"] = Field("right", description=(
        "where the solid lies: line cells, on this side of their direction; surfaces, "
        "`right` behind the faces (their normals point into the fluid), `left` in front; "
        "3-D closed surfaces, `right` inside, `left` outside (a container)"))
    z: float = Field(0.0, description="height of the cutting plane through a surface, in the "
                     "file's units (2-D only)")
    scale: float = Field(1.0, gt=0, description="factor on the file's coordinates, e.g. 0.001 "
                         "for a CAD file in mm")
    translate: Vector = Field((0.0, 0.0), description="shift (m) added after scaling: (x y) "
                              "in 2-D, (x y z) in 3-D")
    velocity: Vector = Field((0.0, 0.0), description="constant wall velocity (m/s)")
    _polylines: list | None = PrivateAttr(None)
    _surface: Any = PrivateAttr(None)
    _dim: int = PrivateAttr(2)

    @model_validator(mode="after")
    def _dimension(self, info: ValidationInfo):
        self._dim = case_dimension(info)
        if self._dim == 3:
            if "z" in self.model_fields_set:
                raise ValueError("z (the cutting plane of a 2-D case's mesh wall) has no "
                                 "meaning in 3-D, where the whole surface is the wall: "
                                 "remove it")
            if "translate" not in self.model_fields_set:
                self.translate = (0.0, 0.0, 0.0)
        return self

    def load(self, case_dir) -> None:
        """Read the mesh (relative to ``case_dir``); raises MeshWallError with the reason."""
        path = _resolve(self.file, case_dir)
        if self._dim == 3:
            from sphfoam.case.meshsolids import read_surface

            self._surface = read_surface(path, self.scale, self.translate)
            return
        from sphfoam.case.meshwalls import read_mesh_walls

        self._polylines = read_mesh_walls(path, z=self.z, scale=self.scale,
                                          translate=self.translate)

    @property
    def polylines(self) -> list[list[tuple[float, float]]]:
        """The wall lines of a 2-D case (solid on their right before ``side``), once
        :meth:`load` ran."""
        if self._polylines is None:
            raise RuntimeError(f"mesh wall {self.file}: load(case_dir) has not been called"
                               + (" (or the case is 3-D: see surface)" if self._dim == 3
                                  else ""))
        return self._polylines

    @property
    def surface(self):
        """The surface of a 3-D case (sphfoam.case.meshsolids.Surface), once :meth:`load`
        ran."""
        if self._surface is None:
            raise RuntimeError(f"mesh wall {self.file}: load(case_dir) has not been called"
                               + (" (or the case is 2-D: see polylines)" if self._dim == 2
                                  else ""))
        return self._surface


WallRegion = Annotated[BoxWalls | BlockWalls | CylinderWalls | ExtrudeWalls | PolylineWalls
                       | SlopeWalls | MeshWalls, Field(discriminator="type")]


class Domain(Strict):
    min: Vector
    max: Vector
    periodic: list[Literal["x", "y", "z"]] = Field(default_factory=list, description=(
        "periodic axes: a particle leaving through max re-enters through min, and pairs "
        "interact across the seam (channel flows; a narrow 3-D flume periodic across y)"))

    @model_validator(mode="after")
    def _order(self, info: ValidationInfo):
        if not all(b > a for a, b in zip(self.min, self.max)):
            raise ValueError(f"domain max {self.max} must exceed min {self.min} in "
                             f"{_axes(len(self.min))} (an empty domain holds no particle)")
        if "z" in self.periodic and case_dimension(info) == 2:
            raise ValueError("z is periodic only in a 3-D case (system/particleDict "
                             "dimension 3)")
        return self

    @field_validator("periodic", mode="before")
    @classmethod
    def _one(cls, v):
        return [v] if isinstance(v, str) else v


class ParticleDict(Strict):
    dimension: Literal[2, 3] = Field(2, description=(
        "2: x, y with y up; 3: x, y, z with z up. Every point and vector of the case "
        "(here and constant/g) then has this many components"))
    dx: float = Field(gt=0, description="initial particle spacing")
    fluid: dict[str, FluidRegion] = Field(min_length=1)
    walls: dict[str, WallRegion] = Field(default_factory=dict)
    minSpacing: float = Field(0.5, gt=0, le=1, description=(
        "fluid particles of different regions closer than minSpacing dx are thinned (the "
        "particle of the later region in the file goes): the seam where the usual grid meets "
        "a rotated one above a slope (T §5.3.4). Within a region, and between regions that "
        "touch on the same grid, no two particles are closer than dx"))
    domain: Domain | None = Field(None, description=(
        "particles leaving this box are removed (and reported); default: the box around all "
        "initial particles, enlarged by half its size upwards and 10 dx elsewhere"))


# --- constant/waveProperties ---------------------------------------------------------------
class InitialWave(Strict):
    """A solitary wave placed in the still water at t = 0 (P §4)."""

    theory: str = Field(description="wave theory (sphfoam models waveTheory), e.g. mcCowan")
    height: float = Field(gt=0, description="wave height A above the still water level (m)")
    x0: float = Field(description="crest position at t = 0 (m)")
    direction: Literal[1, -1] = Field(1, description="+1: travelling towards +x; -1: -x")
    velocity: Literal["continuity", "theory"] = Field("continuity", description=(
        "`continuity`: a theory whose (u, w) is not divergence-free or whose flux is not "
        "c eta (KdV1, KdV2, Laitone) gets its u scaled per column to the flux c eta and w "
        "from continuity, so the start is solenoidal and the surface translates at c "
        "(sphfoam.setup.waves; the exact, McCowan and Boussinesq waves, and Fenton's where "
        "its series is kinematically consistent to 1e-3, keep their own); `theory`: the "
        "theory's own u and w as published (P §4's KdV2)"))


class WaveProperties(Strict):
    """Initial solitary waves: each box fluid region of particleDict is filled column by
    column up to its top (the still water level) plus the sum of the waves' elevations."""

    waves: dict[str, InitialWave] = Field(default_factory=dict, description=(
        "named waves, each { theory ...; height ...; x0 ...; direction 1; }"))


# --- system/metricsDict --------------------------------------------------------------------
class MetricsDict(Strict):
    """Error metrics of a finished run against its reference (``sphfoam metrics``,
    ``sphfoam study``): each reads what a function object of system/controlDict wrote."""

    metrics: dict[str, dict[str, Any]] = Field(min_length=1, description=(
        "named metrics, each { type <metric>; function <object>; ... } (sphfoam models "
        "metric), e.g. `H18 { type waveHeight; function gauges; x 18; reference 0.15; }`"))
    pareto: str | None = Field(None, description=(
        "the metric whose |error| a study plots against cost; one of `metrics`"))

    @field_validator("pareto")
    @classmethod
    def _pareto(cls, v, info):
        from sphfoam.case.errors import did_you_mean

        names = list(info.data.get("metrics") or {})
        if v is not None and names and v not in names:
            raise ValueError(f"'{v}' is not one of the metrics{did_you_mean(v, names) or ';'} "
                             f"metrics: {', '.join(names)}")
        return v
