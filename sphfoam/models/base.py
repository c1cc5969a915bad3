"""What a model contributes to the generated pipeline, and the hooks it may implement.

A :class:`PipelineModel` declares

* :meth:`~PipelineModel.terms`: named :class:`~sphfoam.engine.terms.Term` objects, each with
  its stages, the particle and neighbour kinds it concerns, its code and the quantities and
  fields it reads and writes (the contract: see :mod:`sphfoam.engine.terms`);
* :meth:`~PipelineModel.params`: the scalar coefficients its code reads, each named with the
  model's ``prefix`` (bound as ``name = prm[i]`` in every generated function);
* :meth:`~PipelineModel.imports`: the import lines its code needs;
* ``particle_fields``: per-particle fields the set-up must write (read as ``fld[F_<name>, i]``);
* :meth:`~PipelineModel.neighbour_kinds`: for a boundary, which neighbours are ghosts, wet
  walls and dry walls (conditions on particle ``{i}`` of kind ``{kind}``);
* :meth:`~PipelineModel.schedule`: when its ``filter`` stage runs (a density filter);
* :meth:`~PipelineModel.dt_limit`: a cap on the time step (e.g. viscous diffusion).

Names the code of a term may read inside the pair loop of particle ``a`` with neighbour ``b``::

    a, b                  particle indices
    xa, ya, ua, va        position and velocity of a
    rhoa, pa, ca, rhob, pb, cb, mb, kindb
    dx_ab, dy_ab, r2, q              r_ab = r_a - r_b, |r_ab|^2, q = |r_ab| / h (r2 > 0)
    u_ab, v_ab, vdotr                v_ab = v_a - v_b and v_ab . r_ab
    h, inv_h, eta2, gx, gy           smoothing length, 1/h, (0.1 h)^2 guard of T(3.32), gravity

and, declared in ``reads``: ``Wab`` (``W``), ``gWx, gWy`` (``gradW``), ``uc_ab, vc_ab``
(``uc``), ``aux[I_<name>, i]`` (``aux.<name>``) and ``fld[F_<name>, i]`` (``field.<name>``).
Rates terms accumulate into ``acc_x, acc_y`` (``acc``) and ``drho_a`` (``drho``).

Run-time hooks (Python, called by :class:`sphfoam.engine.simulation.Simulation` for every
selected model that implements them; the engine names no model). ``run`` is a
:class:`sphfoam.engine.context.RunContext`: the particles' named arrays, the auxiliary
fields by name, the neighbour list, the time, the coefficients by name, the cell grid and
the walls; never the simulation itself:

``attach(run)``                    once, when the simulation is built
``before_neighbours(run)``         at the start of each neighbour update (before binning)
``add_particles(run, cell)``       after binning; may append particles (e.g. mirror ghosts)
                                   and returns the cell index of the appended ones
``keeps_neighbours(run)``          at the start of a step whose neighbour list could be reused
                                   (no particle moved too far since it was built): whether the
                                   particles this model added at the build still serve (True:
                                   reuse). A model with ``add_particles`` or ``before_neighbours``
                                   and without this hook gets a new list every step
``after_sort(run, order)``         after the particles were re-sorted by ``order``
``before_evaluation(run)``         before every evaluation of the pipeline (e.g. refresh ghosts)
``before_passes(run)``             before the pair passes of every evaluation of the rates or
                                   the density rate (not before the equation of state alone,
                                   as output runs it): e.g. wall velocities the passes read
``after_rates(run)``               after every evaluation of the rates: may add a force to
                                   ``run.state.ax, ay`` (e.g. a wall shear stress)
``after_density_rate(run)``        after every density-only pass: may add to ``run.state.drho``
``walls_moved(run, offsets, velocities)``  prescribed wall motion at a stage time
``after_step(run)``                at the end of each step, before anything sees the state
``advection_velocity(run, *U)``   the velocity positions move with (e.g. XSPH), from the
                                   velocity's components U = (u, v) or (u, v, w); several are
                                   applied in selection order, each to the previous one's
                                   result (XSPH's v + dv, then a shifting's + delta_u)
``summary()``                      a line for the end of the run's log ("" for none)

On a backend whose arrays live on a device (CUDA) the hooks run only in a form that
backend can run: declared as data, :meth:`~PipelineModel.device_forms`
(:mod:`sphfoam.engine.hookforms`), or a *device form* class the model names
(``device_form``, "module:Class", standing for the hooks in ``device_hooks``;
:mod:`sphfoam.engine.cuda.forms`); a model with a hook neither covers is refused there by
name.
"""

from __future__ import annotations

from typing import ClassVar

from sphfoam.context import CaseContext
from sphfoam.engine.terms import THREE_D_FIELDS, Term
from sphfoam.registry import Model

__all__ = ["CaseContext", "PipelineModel", "Term", "HOOK_NAMES"]

#: the run-time hooks above
HOOK_NAMES = ("attach", "before_neighbours", "add_particles", "keeps_neighbours", "after_sort",
              "before_evaluation", "before_passes", "after_rates", "after_density_rate",
              "walls_moved", "after_step",
              "advection_velocity", "summary")


class PipelineModel(Model):
    """A model that contributes terms to the generated pipeline (see the module docstring)."""

    prefix: str = ""
    #: per-particle fields the set-up writes and the code reads as ``fld[F_<name>, i]``
    particle_fields: tuple[str, ...] = ()
    #: the device form of the run-time hooks, "module:Class" (:mod:`sphfoam.engine.cuda.
    #: forms`), and the hooks it stands for
    device_form: ClassVar[str] = ""
    device_hooks: ClassVar[tuple[str, ...]] = ()

    def fields_in(self, dim: int) -> tuple[str, ...]:
        """The ``particle_fields`` a case of ``dim`` dimensions has: the z component of a
        wall normal (``nz``) only in 3-D."""
        return tuple(f for f in self.particle_fields if dim == 3 or f not in THREE_D_FIELDS)

    def terms(self) -> list[Term]:
        return []

    def neighbour_kinds(self) -> dict[str, str]:
        return {}

    def schedule(self):
        """A :class:`~sphfoam.engine.schedule.Schedule` for the ``filter`` stage, or None."""
        return None

    def dt_limit(self, ctx: CaseContext) -> float:
        """Largest stable time step this model allows (inf: no limit of its own)."""
        return float("inf")

    def imports(self) -> list[str]:
        return []

    def params(self, ctx: CaseContext) -> dict[str, float]:
        return {}

    def device_forms(self) -> tuple:
        """Its run-time hooks as declared forms (:mod:`sphfoam.engine.hookforms`), run by a
        backend whose arrays live on a device in place of the hooks (none by default)."""
        return ()

    def implements(self, hook: str) -> bool:
        """Whether this model implements the run-time hook ``hook``."""
        return hook in HOOK_NAMES and callable(getattr(self, hook, None))
