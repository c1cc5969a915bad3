"""Pictures of the particles: ``sphfoam render``.

One PNG per written time directory, the fluid particles coloured by a field (the velocity
magnitude |U| by default) and the wall particles grey, on equal axes that stay the same for
every frame (the box around all particles of all frames), with a colour bar whose range is
fixed over the frames (min..max of the field over the fluid particles of all frames, unless
given). Each particle is a disc 1.3 dx across, so the water reads as one body. The
frames are joined into an animated GIF (matplotlib's PillowWriter) or an MP4 (matplotlib's
FFMpegWriter, when ``ffmpeg`` is on the PATH). Everything is drawn with whole arrays (one
scatter per frame and kind), never per particle.

Output: ``<case>/postProcessing/render/<field>/<time>.png`` and
``<case>/postProcessing/render/<field>.gif`` (or ``.mp4``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sphfoam.case.case import Case
from sphfoam.case.errors import CaseError
from sphfoam.case.times import list_times
from sphfoam.engine.state import FLUID, WALL
from sphfoam.io.fields import has_particles, read_state

#: the fields a frame can be coloured by besides any scalar field of the time directory
DERIVED = {"U": "|U| (m/s)", "Ux": "Ux (m/s)", "Uy": "Uy (m/s)"}
UNITS = {"p": "p (Pa)", "rho": "rho (kg/m^3)", "mass": "mass (kg/m)"}
MOVIES = ("auto", "gif", "mp4", "none")
WALL_GREY = "#9a9a9a"
#: marker diameter in dx: discs a little wider than the spacing, so water reads as a body
MARKER = 1.3


@dataclass
class Rendered:
    frames: list[Path] = field(default_factory=list)
    movie: Path | None = None
    vmin: float = math.nan
    vmax: float = math.nan


def ffmpeg_available() -> bool:
    from matplotlib import animation

    return animation.writers.is_available("ffmpeg")


def field_values(fields: dict, name: str) -> np.ndarray:
    """The per-particle values of ``name``: |U|, Ux, Uy, or a scalar field of the time
    directory (p, rho, mass, ...)."""
    if name in DERIVED:
        U = np.asarray(fields["U"], float)
        return np.hypot(U[:, 0], U[:, 1]) if name == "U" else U[:, 0 if name == "Ux" else 1]
    a = fields.get(name)
    if a is None or np.ndim(a) != 1:
        raise KeyError(name)
    return np.asarray(a, float)


def _choices(fields: dict) -> list[str]:
    return list(DERIVED) + sorted(k for k, a in fields.items()
                                  if np.ndim(a) == 1 and k not in ("type", "origId"))


def render_case(case_dir, field_name: str = "U", times: list[float] | None = None,
                movie: str = "auto", fps: float = 5.0, width: int = 1000,
                value_range: tuple[float, float] | None = None,
                box: tuple[float, float, float, float] | None = None, log=print) -> Rendered:
    """PNG frames of the written times (all, or the ``times`` given) and a movie
    (``movie``: auto = MP4 with ffmpeg, else GIF; gif; mp4; none). ``width`` is the frame
    width in pixels; every frame has the same size. ``box`` (x0, y0, x1, y1) shows only
    that part of the case (and takes the colour range from the particles inside it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    case = Case(case_dir)
    if movie not in MOVIES:
        raise CaseError.single("--movie", "", f"'{movie}' is not one of {', '.join(MOVIES)}")
    if movie == "mp4" and not ffmpeg_available():
        raise CaseError.single("--movie", "", "mp4 needs ffmpeg on the PATH (not found); "
                               "use --movie gif")
    if movie == "auto":
        movie = "mp4" if ffmpeg_available() else "gif"
    folders = [(t, p) for t, p in list_times(case.path) if has_particles(p)]
    if times:
        want = list(times)
        folders = [(t, p) for t, p in folders
                   if any(abs(t - w) <= 1e-9 * max(1.0, abs(w)) for w in want)]
    if not folders:
        raise CaseError.single(str(case.path), "", "no time directory with particles"
                               + (" at the times asked for" if times else
                                  ": run `sphfoam setup` or `sphfoam run` first"))
    dx = case.particles.dx
    if box is not None and not (box[2] > box[0] and box[3] > box[1]):
        raise CaseError.single("--box", "", f"x1 > x0 and y1 > y0 needed, got {box}")

    # pass 1: the fixed axes and colour range over all frames
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    vmin, vmax = np.inf, -np.inf
    for _, folder in folders:
        f = read_state(folder)
        try:
            v = field_values(f, field_name)
        except KeyError:
            raise CaseError.single("--field", "", f"'{field_name}' is not a field of "
                                   f"{folder.name}/; choose from: "
                                   + ", ".join(_choices(f))) from None
        pos = np.asarray(f["positions"], float)[:, :2]
        lo, hi = np.minimum(lo, pos.min(axis=0)), np.maximum(hi, pos.max(axis=0))
        fluid = (np.asarray(f["type"]) == FLUID) & np.isfinite(v)
        if box is not None:
            fluid &= (pos[:, 0] >= box[0]) & (pos[:, 0] <= box[2]) & \
                (pos[:, 1] >= box[1]) & (pos[:, 1] <= box[3])
        if fluid.any():
            vmin, vmax = min(vmin, float(v[fluid].min())), max(vmax, float(v[fluid].max()))
    if value_range is not None:
        vmin, vmax = map(float, value_range)
    if not (np.isfinite(vmin) and np.isfinite(vmax)):
        vmin, vmax = 0.0, 1.0
    if vmax <= vmin:
        vmax = vmin + max(abs(vmin), 1.0) * 1e-6
    lo, hi = lo - 2 * dx, hi + 2 * dx
    if box is not None:
        lo, hi = np.array(box[:2], float), np.array(box[2:], float)

    # the figure: equal axes of a fixed size in pixels, a colour bar on the right
    dpi = 100
    span = hi - lo
    left, right, bottom, top = 70, 110, 50, 40                 # margins (px)
    ax_w = max(width - left - right, 100)
    ax_h = max(int(round(ax_w * span[1] / span[0])), 60)
    fig_w, fig_h = ax_w + left + right, ax_h + bottom + top
    fig = plt.figure(figsize=(fig_w / dpi, fig_h / dpi), dpi=dpi)
    ax = fig.add_axes([left / fig_w, bottom / fig_h, ax_w / fig_w, ax_h / fig_h])
    cax = fig.add_axes([(left + ax_w + 15) / fig_w, bottom / fig_h, 15 / fig_w, ax_h / fig_h])
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    px_per_m = ax_w / span[0]
    size = (MARKER * dx * px_per_m * 72.0 / dpi) ** 2            # marker diameter (pt^2)
    empty = np.zeros((0, 2))
    walls = ax.scatter(empty[:, 0], empty[:, 1], s=size, marker="o", c=WALL_GREY,
                       linewidths=0, snap=False)
    fluid_sc = ax.scatter(empty[:, 0], empty[:, 1], s=size, marker="o", c=[], cmap="viridis",
                          vmin=vmin, vmax=vmax, linewidths=0, snap=False)
    label = DERIVED.get(field_name) or UNITS.get(field_name, field_name)
    fig.colorbar(fluid_sc, cax=cax, label=label)
    title = ax.set_title("")

    out_dir = case.path / "postProcessing" / "render" / field_name
    out_dir.mkdir(parents=True, exist_ok=True)
    result = Rendered(vmin=vmin, vmax=vmax)
    writer = None
    if movie != "none":
        result.movie = out_dir.parent / f"{field_name}.{movie}"
        writer = (animation.FFMpegWriter(fps=fps) if movie == "mp4"
                  else animation.PillowWriter(fps=fps))
        writer.setup(fig, str(result.movie), dpi=dpi)
    try:
        for t, folder in folders:                              # pass 2: the frames
            f = read_state(folder)
            pos = np.asarray(f["positions"], float)[:, :2]
            kind = np.asarray(f["type"])
            v = field_values(f, field_name)
            fl, wl = kind == FLUID, kind == WALL
            walls.set_offsets(pos[wl] if wl.any() else empty)
            fluid_sc.set_offsets(pos[fl] if fl.any() else empty)
            fluid_sc.set_array(v[fl])
            title.set_text(f"{case.name}: t = {t:.4g} s, {label} of {int(fl.sum())} fluid "
                           f"particles")
            png = out_dir / f"{folder.name}.png"
            fig.savefig(png, dpi=dpi)
            result.frames.append(png)
            if writer is not None:
                writer.grab_frame()
    finally:
        if writer is not None:
            writer.finish()
        plt.close(fig)
    rel = out_dir.relative_to(case.path)
    log(f"render: {len(result.frames)} frame(s) of {label} in {rel}/ "
        f"({fig_w} x {fig_h} px, colour range {vmin:.4g} .. {vmax:.4g})"
        + (f", {result.movie.relative_to(case.path)}" if result.movie else ""))
    return result
