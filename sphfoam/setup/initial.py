"""``sphfoam setup``: the particles of system/particleDict, hydrostatic and at rest, written
as the case's ``0/`` (with the one-cell mesh and ``CASE.foam`` ParaView's reader needs).
A case with controlDict ``settling`` is set up by
:func:`sphfoam.setup.settling.setup_case`, which uses the pieces here and settles the
particles before writing ``0/``."""

from __future__ import annotations

from sphfoam.case.case import Case
from sphfoam.engine.state import ParticleState
from sphfoam.io.polymesh import write_foam_files
from sphfoam.io.timedirs import case_lock, write_time
from sphfoam.case.geometry import default_domain, fitted_boxes
from sphfoam.setup.particles import generate
from sphfoam.setup.sanity import check_geometry


def setup_case(case: Case, log=print) -> ParticleState:
    """Generate particles from system/particleDict and write them to ``0/`` (a case with
    controlDict ``settling``: :func:`sphfoam.setup.settling.setup_case`)."""
    case.validate()
    if case.control.settling is not None:
        raise ValueError("this case settles its particles (controlDict settling): set it up "
                         "with sphfoam.setup.settling.setup_case")
    check_geometry(case)
    with case_lock(case.path, "setup"):
        return _setup(case, log)


def _setup(case: Case, log) -> ParticleState:
    return write_start(case, generate_case(case), log)


def generate_case(case: Case) -> ParticleState:
    """The particles of the case's system/particleDict for its boundary model and motions,
    hydrostatic and at rest (nothing written)."""
    sph = case.models.sph
    if case.dimension == 3:
        from sphfoam.setup.particles3d import generate3d

        return generate3d(case.particles, case.context, sph["equationOfState"],
                          boundary=sph["boundary"], moving=bool(case.models.motions),
                          waves=list(case.waves.values()),
                          fields=[f for m in sph.values()
                                  for f in getattr(m, "particle_fields", ())],
                          support_radius=case.context.support)
    return generate(case.particles, case.context, sph["equationOfState"],
                    boundary=sph["boundary"], support_radius=case.context.support,
                    moving=bool(case.models.motions), waves=list(case.waves.values()),
                    fields=[f for m in sph.values() for f in getattr(m, "particle_fields", ())])


def write_start(case: Case, state: ParticleState, log) -> ParticleState:
    """Write ``state`` as the case's ``0/`` (time 0, step 0), with the one-cell mesh and
    CASE.foam that ParaView's OpenFOAM reader needs."""
    sim_p = case.models.sph["equationOfState"].pressure(state.rho, case.context)
    write_time(case, state, 0.0, 0, case.control.deltaT, p=sim_p)
    write_foam_files(case.path, *default_domain(case.particles), case.particles.dx)
    for note in fitted_boxes(case.particles, waves=bool(case.waves)):
        log(f"setup: {note}")
    log(f"setup: {state.n_fluid} fluid + {state.n - state.n_fluid} wall particles "
        f"(dx = {case.particles.dx:g} m) written to {case.path / '0'}")
    return state
