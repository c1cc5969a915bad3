"""Pictures of the particles: ``sphfoam render``.

One PNG per written time directory, the fluid particles coloured by a field (the velocity
magnitude |U| by default) and the wall particles grey, on equal axes that stay the same for
every frame (the box around all particles of all frames), with a colour bar whose range is
fixed over the frames (min..max of the field over the fluid particles of all frames, unless
given). Each particle is a disc 1.3 dx across, so the water reads as one body. The
frames are joined into an animated GIF (matplotlib's PillowWriter) or an MP4 (matplotlib's
FFMpegWriter, when ``ffmpeg`` is on the PATH). Everything is drawn with whole arrays (one
scatter per frame and kind), never per particle.

A 3-D case (``dimension 3;`` in system/particleDict) gets two panels per frame: a 3-D
view (matplotlib's mplot3d, equal axes, z up) of the fluid particles coloured by the field,
the wall particles light and transparent, and a slice: the particles within a slab of
``slab`` (default dx) around the plane ``slice`` (``y=0.2``; default the plane y through
the middle of the particles), fluid coloured by the field and walls grey, on equal axes
of the plane's two in-plane coordinates. ``box`` then bounds the slice view (its first and
second in-plane axes: x z for a y slice, y z for x, x y for z).

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
#: ... and in 3-D
DERIVED_3D = {**DERIVED, "Uz": "Uz (m/s)"}
AXES = "xyz"
#: the 3-D view's wall particles: light and transparent, so the water shows through
WALL_3D = (0.55, 0.55, 0.55, 0.06)
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
    """The per-particle values of ``name``: |U|, Ux, Uy (Uz in 3-D), or a scalar field of the
    time directory (p, rho, mass, ...)."""
    U = np.asarray(fields["U"], float) if "U" in fields else None
    if name in DERIVED_3D and U is not None and (name != "Uz" or U.shape[1] == 3):
        if name == "U":
            return np.hypot(U[:, 0], U[:, 1]) if U.shape[1] == 2 else np.linalg.norm(U, axis=1)
        return U[:, "xyz".index(name[1])]
    a = fields.get(name)
    if a is None or np.ndim(a) != 1:
        raise KeyError(name)
    return np.asarray(a, float)


def _choices(fields: dict) -> list[str]:
    three = np.ndim(fields.get("U")) == 2 and np.shape(fields["U"])[1] == 3
    return list(DERIVED_3D if three else DERIVED) + sorted(
        k for k, a in fields.items() if np.ndim(a) == 1 and k not in ("type", "origId"))


def parse_slice(text: str | None) -> tuple[int, float | None]:
    """``"y=0.2"`` -> (1, 0.2); ``"y"`` -> (1, None): the plane through the middle."""
    if text is None:
        return 1, None
    axis, _, value = text.partition("=")
    axis = axis.strip().lower()
    if axis not in AXES:
        raise CaseError.single("--slice", "", f"'{text}': give AXIS=VALUE with AXIS x, y or "
                               "z, e.g. y=0.2")
    try:
        return AXES.index(axis), (float(value) if value.strip() else None)
    except ValueError:
        raise CaseError.single("--slice", "", f"'{text}': {value!r} is not a number") from None


def render_case(case_dir, field_name: str = "U", times: list[float] | None = None,
                movie: str = "auto", fps: float = 5.0, width: int = 1000,
                value_range: tuple[float, float] | None = None,
                box: tuple[float, float, float, float] | None = None,
                slice_at: str | None = None, slab: float | None = None,
                log=print) -> Rendered:
    """PNG frames of the written times (all, or the ``times`` given) and a movie
    (``movie``: auto = MP4 with ffmpeg, else GIF; gif; mp4; none). ``width`` is the frame
    width in pixels; every frame has the same size. ``box`` (x0, y0, x1, y1) shows only
    that part of the case (and takes the colour range from the particles inside it; in
    3-D, of the slice). 3-D cases only: ``slice_at`` ("y=0.2") and ``slab`` (its thickness,
    m) choose the slice panel (see the module)."""
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
    if case.dimension == 3:
        return _render_3d(case, folders, field_name, movie, fps, width, value_range, box,
                          slice_at, slab, log)
    for opt, v in (("--slice", slice_at), ("--slab", slab)):
        if v is not None:
            raise CaseError.single(opt, "", f"{case.name} is a 2-D case: a slice is drawn "
                                   "for 3-D cases (`dimension 3;` in system/particleDict)")

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


def _writer(movie: str, fps: float, out_dir: Path, field_name: str, fig, dpi: int):
    """The movie writer (set up on ``fig``) and its path, or (None, None)."""
    from matplotlib import animation

    if movie == "none":
        return None, None
    path = out_dir.parent / f"{field_name}.{movie}"
    writer = (animation.FFMpegWriter(fps=fps) if movie == "mp4"
              else animation.PillowWriter(fps=fps))
    writer.setup(fig, str(path), dpi=dpi)
    return writer, path


def _render_3d(case, folders, field_name, movie, fps, width, value_range, box, slice_text,
               slab, log) -> Rendered:
    """The frames of a 3-D case: a 3-D view and a slice (see the module)."""
    import matplotlib.pyplot as plt

    dx = case.particles.dx
    axis, where = parse_slice(slice_text)
    if slab is None:
        slab = dx
    if not slab > 0:
        raise CaseError.single("--slab", "", f"the slab's thickness must be > 0, got {slab}")
    plane = [a for a in range(3) if a != axis]         # the slice's in-plane axes

    def frames():
        for t, folder in folders:
            f = read_state(folder, dim=3)
            try:
                v = field_values(f, field_name)
            except KeyError:
                raise CaseError.single("--field", "", f"'{field_name}' is not a field of "
                                       f"{folder.name}/; choose from: "
                                       + ", ".join(_choices(f))) from None
            yield t, folder, np.asarray(f["positions"], float), np.asarray(f["type"]), v

    def value_span(pos, kind, v, where):
        sel = (kind == FLUID) & np.isfinite(v)
        if box is not None:
            sel &= np.abs(pos[:, axis] - where) <= 0.5 * slab
            sel &= (pos[:, plane[0]] >= box[0]) & (pos[:, plane[0]] <= box[2]) & \
                (pos[:, plane[1]] >= box[1]) & (pos[:, plane[1]] <= box[3])
        return (float(v[sel].min()), float(v[sel].max())) if sel.any() else (np.inf, -np.inf)

    # pass 1: the fixed axes, the slice's plane and the colour range over all frames (a
    # second pass for the range in the box when the plane is the middle of them all)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    vmin, vmax = np.inf, -np.inf
    for _, _, pos, kind, v in frames():
        lo, hi = np.minimum(lo, pos.min(axis=0)), np.maximum(hi, pos.max(axis=0))
        if box is None or where is not None:
            a, b = value_span(pos, kind, v, where)
            vmin, vmax = min(vmin, a), max(vmax, b)
    if where is None:
        where = 0.5 * (lo[axis] + hi[axis])
        if box is not None:
            for _, _, pos, kind, v in frames():
                a, b = value_span(pos, kind, v, where)
                vmin, vmax = min(vmin, a), max(vmax, b)
    if value_range is not None:
        vmin, vmax = map(float, value_range)
    if not (np.isfinite(vmin) and np.isfinite(vmax)):
        vmin, vmax = 0.0, 1.0
    if vmax <= vmin:
        vmax = vmin + max(abs(vmin), 1.0) * 1e-6
    lo, hi = lo - 2 * dx, hi + 2 * dx
    s_lo, s_hi = lo[plane], hi[plane]
    if box is not None:
        s_lo, s_hi = np.array(box[:2], float), np.array(box[2:], float)

    # the figure: the 3-D view on the left, the slice on equal axes on the right, a colour bar
    dpi = 100
    left, gap, right, bottom, top = 20, 90, 110, 50, 75            # margins (px)
    panel = max((width - left - gap - right) // 2, 100)
    s_span = s_hi - s_lo
    s_h = max(int(round(panel * s_span[1] / s_span[0])), 60)
    h = max(s_h, int(0.8 * panel))
    fig_w, fig_h = left + 2 * panel + gap + right, h + bottom + top
    fig = plt.figure(figsize=(fig_w / dpi, fig_h / dpi), dpi=dpi)
    ax3 = fig.add_axes([left / fig_w, bottom / fig_h, panel / fig_w, h / fig_h],
                       projection="3d")
    x_s = left + panel + gap
    ax = fig.add_axes([x_s / fig_w, (bottom + (h - s_h) / 2) / fig_h, panel / fig_w,
                       s_h / fig_h])
    cax = fig.add_axes([(x_s + panel + 15) / fig_w, bottom / fig_h, 15 / fig_w, h / fig_h])
    span = hi - lo
    ax3.set_xlim(lo[0], hi[0])
    ax3.set_ylim(lo[1], hi[1])
    ax3.set_zlim(lo[2], hi[2])
    ax3.set_box_aspect(span)
    ax3.view_init(elev=25, azim=-60)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z (m)")
    ax.set_xlim(s_lo[0], s_hi[0])
    ax.set_ylim(s_lo[1], s_hi[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{AXES[plane[0]]} (m)")
    ax.set_ylabel(f"{AXES[plane[1]]} (m)")
    size3 = (MARKER * dx * 0.7 * panel / span.max() * 72.0 / dpi) ** 2
    size = (MARKER * dx * panel / s_span[0] * 72.0 / dpi) ** 2
    label = DERIVED_3D.get(field_name) or UNITS.get(field_name, field_name)
    norm = dict(cmap="viridis", vmin=vmin, vmax=vmax)
    empty = np.zeros((0, 2))
    walls = ax.scatter(empty[:, 0], empty[:, 1], s=size, c=WALL_GREY, linewidths=0,
                       snap=False)
    fluid_sc = ax.scatter(empty[:, 0], empty[:, 1], s=size, c=[], linewidths=0, snap=False,
                          **norm)
    fig.colorbar(fluid_sc, cax=cax, label=label)
    title = fig.suptitle("", y=1 - 12 / fig_h, va="top")

    out_dir = case.path / "postProcessing" / "render" / field_name
    out_dir.mkdir(parents=True, exist_ok=True)
    result = Rendered(vmin=vmin, vmax=vmax)
    writer, result.movie = _writer(movie, fps, out_dir, field_name, fig, dpi)
    drawn3 = []
    try:
        for t, folder, pos, kind, v in frames():                     # pass 2: the frames
            for artist in drawn3:
                artist.remove()
            fl, wl = kind == FLUID, kind == WALL
            drawn3 = [ax3.scatter(*pos[wl].T, s=size3, c=[WALL_3D], linewidths=0,
                                  depthshade=False),
                      ax3.scatter(*pos[fl].T, s=size3, c=v[fl], linewidths=0,
                                  depthshade=False, **norm)]
            near = np.abs(pos[:, axis] - where) <= 0.5 * slab
            walls.set_offsets(pos[near & wl][:, plane] if (near & wl).any() else empty)
            fluid_sc.set_offsets(pos[near & fl][:, plane] if (near & fl).any() else empty)
            fluid_sc.set_array(v[near & fl])
            ax.set_title(f"slice {AXES[axis]} = {where:.4g} m (slab {slab:.3g} m)")
            title.set_text(f"{case.name}: t = {t:.4g} s, {label} of {int(fl.sum())} fluid "
                           "particles")
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
        f"({fig_w} x {fig_h} px, 3-D view and slice {AXES[axis]} = {where:.4g} m, colour "
        f"range {vmin:.4g} .. {vmax:.4g})"
        + (f", {result.movie.relative_to(case.path)}" if result.movie else ""))
    return result
