"""Velocity profiles across a channel against start-up theory (T §3.4.1, §3.5.1).

``velocityProfile`` bins the fluid particles in y (bins of width dx centred on the particle
rows between the walls) and averages u_x in each bin at the requested times and at the end of
the run (optionally also over the steps of a time window before each). It writes

* ``postProcessing/<name>/<startTime>/<name>.dat``: one row per bin, columns y, then u and
  the theory at each sampled time; the header records, per time, the centreline velocity
  (u_max of Poiseuille flow) against theory and the largest profile error;
* ``postProcessing/<name>/<startTime>/uMax.dat``: the same errors, one row per sampled time;
* ``<name>.png`` at the end: SPH against theory at the sampled times, like T Figs 3.3-3.9
  (with ``theory logLaw`` also the velocity-deficit plot of T Fig 3.15).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from sphfoam.engine.state import FLUID
from sphfoam.registry import Coeffs, register
from sphfoam.reference import channel_theory as ct
from sphfoam.sampling.base import FunctionObject

_SUMMARY_COLUMNS = ("time", "uCentre", "uCentreTheory", "centreError%", "uMaxBins",
                    "uMaxBinsTheory", "maxError%", "profileError%")


@register
class VelocityProfile(FunctionObject):
    """u_x(y) across a channel between walls at ``y0`` and ``y0 + l``, binned by particle rows.

    With ``theory poiseuille`` the profiles are compared with the start-up series T(3.42)
    (body force ``F``, viscosity ``nu``), with ``couette`` with T(3.46) (top wall at ``u0``),
    with ``logLaw`` with the velocity-deficit law of a turbulent channel (T Fig 3.15,
    matched to the SPH centreline velocity) with u* from the force balance: each wall
    carries half the body force on the fluid, u*^2 = F M / (2 rho0 L) for a channel periodic
    over L in x holding the fluid mass M per unit depth (F l/2 when the fluid fills l), or
    u*^2 = F l/2 when it is not periodic.
    The centreline velocity is the quadratic through the three bins nearest the centre, so
    it is u_max of Poiseuille flow whatever the parity of the number of rows.
    """

    name = "velocityProfile"
    doc = ("u_x(y) across a channel at given times against the start-up series T(3.42) "
           "(Poiseuille), T(3.46) (Couette) or the log law (T §3.5.1)")
    columns = ("y",)

    class Coeffs(Coeffs):
        times: list[float] = Field(default_factory=list, description=(
            "times at which to sample, e.g. `(2 5 10 20)` (the first step at or after each; "
            "the theory is evaluated at the time actually sampled); the end of the run is "
            "always sampled too"))
        y0: float = Field(0.0, description="y of the bottom wall (m)")
        l: float = Field(gt=0, description="channel width (m): the top wall is at y0 + l")
        binWidth: float | None = Field(None, gt=0, description=(
            "width of the y bins (m); default dx, one bin per initial particle row"))
        theory: Literal["poiseuille", "couette", "logLaw", "none"] = Field(
            "none", description="analytical profile to compare with: start-up Poiseuille "
            "T(3.42), start-up Couette T(3.46), velocity-deficit law (T Fig 3.15) or none")
        F: float | None = Field(None, description=(
            "driving force per unit mass (m/s^2); default: the x component of constant/g"))
        nu: float | None = Field(None, ge=0, description=(
            "kinematic viscosity (m^2/s) of the theory; default: nu of "
            "constant/transportProperties"))
        u0: float = Field(0.0, description="velocity of the top wall (m/s), theory couette")
        kappa: float = Field(ct.KAPPA, gt=0, description="von Karman constant, theory logLaw")
        window: float = Field(0.0, ge=0, description=(
            "average the profile over every step of the last `window` seconds before each "
            "sampled time (for unsteady, e.g. turbulent, flows); 0: the instantaneous profile"))
        plot: bool = Field(True, description="at the end of the run, save `<name>.png` "
                           "comparing the profiles with the theory")

        @field_validator("times", mode="before")
        @classmethod
        def _one(cls, v):
            return [v] if isinstance(v, (int, float)) else v

        @model_validator(mode="after")
        def _check(self):
            if self.theory == "couette" and self.u0 == 0:
                raise ValueError("theory couette needs the top-wall velocity u0")
            return self

    # --- run-time ------------------------------------------------------------------------
    def start(self, case, ctx, start_time_name):
        super().start(case, ctx, start_time_name)
        self._fh.close()                       # the table is rewritten after every sample
        c = self.coeffs
        self.F = float(c.F) if c.F is not None else float(ctx.g[0])
        self.nu = float(c.nu) if c.nu is not None else float(ctx.nu)
        if c.theory == "poiseuille" and self.nu <= 0:
            raise ValueError(f"{self.object_name}: theory poiseuille needs nu > 0")
        self.w = float(c.binWidth or ctx.dx)
        self.edges = self.yc = None            # aligned with the particle rows at the first sample
        self.us_theory = ct.friction_velocity(self.F, c.l)     # until the first sample
        try:
            t0 = float(start_time_name)
        except ValueError:
            t0 = 0.0
        eps = 1e-9 * max(1.0, abs(t0))
        end = getattr(getattr(case, "control", None), "endTime", None)
        self.pending = sorted({t for t in list(c.times) + ([end] if end is not None else [])
                               if t >= t0 - eps})
        self.samples: list[dict] = []
        self.sim = None
        self._acc = self._acc_n = None           # running sums of the averaging window
        self.summary_file = self.folder / "uMax.dat"

    def _eps(self, t: float) -> float:
        return 1e-9 * max(1.0, abs(t))

    def due(self, sim, wrote: bool, previous_time: float | None = None) -> bool:
        """Every step of the averaging window before each requested time (a function of the
        simulated time alone, so a restart samples the same steps)."""
        return bool(self.pending) and \
            sim.time >= self.pending[0] - self.coeffs.window - self._eps(sim.time)

    def execute(self, sim):
        self.sim = sim
        if not self.pending:
            return
        eps = self._eps(sim.time)
        if sim.time >= self.pending[0] - eps:
            requested = self.pending.pop(0)
            while self.pending and sim.time >= self.pending[0] - eps:
                self.pending.pop(0)           # several sample times within one step
            self.sample(sim, requested)
            self.write()
        elif self.coeffs.window > 0 and sim.time >= self.pending[0] - self.coeffs.window - eps:
            self._accumulate(sim.state)

    def _accumulate(self, state):
        if self.yc is None:
            self.make_bins(state)
        u, _ = self.profile(state)
        ok = np.isfinite(u)
        if self._acc is None:
            self._acc, self._acc_n = np.zeros(u.shape), np.zeros(u.shape)
        self._acc += np.where(ok, u, 0.0)
        self._acc_n += ok

    def end(self):
        sim = self.sim
        if sim is not None and (not self.samples or
                                abs(self.samples[-1]["time"] - sim.time) > 1e-12 * max(1.0, sim.time)):
            self.sample(sim, None)
        self.write()
        if self.coeffs.plot and self.samples:
            self.plot()

    # --- sampling --------------------------------------------------------------------------
    def make_bins(self, state) -> None:
        """Bins of width w centred on the rows of the particle lattice: the offset of the rows
        from y0 (in units of w, a circular mean over the fluid particles) is dx/2 when the
        fluid fills the cell centres of 0 < y < l, 0 when the rows sit at k dx (wall rows on
        the wall lines, as in the thesis); every bin centre lies inside the channel, at least
        w/4 from a wall."""
        c, w = self.coeffs, self.w
        y = state.y[state.kind == FLUID]
        dom = getattr(getattr(self.case, "particles", None), "domain", None)
        if dom is not None and "x" in dom.periodic:
            mass = float(np.sum(state.m[state.kind == FLUID]))
            self.us_theory = math.sqrt(abs(self.F) * mass /
                                       (2.0 * self.ctx.rho0 * (dom.max[0] - dom.min[0])))
        inside = (y > c.y0) & (y < c.y0 + c.l)
        phase = 2.0 * np.pi * (y[inside] - c.y0) / w
        s = (math.atan2(np.sin(phase).mean(), np.cos(phase).mean()) / (2.0 * np.pi)) % 1.0 \
            if inside.any() else 0.5
        j = np.arange(-1, int(c.l / w) + 2)
        yc = c.y0 + (s + j) * w
        self.yc = yc[(yc > c.y0 + 0.25 * w) & (yc < c.y0 + c.l - 0.25 * w)]
        self.edges = np.concatenate([self.yc - 0.5 * w, self.yc[-1:] + 0.5 * w])

    def profile(self, state) -> tuple[np.ndarray, np.ndarray]:
        """Mean u_x of the fluid particles in each bin (NaN where a bin is empty), count."""
        f = state.kind == FLUID
        y, u = state.y[f], state.u[f]
        k = np.searchsorted(self.edges, y, side="right") - 1
        ok = (k >= 0) & (k < self.yc.size)
        cnt = np.bincount(k[ok], minlength=self.yc.size).astype(float)
        s = np.bincount(k[ok], weights=u[ok], minlength=self.yc.size)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(cnt > 0, s / np.maximum(cnt, 1), np.nan), cnt

    def theory(self, y, t, u_centre: float | None = None) -> np.ndarray | None:
        c = self.coeffs
        y = np.asarray(y, float) - c.y0
        if c.theory == "poiseuille":
            return ct.poiseuille(y, t, self.F, self.nu, c.l)
        if c.theory == "couette":
            return ct.couette(y, t, c.u0, self.nu, c.l)
        if c.theory == "logLaw" and u_centre is not None:
            return ct.velocity_deficit(y, u_centre, self.us_theory, c.l, c.kappa)
        return None

    def scale(self) -> float:
        """Velocity the profile errors are measured against."""
        c = self.coeffs
        if c.theory == "poiseuille":
            return ct.poiseuille_umax(self.F, self.nu, c.l)
        if c.theory == "couette":
            return abs(c.u0)
        return float("nan")

    def centre(self, u) -> float:
        """u at y0 + l/2: the quadratic through the three valid bins nearest the centre."""
        c = self.coeffs
        ym = c.y0 + 0.5 * c.l
        ok = np.flatnonzero(np.isfinite(u))
        if ok.size == 0:
            return float("nan")
        if ok.size < 3:
            return float(u[ok[np.argmin(abs(self.yc[ok] - ym))]])
        near = ok[np.argsort(abs(self.yc[ok] - ym), kind="stable")[:3]]
        coef = np.polyfit((self.yc[near] - ym) / c.l, u[near], 2)
        return float(coef[-1])

    def sample(self, sim, requested):
        c = self.coeffs
        t = float(sim.time)
        if self.yc is None:
            self.make_bins(sim.state)
        u, cnt = self.profile(sim.state)
        steps = 1
        if self._acc is not None:             # the mean over the window, this step included
            ok = np.isfinite(u)
            n = self._acc_n + ok
            steps = int(self._acc_n.max()) + 1
            with np.errstate(invalid="ignore", divide="ignore"):
                u = np.where(n > 0, (self._acc + np.where(ok, u, 0.0)) / np.maximum(n, 1),
                             np.nan)
            self._acc = self._acc_n = None
        uc = self.centre(u)
        th = self.theory(self.yc, t, uc)
        rec = {"time": t, "requested": requested, "u": u, "count": cnt, "theory": th,
               "uCentre": uc, "steps": steps}
        ok = np.isfinite(u)
        if th is not None and c.theory != "logLaw":
            thc = float(self.theory([c.y0 + 0.5 * c.l], t)[0])
            umax_i = int(np.nanargmax(np.where(ok, u, -np.inf))) if ok.any() else 0
            rec.update(uCentreTheory=thc,
                       centreError=100.0 * (uc - thc) / thc if thc else float("nan"),
                       uMaxBins=float(u[umax_i]), uMaxBinsTheory=float(np.max(th[ok])),
                       profileError=100.0 * float(np.max(np.abs(u[ok] - th[ok]))) / self.scale())
            rec["maxError"] = 100.0 * (rec["uMaxBins"] - rec["uMaxBinsTheory"]) / \
                rec["uMaxBinsTheory"] if rec["uMaxBinsTheory"] else float("nan")
        if c.theory == "logLaw":
            rec.update(self._log_fit(u))
        self.samples.append(rec)

    def _log_fit(self, u) -> dict:
        """u* from the slope of u against ln(eta / (l/2)) (the first row at each wall, the
        bins within 1.5 w of it, omitted, as in T Fig 3.15), both halves of the channel
        together."""
        c = self.coeffs
        eta = np.minimum(self.yc - c.y0, c.y0 + c.l - self.yc)
        sel = np.isfinite(u) & (eta > 1.5 * self.w)
        out = {"uStarTheory": self.us_theory, "uStarFit": float("nan")}
        if np.count_nonzero(sel) >= 3:
            slope = np.polyfit(np.log(eta[sel] / (0.5 * c.l)), u[sel], 1)[0]
            out["uStarFit"] = float(c.kappa * slope)
        return out

    # --- output ------------------------------------------------------------------------------
    def _label(self, rec) -> str:
        return f"{rec['time']:.6g}"

    def header_lines(self) -> list[str]:
        c = self.coeffs
        lines = [f"# {self.name}: {self.doc}"]
        if c.theory == "poiseuille":
            lines.append(f"# theory poiseuille T(3.42): F = {self.F:g} m/s^2, nu = {self.nu:g} "
                         f"m^2/s, l = {c.l:g} m, y0 = {c.y0:g} m, steady u_max = "
                         f"{self.scale():.6g} m/s (T(3.41))")
        elif c.theory == "couette":
            lines.append(f"# theory couette T(3.46): u0 = {c.u0:g} m/s, nu = {self.nu:g} m^2/s, "
                         f"l = {c.l:g} m, y0 = {c.y0:g} m")
        elif c.theory == "logLaw":
            lines.append(f"# theory logLaw (velocity deficit, kappa = {c.kappa:g}): F = "
                         f"{self.F:g} m/s^2, l = {c.l:g} m, u* from the force balance = "
                         f"{self.us_theory:.6g} m/s (sqrt(F l/2) = "
                         f"{ct.friction_velocity(self.F, c.l):.6g})")
        if self.yc is not None:
            lines.append(f"# bins: {self.yc.size} of width {self.w:.6g} m centred on the particle "
                         "rows; u = mean u_x of the fluid particles in a bin"
                         + (f", averaged over the steps of the last {c.window:g} s before "
                            "each time" if c.window > 0 else ""))
        for r in self.samples:
            if "centreError" in r:
                lines.append(
                    f"# time {self._label(r)}: u_centre SPH {r['uCentre']:.6g}, theory "
                    f"{r['uCentreTheory']:.6g}, error {r['centreError']:+.3f} %; max bin SPH "
                    f"{r['uMaxBins']:.6g}, theory {r['uMaxBinsTheory']:.6g}, error "
                    f"{r['maxError']:+.3f} %; max |u - theory| = {r['profileError']:.3f} % of "
                    f"{self.scale():.4g}")
            elif "uStarFit" in r:
                lines.append(f"# time {self._label(r)}: u_centre SPH {r['uCentre']:.6g}; u* "
                             f"fitted {r['uStarFit']:.6g}, force balance {r['uStarTheory']:.6g}")
            else:
                lines.append(f"# time {self._label(r)}: u_centre SPH {r['uCentre']:.6g}")
        cols = ["y"]
        for r in self.samples:
            cols.append(f"u({self._label(r)})")
            if r["theory"] is not None:
                cols.append(f"theory({self._label(r)})")
        lines.append("# " + "\t".join(cols))
        return lines

    def write(self):
        if self.yc is None:
            return
        rows = [self.yc]
        for r in self.samples:
            rows.append(r["u"])
            if r["theory"] is not None:
                rows.append(r["theory"])
        table = np.column_stack(rows)
        with self.file.open("w") as fh:
            fh.write("\n".join(self.header_lines()) + "\n")
            for row in table:
                fh.write("\t".join(f"{v:.9g}" for v in row) + "\n")
        if self.coeffs.theory in ("poiseuille", "couette"):
            with self.summary_file.open("w") as fh:
                fh.write(f"# {self.object_name}: centreline (u_max of Poiseuille flow) and "
                         "profile errors against theory, in % (profile error: max |u - theory| "
                         f"over the bins, in % of {self.scale():.6g} m/s)\n")
                fh.write("# " + "\t".join(_SUMMARY_COLUMNS) + "\n")
                for r in self.samples:
                    fh.write("\t".join(f"{r[k.rstrip('%')]:.9g}" for k in _SUMMARY_COLUMNS)
                             + "\n")
        elif self.coeffs.theory == "logLaw":
            with self.summary_file.open("w") as fh:
                fh.write(f"# {self.object_name}: centreline velocity and friction velocity "
                         "(fitted to the velocity-deficit law, and from the force balance)\n")
                fh.write("# time\tuCentre\tuStarFit\tuStarTheory\n")
                for r in self.samples:
                    fh.write(f"{r['time']:.9g}\t{r['uCentre']:.9g}\t{r['uStarFit']:.9g}\t"
                             f"{r['uStarTheory']:.9g}\n")

    def plot(self):
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        c = self.coeffs
        log = c.theory == "logLaw"
        fig, axes = plt.subplots(1, 2 if log else 1, figsize=(11 if log else 6.5, 5),
                                 squeeze=False)
        ax = axes[0, 0]
        colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        yfine = c.y0 + np.linspace(0.0, c.l, 201)
        for i, r in enumerate(self.samples):
            col = colours[i % len(colours)]
            ax.plot(r["u"], self.yc, "o", ms=3.5, color=col, label=f"SPH, t = {r['time']:.4g} s")
            th = self.theory(yfine, r["time"], r["uCentre"])
            if th is not None:
                ax.plot(th, yfine, "-", lw=1.2, color=col)
        if log and self.samples:
            r = self.samples[-1]
            lam = r["uCentre"] * 4.0 * (yfine - c.y0) * (c.y0 + c.l - yfine) / c.l ** 2
            ax.plot(lam, yfine, "k:", lw=1, label="laminar profile matched to u_centre")
        name = {"poiseuille": "T(3.42)", "couette": "T(3.46)", "logLaw": "velocity-deficit law"}
        if c.theory in name:
            ax.plot([], [], "k-", label=f"theory, {name[c.theory]}")
        ax.set(xlabel=r"$u_x$ (m/s)", ylabel="y (m)", ylim=(c.y0, c.y0 + c.l),
               title=f"{self.object_name}: dx = {self.ctx.dx:.4g} m, "
                     f"{self.yc.size} rows across")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        if log and self.samples:
            r = self.samples[-1]
            ax2 = axes[0, 1]
            us = self.us_theory
            eta = np.minimum(self.yc - c.y0, c.y0 + c.l - self.yc)
            w = self.w
            sel = np.isfinite(r["u"]) & (eta > 1.5 * w)
            ax2.plot(np.log(eta[sel] / (0.5 * c.l)), (r["u"][sel] - r["uCentre"]) / us, "o",
                     ms=3.5, label=f"SPH, t = {r['time']:.4g} s")
            z = np.linspace(np.log(w / c.l), 0.0, 50)
            ax2.plot(z, z / c.kappa, "k--", label=rf"$(u - u_c)/u_* = \ln(y/y_0)/\kappa$")
            ax2.set(xlabel=r"$\ln(y / y_0)$, $y_0 = l/2$", ylabel=r"$(u - u_c) / u_*$",
                    title=f"velocity deficit, u* = {us:.4g} m/s (fitted "
                          f"{r.get('uStarFit', math.nan):.4g})")
            ax2.grid(alpha=0.3)
            ax2.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(self.folder / f"{self.object_name}.png", dpi=120)
        plt.close(fig)
