"""A wave breaking on a beach (T ch. 5): breakingPoint, surfaceProfiles, the shoreline of
runUp mode beach and their metrics on synthetic particle sets with known answers."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from sphfoam import registry
from sphfoam.case.foamdict import parse
from sphfoam.engine.state import FLUID, WALL, ParticleState
from sphfoam.models.base import CaseContext
from sphfoam.models.kernels import WendlandC2
from sphfoam.sampling import beach

DX = 0.02
D = 0.5          # still level


class FakeSim:
    def __init__(self, x, y, u=None, time=0.0, kind=None):
        n = len(x)
        z = np.zeros(n)
        self.state = ParticleState(np.asarray(x, float), np.asarray(y, float),
                                   z.copy() if u is None else np.asarray(u, float), z.copy(),
                                   np.full(n, 1000.0), np.full(n, 1000.0 * DX * DX),
                                   np.full(n, FLUID) if kind is None else kind)
        self.time = time


def fake_case(tmp_path):
    kernel = WendlandC2()
    case = SimpleNamespace(path=tmp_path, models=SimpleNamespace(sph={"kernel": kernel}),
                           control=SimpleNamespace(timePrecision=6))
    ctx = CaseContext(dx=DX, h=1.3 * DX, rho0=1000.0, nu=1e-6, g=(0.0, -9.81),
                      fluid_height=D)
    return case, ctx


def build(text, name="fo", family="functionObject"):
    fo = registry.build(family, parse(text))
    fo.object_name = name
    return fo


def wave(x_crest, height, face, length=8.0, lean=0.0):
    """Particles on a dx lattice under a surface: still level D, a crest plateau of
    ``height`` over the 0.4 m behind x_crest, a back slope 1:4 and a front face at
    ``face`` degrees to the horizontal ahead of it (``lean`` > 0: the front overhangs, the
    face x = x_crest + (y - D) lean for y above D). Column tops are the cell tops."""
    xc = (np.arange(int(round(length / DX))) + 0.5) * DX
    yc = (np.arange(int((D + height) / DX) + 2) + 0.5) * DX
    X, Y = (a.ravel() for a in np.meshgrid(xc, yc))
    top = D + height
    back = top - (x_crest - 0.4 - X) / 4.0
    if lean > 0:
        front_x = x_crest + (Y - D) * lean
        inside = np.where(X <= x_crest, Y + DX / 2 <= np.minimum(top, back),
                          (Y + DX / 2 <= top) & (X <= front_x))
        inside |= Y + DX / 2 <= D
    else:
        t = math.tan(math.radians(face))
        front = top - (X - x_crest) * t
        surf = np.maximum(np.minimum(np.minimum(top, back), front), D)
        inside = Y + DX / 2 <= surf + 1e-9
    return X[inside], Y[inside]


# --- the front face ----------------------------------------------------------------------------
@pytest.mark.parametrize("angle", [20.0, 45.0, 60.0, 70.0, 80.0])
def test_face_angle_of_a_known_front(angle):
    """A straight front face at a known angle, 15 dx high: recovered within 5 degrees (the
    lattice quantises each front to dx: the face's 0.12 m between 0.5 and 0.9 of the crest
    spans 6 dx, and a steep face only 1-2 dx across)."""
    H = 0.3
    x, y = wave(4.0, H, angle)
    levels = np.arange(D + 0.5 * H, D + 0.9 * H + 1e-9, DX / 2)
    fronts = beach.face_fronts(x, y + DX / 2, levels, 3.9, DX)
    assert np.isfinite(fronts).all()
    assert beach.face_angle(levels, fronts) == pytest.approx(angle, abs=5.0)


def test_vertical_and_overhanging_fronts():
    x, y = wave(4.0, 0.15, 90.0)
    levels = np.linspace(D + 0.075, D + 0.135, 7)
    vertical = beach.face_angle(levels, beach.face_fronts(x, y + DX / 2, levels, 3.9, DX))
    assert vertical == pytest.approx(90.0, abs=1e-9)
    x, y = wave(4.0, 0.3, 0.0, lean=0.5)             # the top 0.5 dx per dx of height ahead
    levels = np.arange(D + 0.15, D + 0.27 + 1e-9, DX / 2)
    over = beach.face_angle(levels, beach.face_fronts(x, y + DX / 2, levels, 3.9, DX))
    assert over == pytest.approx(90.0 + math.degrees(math.atan(0.5)), abs=5.0)


def test_face_walk_stops_at_a_gap():
    """Water further ahead at the same height (a splash, the shoreline) is not the face."""
    x, y = wave(4.0, 0.15, 45.0)
    xs, ys = np.append(x, [5.0, 5.0 + DX]), np.append(y, [D + 0.1, D + 0.1])
    f = beach.face_fronts(xs, ys + DX / 2, [D + 0.1], 3.9, DX)[0]
    assert 4.0 < f < 4.2


# --- breakingPoint -------------------------------------------------------------------------------
def test_breaking_point_geometric_and_kinematic(tmp_path):
    """A wave travelling at c = 2 m/s whose front steepens 30 -> 60 -> 90 degrees: the
    geometric breaking point is the first vertical front, with its time from the crest
    passing the toe gauge; the crest particles reach u = 1.5 c a sample later (the crest
    celerity, from the vertex of the flat synthetic crest over 0.2 s, is within 15 %)."""
    case, ctx = fake_case(tmp_path)
    fo = build("type breakingPoint; xMin 1; xMax 7.5; still 0.5; toe 2.5; "
               "celerityWindow 0.2; minHeight 0.05;")
    fo.start(case, ctx, "0")
    c = 2.0
    faces = [30, 30, 45, 60, 75, 90, 90, 90]
    for k, face in enumerate(faces):
        t = 0.1 * k
        xcr = 2.0 + c * t
        x, y = wave(xcr, 0.15, face)
        u = np.where(y > D + 0.12, (0.5 if k < 6 else 1.5) * c, 0.0)
        fo.execute(FakeSim(x, y, u, time=t))
    fo.end()
    rows = beach.read_breaking(tmp_path / "postProcessing/fo/0/summary.dat")
    assert list(rows) == ["geometric", "kinematic"]
    g, kin = rows["geometric"], rows["kinematic"]
    assert g["time"] == pytest.approx(0.5)
    assert g["x"] == pytest.approx(2.0 + c * 0.5, abs=2 * DX)          # the face
    # crest (the plateau's parabola vertex, 0.2 m behind x_crest) passes 2.5 m at ~0.35 s
    assert g["tToe"] == pytest.approx((2.5 - 2.0 + 0.2) / c, abs=0.03)
    assert g["toeToBreaking"] == pytest.approx(g["time"] - g["tToe"], abs=1e-9)
    assert kin["time"] == pytest.approx(0.6)
    data = np.loadtxt(tmp_path / "postProcessing/fo/0/fo.dat", ndmin=2)
    assert data.shape == (len(faces), 8)
    np.testing.assert_allclose(data[2:, 6], c, rtol=0.15)                # celerity
    assert np.isnan(data[:2, 6]).all()                 # less than celerityWindow of data
    assert data[0, 4] == pytest.approx(30.0, abs=4.0)


def test_breaking_point_carries_on_after_a_restart(tmp_path):
    """A run killed between the geometric criterion's first sample and its `persist` and
    restarted from t = 0.5 writes the summary of the run that was not broken: the toe time
    from the samples before the restart, the breaking points from the criteria's state
    carried over, the celerity window refilled (sphfoam.sampling.beach._resume)."""
    case, ctx = fake_case(tmp_path)
    spec = ("type breakingPoint; xMin 1; xMax 7.5; still 0.5; toe 2.5; celerityWindow 0.2; "
            "minHeight 0.05;")
    c, faces = 2.0, [30, 30, 45, 60, 75, 90, 90, 90]

    def sim(k):
        x, y = wave(2.0 + c * 0.1 * k, 0.15, faces[k])
        return FakeSim(x, y, np.where(y > D + 0.12, (0.5 if k < 6 else 1.5) * c, 0.0),
                       time=0.1 * k)

    whole = build(spec, name="whole")
    whole.start(case, ctx, "0")
    for k in range(len(faces)):
        whole.execute(sim(k))
    whole.end()
    broken = build(spec, name="broken")
    broken.start(case, ctx, "0")
    for k in range(6):                        # killed after the sample at 0.5 s
        broken.execute(sim(k))
    again = build(spec, name="broken")
    again.start(case, ctx, "0.5")             # restarted from the time directory 0.5
    for k in range(6, len(faces)):
        again.execute(sim(k))
    again.end()
    want = beach.read_breaking(tmp_path / "postProcessing/whole/0/summary.dat")
    got = beach.read_breaking(tmp_path / "postProcessing/broken/0.5/summary.dat")
    assert math.isfinite(want["geometric"]["toeToBreaking"])
    for crit in ("geometric", "kinematic"):
        for col, v in want[crit].items():
            assert got[crit][col] == pytest.approx(v, rel=1e-8), (crit, col)
    rows = np.loadtxt(tmp_path / "postProcessing/broken/0.5/broken.dat", ndmin=2)
    ref = np.loadtxt(tmp_path / "postProcessing/whole/0/whole.dat", ndmin=2)[6:]
    np.testing.assert_allclose(rows, ref, rtol=1e-8)  # the celerity right after the restart


def test_breaking_point_not_found_and_checks(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type breakingPoint; xMin 1; xMax 7.5; still 0.5;")
    fo.start(case, ctx, "0")
    x, y = wave(3.0, 0.15, 30)
    fo.execute(FakeSim(x, y, time=0.0))
    fo.end()
    rows = beach.read_breaking(tmp_path / "postProcessing/fo/0/summary.dat")
    assert math.isnan(rows["geometric"]["time"]) and math.isnan(rows["kinematic"]["time"])
    with pytest.raises(Exception, match="xMax"):
        build("type breakingPoint; xMin 2; xMax 1;")
    with pytest.raises(Exception, match="faceTo"):
        build("type breakingPoint; xMin 1; xMax 2; faceFrom 0.8; faceTo 0.6;")


# --- surfaceProfiles -------------------------------------------------------------------------------
def test_surface_profiles_write_the_known_surface(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type surfaceProfiles; times (0.5 1); xMin 2; xMax 6; still 0.5;")
    fo.start(case, ctx, "0")
    x, y = wave(4.0, 0.15, 45.0)
    walls_x = np.arange(0, 8, DX)
    xs = np.concatenate([x, walls_x])
    ys = np.concatenate([y, np.full(walls_x.size, -DX / 2)])
    kind = np.concatenate([np.full(x.size, FLUID), np.full(walls_x.size, WALL)])
    for t in (0.2, 0.52, 0.7, 1.3):            # as `sphfoam sample` does: every time
        sim = FakeSim(xs, ys, time=t, kind=kind)
        assert fo.due(sim, False) == (t in (0.52, 1.3))
        fo.execute(sim)
    fo.end()
    folders = sorted(p.name for p in (tmp_path / "postProcessing/fo/0").iterdir() if p.is_dir())
    assert folders == ["0.52", "1.3"]
    prof = np.loadtxt(tmp_path / "postProcessing/fo/0/0.52/profile.dat")
    gx, eta = prof[:, 0], prof[:, 1]
    assert gx[0] == pytest.approx(2.0) and gx[-1] == pytest.approx(6.0)
    assert np.diff(gx) == pytest.approx(DX / 2)
    exact = np.maximum(np.minimum(np.minimum(0.15, 0.15 - (3.6 - gx) / 4),
                                  0.15 - (gx - 4.0)), 0.0)
    assert np.abs(eta - exact).max() <= DX + 1e-9                  # lattice: within dx
    assert np.abs(eta - exact).mean() <= DX / 2
    part = np.loadtxt(tmp_path / "postProcessing/fo/0/0.52/particles.dat")
    assert part.shape == (int(((x >= 2) & (x <= 6)).sum()), 5)     # fluid only
    assert (tmp_path / "postProcessing/fo/0/0.52/profile.png").stat().st_size > 1000
    rows = np.loadtxt(tmp_path / "postProcessing/fo/0/fo.dat", ndmin=2)
    np.testing.assert_allclose(rows[:, :2], [[0.52, 0.5], [1.3, 1.0]])


# --- the shoreline and the metrics ---------------------------------------------------------------
def test_beach_shoreline_x_and_metrics(tmp_path):
    from sphfoam.case.metrics_dict import evaluate_metrics

    case, ctx = fake_case(tmp_path)
    a = math.radians(5.0)
    ru = build(f"type runUp; mode beach; start (5 0); angle 5; still {D};", name="shore")
    ru.start(case, ctx, "0")
    for t, xs in ((0.0, 10.7), (1.0, 12.0), (2.0, 11.0)):
        # a water layer on the slope up to x = xs
        px = np.arange(5.0, xs, DX)
        py = (px - 5.0) * math.tan(a) + DX / 2
        py = np.where(py < D, D - DX / 2, py)
        ru.execute(FakeSim(px, py, time=t))
    ru.end()
    data = np.loadtxt(tmp_path / "postProcessing/shore/0/shore.dat", ndmin=2)
    assert data.shape[1] == 5
    # onBeach: the beach's own height dx/2 beyond the furthest particle (the layer's
    # particles sit dx/2 above the beach: highestParticle reads dx higher)
    px = np.arange(5.0, 12.0, DX)
    py = (px - 5.0) * math.tan(a) + DX / 2
    from sphfoam.sampling.waves import beach_shoreline
    r, xs = beach_shoreline(px, py, (5, 0), 5, DX, still=D, on_beach=True)
    s_top = (px[-1] - 5.0) / math.cos(a) + (DX / 2) * math.sin(a) + DX / 2
    assert r == pytest.approx(s_top * math.sin(a) - D, abs=1e-9)
    assert xs == pytest.approx(5.0 + s_top * math.cos(a), abs=1e-9)
    assert beach_shoreline(px, py, (5, 0), 5, DX, still=D)[0] == pytest.approx(
        py[-1] + DX / 2 - D)
    with pytest.raises(Exception, match="mode beach only"):
        build("type runUp; mode wall; x 1; shoreline onBeach;")
    assert data[1, 3] == pytest.approx(12.0, abs=DX)
    assert data[2, 4] == pytest.approx(12.0, abs=DX)                  # x at the maximum
    assert data[1, 1] == pytest.approx(7.0 * math.tan(a) + DX - D, abs=2 * DX)

    bp = build("type breakingPoint; xMin 1; xMax 7.5; still 0.5; toe 2.5;", name="breaking")
    bp.start(case, ctx, "0")
    bp.found["geometric"] = (3.0, 9.0, 0.2)
    bp.samples = [(0.0, 2.0, 0.2), (1.0, 3.0, 0.2)]
    bp.end()
    spec = {"R": {"type": "runUp", "function": "shore", "reference": 0.4},
            "xR": {"type": "runUpPosition", "function": "shore", "reference": 10.43,
                   "origin": 5.0},
            "tR": {"type": "runUpPosition", "function": "shore", "quantity": "time"},
            "tb": {"type": "breakingTime", "function": "breaking", "reference": 1.96},
            "xb": {"type": "breakingTime", "function": "breaking", "quantity": "x"},
            "kb": {"type": "breakingTime", "function": "breaking", "criterion": "kinematic"}}
    vals = evaluate_metrics(tmp_path, spec, strict=False)
    assert vals["xR"].value == pytest.approx(7.0, abs=DX)
    assert vals["xR"].error == pytest.approx(100 * (vals["xR"].value - 10.43) / 10.43)
    assert vals["tR"].value == 1.0 and vals["tR"].unit == "s"
    assert vals["tb"].value == pytest.approx(3.0 - 0.5)               # toe passed at 0.5 s
    assert vals["xb"].value == 9.0 and vals["xb"].unit == "m"
    assert math.isnan(vals["kb"].value) and "kinematic" in vals["kb"].problem


# --- the tutorial, end to end at a tiny resolution ---------------------------------------------
def test_coarse_beach_case_breaks_and_runs_up(tutorial):
    """tutorials/solitaryBeach scaled down to run in seconds: d = 0.1 m, d/dx = 5, a steeper
    wave (H/d = 0.5 from the Goring paddle, 0.5 m before the toe) on the 5° beach, which
    plunges (Grilli's slope parameter S0 = 1.521 tan(5°)/sqrt(H/d) = 0.19, plunging for
    0.025 < S0 < 0.3), with the tutorial's models (free-slip mirror ghosts, no SPS) and
    its settling (0.2 s here). The run-up (the tutorial's `shoreline onBeach`) is written,
    consistent with its x on the beach and above half the depth (0.74 d when written, at
    3.08 s, with the tutorial's hydrostatic ghosts and smooth wall law; 0.71 d on the
    frictionless ghosts of T(3.80) before them; the tutorial's earlier hybrid walls with SPS
    and the wall law stopped it at 0.1 d, issue 14); the breaking point by the tutorial's kinematic criterion is found on the
    beach after the crest passed the toe gauge and before the maximum run-up; the geometric one is not meaningful (the
    crest stands 2.5 dx high: its face is about dx high), and the
    tutorial's metrics evaluate. (At d/dx = 5 the crest particles outrun the crest only in
    the bore at the shoreline: this checks the machinery end to end, not T's breaking
    time.)"""
    from sphfoam.case.metrics_dict import evaluate_metrics
    from sphfoam.timeloop import run_case

    d, dx, toe = 0.1, 0.02, 0.5
    length = 0.4 / math.sin(math.radians(5.0))
    edits = {
        "system/particleDict:dx": dx,
        "system/particleDict:fluid.flat.min": [0.0, 0.0],
        "system/particleDict:fluid.flat.max": [toe, d],
        "system/particleDict:fluid.beach.points": [
            [toe, 0.0], [toe + d / math.tan(math.radians(5)), d], [toe, d]],
        "system/particleDict:fluid.beach.grid.origin": [toe, 0.0],
        "system/particleDict:walls.bed.points": [[-0.3, 0.0], [toe, 0.0]],
        "system/particleDict:walls.beach.start": [toe, 0.0],
        "system/particleDict:walls.beach.length": length,
        "system/particleDict:walls.paddle.points": [[0.0, 0.4], [0.0, 0.0]],
        "system/particleDict:walls.paddle.motion.waveMaker.height": 0.5 * d,
        "system/particleDict:walls.paddle.motion.waveMaker.depth": d,
        "constant/sphProperties:equationOfState.vmax": math.sqrt(9.81 * 1.5 * d),
        "system/controlDict:endTime": 4.0,
        "system/controlDict:settling.endTime": 0.2,         # sound crosses in 0.1 s
        "system/controlDict:writeInterval": 1.25,
        "system/controlDict:functions.toe.x": [toe - 0.15],
        "system/controlDict:functions.toe.still": d,
        "system/controlDict:functions.breaking.xMin": 0.3,
        "system/controlDict:functions.breaking.xMax": toe + length,
        "system/controlDict:functions.breaking.still": d,
        "system/controlDict:functions.breaking.toe": toe - 0.15,
        "system/controlDict:functions.breaking.after": toe,
        "system/controlDict:functions.breaking.minHeight": 0.02,
        # five particles per depth: with the tutorial's hydrostatic ghosts and wall law the
        # crest particles outrun the crest for single samples only (u/c = 1.002 at 1.70 s,
        # 1.048 at 2.31 s, measured), so the machinery is checked without `persist`
        "system/controlDict:functions.breaking.persist": 0.0,
        "system/controlDict:functions.shoreline.start": [toe, 0.0],
        "system/controlDict:functions.shoreline.length": length,
        "system/controlDict:functions.shoreline.still": d,
        "system/controlDict:functions.profiles.times": [1.0],
        "system/controlDict:functions.profiles.xMin": toe,
        "system/controlDict:functions.profiles.xMax": toe + 2.0,
        "system/controlDict:functions.profiles.yMin": 0.0,
        "system/controlDict:functions.profiles.yMax": 0.3,
        "system/controlDict:functions.profiles.still": d,
        "system/controlDict:functions.profiles.plot": False,
        "system/metricsDict:metrics.toeHeight.x": toe - 0.15,
        "system/metricsDict:metrics.toeHeight.reference": 0.5 * d,
    }
    case = tutorial("solitaryBeach", edits)
    run_case(case, progress=False, echo=None)
    pp = case / "postProcessing"
    rows = beach.read_breaking(pp / "breaking/0/summary.dat")
    assert list(rows) == ["kinematic", "geometric"]
    k, g = rows["kinematic"], rows["geometric"]
    shore = np.loadtxt(pp / "shoreline/0/shoreline.dat", ndmin=2)
    i = int(np.nanargmax(shore[:, 1]))
    still_shore = toe + d / math.tan(math.radians(5))
    assert shore[i, 1] > 0.5 * d                           # the tongue ran up the beach,
    assert shore[i, 4] > still_shore + 0.05                # beyond the still shoreline
    assert shore[i, 1] == pytest.approx((shore[i, 4] - toe) * math.tan(math.radians(5)) - d)
    assert toe < k["x"] <= toe + length * math.cos(math.radians(5))
    assert 0.0 < k["tToe"] < k["time"] < shore[i, 0]       # breaks before the maximum
    # the geometric criterion needs the face resolved (the crest stands 2.5 dx high here):
    # without `persist` a single sample can read a face (1.02 s, at x = 0.69 m, measured)
    assert math.isnan(g["time"]) or 0.0 < g["tToe"] < g["time"] < shore[i, 0]
    assert [p.parent.name[:3] for p in (pp / "profiles/0").glob("*/profile.dat")] == ["1.0"]
    vals = evaluate_metrics(case, strict=False)
    assert vals["runUp"].value == pytest.approx(shore[i, 1])
    assert vals["breakingTime"].value == pytest.approx(k["toeToBreaking"])
    assert 0 < vals["toeHeight"].value < 0.07


def test_connected_shoreline_leaves_out_particles_apart_from_the_water(tmp_path):
    """`shoreline connected`: the shoreline is the top of the layer in contact whose particles
    each lie within the kernel's support of the one below; particles further up the beach
    beyond a larger gap (they feel no pressure from the water and slide on by themselves, as
    at d/dx = 20 in the tutorial) do not count. `onBeach` counts them."""
    from sphfoam.sampling.waves import beach_shoreline

    case, ctx = fake_case(tmp_path)
    a = math.radians(5.0)
    support = WendlandC2().support * ctx.h                     # 2 x 1.3 dx = 2.6 dx
    s = np.arange(0.0, 3.0, DX)                                 # the layer, up to s = 2.98 m
    s_free = np.array([s[-1] + 1.5 * support, s[-1] + 4.0 * support])  # apart from it
    for along, top in ((s, s[-1]), (np.append(s, s_free), s[-1])):
        px = 5.0 + along * math.cos(a) - (DX / 2) * math.sin(a)
        py = along * math.sin(a) + (DX / 2) * math.cos(a)
        r, xs = beach_shoreline(px, py, (5, 0), 5, DX, on_beach=True, gap=support)
        assert r == pytest.approx((top + DX / 2) * math.sin(a), abs=1e-9)
        assert xs == pytest.approx(5.0 + (top + DX / 2) * math.cos(a), abs=1e-9)
    r_on = beach_shoreline(px, py, (5, 0), 5, DX, on_beach=True)[0]
    assert r_on == pytest.approx((s_free[-1] + DX / 2) * math.sin(a), abs=1e-9)
    # a gap within the support keeps the layer connected
    near = np.append(s, s[-1] + 0.9 * support)
    r = beach_shoreline(5.0 + near * math.cos(a) - (DX / 2) * math.sin(a),
                        near * math.sin(a) + (DX / 2) * math.cos(a), (5, 0), 5, DX,
                        on_beach=True, gap=support)[0]
    assert r == pytest.approx((near[-1] + DX / 2) * math.sin(a), abs=1e-9)

    ru = build("type runUp; mode beach; start (5 0); angle 5; shoreline connected;",
               name="shore")
    ru.start(case, ctx, "0")
    ru.execute(FakeSim(px, py, time=0.0))
    ru.end()
    data = np.loadtxt(tmp_path / "postProcessing/shore/0/shore.dat", ndmin=2)
    assert data[0, 1] == pytest.approx((s[-1] + DX / 2) * math.sin(a), abs=1e-9)
    with pytest.raises(Exception, match="mode beach only"):
        build("type runUp; mode wall; x 1; shoreline connected;")


def test_breaking_point_needs_the_criterion_to_persist(tmp_path):
    """A crest that stalls over the toe for a moment (its fitted celerity collapsing, so
    u/c passes 1 for 0.01-0.03 s, as the tutorial's d/dx = 10 run did 0.25 s past the toe)
    is not the breaking point: a criterion must hold for `persist` (0.05 s by default); the
    breaking point is then the first sample of the run of samples that held."""
    case, ctx = fake_case(tmp_path)
    c = 2.0
    for name, persist, want in (("held", 0.05, 0.6), ("first", 0.0, 0.2)):
        fo = build(f"type breakingPoint; xMin 1; xMax 7.5; still 0.5; toe 1.5; "
                   f"celerityWindow 0.1; minHeight 0.05; persist {persist};", name=name)
        fo.start(case, ctx, "0")
        for k in range(16):                  # every 0.05 s; u = 1.5 c at 0.2 s (a blip)
            t = 0.05 * k                     # and from 0.6 s on (it breaks for good)
            x, y = wave(2.0 + c * t, 0.15, 30)
            fast = k == 4 or k >= 12
            fo.execute(FakeSim(x, y, np.where(y > D + 0.12, (1.5 if fast else 0.5) * c, 0.0),
                               time=t))
        fo.end()
        rows = beach.read_breaking(tmp_path / f"postProcessing/{name}/0/summary.dat")
        assert rows["kinematic"]["time"] == pytest.approx(want), name
        assert math.isnan(rows["geometric"]["time"])
