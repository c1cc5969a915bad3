"""Wave sampling function objects (sphfoam/sampling/waves.py) on synthetic particle sets.

Gauge T §4.3.2 against an analytic solitary-wave surface, SPH probes against a linear field,
run-up on a wall and a beach, crest celerity of a translated wave, and the start/execute/end
cycle of every object against a fake simulation. No SPH run.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import sphfoam.sampling.waves as waves
from sphfoam import registry
from sphfoam.case.foamdict import parse
from sphfoam.engine.state import FLUID, GHOST, WALL, ParticleState
from sphfoam.models.base import CaseContext
from sphfoam.models.kernels import CubicSpline, Gaussian, Quintic, WendlandC2
from sphfoam.sampling.base import FunctionObjectCoeffs

D, A, DX = 1.0, 0.3, 0.02                    # depth, wave height, particle spacing
K = math.sqrt(3.0 * A / (4.0 * D**3))         # Boussinesq sech^2 wavenumber
NAMES = ("waveGauges", "probes", "lines", "runUp", "crestTracker")


def eta_sech2(x, x0):
    return A / np.cosh(K * (np.asarray(x) - x0)) ** 2


def lattice(surface, length=20.0, top=D + A, dx=DX):
    """Particles at the cell centres of a dx lattice filling 0 <= y <= surface(x), as the
    set-up places them."""
    xc = (np.arange(int(round(length / dx))) + 0.5) * dx
    yc = (np.arange(int(top / dx) + 2) + 0.5) * dx
    X, Y = (a.ravel() for a in np.meshgrid(xc, yc))
    keep = Y <= surface(X)
    return X[keep], Y[keep]


def stretched(surface, length=20.0, dx=DX):
    """Columns of particles at x = (i + 1/2) dx with n = round(S/dx) rows evenly spaced by
    S/n, so the top particle sits half a (local) spacing below the surface S(x)."""
    xc = (np.arange(int(round(length / dx))) + 0.5) * dx
    s = surface(xc)
    n = np.rint(s / dx).astype(int)
    j = np.concatenate([np.arange(m) for m in n])
    return np.repeat(xc, n), (j + 0.5) * np.repeat(s / n, n)


# --- fakes -------------------------------------------------------------------------------------
class FakeSim:
    """What a function object reads from a Simulation: state, time, eos()."""

    def __init__(self, x, y, u=None, v=None, p=None, kind=None, time=0.0, rho0=1000.0):
        n = len(x)
        z = np.zeros(n)
        self.state = ParticleState(x, y, z if u is None else u, z if v is None else v,
                                   np.full(n, rho0), np.full(n, rho0 * DX * DX),
                                   np.full(n, FLUID) if kind is None else kind)
        if p is not None:
            self.state.p[:] = p
        self.time = time
        self.eos_calls = 0

    def eos(self):
        self.eos_calls += 1


def fake_case(tmp_path, kernel=None):
    kernel = kernel or WendlandC2()
    case = SimpleNamespace(path=tmp_path, models=SimpleNamespace(sph={"kernel": kernel}),
                           control=SimpleNamespace(timePrecision=6))
    ctx = CaseContext(dx=DX, h=kernel.coeffs.hdx * DX, rho0=1000.0, nu=1e-6, g=(0.0, -9.81),
                      fluid_height=D)
    return case, ctx


def build(spec_text: str, name="fo"):
    """A function object from its controlDict text, as the case layer builds it."""
    fo = registry.build("functionObject", parse(spec_text))
    fo.object_name = name
    return fo


def read_dat(path):
    lines = path.read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("#")]
    data = np.loadtxt(path, ndmin=2)
    return header, header[-1][2:].split("\t"), data


# --- registry ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_registered_with_doc_docstring_and_described_keys(name):
    cls = registry.get("functionObject", name)
    assert cls.__module__ == "sphfoam.sampling.waves"
    assert cls.doc and "\n" not in cls.doc
    assert cls.__dict__.get("__doc__", "").strip()
    inherited = set(FunctionObjectCoeffs.model_fields)
    for key, f in cls.Coeffs.model_fields.items():
        assert key in inherited or f.description, f"{name}.{key} has no description"


# --- wave gauge, T §4.3.2 ----------------------------------------------------------------------
def test_gauge_reads_a_solitary_wave_surface():
    """Columns whose top particle sits half a spacing below S = d + eta: the gauge reads eta
    to 0.02 dx (the residual is the linear interpolation over <= 5 dx and the column spacing
    S/n differing from dx by < dx/2n)."""
    x0 = 10.0
    x, y = stretched(lambda s: D + eta_sech2(s, x0))
    g = np.linspace(2.0, 18.0, 401)
    eta = waves.surface_elevation(x, y, g, DX, still=D)
    assert np.max(np.abs(eta - eta_sech2(g, x0))) < 0.02 * DX


def test_gauge_on_a_fixed_lattice_is_within_half_a_spacing():
    """On the set-up's fixed lattice the top particle is 0..dx below the surface, so the reading
    (top + dx/2) is within dx/2 of eta, unbiased on average."""
    x0 = 9.97
    x, y = lattice(lambda s: D + eta_sech2(s, x0))
    g = np.linspace(2.0, 18.0, 801)
    err = waves.surface_elevation(x, y, g, DX, still=D) - eta_sech2(g, x0)
    assert np.max(np.abs(err)) <= 0.5 * DX + 1e-12
    assert np.sqrt(np.mean(err**2)) < 0.3 * DX
    assert abs(np.mean(err)) < 0.05 * DX


def test_flat_water_reads_zero_exactly():
    x, y = lattice(lambda s: np.full_like(s, D), length=4.0)
    g = np.concatenate([np.linspace(0.0, 4.0, 97), (np.arange(200) + 0.5) * DX])  # ends too
    eta = waves.surface_elevation(x, y, g, DX, still=D)
    assert np.all(eta == 0.0)
    np.testing.assert_array_equal(waves.surface_elevation(x, y, g, DX), D)   # still = 0: y


def test_gauge_windows_and_interpolation():
    """Highest particle in [x_g - 2.5 dx, x_g) and in [x_g, x_g + 2.5 dx], joined linearly."""
    x = np.array([0.0, 0.5, 1.0, 3.0, 5.0]) * DX
    y = np.array([0.9, 0.5, 0.2, 0.6, 0.4])
    # gauge at 2 dx: left window [-0.5, 2) dx holds 0, 0.5, 1 -> highest (0, 0.9);
    # right [2, 4.5] dx holds 3 -> (3, 0.6); line at 2 dx: 0.9 - 0.3 * 2/3 = 0.7
    assert waves.surface_elevation(x, y, [2 * DX], DX)[0] == pytest.approx(0.7 + DX / 2)
    # gauge on a particle: it is in the right window
    assert waves.surface_elevation(x, y, [3 * DX], DX)[0] == pytest.approx(
        0.2 + (0.6 - 0.2) * 2 / 2 + DX / 2)
    # one side only reads that particle; no particle within 2.5 dx: NaN
    assert waves.surface_elevation(x, y, [7.4 * DX], DX)[0] == pytest.approx(0.4 + DX / 2)
    assert np.isnan(waves.surface_elevation(x, y, [9 * DX], DX)[0])


def test_wave_gauges_object(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type waveGauges; x (5 9.5 10 12.25); still 1;")
    x0 = 10.0
    x, y = stretched(lambda s: D + eta_sech2(s, x0))
    # wall and ghost particles above the surface must not count
    x = np.concatenate([x, [10.0, 5.0]])
    y = np.concatenate([y, [3.0, 3.0]])
    kind = np.concatenate([np.full(x.size - 2, FLUID), [WALL, GHOST]])
    fo.start(case, ctx, "0")
    for t in (0.0, 0.1):
        fo.execute(FakeSim(x, y, kind=kind, time=t))
    fo.end()
    f = tmp_path / "postProcessing" / "fo" / "0" / "fo.dat"
    header, cols, data = read_dat(f)
    assert cols == ["time", "eta(5)", "eta(9.5)", "eta(10)", "eta(12.25)"]
    assert data.shape == (2, 5)
    np.testing.assert_allclose(data[:, 1:], np.tile(eta_sech2([5, 9.5, 10, 12.25], x0), (2, 1)),
                               atol=0.02 * DX)


# --- probes ------------------------------------------------------------------------------------
@pytest.mark.parametrize("kernel", [WendlandC2, CubicSpline, Quintic, Gaussian])
def test_probes_interpolate_a_linear_field(kernel):
    """Shepard-normalised SPH interpolation reproduces p = a + b y (and u, v) in the interior
    of a lattice, away from the kernel support of the edges."""
    kern = kernel()
    h = kern.coeffs.hdx * DX
    x, y = lattice(lambda s: np.full_like(s, D), length=2.0)
    p = 1000.0 + 9810.0 * (D - y)
    u, v = 0.3 + 0.5 * y, -0.1 * x
    rng = np.random.default_rng(1)
    xq = rng.uniform(0.5, 1.5, 50)
    yq = rng.uniform(0.2, 0.8, 50)
    out = waves.sph_interpolate(x, y, np.full(x.size, DX * DX), np.stack([p, u, v]), xq, yq,
                                kern, h)
    np.testing.assert_allclose(out[0], 1000.0 + 9810.0 * (D - yq), rtol=1e-3)
    np.testing.assert_allclose(out[1], 0.3 + 0.5 * yq, rtol=1e-3)
    np.testing.assert_allclose(out[2], -0.1 * xq, rtol=1e-3)
    # above the water by more than the kernel support, or beyond its end: NaN
    far = waves.sph_interpolate(x, y, np.full(x.size, DX * DX), np.stack([p]),
                                [1.0, 3.0], [D + 1.01 * kern.support * h, 0.5], kern, h)
    assert np.all(np.isnan(far))


def test_probes_object(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type probes; points ((1 0.5) (1.2 0.3 0) (1 5));")
    x, y = lattice(lambda s: np.full_like(s, D), length=2.0)
    sim = FakeSim(x, y, u=0.2 + 0 * x, v=0.1 * y, p=9810.0 * (D - y), time=0.5)
    fo.start(case, ctx, "0")
    fo.execute(sim)
    fo.end()
    assert sim.eos_calls == 1                   # pressure brought up to date first
    header, cols, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert cols[:4] == ["time", "p(1,0.5)", "Ux(1,0.5)", "Uy(1,0.5)"]
    assert len(cols) == 10 and data.shape == (1, 10)
    np.testing.assert_allclose(data[0, 1:7], [4905.0, 0.2, 0.05, 9810 * 0.7, 0.2, 0.03],
                               rtol=1e-3)
    assert np.all(np.isnan(data[0, 7:]))        # (1 5) is far above the water


# --- lines -------------------------------------------------------------------------------------
def test_lines_follow_the_crest(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type lines; follow crest; nPoints 11; y0 0; still 1; xMin 2;")
    x0 = 10.01
    x, y = stretched(lambda s: D + eta_sech2(s, x0))
    u = 0.4 + 0.1 * y                          # a known linear profile
    fo.start(case, ctx, "0")
    for t in (0.0, 0.25):
        fo.execute(FakeSim(x, y, u=u, p=9810.0 * (D + A - y), time=t))
    fo.end()
    header, cols, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert cols == ["time", "x", "surface"] and data.shape == (2, 3)
    top = x[np.argmax(y)]
    assert data[0, 1] == pytest.approx(top)
    assert data[0, 2] == pytest.approx(D + eta_sech2(top, x0), abs=0.02 * DX)
    for t in ("0", "0.25"):
        _, lcols, line = read_dat(tmp_path / "postProcessing/fo/0" / t / "line.dat")
        assert lcols == ["y", "Ux", "Uy", "p"] and line.shape == (11, 4)
    np.testing.assert_allclose(line[:, 0], np.linspace(0.0, data[1, 2], 11))
    inner = line[1:-2]                          # away from the bed and the surface
    np.testing.assert_allclose(inner[:, 1], 0.4 + 0.1 * inner[:, 0], rtol=1e-3)


def test_lines_at_fixed_x(tmp_path):
    case, ctx = fake_case(tmp_path)
    fo = build("type lines; x (0.5 1.5); nPoints 5;")
    x, y = lattice(lambda s: np.full_like(s, D), length=2.0)
    fo.start(case, ctx, "0")
    fo.execute(FakeSim(x, y, u=0.1 + 0 * x, time=1.0))
    fo.end()
    _, cols, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert cols == ["time", "x_0", "surface_0", "x_1", "surface_1"]
    np.testing.assert_allclose(data[0], [1.0, 0.5, D, 1.5, D])
    _, lcols, line = read_dat(tmp_path / "postProcessing/fo/0/1/line.dat")
    assert lcols[:4] == ["y(0.5)", "Ux(0.5)", "Uy(0.5)", "p(0.5)"] and line.shape == (5, 8)
    np.testing.assert_allclose(line[:, 1], 0.1, rtol=1e-9)


def test_lines_needs_x_or_crest():
    with pytest.raises(Exception, match="x"):
        build("type lines;")
    with pytest.raises(Exception, match="not both"):
        build("type lines; x (1); follow crest;")


# --- run-up ------------------------------------------------------------------------------------
def test_run_up_on_a_wall():
    wall = 2.0
    x, y = lattice(lambda s: np.full_like(s, D), length=wall)
    assert waves.wall_run_up(x, y, wall, DX, still=D) == 0.0           # still water
    # water piled against the wall: the last two columns reach D + 0.2
    x2, y2 = lattice(lambda s: np.where(s > wall - 2 * DX, D + 0.2, D), length=wall)
    assert waves.wall_run_up(x2, y2, wall, DX, still=D) == pytest.approx(0.2)
    # a jet 3 dx from the wall is not in contact
    x3, y3 = np.append(x, wall - 3 * DX), np.append(y, D + 0.5)
    assert waves.wall_run_up(x3, y3, wall, DX, still=D) == 0.0


def test_run_up_on_a_beach():
    ang = 10.0
    t = math.tan(math.radians(ang))
    start = (1.0, 0.0)
    slope = lambda s: np.maximum(0.0, (s - start[0]) * t)           # noqa: E731
    # still water over the beach, particles at least dx/2 above the slope line
    x, y = lattice(lambda s: np.full_like(s, D), length=8.0)
    keep = y - slope(x) >= 0.5 * DX / math.cos(math.radians(ang))
    x, y = x[keep], y[keep]
    r0 = waves.beach_run_up(x, y, start, ang, DX, still=D)
    assert r0 == 0.0
    # a tongue of water one particle thick, dx/2 above the slope, up to elevation D + 0.15
    s = np.arange(0.0, 10.0, DX)
    n = 0.5 * DX
    a = math.radians(ang)
    tx, ty = start[0] + s * math.cos(a) - n * math.sin(a), start[1] + s * math.sin(a) + \
        n * math.cos(a)
    tip = ty <= D + 0.15
    tx, ty = tx[tip & (ty > D)], ty[tip & (ty > D)]
    r = waves.beach_run_up(np.append(x, tx), np.append(y, ty), start, ang, DX, still=D)
    assert r == pytest.approx(ty.max() + DX / 2 - D)
    assert 0.15 - DX < r <= 0.15 + DX / 2
    # spray well above the slope does not count; a beach shorter than the tongue cuts it
    sx, sy = np.append(x, 6.0), np.append(y, D + 1.0)
    assert waves.beach_run_up(sx, sy, start, ang, DX, still=D) == 0.0
    short = waves.beach_run_up(np.append(x, tx), np.append(y, ty), start, ang, DX, still=D,
                               length=(D - start[1]) / math.sin(a))
    assert short < r


def test_run_up_object(tmp_path):
    case, ctx = fake_case(tmp_path)
    wall = 2.0
    fo = build(f"type runUp; mode wall; x {wall}; still {D};")
    fo.start(case, ctx, "0.5")
    for t, extra in ((0.5, 0.0), (0.6, 0.2), (0.7, 0.1)):
        x, y = lattice(lambda s: np.where(s > wall - 2 * DX, D + extra, D), length=wall)
        fo.execute(FakeSim(x, y, time=t))
    fo.end()
    _, cols, data = read_dat(tmp_path / "postProcessing/fo/0.5/fo.dat")
    assert cols == ["time", "runUp", "maxRunUp"]
    np.testing.assert_allclose(data, [[0.5, 0.0, 0.0], [0.6, 0.2, 0.2], [0.7, 0.1, 0.2]],
                               atol=1e-12)
    beach = build("type runUp; mode beach; start (1 0); angle 10;")
    assert beach.coeffs.start == (1.0, 0.0)
    with pytest.raises(Exception, match="start"):
        build("type runUp; mode beach;")
    with pytest.raises(Exception, match="wall position"):
        build("type runUp; mode wall;")


# --- crest tracker -----------------------------------------------------------------------------
def test_crest_tracker_celerity(tmp_path):
    """A sech^2 wave translated at c over a fixed lattice (its surface quantised to dx): the
    fitted celerity is within 0.5 %, x_c within a fraction of dx, eta_c within dx/2."""
    case, ctx = fake_case(tmp_path)
    c = 1.7
    fo = build("type crestTracker; xMin 0.01; xMax 19.99; still 1; fitFrom 4; fitTo 16;")
    fo.start(case, ctx, "0")
    times = np.linspace(0.0, 8.0, 17)
    for t in times:
        x, y = lattice(lambda s, t=t: D + eta_sech2(s, 3.0 + c * t))
        fo.execute(FakeSim(x, y, time=t))
    fo.end()
    _, cols, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert cols == ["time", "xCrest", "etaCrest", "c"] and data.shape == (17, 4)
    np.testing.assert_allclose(data[:, 1], 3.0 + c * times, atol=0.5 * DX)
    np.testing.assert_allclose(data[:, 2], A, atol=0.5 * DX)
    np.testing.assert_allclose(data[:, 3], c, rtol=0.05)      # instantaneous, central differences
    _, scols, summary = read_dat(tmp_path / "postProcessing/fo/0/celerity.dat")
    assert scols[:3] == ["c", "x0", "etaMean"]
    row = dict(zip(scols, summary[0]))
    assert row["c"] == pytest.approx(c, rel=0.005)
    sel = (3.0 + c * times >= 4.0) & (3.0 + c * times <= 16.0)
    assert row["nSamples"] == np.count_nonzero(sel)
    assert row["x0"] == pytest.approx(3.0, abs=DX)


def test_crest_of_sampled_surface():
    g = np.linspace(0.0, 20.0, 2001)
    xc, ec = waves.crest(g, eta_sech2(g, 7.123))
    assert xc == pytest.approx(7.123, abs=1e-3)         # a tenth of the gauge spacing
    assert ec == pytest.approx(A, rel=1e-4)
    assert waves.crest(g, np.zeros_like(g)) == (0.0, 0.0)       # flat: no crest to refine
    assert waves.fit_celerity([0.0, 1.0, 2.0], [1.0, 2.5, 4.0])[:2] == pytest.approx((1.5, 1.0))
    assert np.isnan(waves.fit_celerity([1.0], [2.0])[0])


def test_crest_cut_off_by_the_gauge_range():
    """P's wall case (A/d = 0.3, d = 10 m, EulerWave; gauges 5-65 m every dx = 0.625 m as its
    celerity study had them): while the crest is within 18 m of either end, the readings
    above eta_c / 2 run into it. The parabola through the cut-off set put x_c up to 1.8 m
    off and the celerity fitted 10 -> 40 m 0.9 % high, 20 -> 50 m 0.8 % low; symmetric about
    the highest reading x_c is within 0.04 m (measured 0.037 m) and every fit within 0.05 %
    (measured <= 0.032 %) of c. A crest inside the range is fitted as before."""
    from sphfoam.reference.solitary import EulerWave

    w = EulerWave(3.0, 10.0)
    c = w.c
    gx = 5.0 + 0.625 * np.arange(97)
    t = np.arange(0.0, 6.0, 0.05)
    xc = np.array([waves.crest(gx, w.eta(gx, s))[0] for s in t])
    inside = (c * t >= 10.0) & (c * t <= 60.0)
    assert np.max(np.abs(xc - c * t)[inside]) <= 0.04
    for lo, hi in ((10, 60), (10, 40), (20, 50), (30, 60)):
        sel = (xc >= lo) & (xc <= hi)
        assert waves.fit_celerity(t[sel], xc[sel])[0] == pytest.approx(c, rel=5e-4)
    wide = np.linspace(-40.0, 95.0, 217)            # the whole crest inside: unchanged fit
    x_in = waves.crest(wide, w.eta(wide, 3.0))[0]
    assert x_in == pytest.approx(3.0 * c, abs=0.04)

# --- sub-particle surface: fluid fraction 1/2 (issue 13) ----------------------------------------
KERNELS = [CubicSpline(), Gaussian(), Quintic(), WendlandC2()]


def columns(surface, length=6.0, dx=DX):
    """``stretched`` with each particle's volume dx * (S/n), as the set-up gives them."""
    xc = (np.arange(int(round(length / dx))) + 0.5) * dx
    s = surface(xc)
    n = np.rint(s / dx).astype(int)
    j = np.concatenate([np.arange(m) for m in n])
    dy = np.repeat(s / n, n)
    return np.repeat(xc, n), (j + 0.5) * dy, dx * dy


SURFACES = {
    "flat": lambda s: np.full_like(s, D + 0.0123),                       # off the lattice
    "sloped": lambda s: D + 0.05 * s,
    "sine": lambda s: D + 0.1 * np.sin(2 * np.pi * s / 1.5),
    "solitary": lambda s: D + eta_sech2(s, 3.0),
}


@pytest.mark.parametrize("kernel", KERNELS, ids=lambda k: k.name)
@pytest.mark.parametrize("shape", list(SURFACES))
def test_fraction_surface_is_sub_particle(kernel, shape):
    """Where sum_b V_b W crosses 1/2 is the surface to <= 0.1 dx (measured: <= 0.03 dx, the
    sine's curvature and the kernel sum's lattice error), away from the set's ends."""
    S = SURFACES[shape]
    x, y, v = columns(S)
    g = np.linspace(1.0, 5.0, 161)
    h = kernel.coeffs.hdx * DX
    eta = waves.fraction_surface(x, y, v, g, kernel, h, DX, still=D)
    assert np.max(np.abs(eta - (S(g) - D))) <= 0.1 * DX


def test_fraction_surface_with_disordered_particles():
    """Particles jittered by up to +-0.1 dx about the columns (the top ones move the surface
    they stand for by as much): within 0.15 dx (measured 0.10 dx)."""
    x, y, v = columns(SURFACES["sine"])
    rng = np.random.default_rng(7)
    x = x + rng.uniform(-0.1, 0.1, x.size) * DX
    y = y + rng.uniform(-0.1, 0.1, y.size) * DX
    k = CubicSpline()
    g = np.linspace(1.0, 5.0, 81)
    eta = waves.fraction_surface(x, y, v, g, k, 1.3 * DX, DX, still=D)
    assert np.max(np.abs(eta - (SURFACES["sine"](g) - D))) <= 0.15 * DX


def _sheet(x0, x1, bottom, rows, dx=DX):
    """A detached sheet: ``rows`` lattice rows from ``bottom`` over x0..x1 (a splash)."""
    xs = (np.arange(int(round((x1 - x0) / dx))) + 0.5) * dx + x0
    X, Y = np.meshgrid(xs, bottom + (np.arange(rows) + 0.5) * dx)
    return X.ravel(), Y.ravel(), np.full(X.size, dx * dx)


@pytest.mark.parametrize("kernel", KERNELS, ids=lambda k: k.name)
def test_wire_gauge_reads_a_column_as_the_fraction_gauge_and_a_splash_by_its_thickness(kernel):
    """One column of water: the wire gauge's lowest wet height plus its wetted length is the
    fraction gauge's surface (the same crossing, to 1e-9 m). A sheet three rows thick passing
    0.3 m above the water: the fraction gauge reads the sheet's top, the wire gauge the
    water's surface plus the sheet's thickness, 3 dx to 0.1 dx."""
    S = SURFACES["sine"]
    x, y, v = columns(S)
    g = np.linspace(2.0, 4.0, 41)
    h = kernel.coeffs.hdx * DX
    frac = waves.fraction_surface(x, y, v, g, kernel, h, DX, still=D)
    wire = waves.wire_surface(x, y, v, g, kernel, h, DX, still=D)
    assert np.max(np.abs(wire - frac)) <= 1e-9
    sx, sy, sv = _sheet(1.5, 4.5, D + 0.4, 3)
    xa, ya, va = np.concatenate([x, sx]), np.concatenate([y, sy]), np.concatenate([v, sv])
    frac2 = waves.fraction_surface(xa, ya, va, g, kernel, h, DX, still=D)
    wire2 = waves.wire_surface(xa, ya, va, g, kernel, h, DX, still=D)
    assert np.max(np.abs(frac2 - 0.4 - 3 * DX)) <= 0.1 * DX         # the sheet's top
    assert np.max(np.abs(wire2 - frac - 3 * DX)) <= 0.1 * DX
    assert np.isnan(waves.wire_surface(x, y, v, [7.0], kernel, h, DX)[0])


def test_fraction_surface_no_fluid_is_nan():
    x, y, v = columns(SURFACES["flat"], length=1.0)
    eta = waves.fraction_surface(x, y, v, [0.5, 3.0], CubicSpline(), 1.3 * DX, DX)
    assert np.isfinite(eta[0]) and np.isnan(eta[1])
    assert np.isnan(waves.fraction_surface([], [], [], [0.5], CubicSpline(), 1.3 * DX, DX)[0])


def test_fraction_run_up_on_the_wall():
    """Mirrored across the wall, the 1/2 crossing on it is the contact height:
    still water reads its level, a column piled against the wall its top, to 0.1 dx."""
    k, h = CubicSpline(), 1.3 * DX
    wall = 2.0
    x, y, v = columns(lambda s: np.full_like(s, D + 0.0123), length=wall)
    assert waves.fraction_wall_run_up(x, y, v, wall, k, h, DX, still=D) == \
        pytest.approx(0.0123, abs=0.1 * DX)
    x2, y2, v2 = columns(lambda s: D + 0.1 * s / wall, length=wall)      # rising to the wall
    assert waves.fraction_wall_run_up(x2, y2, v2, wall, k, h, DX, still=D) == \
        pytest.approx(0.1, abs=0.1 * DX)
    assert np.isnan(waves.fraction_wall_run_up(x, y, v, wall + 1.0, k, h, DX))
    # a beach's shoreline (a layer thinner than the kernel) is refused with a clear message
    with pytest.raises(Exception, match="mode wall only"):
        build("type runUp; mode beach; start (1 0); angle 10; surface fraction;")


def test_fraction_mode_in_the_objects(tmp_path):
    """waveGauges, crestTracker and runUp with ``surface fraction``; the default stays the
    thesis's particle gauge. On this single column ``surface wire`` reads what the fraction
    gauge reads, in waveGauges and crestTracker."""
    case, ctx = fake_case(tmp_path)
    assert build("type waveGauges; x (1);").coeffs.surface == "particle"
    assert build("type waveGauges; x (1);").header_doc == waves.WaveGauges.doc
    with pytest.raises(Exception, match="fraction"):
        build("type waveGauges; x (1); surface fractions;")
    x0 = 10.0
    x, y, v = columns(lambda s: D + eta_sech2(s, x0), length=20.0)
    sim = FakeSim(x, y)
    sim.state.m[:] = sim.state.rho * v                        # V_b = m_b / rho_b
    fo = build("type waveGauges; x (5 9.5 10 12.25); still 1; surface fraction;")
    fo.start(case, ctx, "0")
    fo.execute(sim)
    fo.end()
    _, _, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    np.testing.assert_allclose(data[0, 1:], eta_sech2([5, 9.5, 10, 12.25], x0), atol=0.1 * DX)
    head = (tmp_path / "postProcessing/fo/0/fo.dat").read_text().splitlines()[0]
    assert head.startswith("# waveGauges: free-surface elevation eta(t) at wave gauges; "
                           "surface fraction: sub-particle") and "highest particle" not in head
    ct = build("type crestTracker; xMin 2; xMax 18; still 1; surface fraction;")
    ct.start(case, ctx, "0")
    xc, ec = ct.measure(sim.state.x, sim.state.y, v)
    assert xc == pytest.approx(x0, abs=0.1 * DX) and ec == pytest.approx(A, abs=0.1 * DX)
    ru = build(f"type runUp; mode wall; x 20; still {D}; surface fraction;")
    ru.start(case, ctx, "0")
    assert ru.measure(sim.state.x, sim.state.y, v) == pytest.approx(
        eta_sech2(20.0, x0), abs=0.1 * DX)
    fw = build("type waveGauges; x (5 9.5 10 12.25); still 1; surface wire;")
    fw.start(case, ctx, "0")                   # surface wire: the same on one column
    fw.execute(sim)
    fw.end()
    _, _, wire = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert "; surface wire: what a wire gauge reads" in \
        (tmp_path / "postProcessing/fo/0/fo.dat").read_text().splitlines()[0]
    np.testing.assert_allclose(wire[-1, 1:], data[0, 1:], rtol=0, atol=1e-9)
    cw = build("type crestTracker; xMin 2; xMax 18; still 1; surface wire;")
    cw.start(case, ctx, "0")
    assert cw.measure(sim.state.x, sim.state.y, v) == pytest.approx((xc, ec), abs=1e-9)


# --- surface volume: the column's water volume (issue 13) ----------------------------------------
def test_column_depth_is_the_columns_volume_whatever_the_heights():
    """sum_b V_b G(x - x_b) of columns holding S(x_c) dx of water reads S to 0.01 dx (the
    window's smoothing, 1/2 width^2 S'', is 0.001 dx here) and does not move at all when the
    particles of each column are shuffled up and down."""
    S = SURFACES["solitary"]
    x, y, v = columns(S)
    g = np.linspace(1.0, 5.0, 161)
    depth = waves.column_depth(x, v, g, DX)
    assert np.max(np.abs(depth - S(g))) <= 0.01 * DX
    rng = np.random.default_rng(3)
    shuffled = waves.column_depth(x, v, g, DX)
    y2 = y + rng.uniform(-0.4, 0.4, y.size) * DX                    # x kept: the same columns
    assert y2.std() > 0 and np.array_equal(shuffled, depth)


def _reference(tmp_path, x, y, v):
    """A case's first time directory ``0`` holding fluid particles of volume ``v``."""
    from sphfoam.io.fields import write_state

    n = len(x)
    write_state(tmp_path / "0", {"positions": np.column_stack([x, y]),
                                 "rho": np.full(n, 1000.0), "mass": 1000.0 * np.asarray(v),
                                 "type": np.full(n, FLUID, dtype=np.int32)})


def test_volume_mode_in_the_objects(tmp_path):
    """waveGauges and crestTracker with ``surface volume``: the bed is calibrated on the case's
    first time directory (still water), the wave read to 0.01 dx, and a surface layer whose
    particles are disordered reads as it did; the fraction gauge moves with the disorder."""
    case, ctx = fake_case(tmp_path)
    _reference(tmp_path, *columns(lambda s: np.full_like(s, D), length=20.0))
    x0 = 10.0
    S = lambda s: D + eta_sech2(s, x0)                          # noqa: E731
    x, y, v = columns(S, length=20.0)
    sim = FakeSim(x, y)
    sim.state.m[:] = sim.state.rho * v
    gx = [0.05, 5, 9.5, 10, 12.25]
    fo = build("type waveGauges; x (0.05 5 9.5 10 12.25); still 1; surface volume;")
    fo.start(case, ctx, "0")
    fo.execute(sim)
    # the top two rows of every column squeezed down by 0.3 of their spacing: the same water
    top = np.zeros(x.size, dtype=bool)
    for xc in np.unique(x):
        col = np.flatnonzero(x == xc)
        top[col[np.argsort(y[col])[-2:]]] = True
    sim.state.y[top] -= 0.3 * DX
    fo.execute(sim)
    fo.end()
    _, _, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert np.isnan(data[0, 1]) and np.isnan(data[1, 1])     # within 5 width of the water's end
    np.testing.assert_allclose(data[0, 2:], eta_sech2(gx[1:], x0), atol=0.01 * DX)
    np.testing.assert_allclose(data[1, 2:], data[0, 2:], atol=1e-12)
    frac = waves.fraction_surface(sim.state.x, sim.state.y, v, gx[1:],
                                  case.models.sph["kernel"], ctx.h, DX, still=D)
    assert np.max(np.abs(frac - eta_sech2(gx[1:], x0))) > 0.05 * DX
    ct = build("type crestTracker; xMin 2; xMax 18; still 1; surface volume;")
    ct.start(case, ctx, "0")
    xc, ec = ct.measure(x, y, v)
    assert xc == pytest.approx(x0, abs=0.1 * DX) and ec == pytest.approx(A, abs=0.01 * DX)
    with pytest.raises(Exception, match="volume"):
        build("type runUp; mode wall; x 20; surface volume;")


def test_volume_mode_without_a_time_directory_calibrates_on_the_first_state(tmp_path):
    """No time directory in the case (a state sampled directly): the first state sampled
    gives the bed, and the surface then follows the columns' water, smoothed by the window
    (standard deviation w = 2 dx here) by 1/2 w^2 eta'' = -w^2 A K^2 at the crest."""
    case, ctx = fake_case(tmp_path)
    still = columns(lambda s: np.full_like(s, D), length=20.0)
    wave = columns(lambda s: D + eta_sech2(s, 10.0), length=20.0)
    fo = build("type waveGauges; x (10); still 1; surface volume; volumeWidth 2;")
    fo.start(case, ctx, "0")
    for x, y, v in (still, wave):
        sim = FakeSim(x, y)
        sim.state.m[:] = sim.state.rho * v
        fo.execute(sim)
    fo.end()
    _, _, data = read_dat(tmp_path / "postProcessing/fo/0/fo.dat")
    assert data[0, 1] == pytest.approx(0.0, abs=0.01 * DX)    # the fraction gauge on a lattice
    w = 2 * DX                                      # the window smooths by 1/2 w^2 eta''
    assert data[1, 1] == pytest.approx(A - w**2 * A * K**2, abs=0.01 * DX)


def test_volume_width_belongs_to_surface_volume():
    """``volumeWidth`` with another surface mode would be ignored: it is refused, naming it."""
    for obj in ("waveGauges; x (1)", "crestTracker"):
        assert build(f"type {obj}; surface volume; volumeWidth 2;").coeffs.volumeWidth == 2
        with pytest.raises(Exception, match="volumeWidth applies to surface volume only"):
            build(f"type {obj}; surface fraction; volumeWidth 2;")
