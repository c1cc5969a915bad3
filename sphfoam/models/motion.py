"""Prescribed wall motion (``motion { type ...; }`` of a wall in ``system/particleDict``).

A motion is a rigid translation d(t) of one wall entry: its particles sit at x0 + d(t) and
move with d'(t) at every stage of every step (the integrators ask for the stage time), and a
mirrored-ghost wall segment moves likewise. d(0) need not be zero; set-up places the wall at
its particleDict position, which is the position at t = 0.
"""

from __future__ import annotations

import abc

from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

import sphfoam.registry as registry
from sphfoam.case import foamdict
from sphfoam.registry import Coeffs, Model, register


class Motion(Model, abc.ABC):
    family = "motion"
    #: the case dimensions it moves walls in (a 3-D case refuses one without 3 by name)
    dims: tuple[int, ...] = (2,)

    def resolve(self, case_path: Path) -> None:
        """Load whatever the motion reads from the case (e.g. a table file)."""

    @property
    def components(self) -> int | None:
        """How many components its displacement has (2 or 3, the case's dimension), where
        it says (None: whatever the case's dimension)."""
        return None

    #: the entry that sets ``components`` (an error names it)
    components_key = "type"

    @abc.abstractmethod
    def displacement(self, t: float) -> tuple[float, float]:
        ...

    @abc.abstractmethod
    def velocity(self, t: float) -> tuple[float, float]:
        ...


@register
class PistonPaddle(Motion):
    """A piston wave paddle: the wall translates along ``direction`` by the trajectory X(t)
    of a named wave maker (``sphfoam models waveMaker``)."""

    name = "pistonPaddle"
    doc = "piston wave paddle moving along a direction by a wave maker's X(t)"
    dims = (2, 3)

    class Coeffs(Coeffs):
        direction: tuple[float, ...] = Field((1.0, 0.0), description=(
            "direction of the stroke: (x y) in 2-D, (x y z) in 3-D"))
        waveMaker: dict[str, Any] = Field(description="{ type <waveMaker>; coeffs }")

        @field_validator("direction")
        @classmethod
        def _unit(cls, v):
            if len(v) not in (2, 3):
                raise ValueError(f"expected (x y) or (x y z), got {v!r}")
            n = float(np.linalg.norm(v))
            if n == 0:
                raise ValueError("direction must not be zero")
            return tuple(c / n for c in v)

        @field_validator("waveMaker")
        @classmethod
        def _known(cls, v):
            if "type" not in v:
                raise ValueError("needs a 'type'; registered: "
                                 + ", ".join(registry.names("waveMaker")))
            try:
                registry.build("waveMaker", v)
            except registry.UnknownModel as e:
                raise ValueError(str(e)) from None
            except ArithmeticError as e:     # e.g. a depth so large its cube overflows
                raise ValueError(f"the wave maker's coefficients give no stroke ({e})") \
                    from None
            return v

    def __init__(self, coeffs=None):
        super().__init__(coeffs)
        self.maker = registry.build("waveMaker", self.coeffs.waveMaker)

    components_key = "direction"

    @property
    def components(self) -> int:
        return len(self.coeffs.direction)

    def displacement(self, t):
        X = self.maker.position(t)
        return tuple(X * c for c in self.coeffs.direction)

    def velocity(self, t):
        U = self.maker.velocity(t)
        return tuple(U * c for c in self.coeffs.direction)


@register
class DisplacementTable(Motion):
    """A displacement table: rows (t (dx dy)) in 2-D or (t (dx dy dz)) in 3-D inline in
    ``table``, or columns ``t dx dy [dz]`` in ``file`` (relative to the case), interpolated
    linearly (velocity piecewise constant, as OpenFOAM's tables) or by a C2 cubic spline;
    before the first and after the last time the wall holds still at the end values."""

    name = "displacementTable"
    doc = ("rigid displacement interpolated from a table of (t (dx dy)) or (t (dx dy dz)), "
           "inline or from a file")
    dims = (2, 3)

    class Coeffs(Coeffs):
        table: list[tuple[float, tuple[float, ...]]] | None = Field(
            None, description="( (t (dx dy)) ... ) in 2-D, ( (t (dx dy dz)) ... ) in 3-D")
        file: str | None = Field(None, description="file with columns t dx dy (3-D: t dx dy "
                                 "dz), relative to the case (and inside it), or an absolute "
                                 "path to use a file elsewhere on purpose")
        interpolation: Literal["linear", "spline"] = "linear"

        @model_validator(mode="after")
        def _one(self):
            if (self.table is None) == (self.file is None):
                raise ValueError("give exactly one of 'table' and 'file'")
            if self.table is not None:
                t = [r[0] for r in self.table]
                if len(t) < 2 or any(b <= a for a, b in zip(t, t[1:])):
                    raise ValueError("table needs at least two rows with strictly increasing t")
                n = {len(r[1]) for r in self.table}
                if len(n) != 1 or n.pop() not in (2, 3):
                    raise ValueError("every row's displacement needs the same 2 (dx dy) or "
                                     "3 (dx dy dz) components")
            return self

    def __init__(self, coeffs=None):
        super().__init__(coeffs)
        c = self.coeffs
        self._data = None
        if c.table is not None:
            self._set(np.array([[t, *d] for t, d in c.table], float), "table")

    @property
    def components(self) -> int | None:
        """2 or 3 (the table's or the file's), None before the file is read."""
        return None if self._data is None else self._data.shape[1] - 1

    @property
    def components_key(self) -> str:
        return "table" if self.coeffs.file is None else "file"

    def _set(self, data: np.ndarray, where: str):
        if data.ndim != 2 or data.shape[1] not in (3, 4) or data.shape[0] < 2:
            raise ValueError(f"{where}: needs at least two rows of t dx dy (3-D: t dx dy dz)")
        if not np.isfinite(data).all():
            raise ValueError(f"{where}: holds a non-finite number (inf or nan)")
        if np.any(np.diff(data[:, 0]) <= 0):
            raise ValueError(f"{where}: times must increase strictly")
        self._data = data
        if self.coeffs.interpolation == "spline":
            from scipy.interpolate import CubicSpline

            self._spline = CubicSpline(data[:, 0], data[:, 1:], axis=0, bc_type="natural")

    def resolve(self, case_path: Path) -> None:
        if self.coeffs.file is None:
            return
        from sphfoam.case.paths import resolve_file

        # $FOAM_CASE / $FOAM_CASENAME / <case> expand as in OpenFOAM file names
        f = resolve_file(case_path, foamdict.expand(str(self.coeffs.file), case_path),
                         absolute=True)
        self._set(np.loadtxt(f, ndmin=2, comments=("#", "//")), self.coeffs.file)

    def _clamp(self, t):
        d = self._data
        if d is None:
            raise RuntimeError("displacementTable: file not loaded (resolve the case first)")
        return min(max(t, d[0, 0]), d[-1, 0]), t <= d[0, 0] or t >= d[-1, 0]

    def displacement(self, t):
        tc, _ = self._clamp(t)
        d = self._data
        if self.coeffs.interpolation == "spline":
            return tuple(float(v) for v in self._spline(tc))
        return tuple(float(np.interp(tc, d[:, 0], d[:, k])) for k in range(1, d.shape[1]))

    def velocity(self, t):
        tc, outside = self._clamp(t)
        d = self._data
        if outside:
            return (0.0,) * (d.shape[1] - 1)
        if self.coeffs.interpolation == "spline":
            return tuple(float(v) for v in self._spline(tc, 1))
        i = int(np.clip(np.searchsorted(d[:, 0], tc, side="right") - 1, 0, len(d) - 2))
        dt = d[i + 1, 0] - d[i, 0]
        return tuple((d[i + 1, k] - d[i, k]) / dt for k in range(1, d.shape[1]))
