"""A case's models assembled into a :class:`~sphfoam.engine.simulation.Simulation`: the
selection, its compiled pipeline, the wall segments and motions, the time-step controls."""

from __future__ import annotations

from sphfoam.case.case import SPH_PROPERTIES, Case
from sphfoam.case.errors import CaseError
from sphfoam.case.geometry import default_domain, planes_of, segments_of
from sphfoam.case.schemas import SPH_FAMILIES
from sphfoam.engine.build import build_pipeline
from sphfoam.engine.plan import Selection
from sphfoam.engine.simulation import Simulation
from sphfoam.engine.state import WALL, ParticleState


def selection(case: Case) -> Selection:
    """The models of the case in pipeline order, with its time-step and periodicity
    switches."""
    domain = case.particles.domain
    periodic = domain.periodic if domain is not None else []
    return Selection(**{f: case.models.sph[f] for f in SPH_FAMILIES},
                     adjust_time_step=case.control.adjustTimeStep,
                     periodic_x="x" in periodic, periodic_y="y" in periodic,
                     periodic_z="z" in periodic, precision=case.schemes.precision,
                     dim=case.dimension, still_walls=still_walls(case))


def still_walls(case: Case) -> bool:
    """Whether every wall particle keeps velocity 0 all run: no prescribed motion, no
    constant wall velocity, and a boundary that leaves wall velocities as set up."""
    walls = case.particles.walls.values()
    return (bool(getattr(case.models.sph["boundary"], "keeps_wall_velocity", False))
            and not case.models.motions
            and not any(any(getattr(w, "velocity", ())) for w in walls))


def build_simulation(case: Case, state: ParticleState, backend: str | None = None):
    """The case's simulation on its backend (``sphSchemes`` ``backend``, or ``backend``)."""
    ctx = case.context
    sel = selection(case)
    lo, hi = default_domain(case.particles)
    check_wall_fields(case, state)
    if (backend or getattr(case.schemes, "backend", "cpu")) == "cuda":
        return _cuda_simulation(case, state, sel, lo, hi)
    pipe = build_pipeline(sel, ctx, domain_lo=lo, domain_hi=hi)
    return Simulation(state, pipe, case.models.integrator, **_stepping(case, sel, lo, hi))


def _stepping(case: Case, sel: Selection, lo, hi) -> dict:
    """What every backend's simulation takes from the case besides the state, the pipeline
    and the integrator: walls, motions, domain and the time-step controls."""
    c, ctx = case.control, case.context
    return dict(segments=segments_of(case.particles), planes=planes_of(case.particles),
                motions=case.models.motions,
                domain_lo=lo, domain_hi=hi, beta=c.maxCo,
                force_condition=case.schemes.timeStepControl.forceCondition,
                adjust_time_step=c.adjustTimeStep, delta_t=c.deltaT, max_delta_t=c.maxDeltaT,
                cell_size_factor=case.schemes.neighbourSearch.cellSizeFactor,
                dt_limit=min(m.dt_limit(ctx) for m in sel.models()))


def check_wall_fields(case: Case, state: ParticleState) -> None:
    """The particles must have been set up for the selected boundary (and motions)."""
    bnd = case.models.sph["boundary"]
    pd = case.particles
    problem = None
    walls = state.kind == WALL
    missing = [k for k in bnd.fields_in(state.dim) if k not in state.extra] \
        if walls.any() else []
    if case.models.motions:
        missing += [k for k in ("patch", "x0", "y0", "z0")[:1 + state.dim]
                    if k not in state.extra]
    for family, mdl in case.models.sph.items():
        lacking = [k for k in mdl.fields_in(state.dim) if k not in state.extra]
        if family != "boundary" and walls.any() and lacking and not missing:
            raise CaseError.single(SPH_PROPERTIES, family,
                                   f"the particles lack the wall field(s) {', '.join(lacking)} "
                                   f"{mdl.name} reads: run 'sphfoam setup --force' again")
    if missing:
        problem = f"the particles lack the field(s) {', '.join(missing)}"
    elif bnd.wall_placement == "none" and walls.any():
        problem = f"the particles include wall particles, which {bnd.name} does not use"
    elif walls.any() and "wallDist" in state.extra:
        d = state.extra["wallDist"][walls]
        if bnd.wall_layers == 1 and d.max() > pd.dx:      # a vertex's is sqrt(3) dx / 2
            problem = "there is more than one row of wall particles"
    if problem:
        raise CaseError.single(SPH_PROPERTIES, "boundary.type",
                               f"{problem}: they were set up for another boundary; run "
                               f"'sphfoam setup --force' again for {bnd.name}")


def _cuda_simulation(case: Case, state: ParticleState, sel, lo, hi):
    """The CUDA backend's simulation (``sphfoam.engine.cuda``); what it cannot run is
    refused by name."""
    from sphfoam.engine.cuda import BackendUnavailable, cuda_module
    from sphfoam.engine.cuda.build import CudaPipeline, Unsupported

    try:
        cuda_module()
        pipe = CudaPipeline(sel, case.context, lo, hi, motions=case.models.motions)
    except (BackendUnavailable, Unsupported) as e:
        raise CaseError.single("system/sphSchemes", "backend", str(e)) from None
    from sphfoam.engine.cuda.runtime import CudaSimulation

    return CudaSimulation(state, pipe, case.models.integrator, **_stepping(case, sel, lo, hi))
