"""``slices``: fields interpolated on a plane and written for ParaView (OpenFOAM's
``cuttingPlane``, as a regular grid of points rather than mesh faces)."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, model_validator

from sphfoam.case.schemas import Vector
from sphfoam.registry import register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs
from sphfoam.sampling.interp import fluid_arrays, shepard


def plane_axes(normal) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e1, e2, n) of a plane with normal ``normal``: n normalised; e2 the vertical z
    projected on the plane (+y for a horizontal plane); e1 = e2 x n, so that e1, e2, n are
    right-handed (normal +z: e1 = +x, e2 = +y; normal +y: e1 = -x, e2 = +z; normal +x:
    e1 = +y, e2 = +z)."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    up = np.array([0.0, 0.0, 1.0])
    e2 = up - np.dot(up, n) * n
    if np.linalg.norm(e2) < 1e-9:
        e2 = np.array([0.0, 1.0, 0.0]) - n[1] * n
    e2 /= np.linalg.norm(e2)
    e1 = np.cross(e2, n)
    return e1, e2, n


def _vts(path, pts, dims, fields: dict[str, np.ndarray], time: float) -> None:
    """A VTK XML StructuredGrid (.vts, ASCII) of the points (n1 * n2, 3), e1 fastest,
    with point data ``fields`` (scalars (n,) or vectors (n, 3)); the time as field data."""
    n1, n2 = dims

    def arr(a):
        return " ".join("nan" if not np.isfinite(v) else f"{v:.9g}" for v in np.ravel(a))

    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="StructuredGrid" version="0.1" byte_order="LittleEndian">',
             f'  <StructuredGrid WholeExtent="0 {n1 - 1} 0 {n2 - 1} 0 0">',
             '    <FieldData>',
             '      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" '
             f'format="ascii">{time:.12g}</DataArray>',
             '    </FieldData>',
             f'    <Piece Extent="0 {n1 - 1} 0 {n2 - 1} 0 0">',
             '      <PointData Scalars="p" Vectors="U">']
    for name, a in fields.items():
        ncomp = 1 if a.ndim == 1 else a.shape[1]
        lines.append(f'        <DataArray type="Float64" Name="{name}" '
                     f'NumberOfComponents="{ncomp}" format="ascii">{arr(a)}</DataArray>')
    lines += ['      </PointData>', '      <Points>',
              '        <DataArray type="Float64" NumberOfComponents="3" format="ascii">'
              f'{arr(pts)}</DataArray>',
              '      </Points>', '    </Piece>', '  </StructuredGrid>', '</VTKFile>']
    path.write_text("\n".join(lines) + "\n")


@register
class Slices(FunctionObject):
    """p, U and rho interpolated on a rectangle of a plane, written for ParaView.

    The plane passes through ``point`` with normal ``normal``; the rectangle is centred on
    ``point``, ``size`` (L1 L2) long along the plane's axes e1, e2 (e2: the vertical z
    projected on the plane, +y for a horizontal plane; e1 = e2 x n, see ``plane_axes``), with
    grid points every ``spacing`` (default dx) from edge to edge. At each point the fields
    are the Shepard-normalised kernel sum over the fluid particles, as ``probes`` and
    ``pressureSensors``: A(r) = sum_b A_b V_b W / sum_b V_b W, with the case's kernel and h
    (the pressure brought up to date with the equation of state first); where the kernel sum
    sum_b V_b W is below ``kernelSumMin`` (0.5: the SPH fluid fraction 1/2, the free surface
    of the fraction gauges) the point is outside the water and its fields are NaN. The kernel
    sum is written too (``kernelSum``).

    Each sample writes ``postProcessing/<name>/<startTime>/<time>/<name>.vts`` (a VTK XML
    structured grid, ParaView opens it; the points in place in 3-D), and at the end
    ``postProcessing/<name>/<startTime>/<name>.pvd`` lists them as a time series.
    ``<name>.dat`` holds, per sample, the number of wet points and the mean and largest
    pressure over them. 3-D only.
    """

    name = "slices"
    doc = "p, U, rho interpolated (Shepard-normalised) on a plane grid, written as VTK " \
          ".vts for ParaView"
    dims = (3,)
    columns = ("time", "wetPoints", "pMean", "pMax")

    class Coeffs(FunctionObjectCoeffs):
        point: Vector = Field(description="centre of the rectangle, on the plane (m)")
        normal: Vector = Field(description="normal of the plane")
        size: tuple[float, float] = Field(description=(
            "lengths (L1 L2) of the rectangle along the plane's axes e1, e2 (m)"))
        spacing: float | None = Field(None, gt=0, description=(
            "grid spacing (m); default the case's dx"))
        kernelSumMin: float = Field(0.5, ge=0, description=(
            "least kernel sum sum_b V_b W for a point to be in the water (else NaN)"))

        @model_validator(mode="after")
        def _plane(self):
            if math.hypot(*self.normal) == 0.0:
                raise ValueError("normal of zero length")
            if min(self.size) <= 0:
                raise ValueError(f"size {self.size}: both lengths must be positive")
            return self

    def grid(self, dx: float) -> tuple[np.ndarray, tuple[int, int]]:
        """(points (n1 n2, 3), (n1, n2)), e1 fastest."""
        c = self.coeffs
        e1, e2, _ = plane_axes(c.normal)
        step = c.spacing or dx
        n1 = int(math.floor(c.size[0] / step + 1e-9)) + 1
        n2 = int(math.floor(c.size[1] / step + 1e-9)) + 1
        s1 = (np.arange(n1) - 0.5 * (n1 - 1)) * step
        s2 = (np.arange(n2) - 0.5 * (n2 - 1)) * step
        a, b = np.meshgrid(s1, s2, indexing="xy")              # (n2, n1): e1 fastest
        pts = np.asarray(c.point)[None, :] + a.reshape(-1, 1) * e1 + b.reshape(-1, 1) * e2
        return pts, (n1, n2)

    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        self.points, self.shape = self.grid(ctx.dx)
        self.precision = int(getattr(getattr(case, "control", None), "timePrecision", 6) or 6)
        self.written: list[tuple[float, str]] = []

    def sample(self, state) -> dict[str, np.ndarray]:
        """The fields at the grid points: p, U (n, 3), rho, kernelSum."""
        kernel = self.case.models.sph["kernel"]
        f, pos, vol = fluid_arrays(state, 3, self.points, kernel.support * self.ctx.h)
        n = len(self.points)
        if not f.size:
            nan = np.full(n, np.nan)
            return {"p": nan, "U": np.full((n, 3), np.nan), "rho": nan, "kernelSum": np.zeros(n)}
        vals, ksum = shepard(pos, vol, np.stack([state.p[f], state.u[f], state.v[f],
                                                 state.w[f], state.rho[f]]), self.points,
                             kernel, self.ctx.h, 3)
        vals[:, ksum < self.coeffs.kernelSumMin] = np.nan
        return {"p": vals[0], "U": vals[1:4].T.copy(), "rho": vals[4], "kernelSum": ksum}

    def execute(self, sim):
        from sphfoam.case.times import time_name

        eos = getattr(sim, "eos", None)
        if callable(eos):
            eos()
        fields = self.sample(sim.state)
        tname = time_name(float(sim.time), self.precision)
        folder = self.folder / tname
        folder.mkdir(parents=True, exist_ok=True)
        _vts(folder / f"{self.object_name}.vts", self.points, self.shape, fields,
             float(sim.time))
        self.written = [w for w in self.written if w[1] != tname]
        self.written.append((float(sim.time), tname))
        wet = np.isfinite(fields["p"])
        self.write_row((sim.time, int(wet.sum()),
                        float(fields["p"][wet].mean()) if wet.any() else float("nan"),
                        float(fields["p"][wet].max()) if wet.any() else float("nan")))

    def end(self):
        super().end()
        rows = "\n".join(f'    <DataSet timestep="{t:.12g}" part="0" '
                         f'file="{n}/{self.object_name}.vts"/>' for t, n in self.written)
        (self.folder / f"{self.object_name}.pvd").write_text(
            '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
