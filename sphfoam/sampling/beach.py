"""A solitary wave breaking on a beach (T ch. 5): the breaking point and surface profiles.

``breakingPoint`` finds when and where the wave breaks, by the thesis's definition (T §5.5.1:
"the breaking point, or the point at which the front face of the wave becomes vertical") or
by the kinematic criterion (the crest particles outrun the crest); ``surfaceProfiles`` writes
the free surface and the particles at chosen times (the shapes of T Figs 5.6-5.19), as
``.dat`` tables and PNG pictures. The metrics ``breakingTime`` and ``runUpPosition`` read
them (and ``runUp mode beach``) for ``system/metricsDict`` (sphfoam.study.beach_metrics).

Both objects read the fluid particles only and use the surface convention of
:mod:`sphfoam.sampling.waves` (a particle's cell top, y + dx/2, is the surface).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Literal

import numpy as np
from numba import njit
from pydantic import Field, field_validator, model_validator

from sphfoam.io.tables import join_series, start_folders
from sphfoam.registry import register
from sphfoam.sampling.base import FunctionObject, FunctionObjectCoeffs
from sphfoam.sampling.waves import (GAUGE_WINDOW, _fluid, _label, crest, fraction_surface,
                                    surface_elevation)


def _as_list(v):
    return [v] if isinstance(v, (int, float)) else v


# --- the front face ------------------------------------------------------------------------
@njit(cache=True)
def _face_fronts(xs, ys, levels, x_crest, half_band, gap):
    """Front of the wave at each height: for each level y_k, the particles (x-sorted ``xs``,
    ``ys``) with |y - y_k| <= ``half_band`` are walked forwards from the first one at or
    beyond x_crest - gap while consecutive ones are at most ``gap`` apart; the last one's x
    is the face at that height (NaN with no particle in the band near the crest).  The walk
    stops at the first gap, so water further ahead (the shoreline) is not taken for the
    face."""
    nl = levels.size
    out = np.full(nl, np.nan)
    for k in range(nl):
        last = np.nan
        for i in range(xs.size):
            if abs(ys[i] - levels[k]) > half_band or xs[i] < x_crest - gap:
                continue
            if math.isnan(last):
                last = xs[i]
            elif xs[i] - last <= gap:
                last = xs[i]
            else:
                break
        out[k] = last
    return out


def face_fronts(x, y, levels, x_crest, dx, *, gap: float = 2.0):
    """x of the wave's front face at each height of ``levels`` (see :func:`_face_fronts`),
    from the fluid particles (x, y); bands of +-dx/2 around each level, ``gap`` in dx."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    return _face_fronts(np.ascontiguousarray(x[order]),
                        np.ascontiguousarray(np.asarray(y, dtype=float)[order]),
                        np.ascontiguousarray(np.asarray(levels, dtype=float)),
                        float(x_crest), 0.5 * dx * (1 + 1e-9), gap * dx)


def face_angle(levels, fronts) -> float:
    """Angle (degrees) of the front face to the horizontal, from the least-squares line
    x_front = a + s y through the (level, front) pairs: atan2(1, -s); 90 when the face is
    vertical (s = 0), above 90 when it overhangs (s > 0, the crest ahead of its foot), NaN
    with fewer than 2 finite fronts."""
    lv, fr = np.asarray(levels, float), np.asarray(fronts, float)
    ok = np.isfinite(fr)
    if ok.sum() < 2 or np.ptp(lv[ok]) == 0:
        return float("nan")
    s = np.polyfit(lv[ok], fr[ok], 1)[0]
    return math.degrees(math.atan2(1.0, -s))


@njit(cache=True)
def _crest_speed(xs, ys, us, x_lo, x_hi, y_lo):
    """Largest horizontal velocity of the particles with x_lo <= x <= x_hi and y >= y_lo and
    the x of that particle (-inf, NaN with none)."""
    best, where = -np.inf, np.nan
    for i in range(xs.size):
        if xs[i] >= x_lo and xs[i] <= x_hi and ys[i] >= y_lo and us[i] > best:
            best, where = us[i], xs[i]
    return best, where


# --- breakingPoint -----------------------------------------------------------------------------
@register
class BreakingPoint(FunctionObject):
    """When and where a wave breaks: its front face turns vertical (T §5.5.1) or its crest
    particles outrun the crest (the kinematic criterion).

    Each sample reads the surface by wave gauges (T §4.3.2) every ``spacing`` (default dx)
    over ``xMin``..``xMax`` and finds the crest (x_c, eta_c) as ``crestTracker`` does.
    *Geometric* (the thesis's definition): the front face is the forward edge of the water at
    heights ``still + f eta_c`` for f from ``faceFrom`` to ``faceTo`` (levels dx/2 apart,
    bands of +-dx/2, walked forwards from the crest until a gap of 2 dx; no level below
    still + 1.5 dx, whose band would reach the still water ahead, and no angle when that
    leaves less than dx of face: a wave must stand about 3 dx high); its angle to the
    horizontal is that of the least-squares line through them, and the wave breaks when it
    first reaches ``angle`` (90°: vertical; the front of a shoaling wave steepens from below
    90° and overhangs, above 90°, once it plunges). *Kinematic*: the largest horizontal
    velocity u of the particles in the top ``crestDepth`` of the crest (x_c - 2 dx to the
    face) reaches ``ratio`` times the crest celerity c = dx_c/dt (least squares over the
    last ``celerityWindow`` seconds, 0.25); u/c = 1 is the classical kinematic breaking criterion
    (e.g. Perlin, Choi & Tian 2013, Annu. Rev. Fluid Mech. 45). Both are evaluated and
    written; ``criterion`` says which one defines the breaking point. Only samples with
    eta_c >= ``minHeight`` and x_c >= ``after`` count, and a criterion must hold in every
    counted sample for ``persist`` seconds (0.05) from its first: the breaking point is that
    first sample.

    Output: ``<name>.dat`` (time, x_c, eta_c, face x, face angle, u of the crest, c, u/c) and
    ``summary.dat``, written when the wave breaks and at the end: its time and x (the face's
    top for geometric, the fastest particle for kinematic), eta_c, the time the crest passed
    ``toe`` (interpolated) and the time from there to breaking (T: 1.96 s in the laboratory,
    T §5.5.1), for both criteria.
    """

    name = "breakingPoint"
    doc = "when and where a wave breaks: its front face turns vertical (T §5.5.1) or its " \
          "crest particles outrun the crest (kinematic criterion)"
    columns = ("time", "xCrest", "etaCrest", "xFace", "faceAngle", "uCrest", "c", "uOverC")
    summary_columns = ("criterion", "time", "x", "etaCrest", "tToe", "toeToBreaking")

    class Coeffs(FunctionObjectCoeffs):
        xMin: float = Field(description="first gauge of the surface (m), e.g. the toe gauge")
        xMax: float = Field(description="last gauge of the surface (m), e.g. the top of the "
                            "beach")
        still: float = Field(0.0, description="still-water level (m): eta = surface y - still")
        spacing: float | None = Field(None, gt=0, description="gauge spacing (m); default dx")
        criterion: Literal["geometric", "kinematic"] = Field("geometric", description=(
            "`geometric`: the front face first reaches `angle` (T §5.5.1: vertical); "
            "`kinematic`: the crest particles' u first reaches `ratio` c"))
        angle: float = Field(90.0, gt=45.0, lt=180.0, description=(
            "face angle to the horizontal (degrees) at which the wave breaks, geometric"))
        faceFrom: float = Field(0.5, gt=0.0, lt=1.0, description=(
            "lowest level of the front face, as a fraction of eta_c above still"))
        faceTo: float = Field(0.9, gt=0.0, lt=1.0, description=(
            "highest level of the front face, as a fraction of eta_c above still"))
        ratio: float = Field(1.0, gt=0.0, description=(
            "u/c at which the wave breaks, kinematic"))
        crestDepth: float = Field(0.1, gt=0.0, lt=1.0, description=(
            "the crest particles: those above still + (1 - crestDepth) eta_c, kinematic"))
        celerityWindow: float = Field(0.25, gt=0.0, description=(
            "time (s) over which the crest celerity dx_c/dt is fitted (the crest's x jumps "
            "by a fraction of dx from sample to sample: over 0.1 s c scatters by 50 % at "
            "d/dx = 10)"))
        minHeight: float | None = Field(None, ge=0.0, description=(
            "only samples with eta_c at least this (m) count; default 3 dx"))
        after: float = Field(-math.inf, description=(
            "only samples with the crest at x_c >= after (m) count, e.g. the toe"))
        toe: float | None = Field(None, description=(
            "x (m) of the gauge the breaking time is measured from (T: 0.15 m before the "
            "toe); default xMin"))
        persist: float = Field(0.05, ge=0.0, description=(
            "time (s) a criterion must hold, in every counted sample, for its first sample "
            "to be the breaking point (0: the first sample alone). A breaking wave stays "
            "broken; a crest that stalls for a moment over the toe (its fitted celerity "
            "collapsing for 0.01-0.03 s: u/c passed 1 there in 4 of the beach study's 5 "
            "finished variants at d/dx = 10) or a noisy face reading does not"))

        @model_validator(mode="after")
        def _check(self):
            if self.xMax <= self.xMin:
                raise ValueError("xMax must be greater than xMin")
            if self.faceTo <= self.faceFrom:
                raise ValueError("faceTo must be greater than faceFrom")
            return self

    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        self.samples: list[tuple[float, float, float]] = []      # (t, x_c, eta_c)
        self.found: dict[str, tuple[float, float, float]] = {}
        #: a criterion met since (t, x, eta_c), not yet for `persist` seconds
        self.pending: dict[str, tuple[float, float, float]] = {}
        self.summary_file = self.folder / "summary.dat"
        self._resume(float(start_time_name))

    def _resume(self, start: float) -> None:
        """A restarted run carries on from what the run before it wrote: its rows up to the
        start time (older folders' rows before the next folder's start) give the samples
        (the toe time and the celerity window) and the criteria's state, replayed sample by
        sample; the kinematic x, which the rows do not hold, comes from that run's summary.
        The rows hold 9 significant digits, so the carried state matches an unbroken run's
        to that rounding."""
        if start <= 0.0:
            return
        folders = [(t, p) for t, p in start_folders(Path(self.case.path), self.object_name)
                   if t < start * (1 - 1e-12)
                   and (p / f"{self.object_name}.dat").is_file()]
        if not folders:
            return
        fast: dict[float, float] = {}
        for _, folder in folders:
            summary = folder / "summary.dat"
            if summary.is_file():
                kin = read_breaking(summary).get("kinematic", {})
                if math.isfinite(kin.get("time", math.nan)):
                    fast[round(kin["time"], 6)] = kin["x"]
        cols, rows = join_series(folders, f"{self.object_name}.dat")
        if cols != list(self.columns):
            return
        for t, xc, ec, xface, ang, _u, _c, ratio in rows[rows[:, 0] <= start * (1 + 1e-12)]:
            self.samples.append((float(t), float(xc), float(ec)))
            self._advance(float(t), float(xc), float(ec), float(xface), float(ang),
                          float(ratio), fast.get(round(float(t), 6), math.nan))

    # --- one sample ---------------------------------------------------------------------
    def measure(self, xf, yf, uf, time):
        """(x_c, eta_c, x_face, angle, u_crest, x_fast, c) of the fluid particles."""
        c, dx = self.coeffs, self.ctx.dx
        step = c.spacing or dx
        gx = c.xMin + step * np.arange(int(math.floor((c.xMax - c.xMin) / step + 1e-9)) + 1)
        nan7 = (math.nan,) * 7
        if xf.size == 0:
            return nan7
        eta = surface_elevation(xf, yf, gx, dx, still=c.still, window=GAUGE_WINDOW)
        xc, ec = crest(gx, eta)
        if not (math.isfinite(xc) and math.isfinite(ec)) or ec <= 0.0:
            return (xc, ec) + (math.nan,) * 5
        # levels of the face, dx/2 apart between faceFrom and faceTo of the crest height
        # (the particle + dx/2 surface convention: a particle at y stands for y + dx/2)
        # no band may reach the still water ahead (its top row reads still +- dx/2): the
        # levels start at least 1.5 dx above still; a face less than dx high is not measured
        lo, hi = c.still + max(c.faceFrom * ec, 1.5 * dx), c.still + c.faceTo * ec
        if hi - lo >= dx * (1 - 1e-9):
            levels = np.linspace(lo, hi, int(math.floor((hi - lo) / (0.5 * dx) + 1e-9)) + 1)
            fronts = face_fronts(xf, yf + 0.5 * dx, levels, xc, dx)
            ang = face_angle(levels, fronts)
        else:
            levels, fronts, ang = np.array([hi]), np.array([math.nan]), math.nan
        xface = float(fronts[np.isfinite(fronts)][-1]) if np.isfinite(fronts).any() \
            else math.nan
        ahead = np.nanmax(fronts) if np.isfinite(fronts).any() else xc
        ucrest, xfast = _crest_speed(np.ascontiguousarray(xf), np.ascontiguousarray(yf),
                                     np.ascontiguousarray(uf), xc - 2.0 * dx, ahead + dx,
                                     c.still + (1.0 - c.crestDepth) * ec - 0.5 * dx)
        if not math.isfinite(ucrest):
            ucrest = math.nan
        return xc, ec, xface, ang, float(ucrest), float(xfast), self.celerity(time, xc)

    def celerity(self, t: float, xc: float) -> float:
        """dx_c/dt: the slope of the least-squares line through x_c of this sample and of
        the earlier ones within celerityWindow whose crest stood at least minHeight (NaN
        until that window holds data)."""
        if not math.isfinite(xc):
            return math.nan
        w = self.coeffs.celerityWindow
        if not self.samples or t - self.samples[0][0] < w * (1 - 1e-9):
            return math.nan
        pts = [(t0, x0) for t0, x0, e0 in self.samples
               if t - t0 <= w * (1 + 1e-9) and math.isfinite(x0) and e0 >= self.min_height]
        pts.append((t, xc))
        tt, xx = np.array(pts).T
        return float(np.polyfit(tt, xx, 1)[0]) if np.ptp(tt) > 0 else math.nan

    def execute(self, sim):
        st, f = _fluid(sim)
        t = float(sim.time)
        xc, ec, xface, ang, ucrest, xfast, cel = self.measure(st.x[f], st.y[f], st.u[f], t)
        self.samples.append((t, xc, ec))
        ratio = ucrest / cel if (math.isfinite(cel) and cel > 0 and math.isfinite(ucrest)) \
            else math.nan
        self.write_row((t, xc, ec, xface, ang, ucrest, cel, ratio))
        if self._advance(t, xc, ec, xface, ang, ratio, xfast):
            self.write_summary()

    def _advance(self, t, xc, ec, xface, ang, ratio, xfast) -> bool:
        """The criteria at one sample: each must hold in every counted sample for `persist`
        seconds from its first, which is then the breaking point. True when one was found
        at this sample."""
        c = self.coeffs
        counts = math.isfinite(ec) and ec >= self.min_height and xc >= c.after
        met = {"geometric": (counts and math.isfinite(ang) and ang >= c.angle - 1e-6,
                             (t, xface, ec)),
               "kinematic": (counts and math.isfinite(ratio) and ratio >= c.ratio,
                             (t, xfast, ec))}
        new = False
        for crit, (ok, where) in met.items():
            if crit in self.found:
                continue
            if not ok:
                self.pending.pop(crit, None)          # it did not hold: start again
                continue
            first = self.pending.setdefault(crit, where)
            if t - first[0] >= c.persist * (1 - 1e-9):
                self.found[crit] = first
                new = True
        return new

    # --- the summary --------------------------------------------------------------------
    @property
    def min_height(self) -> float:
        c = self.coeffs
        return c.minHeight if c.minHeight is not None else 3.0 * self.ctx.dx

    def toe_time(self) -> float:
        """Time the crest (eta_c >= minHeight) first passed x = toe (linear between the
        samples either side)."""
        xt = self.coeffs.toe if self.coeffs.toe is not None else self.coeffs.xMin
        s = [(t, x) for t, x, e in self.samples if math.isfinite(x) and e >= self.min_height]
        for (t0, x0), (t1, x1) in zip(s[:-1], s[1:]):
            if x0 < xt <= x1:
                return t0 + (t1 - t0) * (xt - x0) / (x1 - x0)
        return math.nan

    def write_summary(self) -> None:
        c = self.coeffs
        xt = c.toe if c.toe is not None else c.xMin
        tt = self.toe_time()
        with self.summary_file.open("w") as fh:
            fh.write(f"# {self.object_name} ({self.name}): the breaking point by the "
                     f"{c.criterion} criterion first (geometric: the front face reaches "
                     f"{c.angle:g} degrees, T §5.5.1; kinematic: u of the crest reaches "
                     f"{c.ratio:g} c); tToe: the crest passes x = {xt:g}; toeToBreaking = "
                     "time - tToe; NaN: not found\n")
            fh.write("# " + "\t".join(self.summary_columns) + "\n")
            order = [c.criterion] + [k for k in ("geometric", "kinematic") if k != c.criterion]
            for k in order:
                t, x, e = self.found.get(k, (math.nan,) * 3)
                fh.write("\t".join([k] + [f"{v:.9g}" for v in (t, x, e, tt, t - tt)]) + "\n")

    def end(self):
        super().end()
        self.write_summary()


def read_breaking(path) -> dict[str, dict[str, float]]:
    """The rows of a breakingPoint's ``summary.dat``: {criterion: {column: value}} (first
    row first)."""
    out: dict[str, dict[str, float]] = {}
    cols = None
    for line in open(path):
        if line.startswith("#"):
            cols = line[1:].split()
            continue
        parts = line.split()
        if parts and cols:
            out[parts[0]] = {k: float(v) for k, v in zip(cols[1:], parts[1:])}
    return out


# --- surfaceProfiles ---------------------------------------------------------------------------
@njit(cache=True)
def _window(xs, ys, x_lo, x_hi, y_lo, y_hi):
    """Mask of the points inside the box [x_lo, x_hi] x [y_lo, y_hi]."""
    out = np.zeros(xs.size, dtype=np.bool_)
    for i in range(xs.size):
        out[i] = xs[i] >= x_lo and xs[i] <= x_hi and ys[i] >= y_lo and ys[i] <= y_hi
    return out


@register
class SurfaceProfiles(FunctionObject):
    """Free-surface profiles eta(x) and the particles at chosen times (T Figs 5.6-5.19).

    At the first step at or after each of ``times``: the surface read by wave gauges every
    ``spacing`` (default dx/2) over ``xMin``..``xMax`` (T §4.3.2, the highest particle + dx/2;
    ``surface fraction``: the SPH fluid fraction 1/2, sub-particle), written to
    ``postProcessing/<name>/<time>/profile.dat`` (x, eta, surface y), the fluid particles
    of that window to ``particles.dat`` (x, y, Ux, Uy, p: an overturning jet, which no
    single-valued eta(x) shows) and, with ``plot yes``, ``profile.png``: the particles
    coloured by |U| with the walls grey and the surface line, as the thesis draws them.
    """

    name = "surfaceProfiles"
    doc = "free-surface profile eta(x), the particles and a PNG at chosen times " \
          "(T Figs 5.6-5.19)"
    columns = ("time", "requested", "etaMax", "xEtaMax")

    class Coeffs(FunctionObjectCoeffs):
        times: list[float] = Field(min_length=1, description=(
            "times (s) of the profiles, e.g. `(5.5 6 6.5)` (the first step at or after each)"))
        xMin: float = Field(description="left end of the profile (m)")
        xMax: float = Field(description="right end of the profile (m)")
        yMin: float | None = Field(None, description=(
            "bottom of the picture and of particles.dat (m); default the lowest fluid "
            "particle of the window"))
        yMax: float | None = Field(None, description=(
            "top of the picture and of particles.dat (m); default above the highest"))
        spacing: float | None = Field(None, gt=0, description="gauge spacing (m); default dx/2")
        still: float = Field(0.0, description="still-water level (m): eta = surface y - still")
        surface: Literal["particle", "fraction"] = Field("particle", description=(
            "`particle`: the highest particle + dx/2 (T §4.3.2); `fraction`: the SPH fluid "
            "fraction crosses 1/2 (sub-particle)"))
        plot: bool = Field(True, description="also write profile.png (matplotlib)")

        @field_validator("times", mode="before")
        @classmethod
        def _one(cls, v):
            return _as_list(v)

        @model_validator(mode="after")
        def _check(self):
            if self.xMax <= self.xMin:
                raise ValueError("xMax must be greater than xMin")
            return self

    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        try:
            t0 = float(start_time_name)
        except ValueError:
            t0 = 0.0
        self.pending = sorted(t for t in self.coeffs.times if t >= t0 - 1e-9 * max(1, abs(t0)))
        self.precision = int(getattr(getattr(case, "control", None), "timePrecision", 6) or 6)

    def due(self, sim, wrote: bool, previous_time: float | None = None) -> bool:
        return bool(self.pending) and sim.time >= self.pending[0] - 1e-9 * max(1, sim.time)

    def execute(self, sim):
        eps = 1e-9 * max(1.0, sim.time)
        if not self.pending or sim.time < self.pending[0] - eps:
            return                               # (sphfoam sample executes every time)
        requested = self.pending.pop(0)
        while self.pending and sim.time >= self.pending[0] - eps:
            self.pending.pop(0)
        self.sample(sim, requested)

    def profile(self, st, f) -> tuple[np.ndarray, np.ndarray]:
        """(x, eta) of the surface along the window."""
        c, dx = self.coeffs, self.ctx.dx
        step = c.spacing or 0.5 * dx
        gx = c.xMin + step * np.arange(int(math.floor((c.xMax - c.xMin) / step + 1e-9)) + 1)
        xf, yf = st.x[f], st.y[f]
        if xf.size == 0:
            return gx, np.full(gx.size, np.nan)
        if c.surface == "fraction":
            eta = fraction_surface(xf, yf, st.m[f] / st.rho[f], gx,
                                   self.case.models.sph["kernel"], self.ctx.h, dx,
                                   still=c.still)
        else:
            eta = surface_elevation(xf, yf, gx, dx, still=c.still)
        return gx, eta

    def sample(self, sim, requested: float) -> None:
        from sphfoam.case.times import time_name

        c = self.coeffs
        st, f = _fluid(sim)
        gx, eta = self.profile(st, f)
        ok = np.isfinite(eta)
        j = int(np.argmax(np.where(ok, eta, -np.inf))) if ok.any() else 0
        self.write_row((sim.time, requested, eta[j] if ok.any() else math.nan, gx[j]))
        folder = self.folder / time_name(float(sim.time), self.precision)
        folder.mkdir(parents=True, exist_ok=True)
        with (folder / "profile.dat").open("w") as fh:
            fh.write(f"# {self.object_name} ({self.name}) at time {sim.time:.9g} (requested "
                     f"{requested:g}): free surface by {c.surface}, eta = y - {c.still:g}\n")
            fh.write("# x\teta\ty\n")
            for x, e in zip(gx, eta):
                fh.write(f"{x:.9g}\t{e:.9g}\t{e + c.still:.9g}\n")
        x, y = st.x, st.y
        ylo = c.yMin if c.yMin is not None else -math.inf
        yhi = c.yMax if c.yMax is not None else math.inf
        inside = _window(np.ascontiguousarray(x), np.ascontiguousarray(y), c.xMin, c.xMax,
                         ylo, yhi)
        fl = inside & f
        with (folder / "particles.dat").open("w") as fh:
            fh.write(f"# {self.object_name} ({self.name}) at time {sim.time:.9g}: the fluid "
                     f"particles with {c.xMin:g} <= x <= {c.xMax:g}\n")
            fh.write("# x\ty\tUx\tUy\tp\n")
            np.savetxt(fh, np.column_stack([x[fl], y[fl], st.u[fl], st.v[fl], st.p[fl]]),
                       fmt="%.9g", delimiter="\t")
        if c.plot:
            self.picture(folder / "profile.png", st, inside, f, gx, eta, sim.time)

    def picture(self, png, st, inside, f, gx, eta, time) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        c, dx = self.coeffs, self.ctx.dx
        fig, ax = plt.subplots(figsize=(10, 3.6))
        w = inside & ~f
        fl = inside & f
        s = max(0.5, min(20.0, (72.0 * 10.0 * dx / (c.xMax - c.xMin)) ** 2))
        if w.any():
            ax.scatter(st.x[w], st.y[w], s=s, c="0.6", lw=0, label="walls")
        if fl.any():
            sc = ax.scatter(st.x[fl], st.y[fl], s=s, c=np.hypot(st.u[fl], st.v[fl]),
                            cmap="viridis", lw=0)
            fig.colorbar(sc, ax=ax, label="|U| (m/s)", pad=0.01)
        ax.plot(gx, eta + c.still, "r-", lw=0.8, label=f"surface ({c.surface})")
        ax.axhline(c.still, color="k", ls=":", lw=0.6)
        ax.set(xlabel="x (m)", ylabel="y (m)", xlim=(c.xMin, c.xMax),
               title=f"{self.object_name}: t = {time:.4g} s")
        if fl.any():
            lo = c.yMin if c.yMin is not None else float(st.y[fl].min()) - 2 * dx
            hi = c.yMax if c.yMax is not None else float(np.nanmax(eta) + c.still) + 4 * dx
            ax.set_ylim(lo, hi)
        ax.legend(fontsize=7, loc="upper left")
        fig.tight_layout()
        fig.savefig(png, dpi=110)
        plt.close(fig)
