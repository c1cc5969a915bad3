"""Post-processing of saved time directories: ``sphfoam sample`` and ``sphfoam plot``.

``sample`` evaluates function objects on the written times of a case (like OpenFOAM's
``postProcess -func``), so gauges can be added after a run. ``plot`` draws every function
object against its reference: the wave gauges against a solitary-wave theory, aligned at the
first gauge (T Figs 4.15-4.20), with a table of the wave height at each gauge; probes and
lines against the theory's p, u, w; run-up against the maximum run-up of theory; the crest
against the theory's celerity and height; the dam-break front against Martin & Moyce (1952)
and Ritter (1892); velocity profiles against their channel theory; pressure sensors and
forces (force.dat, moment.dat) as time series; a slice's latest p and |U| on its plane.
Every function object serves 2-D and 3-D cases alike where it has both forms.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import sphfoam.registry as registry
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError, Problem
from sphfoam.case.times import list_times
from sphfoam.engine.state import ParticleState
from sphfoam.io.fields import has_particles, read_state


class SavedRun:
    """What a function object reads of a simulation, from a written time directory."""

    def __init__(self, fields: dict, time: float):
        self.state = ParticleState.from_fields(fields)
        if "p" in fields:
            self.state.p = np.asarray(fields["p"], float).copy()
        self.time = float(time)

    def eos(self):
        """The written pressure is the run's; nothing to recompute."""


def sample(case_dir, names: list[str] | None = None, log=print) -> list[Path]:
    """Run the function objects ``names`` (default: all of system/controlDict) over every
    written time; returns the files written."""
    case = Case(case_dir)
    case.validate()
    functions = case.models.functions
    if names:
        unknown = [n for n in names if n not in functions]
        if unknown:
            raise CaseError.single("system/controlDict", f"functions.{unknown[0]}",
                                   "no such function object; defined: "
                                   + (", ".join(functions) or "(none)"))
        functions = {n: functions[n] for n in names}
    times = [(t, p) for t, p in list_times(case.path) if has_particles(p)]
    if not times:
        raise CaseError.single(str(case.path), "", "no time directory with particles")
    out = []
    for name, fo in functions.items():
        fo.start(case, case.context, times[0][1].name)
        for t, folder in times:
            fo.execute(SavedRun(read_state(folder), t))
        fo.end()
        out.append(fo.file)
        log(f"{name}: {len(times)} times -> {fo.file.relative_to(case.path)}")
    return out


def _wave_of(case: Case, height: float | None, depth: float | None):
    """(H, d) from the options, the wave maker or constant/waveProperties."""
    if height and depth:
        return height, depth
    for mot in case.models.motions.values():
        maker = getattr(mot, "maker", None)
        wave = maker.solitary_wave() if maker is not None else None
        if wave is not None:
            return height or wave[0], depth or wave[1]
    for w, _ in case.waves.values():
        region = next(iter(case.particles.fluid.values()))
        return height or w.height, depth or (region.max[1] - region.min[1])
    raise CaseError.single("constant/waveProperties", "", "no wave height/depth: give "
                           "--height and --depth, or use a solitary-wave paddle (goring, "
                           "massFlux) or initial waves")


def plot_gauges(case_dir, theory: str = "mcCowan", name: str | None = None,
                height: float | None = None, depth: float | None = None, log=print):
    """PNG of every gauge of a ``waveGauges`` object against ``theory`` (crest aligned at the
    first gauge, the theory's celerity thereafter) and a table of the height at each gauge.
    Returns (png, table rows)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    case = Case(case_dir)
    fos = {n: fo for n, fo in case.models.functions.items() if fo.name == "waveGauges"}
    if name:
        fos = {name: fos[name]} if name in fos else {}
    if not fos:
        raise CaseError.single("system/controlDict", "functions",
                               "no waveGauges function object" + (f" named {name}" if name else ""))
    name, fo = next(iter(fos.items()))
    fo.ctx = case.context
    gpos = fo.gauges()                          # x (2-D) or (x y) rows (3-D)
    files = sorted((case.path / "postProcessing" / name).glob(f"*/{name}.dat"),
                   key=lambda p: float(p.parent.name))
    if not files:
        raise CaseError.single(str(case.path), "", f"no postProcessing/{name}: run the case or "
                               f"'sphfoam sample {case.path} -f {name}' first")
    data = np.vstack([np.loadtxt(f, ndmin=2) for f in files])
    data = data[np.argsort(data[:, 0], kind="stable")]
    t, eta = data[:, 0], data[:, 1:]
    xg = np.atleast_1d(gpos if gpos.ndim == 1 else gpos[:, 0])    # the wave runs along x
    where = [f"x = {v:g} m" for v in xg] if gpos.ndim == 1 else \
        [f"(x, y) = ({a:g}, {b:g})" for a, b in gpos]
    H, d = _wave_of(case, height, depth)
    g = math.hypot(*case.context.g)
    wave = registry.build("waveTheory", {"type": theory}).solitary(H, d, g=g)
    i1 = int(np.nanargmax(eta[:, 0]))
    t1 = t[i1]
    rows = []
    fig, ax = plt.subplots(len(xg), 1, figsize=(8, 1.3 * len(xg) + 1), sharex=True)
    ax = np.atleast_1d(ax)
    for k, x in enumerate(xg):
        tt = t1 + (x - xg[0]) / wave.c                 # theory's crest arrival
        theo = wave.eta(np.zeros_like(t), t=t - tt)
        ax[k].plot(t, eta[:, k], "b-", lw=1, label="sphfoam")
        ax[k].plot(t, theo, "k--", lw=1, label=f"{theory}, aligned at x = {xg[0]:g} m")
        ax[k].set_ylabel(where[k], rotation=0, ha="right", fontsize=8)
        ax[k].grid(alpha=0.3)
        imax = int(np.nanargmax(eta[:, k])) if np.isfinite(eta[:, k]).any() else 0
        rows.append((x, float(np.nanmax(eta[:, k])), float(t[imax]), tt,
                     100 * (1 - np.nanmax(eta[:, k]) / H)))
    ax[0].legend(fontsize=8, loc="upper right")
    ax[-1].set_xlabel("t (s)")
    fig.suptitle(f"{case.name}: surface elevation at the gauges, H = {H:g} m, d = {d:g} m")
    fig.tight_layout()
    png = files[-1].parent / f"{name}_{theory}.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    table = files[-1].parent / f"{name}_height.dat"
    with table.open("w") as fh:
        fh.write(f"# wave height at each gauge; theory {theory}, H = {H:g} m, d = {d:g} m, "
                 f"c = {wave.c:.5g} m/s\n# x\tetaMax\ttCrest\ttCrestTheory\tloss%\n")
        for r in rows:
            fh.write("\t".join(f"{v:.6g}" for v in r) + "\n")
    log(f"{png.relative_to(case.path)}, {table.relative_to(case.path)}")
    return png, rows


# --- `sphfoam plot`: every function object against its reference -----------------------------
#: function-object types `plot_case` draws (velocityProfile redraws its own table)
PLOTTED = ("waveGauges", "probes", "lines", "runUp", "crestTracker", "damBreakFront",
           "velocityProfile", "pressureSensors", "forces", "slices")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _series(case: Case, name: str, filename: str | None = None):
    """(columns, rows sorted by time, latest start folder) of a function object's output,
    all restarts joined; None when it wrote nothing."""
    from sphfoam.io.tables import read_table, start_folders

    folders = start_folders(case.path, name)
    cols, parts = None, []
    for _, folder in folders:
        f = folder / (filename or f"{name}.dat")
        if f.is_file():
            c, d = read_table(f)
            if d.size:
                cols = c
                parts.append(d)
    if not parts:
        return None
    data = np.vstack(parts)
    data = data[np.argsort(data[:, 0], kind="stable")]
    return cols, data, folders[-1][1]


def _reference_wave(case: Case, theory: str, height, depth):
    """(wave, H, d) of the case's solitary wave for the references, or None without one."""
    try:
        H, d = _wave_of(case, height, depth)
    except (CaseError, StopIteration):
        return None
    g = math.hypot(*case.context.g)
    return registry.build("waveTheory", {"type": theory}).solitary(H, d, g=g), H, d


def _save(fig, png: Path) -> Path:
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    _pyplot().close(fig)
    return png


def plot_probes(case: Case, name: str, fo, wave, theory: str) -> Path | None:
    """p, Ux, Uy (and Uz in 3-D) at each probe against time; with a solitary wave, the
    theory's p, u, w at the probe (w against the vertical component), z measured from the
    bottom of the first fluid region (crest aligned with the first probe's pressure peak,
    the theory's celerity thereafter)."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    plt = _pyplot()
    pts = np.asarray(fo.coeffs.points, float)
    t = data[:, 0]
    dim = pts.shape[1]
    comps = (("p", "Pa"), ("Ux", "m/s"), ("Uy", "m/s")) + ((("Uz", "m/s"),) if dim == 3 else ())
    vertical = comps[-1][0]
    fig, ax = plt.subplots(len(pts), len(comps), figsize=(4 * len(comps), 2.2 * len(pts) + 0.8),
                           sharex=True, squeeze=False)
    t_peak = None
    region = next(iter(case.particles.fluid.values()))
    up = dim - 1
    bed = region.min[up] if hasattr(region, "min") else min(p[1] for p in region.points)
    for k, pt in enumerate(pts):
        px, py = pt[0], pt[up]
        n = len(comps)
        vals = data[:, 1 + n * k:1 + n * (k + 1)]
        if wave is not None and t_peak is None and np.isfinite(vals[:, 0]).any():
            t_peak, x_peak = t[int(np.nanargmax(vals[:, 0]))], px
        for j, (q, unit) in enumerate(comps):
            a = ax[k, j]
            a.plot(t, vals[:, j], "b-", lw=1, label="sphfoam")
            if wave is not None and t_peak is not None:
                tt = t - t_peak - (px - x_peak) / wave[0].c
                x = np.full_like(t, px)
                z = np.full_like(t, py - bed)
                ref = {"p": wave[0].p, "Ux": wave[0].u, vertical: wave[0].w}.get(q)
                if ref is not None:
                    a.plot(t, ref(x, z, t=tt, x0=px), "k--", lw=1,
                           label=f"{theory}, H = {wave[1]:g} m")
            a.set_ylabel(f"{q} ({unit})")
            a.grid(alpha=0.3)
            if j == 0:
                a.set_title("probe (" + ", ".join(f"{v:g}" for v in pt) + ")", fontsize=9,
                            loc="left")
    ax[0, 0].legend(fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("t (s)")
    fig.suptitle(f"{case.name}: {name} (probes)" + ("" if wave else ", no reference (no "
                                                   "solitary wave in the case)"))
    return _save(fig, folder / f"{name}.png")


def plot_lines(case: Case, name: str, fo, wave, theory: str, n_times: int = 6) -> Path | None:
    """Ux(y) along each line at up to ``n_times`` sampled times (Ux(z) in 3-D); a line that
    follows the crest is drawn against the theory's u(z) under the crest."""
    from sphfoam.io.tables import read_table, start_folders

    files = []
    for _, folder in start_folders(case.path, name):
        for sub in folder.iterdir():
            if (sub / "line.dat").is_file():
                try:
                    files.append((float(sub.name), sub / "line.dat"))
                except ValueError:
                    continue
    if not files:
        return None
    files.sort()
    pick = np.unique(np.linspace(0, len(files) - 1, min(n_times, len(files))).round().astype(int))
    plt = _pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(11, 5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    up = "y"
    for i, k in enumerate(pick):
        t, f = files[k]
        cols, d = read_table(f)
        up = cols[0][0]                            # y, or z in 3-D (z Ux Uy Uz p per line)
        width = 5 if up == "z" else 4
        col = colours[i % len(colours)]
        for j in range(0, len(cols), width):
            tag = cols[j][1:] if len(cols) > width else ""     # "(x)", or "(x,y)" in 3-D
            where_tag = ("x" if up == "y" else "") + tag
            ax[0].plot(d[:, j + 1], d[:, j], "o-", ms=3, lw=0.8, color=col,
                       label=f"t = {t:g} s" + (f" {where_tag}" if tag else ""))
            ax[1].plot(d[:, j + width - 1], d[:, j], "o-", ms=3, lw=0.8, color=col)
    crest = fo.coeffs.follow == "crest"
    if wave is not None and crest:
        w, H, d = wave
        z = np.linspace(0.0, d + H, 60)
        y = fo.coeffs.y0 + z
        ax[0].plot(w.u(0.0, z), y, "k--", lw=1.2, label=f"{theory} under the crest")
        ax[1].plot(w.p(0.0, z), y, "k--", lw=1.2)
    ax[0].set(xlabel="Ux (m/s)", ylabel=f"{up} (m)")
    ax[1].set(xlabel="p (Pa)", ylabel=f"{up} (m)")
    for a in ax:
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    where = "under the crest" if crest else (
        "at x = " + ", ".join(f"{x:g}" for x in fo.coeffs.x) if fo.coeffs.x else
        "at (x y) = " + ", ".join(f"({x:g} {y:g})" for x, y in fo.coeffs.points))
    fig.suptitle(f"{case.name}: {name} (lines {where})")
    return _save(fig, files[-1][1].parent.parent / f"{name}.png")


def run_up_reference(mode: str, A: float, d: float, angle: float | None = None):
    """[(label, R)] of the maximum run-up of a solitary wave of height A in depth d: on a
    vertical wall, linear theory 2A, Su & Mirie's (1980) third order
    R/d = 2a + a^2/2 + 3a^3/4 and, for a = A/d <= 0.5, the fully nonlinear potential flow
    (:func:`sphfoam.reference.wall_reflection.wall_reflection`: the HOS method up to 0.4, a
    few seconds the first time; the boundary-integral method above, half a minute);
    on a plane beach, Synolakis (1987) R/d = 2.831 sqrt(cot beta) (A/d)^(5/4) (non-breaking)."""
    if mode == "wall":
        from sphfoam.reference import wall_reflection as wr

        refs = [("linear theory, 2A", 2.0 * A),
                ("Su & Mirie (1980), third order", d * wr.su_mirie(A / d))]
        if 0.0 < A / d <= wr.MAX_EPS_BIE:
            r = wr.wall_reflection(round(A / d, 12))
            refs.append((f"potential flow, fully nonlinear ({r.method.upper()})", d * r.run_up))
        return refs
    if angle and angle > 0:
        cot = 1.0 / math.tan(math.radians(angle))
        return [("Synolakis (1987), non-breaking", 2.831 * d * math.sqrt(cot) * (A / d) ** 1.25)]
    return []


def plot_run_up(case: Case, name: str, fo, wave) -> Path | None:
    """R(t) and its running maximum against the maximum run-up of theory."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(data[:, 0], data[:, 1], "b-", lw=1, label="run-up R(t)")
    ax.plot(data[:, 0], data[:, 2], "b:", lw=1, label="running maximum")
    if wave is not None:
        for (label, R), ls in zip(run_up_reference(fo.coeffs.mode, wave[1], wave[2],
                                                   fo.coeffs.angle), ("k--", "k-.", "k:")):
            ax.axhline(R, color="k", ls=ls[1:], lw=1, label=f"{label} = {R:.4g} m")
    ax.set(xlabel="t (s)", ylabel="R (m)", title=f"{case.name}: {name} (runUp, "
           f"{fo.coeffs.mode})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, folder / f"{name}.png")


def plot_crest(case: Case, name: str, fo, wave, theory: str) -> Path | None:
    """x_c(t), eta_c(t) and c(t) against the theory's celerity and height."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    t, xc, ec, c = data[:, 0], data[:, 1], data[:, 2], data[:, 3]
    plt = _pyplot()
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    ax[0].plot(t, xc, "b-", lw=1, label="sphfoam")
    ax[1].plot(t, ec, "b-", lw=1)
    ax[2].plot(t, c, "b-", lw=1)
    fit = folder / "celerity.dat"
    if fit.is_file():
        from sphfoam.io.tables import read_table

        fc, fd = read_table(fit)
        if fd.size and np.isfinite(fd[0, 0]):
            cel, x0 = fd[0, 0], fd[0, 1]
            ax[0].plot(t, x0 + cel * t, "g:", lw=1, label=f"fit, c = {cel:.4g} m/s")
            ax[2].axhline(cel, color="g", ls=":", lw=1)
    if wave is not None:
        w, H, _ = wave
        ok = np.isfinite(xc)
        if ok.any():
            i = int(np.flatnonzero(ok)[np.argmax(ec[ok])])
            ax[0].plot(t, xc[i] + w.c * (t - t[i]), "k--", lw=1,
                       label=f"{theory}, c = {w.c:.4g} m/s")
        ax[1].axhline(H, color="k", ls="--", lw=1, label=f"H = {H:g} m")
        ax[2].axhline(w.c, color="k", ls="--", lw=1)
        ax[2].set_ylim(0.0, 2.0 * w.c)             # the start-up of a paddle wave is noise
        ax[1].legend(fontsize=8)
    ax[0].set(xlabel="t (s)", ylabel="x_c (m)", title="crest position")
    ax[1].set(xlabel="t (s)", ylabel="eta_c (m)", title="crest height")
    ax[2].set(xlabel="t (s)", ylabel="c (m/s)", title="celerity")
    for a in ax:
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.suptitle(f"{case.name}: {name} (crestTracker)")
    return _save(fig, folder / f"{name}.png")


def plot_sensors(case: Case, name: str, fo) -> Path | None:
    """Pressure at each sensor against time (no reference: a case's own measurements are
    drawn by its tutorial's scripts)."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 4))
    for k, c in enumerate(cols[1:], start=1):
        ax.plot(data[:, 0], data[:, k], lw=1, label=c)
    ax.set(xlabel="t (s)", ylabel="p (Pa)",
           title=f"{case.name}: {name} (pressureSensors, offset {fo.coeffs.offset:g} dx)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, folder / f"{name}.png")


def plot_forces(case: Case, name: str, fo) -> Path | None:
    """Force and moment components against time: total (solid), pressure (dashed), viscous
    (dotted), from force.dat and moment.dat."""
    s = _series(case, name, "force.dat")
    m = _series(case, name, "moment.dat")
    if s is None or m is None:
        return None
    plt = _pyplot()
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    span = " per metre" if case.dimension == 2 else ""
    for a, (cols, data, _), what in ((ax[0], s, f"force (N{span})"),
                                     (ax[1], m, f"moment (N m{span})")):
        for j, comp in enumerate("xyz"):
            col = f"C{j}"
            for part, style in (("total", "-"), ("pressure", "--"), ("viscous", ":")):
                y = data[:, cols.index(f"{part}_{comp}")]
                if part != "total" and not np.any(y):
                    continue
                a.plot(data[:, 0], y, style, color=col, lw=1, label=f"{part}_{comp}")
        a.set_ylabel(what)
        a.grid(alpha=0.3)
        a.legend(fontsize=7, ncol=3)
    ax[-1].set_xlabel("t (s)")
    fig.suptitle(f"{case.name}: {name} (forces on {' '.join(fo.coeffs.patches)})")
    return _save(fig, s[2] / f"{name}.png")


def read_vts(path: Path) -> tuple[np.ndarray, tuple[int, int], dict[str, np.ndarray]]:
    """(points (n, 3), (n1, n2), point fields) of a .vts written by ``slices``."""
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    piece = root.find("StructuredGrid/Piece")
    ext = [int(v) for v in piece.get("Extent").split()]
    shape = (ext[1] + 1, ext[3] + 1)

    def arr(el):
        a = np.array(el.text.split(), dtype=float)
        k = int(el.get("NumberOfComponents", "1"))
        return a if k == 1 else a.reshape(-1, k)

    fields = {el.get("Name"): arr(el) for el in piece.find("PointData")}
    return arr(piece.find("Points/DataArray")), shape, fields


def plot_slices(case: Case, name: str, fo) -> Path | None:
    """The pressure and speed on the plane at the latest sampled time (NaN, outside the
    water, left blank)."""
    from sphfoam.io.tables import start_folders

    found = []
    for _, folder in start_folders(case.path, name):
        for sub in folder.iterdir():
            f = sub / f"{name}.vts"
            if f.is_file():
                try:
                    found.append((float(sub.name), f, folder))
                except ValueError:
                    continue
    if not found:
        return None
    t, f, folder = max(found, key=lambda r: r[0])
    _, (n1, n2), fields = read_vts(f)
    c = fo.coeffs
    half = (0.5 * (n1 - 1) * (c.spacing or case.particles.dx),
            0.5 * (n2 - 1) * (c.spacing or case.particles.dx))
    plt = _pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.5))
    speed = np.linalg.norm(fields["U"], axis=1)
    for a, vals, what in ((ax[0], fields["p"], "p (Pa)"), (ax[1], speed, "|U| (m/s)")):
        im = a.imshow(vals.reshape(n2, n1), origin="lower", aspect="equal",
                      extent=(-half[0], half[0], -half[1], half[1]))
        fig.colorbar(im, ax=a, label=what)
        a.set(xlabel="s1 along e1 (m)", ylabel="s2 along e2 (m)")
    fig.suptitle(f"{case.name}: {name} (slices) at t = {t:g} s, point "
                 f"{tuple(c.point)}, normal {tuple(c.normal)}")
    return _save(fig, folder / f"{name}.png")


def plot_dam_break(case: Case, name: str, fo) -> Path | None:
    """Z(T) and H(T) against Martin & Moyce (1952) and Ritter's (1892) dry-bed front
    Z = 1 + 2T (the front of the shallow-water solution runs at 2 sqrt(g H0))."""
    from sphfoam.sampling.damBreak import martin_moyce

    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    T, Z, Hh = data[:, cols.index("T")], data[:, cols.index("Z")], data[:, cols.index("H")]
    front, height = martin_moyce()
    width = (fo.coeffs.width or fo.coeffs.H0) / fo.coeffs.H0
    plt = _pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot(T, Z, "b-", label=f"sphfoam, dx = {case.particles.dx:g} m")
    ax[0].plot(front[:, 0], front[:, 1], "k^", label="Martin & Moyce (1952)")
    TT = np.linspace(0.0, max(float(T.max()), 0.1), 50)
    ax[0].plot(TT, width + 2.0 * TT, "k:", label="Ritter (1892), Z = a/H0 + 2T")
    ax[0].set(xlabel=r"$T = t\sqrt{g/H_0}$", ylabel=r"$Z = z/H_0$", title="surge front")
    ax[1].plot(T, Hh, "b-", label="sphfoam")
    ax[1].plot(height[:, 0], height[:, 1], "k^", label="Martin & Moyce (1952)")
    ax[1].set(xlabel=r"$T = t\sqrt{g/H_0}$", ylabel=r"$H = h/H_0$", title="residual height")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(f"{case.name}: {name} (damBreakFront)")
    return _save(fig, folder / f"{name}.png")


def plot_profile(case: Case, name: str, fo) -> Path | None:
    """u(y) at each sampled time (markers) against its theory column (lines), from the
    velocityProfile table."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    y = data[:, 0]
    k = 0
    for j, c in enumerate(cols):
        if c.startswith("u("):
            col = colours[k % len(colours)]
            k += 1
            ax.plot(data[:, j], y, "o", ms=3.5, color=col, label=f"SPH, t = {c[2:-1]} s")
            th = f"theory({c[2:-1]})"
            if th in cols:
                ax.plot(data[:, cols.index(th)], y, "-", lw=1.2, color=col)
    if any(c.startswith("theory(") for c in cols):
        ax.plot([], [], "k-", label=f"theory ({fo.coeffs.theory})")
    ax.set(xlabel="u_x (m/s)", ylabel="y (m)", title=f"{case.name}: {name} (velocityProfile)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, folder / f"{name}.png")


def _measured_columns(case: Case) -> dict[str, list]:
    """Function object -> the measured-series metrics of system/metricsDict that read it
    (``measuredRMS``, ``measuredPeak``: sphfoam.study.measured_metrics), if the case has
    a metricsDict."""
    if not (case.path / "system" / "metricsDict").is_file():
        return {}
    from sphfoam.case.metrics_dict import load_metrics
    from sphfoam.study.measured_metrics import _Measured

    out: dict[str, list] = {}
    for m in load_metrics(case.path).metrics.values():
        if isinstance(m, _Measured):
            out.setdefault(m.coeffs.function, []).append(m)
    return out


def plot_measured(case: Case, name: str, metrics: list) -> Path | None:
    """Each column of ``name`` a measured-series metric reads, against the measurement (the
    metric's file and column), one panel per column over the metrics' widest window."""
    s = _series(case, name)
    if s is None:
        return None
    cols, data, folder = s
    seen: dict[str, object] = {}
    for m in metrics:
        seen.setdefault(m.coeffs.column, m)
    plt = _pyplot()
    fig, ax = plt.subplots(len(seen), 1, figsize=(9, 1.6 * len(seen) + 1), sharex=True,
                           squeeze=False)
    t0 = min(m.coeffs.window[0] for m in metrics)
    t1 = max(m.coeffs.window[1] for m in metrics)
    for a, (col, m) in zip(ax[:, 0], seen.items()):
        tm, vm = m.measured(case.path)
        keep = (tm >= t0) & (tm <= t1)
        a.plot(tm[keep], vm[keep], "k-", lw=0.6, alpha=0.7,
               label=f"measured ({m.coeffs.file}, column {m.coeffs.fileColumn})")
        if col in cols:
            j = cols.index(col)
            ks = (data[:, 0] >= t0) & (data[:, 0] <= t1)
            a.plot(data[ks, 0], data[ks, j], "b-", lw=1, label="sphfoam")
        a.set_ylabel(col, rotation=0, ha="right", fontsize=8)
        a.grid(alpha=0.3)
    ax[0, 0].legend(fontsize=7, loc="upper right")
    ax[-1, 0].set_xlabel("t (s)")
    fig.suptitle(f"{case.name}: {name} against the measurement")
    fig.tight_layout()
    return _save(fig, folder / f"{name}_measured.png")


def plot_case(case_dir, names: list[str] | None = None, theory: str = "mcCowan",
              height: float | None = None, depth: float | None = None, log=print) -> list[Path]:
    """One PNG per function object of the case (or those ``names``) against its reference,
    in its latest ``postProcessing/<name>/<startTime>/``; returns the files written. Objects
    with no output yet are skipped (an error when named, or when nothing is drawn)."""
    case = Case(case_dir)
    functions = case.models.functions
    if names:
        unknown = [n for n in names if n not in functions]
        if unknown:
            raise CaseError.single("system/controlDict", f"functions.{unknown[0]}",
                                   "no such function object; defined: "
                                   + (", ".join(functions) or "(none)"))
        functions = {n: functions[n] for n in names}
    if not functions:
        raise CaseError.single("system/controlDict", "functions", "no function objects to plot")
    wave = _reference_wave(case, theory, height, depth)
    measured = _measured_columns(case)
    out, missing, failed = [], [], []
    for name, fo in functions.items():
        kind = fo.name
        if name in measured:                   # against the case's own measurement
            png = plot_measured(case, name, measured[name])
            if png is None:
                missing.append(name)
            else:
                out.append(png)
                log(f"{name}: {png.relative_to(case.path)}")
            if kind not in ("pressureSensors", "forces", "probes"):
                continue
        if kind == "waveGauges":
            if _series(case, name) is None:
                missing.append(name)
                continue
            try:
                png, _ = plot_gauges(case.path, theory, name, height, depth, log=log)
            except CaseError as e:             # output but no wave: the gauges need one
                failed.extend(e.problems)
                continue
            out.append(png)
            continue
        if kind == "probes":
            png = plot_probes(case, name, fo, wave, theory)
        elif kind == "lines":
            png = plot_lines(case, name, fo, wave, theory)
        elif kind == "runUp":
            png = plot_run_up(case, name, fo, wave)
        elif kind == "crestTracker":
            png = plot_crest(case, name, fo, wave, theory)
        elif kind == "damBreakFront":
            png = plot_dam_break(case, name, fo)
        elif kind == "velocityProfile":
            png = plot_profile(case, name, fo)
        elif kind == "pressureSensors":
            png = plot_sensors(case, name, fo)
        elif kind == "forces":
            png = plot_forces(case, name, fo)
        elif kind == "slices":
            png = plot_slices(case, name, fo)
        else:                                  # a type plot does not know: say so
            log(f"{name}: no plot for function objects of type {kind}")
            continue
        if png is None:
            missing.append(name)
        else:
            out.append(png)
            log(f"{name}: {png.relative_to(case.path)}")
    problems = list(failed)
    if missing:
        problems.append(Problem(str(case.path), "", "no output of " + ", ".join(missing)
                                + ": run the case or `sphfoam sample` first"))
    if problems and (names or not out):
        raise CaseError(problems)
    for p in problems:
        log(f"not plotted: {p}")
    return out
