"""Settling: an initialisation run with every wall and paddle still (T §5.3.4).

The thesis ran every beach case first "with no paddle motion, ... to allow the particles to
settle into position, particularly above the toe of the slope where the two grids meet"
(T §5.3.4, Fig 5.2). With ``settling { endTime T; }`` in system/controlDict the set-up does
the same: the generated layout is written as ``0.unsettled/`` (kept for inspection, e.g.
``sphfoam export vtk``, which exports it as ``VTK/<case>_0.unsettled.vtm``), the case runs for T
seconds with the prescribed wall motions (piston paddles, displacement tables) switched off
and every wall's velocity zero, and the settled state becomes ``0/``:

* the time and step index go back to 0, so the paddle's programme, the function objects and
  the written times all start at the settled state, as if the particles had been set up there;
* every fluid velocity is set to zero: the settled water is still water (the motion left after
  settling is the remains of the start-up transient, not of the flow to be computed: the
  paddle's theory assumes water at rest); positions, densities and the wall particles' state
  (e.g. the evolved densities of stationary ghosts) are kept, so the pressure is the
  model's own hydrostatic field;
* the walls' set-up velocities (a sliding plate's) are restored; walls did not move.

Function objects are not run while settling; the stability checks are (a diverging settling
run stops with a case error naming ``settling``).
"""

from __future__ import annotations

import time

import numpy as np

from sphfoam.engine.state import FLUID, WALL, ParticleState
from sphfoam.engine.threads import RunThreads
from sphfoam.io.timedirs import UNSETTLED, case_lock, write_time


def setup_case(case, log=print) -> ParticleState:
    """``sphfoam setup``: the particles of system/particleDict into ``0/``; with controlDict
    ``settling``, first kept as ``0.unsettled/`` and settled with every wall still."""
    from sphfoam.setup import initial
    from sphfoam.setup.sanity import check_geometry

    if case.control.settling is None:
        return initial.setup_case(case, log)
    case.validate()
    check_geometry(case)
    check_settling(case)
    with case_lock(case.path, "setup"):
        state = initial.generate_case(case)
        p = case.models.sph["equationOfState"].pressure(state.rho, case.context)
        write_time(case, state, 0.0, 0, case.control.deltaT, p=p, name=UNSETTLED)
        T = case.control.settling.endTime
        log(f"setup: the layout before settling written to {case.path / UNSETTLED}; "
            f"settling for {T:g} s with every wall still (controlDict settling)")
        state, steps, _ = settle(case, state, log)
        log(f"setup: settled in {steps} steps; time reset to 0, fluid velocities to zero")
        return initial.write_start(case, state, log)


def check_settling(case) -> None:
    """Settling needs still water: a CaseError when constant/waveProperties puts waves in."""
    from sphfoam.case.errors import CaseError

    if case.control.settling is not None and case.waves:
        raise CaseError.single(
            "system/controlDict", "settling", "the initial waves of constant/waveProperties "
            "would travel (and be stopped) while the particles settle: settle still water "
            "(remove the waves) or start the waves unsettled (remove settling)")


def settle(case, state: ParticleState, log=print) -> tuple[ParticleState, int, float]:
    """Run ``state`` for controlDict ``settling.endTime`` with every wall still; returns the
    settled state (time reset to 0, fluid velocities zero), the steps taken and the last
    time step."""
    from sphfoam.assemble import build_simulation
    from sphfoam.case.errors import CaseError
    from sphfoam.engine.health import HealthMonitor

    check_settling(case)
    t_end = float(case.control.settling.endTime)
    wall = state.kind == WALL
    order = np.argsort(state.id[wall])
    ids_set = state.id[wall][order]
    vel_set = [c[wall][order] for c in state.velocities]
    for c in state.velocities:
        c[wall] = 0.0
    sim = build_simulation(case, state, backend="cpu")   # settling runs on the host
    sim.motions = {}                 # paddles and moving walls stay where they were set up
    sim.time, sim.step_index = 0.0, 0

    def on_removal(rem):
        log(f"settling, time {sim.time:.6g}: removed {rem.count} particle(s) that left the "
            f"domain")

    sim.on_removal = on_removal
    monitor = HealthMonitor.from_case(case)
    monitor.start(sim)
    steps = 0
    eps = 1e-9 * t_end
    tenth = 1                            # a log line every tenth of the settling time
    pool = RunThreads(case.control.threads,
                      f"settling; system/controlDict threads {case.control.threads}", log)
    clock = time.perf_counter
    try:
        while sim.time < t_end - eps:
            remaining = t_end - sim.time
            t_step = clock()
            dt = sim.step(remaining)
            pool.after_step(clock() - t_step, sim.time)
            landed = dt >= remaining * (1 - 1e-12)
            if landed:
                sim.time = t_end
            steps += 1
            if sim.time >= tenth * t_end / 10 - eps or sim.time >= t_end - eps:
                log(f"settling: time {sim.time:.6g} of {t_end:g} s (step {steps}, dt {dt:.4g}, "
                    f"KE {sim.kinetic_energy():.4g} {sim.energy_unit})")
                while tenth * t_end / 10 - eps <= sim.time:
                    tenth += 1
            diagnosis = monitor.check(sim, dt, landed)
            if diagnosis is not None:
                raise CaseError.single(
                    "system/controlDict", "settling.endTime",
                    f"the settling run diverged at time {diagnosis.fail_time:.6g} s (step "
                    f"{diagnosis.step}): {diagnosis.title}. Check the set-up in "
                    f"{case.path / UNSETTLED} (sphfoam export vtk) or settle for less")
    finally:
        pool.end()
    st = sim.state
    fluid = st.kind == FLUID
    for c in st.velocities:
        c[fluid] = 0.0
    wall = np.flatnonzero(st.kind == WALL)
    if ids_set.size and wall.size:    # the set-up wall velocities back (the sim re-sorts)
        k = np.clip(np.searchsorted(ids_set, st.id[wall]), 0, ids_set.size - 1)
        same = ids_set[k] == st.id[wall]
        for c, c_set in zip(st.velocities, vel_set):
            c[wall[same]] = c_set[k[same]]
    return st, steps, sim.last_dt
