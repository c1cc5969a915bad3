"""Models given their 3-D form (issue 33, "Models in 3-D"): each checked on small periodic
cubic lattices against an invariant that fails for a wrong form: XSPH's correction conserves
momentum and moves the particles in z; the 3-D velocity gradient of a linear field gives the
SPS stress and the shear switch of the exact gradient; the renormalised density gradient
and MLS / C-SPH reproduce linear fields exactly."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

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
