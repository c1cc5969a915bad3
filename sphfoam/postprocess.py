"""Post-processing of saved time directories: ``sphfoam sample`` and ``sphfoam plot``.

``sample`` evaluates function objects on the written times of a case (like OpenFOAM's
``postProcess -func``), so gauges can be added after a run. ``plot`` draws the wave-gauge
series of a case against a solitary-wave theory, aligned at the first gauge (T Figs
4.15-4.20), and tabulates the wave height at each gauge.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sphfoam import registry
from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
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
    """(H, d) from the options, a Goring paddle or constant/waveProperties."""
    if height and depth:
        return height, depth
    for mot in case.models.motions.values():
        maker = getattr(mot, "maker", None)
        if maker is not None and maker.name in ("goring", "massFlux"):
            return height or maker.coeffs.height, depth or maker.coeffs.depth
    for w, _ in case.waves.values():
        region = next(iter(case.particles.fluid.values()))
        return height or w.height, depth or (region.max[1] - region.min[1])
    raise CaseError.single("constant/waveProperties", "", "no wave height/depth: give "
                           "--height and --depth, or use a goring paddle or initial waves")


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
    files = sorted((case.path / "postProcessing" / name).glob(f"*/{name}.dat"),
                   key=lambda p: float(p.parent.name))
    if not files:
        raise CaseError.single(str(case.path), "", f"no postProcessing/{name}: run the case or "
                               f"'sphfoam sample {case.path} -f {name}' first")
    data = np.vstack([np.loadtxt(f, ndmin=2) for f in files])
    data = data[np.argsort(data[:, 0], kind="stable")]
    t, eta = data[:, 0], data[:, 1:]
    xg = np.atleast_1d(np.asarray(fo.coeffs.x, float))
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
        ax[k].set_ylabel(f"x = {x:g} m", rotation=0, ha="right", fontsize=8)
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
