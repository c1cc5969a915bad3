"""Shared helpers: copy a tutorial into a temporary directory and edit its dictionaries."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sphfoam.case.edit import clone_case, set_entry  # noqa: F401  (re-exported)

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"

# pytest-xdist gives its workers COLUMNS=80, and the CLI's rich console (made when sphfoam.cli
# is imported, at collection) would fix its width from it: tests that ask CliRunner for a
# wider console would not get one. The workers run as one process does, without it.
os.environ.pop("COLUMNS", None)

#: P's set-up of the wall case (P section 4: the finite Gaussian, XSPH, MLS every 20 steps, the
#: mirrored bed's p_G = p_a, the KdV2 wave, P's predictor-corrector), the wall tutorial's
#: default until issue 35's convergence study; as the study dictionaries' set blocks
P_WALL = {
    "constant/sphProperties:kernel": {"type": "gaussian", "hdx": 1.3333333},
    "constant/sphProperties:velocityCorrection": {"type": "xsph", "epsilon": 0.5},
    "constant/sphProperties:densityFilter": {"type": "mlsReinitialisation", "every": 20},
    "constant/sphProperties:particleShifting": {"type": "none"},
    "constant/sphProperties:boundary.pressure": "mirror",
    "constant/waveProperties:waves.incident.theory": "kdv2",
    "system/sphSchemes:integrator": {"type": "predictorCorrector"},
}


@pytest.fixture
def p_wall() -> dict:
    """The edits that give the wall tutorial P's set-up (:data:`P_WALL`)."""
    return dict(P_WALL)


@pytest.fixture
def tutorial(tmp_path):
    """``tutorial(name, **{"system/controlDict:endTime": 0.1})`` -> a fresh copy."""

    def make(name: str, edits: dict | None = None) -> Path:
        return clone_case(TUTORIALS / name, tmp_path / name, edits)

    return make


def sliding_layer(boundary: dict, wall_fields=None, steps: int = 300):
    """A layer 10 dx deep (dx = 0.01 m, h = 1.3 dx) sliding at 0.5 m/s over three rows of
    wall particles, periodic along the bed, no gravity, Wendland C2, Tait (c0 = 10 m/s),
    density-weighted continuity, Colagrossi-Landrini momentum, artificial viscosity 0.1,
    Verlet: ``steps`` steps on the walls ``boundary`` (a boundary dictionary), the wall
    particles carrying ``wall_fields(x, y, wall)`` (a dict of per-particle fields) where
    given. Returns the fraction of the layer's momentum kept, the final state and the
    initial x, y (indexed by particle id)."""
    import numpy as np

    from sphfoam import registry
    from sphfoam.engine.build import build_pipeline
    from sphfoam.engine.plan import Selection
    from sphfoam.engine.simulation import Simulation
    from sphfoam.engine.state import FLUID, WALL, ParticleState
    from sphfoam.models.base import CaseContext

    rho0, dx, nx, ny, nw, u0 = 1000.0, 0.01, 20, 10, 3, 0.5
    h = 1.3 * dx
    specs = dict(kernel={"type": "wendlandC2"},
                 equationOfState={"type": "tait", "speedOfSound": 10.0},
                 continuity={"type": "densityWeighted"}, momentum={"type": "colagrossiLandrini"},
                 viscosity={"type": "artificial", "alpha": 0.1}, boundary=boundary)
    models = {f: registry.build(f, sp) for f, sp in specs.items()}
    ctx = CaseContext(dx=dx, h=h, rho0=rho0, nu=1e-6, g=(0.0, 0.0), fluid_height=ny * dx,
                      c0=10.0)
    lo, hi = (0.0, -nw * dx), (nx * dx, 2 * ny * dx)
    pipe = build_pipeline(Selection(**models, periodic_x=True), ctx, domain_lo=lo,
                          domain_hi=hi)
    X, Y = np.meshgrid((np.arange(nx) + 0.5) * dx, (np.arange(-nw, ny) + 0.5) * dx)
    x, y = X.ravel(), Y.ravel()
    kind = np.where(y > 0, FLUID, WALL)
    extra = wall_fields(x, y, kind == WALL) if wall_fields is not None else None
    st = ParticleState(x, y, np.where(kind == FLUID, u0, 0.0), np.zeros(x.size),
                       np.full(x.size, rho0), np.full(x.size, rho0 * dx * dx), kind,
                       extra=extra)
    sim = Simulation(st, pipe, registry.build("integrator", {"type": "verlet"}), h=h,
                     support=models["kernel"].support, domain_lo=lo, domain_hi=hi, beta=0.2,
                     force_condition=True, adjust_time_step=True, delta_t=1e-4)
    fluid = st.kind == FLUID
    p0 = np.sum(st.m[fluid] * st.u[fluid])
    for _ in range(steps):
        sim.step()
    s = sim.state
    kept = np.sum(s.m[s.kind == FLUID] * s.u[s.kind == FLUID]) / p0
    return kept, s, x, y
