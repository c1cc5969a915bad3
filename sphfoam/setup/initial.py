"""``sphfoam setup``: the particles of system/particleDict, hydrostatic and at rest, written
as the case's ``0/`` (with the one-cell mesh and ``CASE.foam`` ParaView's reader needs)."""

from __future__ import annotations

from sphfoam.case.case import Case
from sphfoam.engine.state import ParticleState
from sphfoam.io.polymesh import write_foam_files
from sphfoam.io.timedirs import case_lock, write_time
from sphfoam.setup.particles import default_domain, generate
from sphfoam.setup.sanity import check_geometry


def setup_case(case: Case, log=print) -> ParticleState:
    """Generate particles from system/particleDict and write them to ``0/``."""
    case.validate()
    check_geometry(case)
    with case_lock(case.path, "setup"):
        return _setup(case, log)


def _setup(case: Case, log) -> ParticleState:
    sph = case.models.sph
    eos = sph["equationOfState"]
    state = generate(case.particles, case.context, eos, boundary=sph["boundary"],
                     support_radius=case.context.support,
                     moving=bool(case.models.motions),
                     waves=list(case.waves.values()),
                     fields=[f for m in sph.values() for f in getattr(m, "particle_fields", ())])
    sim_p = eos.pressure(state.rho, case.context)
    write_time(case, state, 0.0, 0, case.control.deltaT, p=sim_p)
    # the one-cell mesh and CASE.foam that ParaView's OpenFOAM reader needs
    write_foam_files(case.path, *default_domain(case.particles), case.particles.dx)
    log(f"setup: {state.n_fluid} fluid + {state.n - state.n_fluid} wall particles "
        f"(dx = {case.particles.dx:g} m) written to {case.path / '0'}")
    return state
