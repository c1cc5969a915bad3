"""Models given their 3-D form (issue 33, "Models in 3-D"): each checked on small periodic
cubic lattices against an invariant that fails for a wrong form: XSPH's correction conserves
momentum and moves the particles in z; the 3-D velocity gradient of a linear field gives the
SPS stress and the shear switch of the exact gradient; the renormalised density gradient
and MLS / C-SPH reproduce linear fields exactly; symmetric C-SPH conserves momentum; the
shiftings leave a uniform lattice alone, spread a disordered one evenly, find the faces of a
block as its free surface with outward normals and shift only tangentially there."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from sphfoam import registry
from sphfoam.assemble import selection
from sphfoam.case.case import Case
from sphfoam.engine.build import build_pipeline, core_parameters
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import ParticleState

MATCHED3D = Path(__file__).resolve().parent.parent / "benchmarks" / "cases" / "damBreakMatched3D"
CASE = Case(MATCHED3D)
DX = CASE.context.dx


def _lattice(k, dx=DX, jitter=0.0, seed=0, shape=None):
    """A cubic lattice of k^3 (or ``shape``) sites, dx apart, jittered by jitter dx."""
    nx, ny, nz = shape or (k, k, k)
    g = [np.arange(n) * dx + dx / 2 for n in (nx, ny, nz)]
    x, y, z = (a.ravel().copy() for a in np.meshgrid(*g, indexing="ij"))
    if jitter:
        rng = np.random.default_rng(seed)
        x, y, z = (a + rng.uniform(-jitter, jitter, a.size) * dx for a in (x, y, z))
    return x, y, z, (nx * dx, ny * dx, nz * dx)


def _sim(x, y, z, hi, periodic=True, u=None, rho=None, **models):
    """A 3-D simulation of the matched dam break's models (``models``: family -> spec
    replacing them) on the particles given, all fluid; periodic in every axis or in none."""
    n = x.size
    zero = np.zeros(n)
    u, v, w = u if u is not None else (zero.copy(), zero.copy(), zero.copy())
    rho = np.full(n, 1000.0) if rho is None else rho
    st = ParticleState(x, y, u, v, rho, np.full(n, 1000.0 * DX ** 3), np.zeros(n, np.int64),
                       z=z, w=w)
    sel = dataclasses.replace(selection(CASE), periodic_x=periodic, periodic_y=periodic,
                              periodic_z=periodic, still_walls=False,
                              **{f: registry.build(f, s) for f, s in models.items()})
    margin = 0.0 if periodic else 4 * DX
    lo = (-margin,) * 3
    hi = tuple(a + margin for a in hi)
    ctx = CASE.context
    pipe = build_pipeline(sel, ctx, core_parameters(sel, ctx, lo, hi), domain_lo=lo,
                          domain_hi=hi)
    sim = Simulation(st, pipe, registry.build("integrator", {"type": "symplectic"}),
                     domain_lo=lo, domain_hi=hi, beta=0.2, force_condition=True,
                     adjust_time_step=True, delta_t=1e-5)
    sim.neighbour_update()
    sim.eos()
    sim.rates()
    return sim


def _aux(sim, name):
    return sim.context.aux(name)


# --- XSPH ---------------------------------------------------------------------------------
def test_xsph_in_3d_conserves_momentum_and_moves_particles_with_its_correction():
    """A disordered periodic block with random velocities: the XSPH correction's pair
    weights m_a m_b W_ab / rhobar_ab are symmetric, so sum_a m_a dv_a = 0 in x, y and z to
    round-off; positions move with v + dv in each of the three components; a uniform
    velocity gets no correction."""
    x, y, z, hi = _lattice(10, jitter=0.2, seed=1)
    rng = np.random.default_rng(2)
    vel = tuple(rng.normal(0.0, 0.3, x.size) for _ in range(3))
    rho = 1000.0 * (1.0 + 0.01 * rng.uniform(-1, 1, x.size))
    sim = _sim(x % hi[0], y % hi[1], z % hi[2], hi, u=vel, rho=rho,
               velocityCorrection={"type": "xsph"})
    st = sim.state
    dU = [_aux(sim, f"xsph_d{c}") for c in "uvw"]
    for d, U in zip(dU, st.velocities):
        assert np.abs(d).max() > 0.01 * np.abs(U).max()          # not trivially zero
        assert abs((st.m * d).sum()) < 1e-12 * (st.m * np.abs(d)).sum()
    pU = sim.position_velocity(*st.velocities)
    assert len(pU) == 3
    for p, U, d in zip(pU, st.velocities, dU):
        assert np.array_equal(p, U + d)
    uni = tuple(np.full(x.size, c) for c in (0.3, -0.2, 0.5))
    sim = _sim(x % hi[0], y % hi[1], z % hi[2], hi, u=uni, rho=rho,
               velocityCorrection={"type": "xsph"})
    assert max(np.abs(_aux(sim, f"xsph_d{c}")).max() for c in "uvw") == 0.0


def test_xsph_runs_steps_in_3d():
    """Ten steps of a periodic lattice with a shear flow in z: the selection is accepted in
    3-D and the mean velocity is that of free fall (XSPH moves positions, not momentum: the
    pair forces cancel)."""
    x, y, z, hi = _lattice(10)
    w = 0.1 * np.sin(2 * np.pi * x / hi[0])
    zero = np.zeros(x.size)
    sim = _sim(x, y, z, hi, u=(zero.copy(), zero.copy(), w.copy()),
               velocityCorrection={"type": "xsph"})
    z0 = sim.state.z.copy()
    for _ in range(10):
        sim.step()
    st = sim.state
    assert np.abs(st.w - 0.0).max() > 0.05                    # the flow is still there
    assert abs(np.mean(st.w) - CASE.context.g[2] * sim.time) < 1e-12
    assert abs(np.mean(st.u)) < 1e-12 and abs(np.mean(st.v)) < 1e-12
    assert not np.array_equal(np.sort(st.z), np.sort(z0))


# --- the 3-D velocity gradient: SPS stress and the shear switch ---------------------------
#: a linear velocity field U = G x (every entry of G different from zero)
G = np.array([[0.3, 1.1, -0.7], [0.4, -0.2, 0.9], [-1.3, 0.6, 0.5]])


def _linear_block():
    """A non-periodic cubic block 9 x 9 x 9 with U = G x; the particles more than a support
    from its faces see a full, symmetric lattice support."""
    x, y, z, hi = _lattice(9)
    U = G @ np.vstack([x, y, z])
    return x, y, z, hi, tuple(U[i].copy() for i in range(3))


def _inner(sim, hi):
    st = sim.state
    reach = sim.pipeline.support_radius
    return np.all([(a > reach) & (a < L - reach) for a, L in zip(st.positions, hi)], axis=0)


def test_smagorinsky_sps_stress_of_a_linear_field_in_3d_is_the_exact_strain_rates():
    """Interior particles of a cubic lattice with U = G x: the SPH gradient is c G with one
    scalar c (the lattice's moment sum_b V_b x_ba dW/dx_a, near 1), so every one of the six
    entries of tau/rho of T(3.58)-(3.60) in 3-D is c^2 times the exact tau(G): the six
    ratios agree to 1e-9 (a missing or misplaced entry of S, |S| or the isotropic part
    breaks them) and c = 0.979 (Wendland C2, h = 1.3 dx: the moment of the 3-D tank test in
    tests/test_three_d_engine.py)."""
    x, y, z, hi, U = _linear_block()
    sim = _sim(x, y, z, hi, periodic=False, u=U, turbulence={"type": "smagorinskySPS"})
    inner = _inner(sim, hi)
    assert inner.sum() >= 8
    S = 0.5 * (G + G.T)
    s2 = 2.0 * (S * S).sum()
    m = sim.pipeline.selection.turbulence
    cs2 = (m.coeffs.Cs * DX) ** 2
    blin = (2.0 / 3.0) * m.coeffs.CI * DX ** 2
    nut = cs2 * np.sqrt(s2)
    tau = 2 * nut * (S - np.trace(S) / 3 * np.eye(3)) - blin * s2 * np.eye(3)
    ratios = []
    for (i, j) in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)):
        got = _aux(sim, f"turb_t{'xyz'[i]}{'xyz'[j]}")[inner]
        ratios.append(got / tau[i, j])
    ratios = np.array(ratios)
    assert np.abs(ratios - ratios[0, 0]).max() < 1e-9
    assert ratios[0, 0] == pytest.approx(0.979 ** 2, abs=0.005)


@pytest.mark.parametrize("switch", ["colagrossiLandrini", "balsara"])
def test_improved_artificial_switch_in_3d_is_that_of_the_exact_gradient(switch):
    """k_a = |div v| / (|div v| + N + 1e-4 c_a / h), N = sqrt(S_ij S_ij) (T(3.35)-(3.36)) or
    |curl v| (T(3.34)) over the nine entries: on interior particles of the linear field
    (gradient c G, c from the SPS test's lattice moment) it equals the formula for c G to
    1e-12; a pure rotation in the x-z plane (div 0) gives k = 0."""
    x, y, z, hi, U = _linear_block()
    sim = _sim(x, y, z, hi, periodic=False, u=U,
               viscosity={"type": "improvedArtificial", "switch": switch})
    inner = _inner(sim, hi)
    # c: the lattice moment of the kernel gradient, from a pure dilation U = x
    dil = _sim(x, y, z, hi, periodic=False, u=(x.copy(), 0 * x, 0 * x),
               turbulence={"type": "smagorinskySPS", "Cs": 1.0, "CI": 0.0})
    # S = diag(c, 0, 0), |S| = sqrt(2) c, Cs = 1: tau_xx = 2 nu_t (2/3) c = (4/3) sqrt(2) dx^2 c^2
    txx = _aux(dil, "turb_txx")[_inner(dil, hi)]
    c = np.sqrt(txx / ((4.0 / 3.0) * np.sqrt(2.0) * DX ** 2))
    assert np.ptp(c) < 1e-12 and c[0] == pytest.approx(1.0, abs=0.03)
    Gc = c[0] * G
    div = abs(np.trace(Gc))
    if switch == "balsara":
        other = np.linalg.norm([Gc[2, 1] - Gc[1, 2], Gc[0, 2] - Gc[2, 0], Gc[1, 0] - Gc[0, 1]])
    else:
        S = 0.5 * (Gc + Gc.T)
        other = np.sqrt((S * S).sum())
    ca = sim.state.c[inner]
    want = div / (div + other + 1e-4 * ca / sim.h)
    got = _aux(sim, "visc_k")[inner]
    assert np.abs(got - want).max() < 1e-12
    assert 0.05 < want.min() < 0.95
    rot = _sim(x, y, z, hi, periodic=False, u=(z - z.mean(), 0 * x, -(x - x.mean())),
               viscosity={"type": "improvedArtificial", "switch": switch})
    assert np.abs(_aux(rot, "visc_k")[_inner(rot, hi)]).max() < 1e-12


# --- density: the renormalised gradient (Antuono et al. 2010) and MLS --------------------
def _linear_density(x, y, z, hi):
    L = hi[0]
    return 1000.0 * (1.0 + 0.002 * (x + 2.0 * y - 3.0 * z) / L), \
        1000.0 * 0.002 * np.array([1.0, 2.0, -3.0]) / L


def test_antuono_delta_sph_in_3d_is_exact_for_a_linear_density():
    """A disordered block (not periodic: truncated supports at its faces) with a linear
    density and no velocity: the renormalised gradient <grad rho>^L of every particle is the
    field's gradient to 1e-9 (L = M^-1 of the 3 x 3 M), so every pair term of the diffusion
    vanishes and drho/dt is 0 to round-off; a quadratic density is diffused (drho != 0)."""
    x, y, z, hi = _lattice(9, jitter=0.15, seed=4)
    rho, g = _linear_density(x, y, z, hi)
    sim = _sim(x, y, z, hi, periodic=False, rho=rho,
               densityFilter={"type": "antuonoDeltaSPH"})
    st = sim.state
    for i, c in enumerate("xyz"):
        assert np.abs(_aux(sim, f"rgrad_{c}") - g[i]).max() < 1e-9 * np.abs(g).max()
    assert np.abs(st.drho).max() < 1e-9 * 1000.0 * sim.state.c.max() / sim.h
    rho2 = 1000.0 * (1.0 + 0.05 * ((z - z.mean()) / hi[2]) ** 2)
    sim = _sim(x, y, z, hi, periodic=False, rho=rho2,
               densityFilter={"type": "antuonoDeltaSPH"})
    assert np.abs(sim.state.drho).max() > 1e3 * 1e-9 * 1000.0 * sim.state.c.max() / sim.h


def test_mls_reinitialisation_in_3d_reproduces_a_linear_density():
    """The 4 x 4 MLS of T(3.64)-(3.68) in 3-D: a disordered block (faces and corners
    included) with a linear density keeps it to 1e-12 relative at every particle after the
    pass; a Shepard filter (zeroth order) would not at the faces."""
    x, y, z, hi = _lattice(8, jitter=0.2, seed=5)
    rho, _ = _linear_density(x, y, z, hi)
    for spec, exact in (({"type": "mlsReinitialisation"}, True), ({"type": "shepard"}, False)):
        sim = _sim(x, y, z, hi, periodic=False, rho=rho.copy(), densityFilter=spec)
        st = sim.state
        want, _ = _linear_density(st.x, st.y, st.z, hi)
        sim.filter_density()
        err = np.abs(st.rho - want).max() / 1000.0
        assert (err < 1e-12) if exact else (err > 1e-4), (spec, err)


# --- C-SPH (4 x 4) -------------------------------------------------------------------------
def test_csph_in_3d_gives_the_exact_divergence_of_a_linear_velocity():
    """P(29)-(32) in 3-D (the 4 x 4 moment matrix): with P's corrected gradient of a alone
    (``symmetric no``) sum_b V_b v_ba . grad~_a W_ab is div v exactly for a linear field, so
    the continuity equation gives drho_a/dt = -rho_a tr G at every particle of a disordered,
    non-periodic block whose M is regular (faces and corners included) to 1e-9; the plain
    kernel gradient is off by more than 1e-3 there."""
    x, y, z, hi = _lattice(8, jitter=0.2, seed=6)
    U = G @ np.vstack([x, y, z])
    vel = tuple(U[i].copy() for i in range(3))
    sim = _sim(x, y, z, hi, periodic=False, u=vel,
               kernelCorrection={"type": "csph", "symmetric": False})
    st = sim.state
    ok = _aux(sim, "csph_ok") == 1.0
    want = -st.rho * np.trace(G)
    assert ok.mean() > 0.95
    assert (np.abs(st.drho - want) / np.abs(want))[ok].max() < 1e-9
    plain = _sim(x, y, z, hi, periodic=False, u=tuple(U[i].copy() for i in range(3)))
    assert (np.abs(plain.state.drho - want) / np.abs(want)).max() > 1e-3


def test_symmetric_csph_in_3d_conserves_momentum():
    """``symmetric yes`` (Bonet & Lok 1999): the pair gradient (grad~_a W_ab - grad~_b W_ba)
    / 2 is antisymmetric in a and b, so on a disordered periodic block with random velocities
    and densities sum_a m_a (dv_a/dt - g) = 0 in x, y and z to round-off."""
    x, y, z, hi = _lattice(10, jitter=0.2, seed=7)
    rng = np.random.default_rng(8)
    vel = tuple(rng.normal(0.0, 0.3, x.size) for _ in range(3))
    rho = 1000.0 * (1.0 + 0.01 * rng.uniform(-1, 1, x.size))
    sim = _sim(x % hi[0], y % hi[1], z % hi[2], hi, u=vel, rho=rho,
               kernelCorrection={"type": "csph"})
    st = sim.state
    assert (_aux(sim, "csph_ok") == 1.0).all()
    scale = sum(np.abs(st.m * a).sum() for a in st.accelerations)
    for a, g in zip(st.accelerations, CASE.context.g):
        assert abs((st.m * (a - g)).sum()) < 1e-12 * scale
    assert np.abs(st.ax).max() > 1.0


# --- particle shifting (deltaPlusShifting, lindShifting) ---------------------------------
#: one compiled selection for most shifting checks: delta+ with both Taylor corrections
DPLUS = {"type": "deltaPlusShifting", "correctVelocity": True, "correctDensity": True}


def _evaluate(sim):
    """Neighbours, the step stage (the free-surface detection), pressure and rates."""
    sim.neighbour_update()
    sim.step_pass()
    sim.eos()
    sim.rates()
    return sim


def _shift_sim(x, y, z, hi, spec=DPLUS, **kw):
    return _evaluate(_sim(x, y, z, hi, particleShifting=spec, **kw))


def _shift(sim):
    return np.array([_aux(sim, f"shift_d{c}") for c in "uvw"])


def _set_param(sim, name, value):
    """A coefficient of the compiled selection changed for this simulation alone."""
    sim.prm = sim.prm.copy()
    sim.prm[list(sim.pipeline.module.PARAMS).index(name)] = value


def _nn_spread(st, hi):
    pts = np.column_stack([a % L for a, L in zip(st.positions, hi)])
    d, _ = cKDTree(pts, boxsize=hi).query(pts, k=2)
    return np.std(d[:, 1]) / DX


def test_shifting_in_3d_leaves_a_uniform_lattice_alone():
    """A uniform periodic cubic lattice: every particle sees a full symmetric support, so
    lambda (the smallest eigenvalue of the 3 x 3 M) is the same everywhere and near 1, no
    particle is near a surface, and grad C = 0: no shift in x, y or z (to round-off), and
    Lind's shift in a uniform stream leaves the advection velocity the stream's."""
    x, y, z, hi = _lattice(10)
    sim = _shift_sim(x, y, z, hi)
    lam = _aux(sim, "shift_lambda")
    assert np.allclose(lam, lam[0], rtol=0, atol=1e-12) and abs(lam[0] - 1.0) < 0.03
    c0 = sim.state.c.max()
    assert np.abs(_shift(sim)).max() < 1e-10 * c0
    u0 = tuple(np.full(x.size, c) for c in (0.7, -0.3, 0.4))
    sim = _shift_sim(x, y, z, hi, {"type": "lindShifting"}, u=u0)
    for p, c in zip(sim.position_velocity(*sim.state.velocities), (0.7, -0.3, 0.4)):
        assert np.abs(p - c).max() < 1e-12


def _relax(sim, dt, steps):
    """Positions moved by the shift alone (the stream carries all particles alike)."""
    for _ in range(steps):
        st = sim.state
        for pos, p, U in zip(st.positions, sim.position_velocity(*st.velocities),
                             st.velocities):
            pos += dt * (p - U)
        _evaluate(sim)


@pytest.mark.parametrize("spec", ["deltaPlus", "lind"])
def test_shifting_in_3d_makes_a_disordered_lattice_more_uniform(spec):
    """A periodic lattice jittered by 0.2 dx in x, y and z: the shift spreads it evenly (the
    spread of the nearest-neighbour distances falls below 0.6 of its start in 40 pseudo-steps
    of CFL 0.2); the shift has all three components; Lind's shift needs a speed (a uniform
    stream of 1 m/s: none at rest)."""
    x, y, z, hi = _lattice(10, jitter=0.2, seed=11)
    x, y, z = x % hi[0], y % hi[1], z % hi[2]
    if spec == "deltaPlus":
        sim = _shift_sim(x, y, z, hi)
        dt = 0.2 * sim.h / sim.state.c.max()
    else:
        u0 = tuple(np.full(x.size, c) for c in (0.6, 0.0, -0.8))
        sim = _shift_sim(x, y, z, hi, {"type": "lindShifting"}, u=u0)
        dt = 0.1 * sim.h / 1.0
    s0 = _nn_spread(sim.state, hi)
    d = _shift(sim)
    assert np.all(np.abs(d).max(axis=1) > 0.1 * np.abs(d).max())
    _relax(sim, dt, 40)
    s1 = _nn_spread(sim.state, hi)
    assert s1 < 0.6 * s0, (s0, s1)
    if spec == "lind":
        sim0 = _shift_sim(x, y, z, hi, {"type": "lindShifting"})
        assert np.abs(_shift(sim0)).max() == 0.0


def _faces(st, hi, reach):
    """Masks of the particles of each face's outer layer away from its edges (the face's
    outward normal beside), and of the interior more than a support from every face."""
    pos = st.positions
    out = []
    for i in range(3):
        others = [j for j in range(3) if j != i]
        away = np.all([(pos[j] > reach) & (pos[j] < hi[j] - reach) for j in others], axis=0)
        for side, sel in ((-1, pos[i] < DX), (1, pos[i] > hi[i] - DX)):
            n = np.zeros(3)
            n[i] = side
            out.append((sel & away, n))
    inner = np.all([(a > reach) & (a < L - reach) for a, L in zip(pos, hi)], axis=0)
    return out, inner


def test_free_surface_of_a_3d_block_is_its_faces_with_outward_normals():
    """A cubic block of 10^3 particles in empty space (Marrone et al. 2010 in 3-D): the outer
    layer of each of its six faces has lambda < 0.75 (about 0.5 on a flat face) and a unit
    normal within 2 degrees of the face's outward normal; each corner's normal is the diagonal
    out of it (to 1e-9); the particles more than a support inside have lambda > 0.9."""
    x, y, z, hi = _lattice(10)
    sim = _shift_sim(x, y, z, hi, periodic=False)
    st = sim.state
    lam = _aux(sim, "shift_lambda")
    n = np.array([_aux(sim, f"shift_n{c}") for c in "xyz"])
    faces, inner = _faces(st, hi, sim.pipeline.support_radius)
    assert inner.sum() == 64
    assert lam[inner].min() > 0.9
    for sel, normal in faces:
        assert sel.sum() == 16
        assert lam[sel].max() < 0.75 and lam[sel].min() > 0.3
        assert (normal @ n[:, sel]).min() > np.cos(np.radians(2.0)), normal
        assert np.abs(np.linalg.norm(n[:, sel], axis=0) - 1.0).max() < 1e-12
    # the eight corners: by the lattice's symmetry n is along the diagonal out of the
    # corner (the off-diagonal entries of M and of its adjugate enter)
    pos = np.array(st.positions)
    lo_hi = np.array([(pos[i] < DX) * -1.0 + (pos[i] > hi[i] - DX) for i in range(3)])
    corner = np.all(lo_hi != 0.0, axis=0)
    assert corner.sum() == 8
    assert np.abs(n[:, corner] - lo_hi[:, corner] / np.sqrt(3.0)).max() < 1e-9
    # a uniform lattice's interior is not shifted
    d = _shift(sim)
    assert np.abs(d[:, inner]).max() < 1e-10 * st.c.max()


def test_shifting_in_3d_is_tangential_near_the_free_surface():
    """A jittered block: near the surface (lambda < 0.75 or such a neighbour) the shift has
    no component along the particle's own normal (to round-off) but a tangential one; with
    the surface rule off (surfaceLambda 0) the face layers are pushed outwards, so the check
    can fail."""
    x, y, z, hi = _lattice(10, jitter=0.1, seed=12)
    sim = _shift_sim(x, y, z, hi, periodic=False)
    st = sim.state
    lam = _aux(sim, "shift_lambda")
    n = np.array([_aux(sim, f"shift_n{c}") for c in "xyz"])
    d = _shift(sim)
    faces, inner = _faces(st, hi, sim.pipeline.support_radius)
    surface = lam < 0.75
    assert surface.sum() > 300
    scale = np.abs(d).max()
    assert np.abs((d * n).sum(axis=0))[surface].max() < 1e-12 * scale
    assert np.linalg.norm(d[:, surface], axis=0).max() > 0.1 * scale
    _set_param(sim, "shift_lam", 0.0)
    _evaluate(sim)
    d0, st = _shift(sim), sim.state
    faces, _ = _faces(st, hi, sim.pipeline.support_radius)
    for sel, normal in faces:
        assert (normal @ d0[:, sel]).min() > 0.1 * scale, normal


def test_shifting_corrections_in_3d_use_the_nine_entry_velocity_gradient():
    """correctVelocity and correctDensity sum grad u and grad rho over the same pairs and
    volumes: with u, v, w = (alpha, beta, gamma) (rho - rho0), a linear density on a
    disordered block, grad u = alpha grad rho ... so (delta_u . grad) U = (alpha, beta,
    gamma) delta_u . grad rho at every particle (a swapped entry or component of the 3 x 3
    gradient breaks it); the rates hook adds it to dv/dt in x, y and z."""
    x, y, z, hi = _lattice(8, jitter=0.2, seed=13)
    rho, _ = _linear_density(x, y, z, hi)
    k = np.array([0.5, -1.5, 2.5])
    vel = tuple(ki * (rho - 1000.0) for ki in k)
    sim = _shift_sim(x, y, z, hi, periodic=False, rho=rho, u=vel)
    drho = _aux(sim, "shift_drho")
    assert np.abs(drho).max() > 0.0
    extra = []
    for c, ki in zip("xyz", k):
        a = _aux(sim, f"shift_a{c}")
        assert np.abs(a - ki * drho).max() < 1e-10 * np.abs(ki * drho).max()
        extra.append(a.copy())
    acc = [a.copy() for a in sim.state.accelerations]
    _set_param(sim, "shift_c", 0.0)               # no shift: no correction
    _evaluate(sim)
    for a0, a1, e in zip(acc, sim.state.accelerations, extra):
        assert np.abs(e).max() > 0.0
        assert np.abs((a0 - a1) - e).max() < 1e-9 * np.abs(e).max()


def test_shifting_in_3d_moves_positions_not_momentum():
    """Ten steps of a disordered periodic lattice with delta+ shifting (no corrections):
    the fluid's momentum is that of free fall in x, y, z (the shift moves positions only)
    and the positions move with v + delta_u."""
    x, y, z, hi = _lattice(10, jitter=0.2, seed=14)
    sim = _shift_sim(x % hi[0], y % hi[1], z % hi[2], hi, {"type": "deltaPlusShifting"})
    st = sim.state
    p = sim.position_velocity(*st.velocities)
    for pc, U, d in zip(p, st.velocities, _shift(sim)):
        assert np.array_equal(pc, U + d)
    for _ in range(10):
        sim.step()
    for U, g in zip(st.velocities, CASE.context.g):
        assert abs(np.mean(U) - g * sim.time) < 1e-12
    assert sim.time > 0.0
