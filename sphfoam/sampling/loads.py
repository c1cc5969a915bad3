"""Loads on walls: ``pressureSensors`` (pressure at points on a wall, as DualSPHysics'
MeasureTool interpolates it) and ``forces`` (OpenFOAM's name and output: the force and
moment the fluid exerts on named walls, from the SPH pair forces). Both work in 2-D and
3-D."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from pydantic import Field, model_validator
from pydantic import ValidationInfo

from sphfoam.case.schemas import Vector, case_dimension
from sphfoam.engine.state import FLUID, WALL
from sphfoam.registry import register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs
from sphfoam.sampling.interp import Cells, fluid_arrays, shepard


def _label(v: float) -> str:
    return f"{v:g}"


def _current_pressure(sim) -> None:
    eos = getattr(sim, "eos", None)
    if callable(eos):
        eos()


# --- pressureSensors ---------------------------------------------------------------------------
@register
class PressureSensors(FunctionObject):
    """Pressure at points on a wall, interpolated from the fluid as DualSPHysics' MeasureTool
    does.

    Each sensor point, given on the wall, is moved ``offset`` dx (1.5) into the fluid along
    the wall's unit normal (``normal`` for every sensor, or ``normals`` one per sensor,
    pointing from the wall into the water), out of the wall particles' rows; there the
    pressure is the Shepard-normalised kernel sum over the fluid particles

        p(r) = sum_b p_b V_b W(r - r_b) / sum_b V_b W(r - r_b),   V_b = m_b / rho_b,

    with the case's kernel and h (the pressure brought up to date with the equation of state
    first). A reading counts only where the kernel sum sum_b V_b W(r - r_b) is at least
    ``kernelSumMin`` (0.5, MeasureTool's ``-kclimit`` default: half a support of water;
    about 1 inside the water, 1/2 at a flat free surface); below it (a dry sensor, or one
    too near the free surface) the reading is NaN. Columns: time, then ``p(x,y[,z])`` per
    sensor, labelled with the point as given; the header's notes give the moved points.
    """

    name = "pressureSensors"
    doc = "pressure at points on a wall: Shepard-normalised kernel sum over the fluid at the " \
          "point moved offset dx into the fluid (DualSPHysics' MeasureTool)"
    dims = (2, 3)

    class Coeffs(FunctionObjectCoeffs):
        points: list[Vector] = Field(min_length=1, description=(
            "sensor points on the wall `((x1 y1) ...)` (2-D) or `((x1 y1 z1) ...)` (3-D), m"))
        normal: Vector | None = Field(None, description=(
            "the wall's normal, pointing into the fluid, for every sensor (normalised here)"))
        normals: list[Vector] = Field(default_factory=list, description=(
            "one normal per sensor, instead of `normal`"))
        offset: float = Field(1.5, ge=0, description=(
            "distance the sensor is moved into the fluid along its normal, in dx"))
        kernelSumMin: float = Field(0.5, ge=0, description=(
            "least kernel sum sum_b V_b W at the sensor for a reading (else NaN)"))

        @model_validator(mode="after")
        def _normals(self, info: ValidationInfo):
            if (self.normal is None) == (not self.normals):
                raise ValueError("give either normal (one for every sensor) or normals "
                                 "(one per sensor)")
            if self.normals and len(self.normals) != len(self.points):
                raise ValueError(f"{len(self.normals)} normals for {len(self.points)} "
                                 "points: give one per sensor")
            for n in ([self.normal] if self.normal is not None else self.normals):
                if math.hypot(*n) == 0.0:
                    raise ValueError("a normal of zero length")
            return self

    def sensor_points(self, dx: float) -> np.ndarray:
        """The sensor points moved ``offset`` dx into the fluid along their normals."""
        c = self.coeffs
        p = np.asarray(c.points, dtype=float)
        n = np.asarray([c.normal] * len(p) if c.normal is not None else c.normals, float)
        n /= np.linalg.norm(n, axis=1)[:, None]
        return p + c.offset * dx * n

    def start(self, case, ctx, start_time_name):
        self.columns = ("time",) + tuple(
            "p(" + ",".join(_label(v) for v in pt) + ")" for pt in self.coeffs.points)
        self.moved = self.sensor_points(ctx.dx)
        self.notes = tuple(
            f"sensor {k}: read at (" + " ".join(f"{v:.9g}" for v in q) + ")"
            for k, q in enumerate(self.moved))
        super().start(case, ctx, start_time_name)

    def measure(self, state) -> tuple[np.ndarray, np.ndarray]:
        """(pressures, kernel sums) at the sensors."""
        dim = self.ctx.dim
        kernel = self.case.models.sph["kernel"]
        f, pos, vol = fluid_arrays(state, dim, self.moved, kernel.support * self.ctx.h)
        if not f.size:
            return np.full(len(self.moved), np.nan), np.zeros(len(self.moved))
        vals, ksum = shepard(pos, vol, state.p[f][None, :], self.moved, kernel, self.ctx.h,
                             dim)
        p = vals[0]
        p[ksum < self.coeffs.kernelSumMin] = np.nan
        return p, ksum

    def execute(self, sim):
        _current_pressure(sim)
        p, _ = self.measure(sim.state)
        self.write_row((sim.time, *p))


# --- forces ------------------------------------------------------------------------------------
#: the momentum forms whose pair coefficient ``forces`` evaluates: 0 symmetric, 1 C-L
_PRESSURE_FORMS = {"symmetric": 0, "colagrossiLandrini": 1}
#: the viscosities whose pair force ``forces`` evaluates
_VISCOUS_FORMS = {"none": 0, "artificial": 1, "laminar": 2}
#: the boundaries whose wall particles act on the fluid through the momentum and viscous
#: equations themselves (their pair forces are the fluid's), which ``forces`` sums
_BOUNDARIES = ("stationaryGhosts", "adami", "mDBC")


@njit(cache=True)
def _pair_forces(wpos, wvel, wm, wrho, wp, wc, fpos, fvel, fm, frho, fp, fc, starts, lo,
                 ncell, size, inv_h, gw, support, kernel_dfdq_q, pform, vform, alpha, h, eta2,
                 mu2, cofr):
    """Force and moment on the wall particles (wpos ...) from the fluid (fpos ..., in cell
    order): rows pressure force, viscous force, pressure moment, viscous moment (4, 3)."""
    out = np.zeros((4, 3))
    reach2 = (support / inv_h) ** 2
    for a in range(wpos.shape[0]):
        ci = int(math.floor((wpos[a, 0] - lo[0]) / size))
        cj = int(math.floor((wpos[a, 1] - lo[1]) / size))
        ck = int(math.floor((wpos[a, 2] - lo[2]) / size))
        fpx = 0.0
        fpy = 0.0
        fpz = 0.0
        fvx = 0.0
        fvy = 0.0
        fvz = 0.0
        for i in range(ci - 1, ci + 2):
            if i < 0 or i >= ncell[0]:
                continue
            for j in range(cj - 1, cj + 2):
                if j < 0 or j >= ncell[1]:
                    continue
                for k in range(ck - 1, ck + 2):
                    if k < 0 or k >= ncell[2]:
                        continue
                    c = (i * ncell[1] + j) * ncell[2] + k
                    for b in range(starts[c], starts[c + 1]):
                        dx = wpos[a, 0] - fpos[b, 0]
                        dy = wpos[a, 1] - fpos[b, 1]
                        dz = wpos[a, 2] - fpos[b, 2]
                        r2 = dx * dx + dy * dy + dz * dz
                        if r2 >= reach2 or r2 == 0.0:
                            continue
                        fw = gw * kernel_dfdq_q(math.sqrt(r2) * inv_h)
                        gx = fw * dx
                        gy = fw * dy
                        gz = fw * dz
                        mm = wm[a] * fm[b]
                        if pform == 0:
                            pab = wp[a] / (wrho[a] * wrho[a]) + fp[b] / (frho[b] * frho[b])
                        else:
                            pab = (wp[a] + fp[b]) / (wrho[a] * frho[b])
                        fpx -= mm * pab * gx
                        fpy -= mm * pab * gy
                        fpz -= mm * pab * gz
                        ux = wvel[a, 0] - fvel[b, 0]
                        uy = wvel[a, 1] - fvel[b, 1]
                        uz = wvel[a, 2] - fvel[b, 2]
                        if vform == 1:
                            vdotr = ux * dx + uy * dy + uz * dz
                            pi = -alpha * h * (wc[a] + fc[b]) / (wrho[a] + frho[b]) * \
                                min(vdotr, 0.0) / (r2 + eta2)
                            fvx -= mm * pi * gx
                            fvy -= mm * pi * gy
                            fvz -= mm * pi * gz
                        elif vform == 2:
                            lam = mm * mu2 / (wrho[a] * frho[b]) * \
                                (dx * gx + dy * gy + dz * gz) / (r2 + eta2)
                            fvx += lam * ux
                            fvy += lam * uy
                            fvz += lam * uz
        rx = wpos[a, 0] - cofr[0]
        ry = wpos[a, 1] - cofr[1]
        rz = wpos[a, 2] - cofr[2]
        out[0, 0] += fpx
        out[0, 1] += fpy
        out[0, 2] += fpz
        out[1, 0] += fvx
        out[1, 1] += fvy
        out[1, 2] += fvz
        out[2, 0] += ry * fpz - rz * fpy
        out[2, 1] += rz * fpx - rx * fpz
        out[2, 2] += rx * fpy - ry * fpx
        out[3, 0] += ry * fvz - rz * fvy
        out[3, 1] += rz * fvx - rx * fvz
        out[3, 2] += rx * fvy - ry * fvx
    return out


def wall_patches(case) -> tuple[np.ndarray, np.ndarray]:
    """(positions (n, dim), walls-entry index (n,)) of the wall particles the set-up places
    for the case's particleDict walls (the same functions, layers and first-of-duplicates
    rule as ``sphfoam.setup``), to tell which walls entry a wall particle belongs to."""
    pd = case.particles
    boundary = case.models.sph["boundary"]
    layers = getattr(boundary, "wall_layers", None)
    walls = [w if layers is None else w.model_copy(update={"layers": layers})
             for w in pd.walls.values()]
    if not walls:
        return np.zeros((0, pd.dimension)), np.zeros(0, dtype=np.int64)
    if pd.dimension == 3:
        from sphfoam.setup import particles3d as p3

        anchor = p3.case_anchor(pd)
        made = [p3.wall_points(w, pd.dx, anchor)[0] for w in walls]
        pos = np.concatenate(made)
        patch = np.concatenate([np.full(len(m), i) for i, m in enumerate(made)])
        keep = p3._first_of_duplicates(pos, 0.5 * pd.dx)
    else:
        from sphfoam.setup import particles as p2

        made = [p2.wall_points(w, pd.dx) for w in walls]
        pos = np.column_stack([np.concatenate([m[0] for m in made]),
                               np.concatenate([m[1] for m in made])])
        patch = np.concatenate([np.full(len(m[0]), i) for i, m in enumerate(made)])
        keep = p2._first_of_duplicates(pos[:, 0], pos[:, 1], 0.5 * pd.dx)
    return pos[keep], patch[keep].astype(np.int64)


@register
class Forces(FunctionObject):
    """Force and moment of the fluid on named walls (OpenFOAM's ``forces``).

    ``patches`` names entries of system/particleDict's ``walls``; their wall particles are
    found by the ``patch`` index the set-up writes with moving walls, else by position (the
    wall particles of a still wall stay where the set-up put them: each is matched, within
    dx/4, to the set-up's particles of the walls entries, a particle shared by two entries
    belonging to the first). The force on the body is the reaction of the SPH pair forces
    its wall particles exert on the fluid, summed over its wall particles a and their fluid
    neighbours b in one compiled loop:

    * pressure: F = -sum_a sum_b m_a m_b P_ab grad_a W_ab, P_ab the case's momentum form
      (``symmetric``: p_a/rho_a^2 + p_b/rho_b^2; ``colagrossiLandrini``:
      (p_a + p_b)/(rho_a rho_b)) with the wall particles' own p and rho (stationary ghosts:
      their continuity-evolved density; adami: the extrapolated wall state);
    * viscous: the case's viscosity on the same pairs (``artificial``: -m_a m_b Pi_ab
      grad_a W_ab; ``laminar``: Morris's m_a m_b (mu_a + mu_b)/(rho_a rho_b)
      r_ab.grad_a W_ab/(r_ab^2 + 0.01 h^2) v_ab; ``none``: 0), c from the equation of
      state, and the wall velocities the pair passes see (mDBC with ``noSlip no``: the
      ghost nodes' velocities mirrored); 0 where the boundary keeps its walls out of the
      viscous terms (stationary ghosts with ``noSlip no``);

    moments M = sum_a (r_a - CofR) x F_a. These are exactly the forces that the fluid's
    momentum equation receives from those walls, with the sign reversed. Other momentum
    forms, viscosities and boundaries (repulsive and mirrored walls) are refused by name.

    Written as OpenFOAM writes them: ``postProcessing/<name>/<startTime>/force.dat`` with
    columns Time, total_x/y/z, pressure_x/y/z, viscous_x/y/z and ``moment.dat`` with the
    same columns for the moment about ``CofR``. 2-D: the force per metre of span (z
    components 0; the moment about the z axis in moment's z columns).
    """

    name = "forces"
    doc = "force and moment of the fluid on named walls (pressure and viscous SPH pair " \
          "forces on their wall particles), OpenFOAM's force.dat/moment.dat"
    dims = (2, 3)
    columns = ("Time", "total_x", "total_y", "total_z", "pressure_x", "pressure_y",
               "pressure_z", "viscous_x", "viscous_y", "viscous_z")

    class Coeffs(FunctionObjectCoeffs):
        patches: list[str] = Field(min_length=1, description=(
            "names of system/particleDict `walls` entries: the body"))
        CofR: Vector | None = Field(None, description=(
            "centre of rotation for the moment (m); default the origin"))

        @model_validator(mode="before")
        @classmethod
        def _one(cls, v):
            if isinstance(v, dict) and isinstance(v.get("patches"), str):
                v = {**v, "patches": [v["patches"]]}
            return v

    def start(self, case, ctx, start_time_name):
        from pathlib import Path

        self.case, self.ctx = case, ctx
        sph = case.models.sph
        names = list(case.particles.walls)
        unknown = [p for p in self.coeffs.patches if p not in names]
        if unknown:
            raise ValueError(f"forces {self.object_name!r}: no walls entry {unknown[0]!r} in "
                             f"system/particleDict; walls: {', '.join(names) or '(none)'}")
        self.patch_ids = [names.index(p) for p in self.coeffs.patches]
        b, m, v = sph["boundary"].name, sph["momentum"].name, sph["viscosity"].name
        if b not in _BOUNDARIES:
            raise ValueError(f"forces: boundary {b!r} has no wall particles that act through "
                             f"the momentum equation; forces works with "
                             f"{', '.join(_BOUNDARIES)}")
        if m not in _PRESSURE_FORMS:
            raise ValueError(f"forces: momentum {m!r} has no forces form (have "
                             f"{', '.join(_PRESSURE_FORMS)})")
        if v not in _VISCOUS_FORMS:
            raise ValueError(f"forces: viscosity {v!r} has no forces form (have "
                             f"{', '.join(_VISCOUS_FORMS)})")
        self.pform, self.vform = _PRESSURE_FORMS[m], _VISCOUS_FORMS[v]
        if not sph["boundary"].neighbour_kinds().get("viscousWetWall", True):
            self.vform = 0                      # free slip: no viscous pair with the wall
        self.alpha = float(getattr(sph["viscosity"].coeffs, "alpha", 0.0))
        self.body_ids: np.ndarray | None = None
        self.folder = Path(case.path) / "postProcessing" / self.object_name / start_time_name
        self.folder.mkdir(parents=True, exist_ok=True)
        self.file = self.folder / "force.dat"
        self.moment_file = self.folder / "moment.dat"
        cofr = self.coeffs.CofR or (0.0,) * ctx.dim
        self.cofr = np.zeros(3)
        self.cofr[:ctx.dim] = cofr
        span = "" if ctx.dim == 3 else " per metre of span (2-D)"
        self._fh = self.file.open("w")
        self._mh = self.moment_file.open("w")
        for fh, what in ((self._fh, f"Force (N){span}"),
                         (self._mh, f"Moment (N m){span} about CofR ("
                          + " ".join(f"{v:g}" for v in cofr) + ")")):
            fh.write(f"# {what} of the fluid on {' '.join(self.coeffs.patches)} "
                     f"({self.name}: {self.doc})\n# " + "\t".join(self.columns) + "\n")

    def body(self, state) -> np.ndarray:
        """Mask of the state's particles that are wall particles of the body."""
        wall = state.kind == WALL
        if "patch" in state.extra:
            return wall & np.isin(np.rint(state.extra["patch"]).astype(np.int64),
                                  self.patch_ids)
        if self.body_ids is None:
            from scipy.spatial import cKDTree

            ref, patch = wall_patches(self.case)
            pos = np.column_stack(state.positions[:self.ctx.dim])
            mine = np.zeros(len(pos), bool)
            if len(ref) and wall.any():
                d, j = cKDTree(ref).query(pos[wall])
                mine[np.flatnonzero(wall)] = (d <= 0.25 * self.ctx.dx) & \
                    np.isin(patch[j], self.patch_ids)
            self.body_ids = np.sort(state.id[mine])
            if not self.body_ids.size:
                raise ValueError(f"forces {self.object_name!r}: no wall particles of "
                                 f"{', '.join(self.coeffs.patches)} found")
            self._is_body = np.zeros(int(state.id.max()) + 1, bool)
            self._is_body[self.body_ids] = True
        ids = state.id
        known = ids < len(self._is_body)
        mine = np.zeros(len(ids), bool)
        mine[known] = self._is_body[ids[known]]
        return wall & mine

    def measure(self, state) -> np.ndarray:
        """(4, 3): pressure force, viscous force, pressure moment, viscous moment."""
        ctx, dim = self.ctx, self.ctx.dim
        kernel = self.case.models.sph["kernel"]
        eos = self.case.models.sph["equationOfState"]
        body = np.flatnonzero(self.body(state))
        if not body.size:
            return np.zeros((4, 3))
        reach = kernel.support * ctx.h
        fl, _, _ = fluid_arrays(state, dim, np.column_stack(
            [x[body] for x in state.positions[:dim]]), reach)
        if not fl.size:
            return np.zeros((4, 3))
        gamma = float(eos.coeffs.gamma)

        def arrays(sel):
            pos = np.zeros((len(sel), 3))
            vel = np.zeros_like(pos)
            for k, (x, u) in enumerate(zip(state.positions, state.velocities)):
                pos[:, k], vel[:, k] = x[sel], u[sel]
            rho = np.ascontiguousarray(state.rho[sel], dtype=float)
            c = ctx.c0 * (rho / ctx.rho0) ** (0.5 * (gamma - 1.0))    # T(3.29)
            return pos, vel, np.ascontiguousarray(state.m[sel], float), rho, \
                np.ascontiguousarray(state.p[sel], float), c

        wpos, wvel, wm, wrho, wp, wc = arrays(body)
        fpos, fvel, fm, frho, fp, fc = arrays(fl)
        cells = Cells(fpos, reach)
        o = cells.order
        gw = kernel.alpha(dim) / ctx.h ** (dim + 2)
        return _pair_forces(np.ascontiguousarray(wpos), np.ascontiguousarray(wvel), wm, wrho,
                            wp, wc, cells.pos, np.ascontiguousarray(fvel[o]), fm[o], frho[o],
                            fp[o], fc[o], cells.starts, cells.lo, cells.n, cells.size,
                            1.0 / ctx.h, gw, float(kernel.support), kernel.dfdq_q_jit,
                            self.pform, self.vform, self.alpha, ctx.h, ctx.eta2,
                            2.0 * ctx.rho0 * ctx.nu, self.cofr)

    def execute(self, sim):
        _current_pressure(sim)
        bnd = self.case.models.sph["boundary"]
        if hasattr(sim, "model_hook") and bnd.implements("before_passes"):
            # the wall velocities the pair passes see (mDBC with free slip), put back after
            sim.model_hook(bnd, "before_passes")
            r = self.measure(sim.state)
            sim.model_hook(bnd, "after_rates")
        else:
            r = self.measure(sim.state)
        for fh, p, v in ((self._fh, r[0], r[1]), (self._mh, r[2], r[3])):
            fh.write("\t".join(f"{x:.9g}" for x in (sim.time, *(p + v), *p, *v)) + "\n")
            fh.flush()

    def end(self) -> None:
        self._fh.close()
        self._mh.close()
