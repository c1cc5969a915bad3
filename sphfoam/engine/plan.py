"""The plan of a pipeline: which terms run in which loop, and how, as data.

A :class:`Selection` (the models a case selects and its geometry switches) becomes a
:class:`Plan`: the terms of the selected models, checked and ordered (see
:mod:`sphfoam.engine.terms`); the neighbour kinds the boundary defines; the auxiliary and
particle fields; the pair cache; which stages run over half lists and which prepass loops
there are. Every contract error (:class:`~sphfoam.engine.terms.ContractError`, naming the
models) is raised here, when the plan is made, before any code is written. The plan holds no
code text: the loop bodies are assembled from it by :mod:`sphfoam.engine.bodies`, and each
backend's emitter (:mod:`sphfoam.engine.emit_cpu`) puts them into its own loops.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sphfoam.engine import terms as T


@dataclass
class Selection:
    """The models a case selects, in pipeline order, and the geometry switches."""

    kernel: object
    equationOfState: object
    continuity: object
    momentum: object
    viscosity: object
    boundary: object
    turbulence: object = None
    densityFilter: object = None
    velocityCorrection: object = None
    kernelCorrection: object = None
    particleShifting: object = None
    adjust_time_step: bool = True
    periodic_x: bool = False
    periodic_y: bool = False
    periodic_z: bool = False
    #: the dimension of the case: 2 (x, y) or 3 (x, y, z)
    dim: int = 2
    #: every wall particle keeps one velocity, 0, all run (no prescribed motion, no wall
    #: velocity, a boundary that leaves wall velocities as set up): a pair of two wall
    #: particles then adds nothing to a term of their relative velocity (``Term.relative``)
    still_walls: bool = False
    #: ``sphSchemes`` ``precision``: "double", or "single" (float32 velocities, density,
    #: pressure, aux, coefficients and pair arithmetic; positions in double)
    precision: str = "double"

    def periodic(self, axis: str) -> bool:
        """Whether ``axis`` ("x", "y", "z") is periodic."""
        return bool(getattr(self, f"periodic_{axis}"))

    @property
    def any_periodic(self) -> bool:
        return self.periodic_x or self.periodic_y or self.periodic_z

    @property
    def band_axis(self) -> str:
        """The axis the half lists' bands follow (rows of cells along y in 2-D, layers
        along z in 3-D): where it is periodic the last band's pairs wrap to the first, so
        the stages gather over full lists."""
        return "y" if self.dim == 2 else "z"

    @property
    def bands_periodic(self) -> bool:
        return self.periodic(self.band_axis)

    @property
    def dtype(self):
        """The numpy type of the working arrays and coefficients."""
        return np.dtype(np.float32 if self.precision == "single" else np.float64)

    def models(self):
        return [m for m in (self.kernel, self.equationOfState, self.continuity, self.momentum,
                            self.viscosity, self.turbulence, self.densityFilter,
                            self.velocityCorrection, self.particleShifting,
                            self.kernelCorrection, self.boundary)
                if m is not None]

    def describe(self) -> str:
        txt = ", ".join(f"{m.family}={m.name}" for m in self.models() if m.name != "none")
        per = "".join(a for a in "xyz" if self.periodic(a))
        txt += f", periodic={per}" if per else ""
        txt += ", 3-D" if self.dim == 3 else ""
        return txt + (", precision=single" if self.precision == "single" else "")

    def plan(self) -> "Plan":
        return Plan(self)

    def aux_names(self) -> list[str]:
        return self.plan().aux

    def field_names(self) -> list[str]:
        """Per-particle persistent fields the generated code reads as ``fld[F_<name>, i]``."""
        return self.plan().fields

    def hooks(self, name: str) -> list:
        """The selected models' implementations of the run-time hook ``name`` (see
        ``sphfoam.models.base``), in selection order."""
        return [getattr(m, name) for m in self.models() if m.implements(name)]


#: the run-time hooks a model may implement (sphfoam.engine.context.RunContext)
HOOKS = ("attach", "before_neighbours", "add_particles", "after_sort", "before_evaluation",
         "before_passes", "after_rates", "after_density_rate", "walls_moved", "after_step",
         "keeps_neighbours", "advection_velocity")


def core_parameters(sel: Selection, ctx, domain_lo=(0.0, 0.0, 0.0),
                    domain_hi=(1.0, 1.0, 1.0)) -> dict:
    """h, 1/h, the squared support radius, the eta^2 guard of T(3.32), gravity and, for periodic
    axes, the periods: the single source of these for the pipeline, set-up, sampling and
    benchmarks (all from the selected kernel and the case context)."""
    h = ctx.h
    support = ctx.support or sel.kernel.support_radius(h)   # the case context's, if set
    core = dict(h=h, inv_h=1.0 / h, support2=support * support, eta2=ctx.eta2,
                gx=ctx.g[0], gy=ctx.g[1])
    if sel.dim == 3:
        core["gz"] = ctx.g[2] if len(ctx.g) > 2 else 0.0
    for i, axis in enumerate("xyz"[:sel.dim]):
        if sel.periodic(axis):
            core[f"l{axis}"] = float(domain_hi[i] - domain_lo[i])
    return core


def missing_dimension(model, dim: int) -> str | None:
    """Why ``model`` cannot run in ``dim`` dimensions, naming it (None when it can): a term
    with no code for ``dim``, run-time hooks written for two dimensions only, or an option
    the model has no ``dim``-D form of (its ``dimension_problem``)."""
    problem = getattr(model, "dimension_problem", None)
    why = problem(dim) if problem is not None else None
    if why:
        return f"{model.family} {model.name!r}: {why}"
    for t in model.terms():
        if dim not in t.dims:
            return (f"{model.family} {model.name!r} has no {dim}-D form (term {t.name!r} has "
                    f"code for {', '.join(f'{d}-D' for d in t.dims) or 'no dimension'})")
    hooks = [h for h in HOOKS if model.implements(h)]
    if hooks and dim not in getattr(model, "hook_dims", (2,)):
        return (f"{model.family} {model.name!r} has no {dim}-D form (its run-time hooks "
                f"{', '.join(hooks)} are two-dimensional)")
    return None


class Plan:
    """The selected models' terms, checked, and what each loop of the pipeline runs."""

    def __init__(self, sel: Selection):
        self.sel = sel
        #: the boundary keeps particles of mass 0 in the neighbour list (dormant mirror
        #: ghosts): the maximum of T(3.89), the one sum not weighted by mass, skips them
        self.massless_ghosts = bool(getattr(sel.boundary, "massless_ghosts", False))
        self.models = sel.models()
        self.terms = T.order(T.collect(self.models, sel.dim))
        for t in self.terms:
            if sel.dim not in t.dims:
                raise T.ContractError(f"{t.owner.family} {t.owner.name!r} has no {sel.dim}-D "
                                      f"form (term {t.name!r} has code for "
                                      f"{', '.join(f'{d}-D' for d in t.dims) or 'no dimension'})")
        self.kinds, self.viscous_dry_walls, self.viscous_wet_walls = self._kinds()
        self.fields = []
        for m in self.models:
            for f in m.fields_in(sel.dim):
                if f not in self.fields:
                    self.fields.append(f)
        T.check(self.terms, set(self.fields), self.kinds, sel.dim)
        self.aux = []
        for t in self.terms:
            for w in t.writes:
                if w.startswith("aux.") and w[4:] not in self.aux:
                    self.aux.append(w[4:])
        self.cache = self._pair_cache()
        seen = [m for m in self.models if m.schedule() is not None]
        if len(seen) > 1:
            raise T.ContractError(f"{seen[0].family} {seen[0].name!r} and {seen[1].family} "
                                  f"{seen[1].name!r} both schedule a filter pass")
        self._check_loops()

    # --- kinds ---------------------------------------------------------------------------
    def _kinds(self):
        kinds: dict[str, str] = {"fluid": "{kind} == FLUID"}
        owners: dict[str, object] = {}
        viscous_dry, viscous_wet = False, True
        for m in self.models:
            for k, cond in m.neighbour_kinds().items():
                if k == "viscousWall":
                    viscous_dry = bool(cond)
                    continue
                if k == "viscousWetWall":
                    viscous_wet = bool(cond)
                    continue
                if k not in T.NEIGHBOUR_KINDS or k == "fluid":
                    raise T.ContractError(f"{m.family} {m.name!r} defines the neighbour kind "
                                          f"{k!r}; definable: ghost, wetWall, dryWall")
                if k in owners:
                    o = owners[k]
                    raise T.ContractError(f"{m.family} {m.name!r} and {o.family} {o.name!r} "
                                          f"both define the neighbour kind {k!r}")
                owners[k] = m
                kinds[k] = cond
        present = [k for k in T.NEIGHBOUR_KINDS if k in kinds]
        rest = [k for k in present if kinds[k] == "else"]
        if rest and rest[0] != present[-1]:
            raise T.ContractError(f"the neighbour kind {rest[0]!r} is defined as 'every other "
                                  "particle' but is not the last kind")
        return {k: kinds[k] for k in present}, viscous_dry, viscous_wet

    @property
    def complete(self) -> bool:
        """Every neighbour is of some kind (a kind defined as 'every other particle')."""
        return any(c == "else" for c in self.kinds.values()) or list(self.kinds) == ["fluid"]

    def sees(self, t) -> set[str]:
        out = set()
        for s in t.sees:
            if s == "viscousWall":
                if self.viscous_dry_walls and "dryWall" in self.kinds:
                    out.add("dryWall")
            elif s == "wetWall" and t.viscous and not self.viscous_wet_walls:
                continue
            elif s == "all" or s in self.kinds:
                out.add(s)
        return out

    # --- selection of terms ----------------------------------------------------------------
    def stage(self, stage: str, applies: str) -> list:
        """Terms of ``stage`` that run for particles of kind ``applies``."""
        out = []
        for t in self.terms:
            if stage not in t.stages:
                continue
            if "all" in t.applies or applies in t.applies:
                out.append(t)
            elif applies == "wetWall" and "wall" in t.applies:
                out.append(t)
        return out

    def has_stage(self, stage: str) -> bool:
        return any(stage in t.stages and not t.on_demand for t in self.terms)

    @property
    def fluid_pairs_only(self) -> bool:
        """Whether the neighbour list may leave out pairs of two non-fluid particles: no
        selected term with pair code runs for a non-fluid particle, sees non-fluid
        neighbours and keeps what it sums there (``Term.nonfluid_discarded``), or, with
        every wall still, sums something that does not vanish for two still particles
        (``Term.relative``): no term then keeps anything such a pair adds (7 % of the pairs
        of P's wall case; 42 % of the 3-D matched dam break's, its walls 3 layers deep)."""
        nonfluid = {"all", "wall"} | ({"wetWall"} if "wetWall" in self.kinds else set())
        for t in self.terms:
            if t.on_demand or t.nonfluid_discarded or not t.pair:
                continue
            if t.relative and self.sel.still_walls:
                continue
            if not set(t.stages) & set(T.LOOP_STAGES) or not set(t.applies) & nonfluid:
                continue
            if self.sees(t) - {"fluid"}:
                return False
        return True

    def needed(self, terms: list) -> list:
        """``terms`` without the on-demand definers nothing in the list reads."""
        reads = set()
        for t in terms:
            if not t.on_demand:
                reads |= set(t.reads) | set(t.corrects)
        changed = True
        while changed:
            changed = False
            for t in terms:
                if t.on_demand and set(t.writes) & reads and not set(t.reads) <= reads:
                    reads |= set(t.reads)
                    changed = True
        return [t for t in terms if not t.on_demand or set(t.writes) & reads]

    def needs_prepass(self, stage: str) -> bool:
        """Whether the loops of ``stage`` ("density", "filter") read what the prepass makes:
        a state it sets in place, or an aux or field one of their terms reads. Where they do
        not, they run without it (and compute the kernel rather than read the pair cache):
        the prepass's aux are read by the next rates evaluation and the advection hooks,
        and those always follow a prepass of their own."""
        pre = [t for t in self.terms if "prepass" in t.stages and not t.on_demand]
        if not pre:
            return False
        made = set()
        for t in pre:
            if (set(t.writes) | set(t.corrects)) & set(T.STATE_QUANTITIES):
                return True
            made |= set(t.writes)
        for applies in ("fluid", "wetWall"):
            for t in self.needed(self.stage(stage, applies)):
                if set(t.reads) & made:
                    return True
        return False

    def cache_mode(self, stage: str) -> str | None:
        """How the loops of ``stage`` get the cached pair scalars: "read" after a prepass
        that stored them, None (computed in the loop) otherwise."""
        if not self.cache or (stage != "rates" and not self.needs_prepass(stage)):
            return None
        return "read"

    # --- the per-pair cache ------------------------------------------------------------------
    def _unbranched_prepass(self) -> int | None:
        """Index of the first prepass loop in which every particle walks its whole list
        (all its terms apply to every particle), or None."""
        for i, ts in enumerate(self._prepass_groups()):
            if all("all" in t.applies for t in ts):
                return i
        return None

    def prepass_once(self) -> bool:
        """Whether the prepass runs once per step (its terms say ``per_step``): then the
        loops of the later stages compute the kernel, the pair cache being the first's."""
        return any(t.per_step for t in self.terms
                   if "prepass" in t.stages and not t.on_demand)

    def _pair_cache(self) -> list[str]:
        """Names of the geometry-only pair scalars (``Term.cache``) the loops after the
        prepass read, when a prepass loop walks every particle's list and can store them
        once per evaluation (exact: the same expression of the same r2 and q)."""
        if self._unbranched_prepass() is None or self.prepass_once():
            return []
        names = []
        # the loops of every evaluation (the periodic filter recomputes what it needs)
        for stage in ("rates", "density"):
            for applies in ("fluid", "wetWall"):
                for t in self.needed(self.stage(stage, applies)):
                    for n in t.cache:
                        if n not in names:
                            names.append(n)
        return names

    def prepass_half_terms(self) -> list | None:
        """The terms of the prepass when it can run over half lists (``prepass_half``), else
        None: a single loop of terms that apply to and see every particle and declare their
        per-particle ``sums`` and the ``reaction`` that adds to b's; the kernel's pair
        quantities with their parity; no periodic axis; and every loop that reads what the
        prepass makes, or its pair cache (stored for each pair once, at a's entry, where the
        half-list loops read it), is a half-list loop itself."""
        if self.sel.bands_periodic:
            return None
        groups = self._prepass_groups()
        if len(groups) != 1:
            return None
        ts = self.needed(groups[0])
        for t in ts:
            if t.corrects or (t.on_demand and not t.parity):
                return None
            if not t.on_demand and not (t.reaction and t.sums and "all" in t.applies
                                        and "all" in self.sees(t)):
                return None
        if self.half_terms("rates") is None or self.needs_prepass("filter") or \
                (self.needs_prepass("density") and self.half_terms("density") is None):
            return None
        return ts

    def prepass_half_sums(self) -> list[str]:
        ts = self.prepass_half_terms() or []
        return [n for t in ts for n in t.sums]

    def _prepass_groups(self) -> list[list]:
        pre = [t for t in self.terms if "prepass" in t.stages]
        state = [t for t in pre if not t.on_demand and
                 (set(t.writes) | set(t.corrects)) & set(T.STATE_QUANTITIES)]
        rest = [t for t in pre if t not in state]
        if state:
            state = [t for t in pre if t.on_demand] + state
        return [ts for ts in (state, rest) if [t for t in ts if not t.on_demand]]

    # --- half lists ------------------------------------------------------------------------
    def half_terms(self, stage: str):
        """(fluid terms, wet-wall terms) of ``stage`` when each of its pairs can be evaluated
        once for both particles (every term with pair code declares its ``reaction``, none
        has ``final`` code, every definer of a pair quantity its ``parity``; the bands of
        the half-list loops, rows of cells in 2-D and layers of cells in 3-D, not
        periodic), else None: then the stage is only the gather over full lists."""
        if self.sel.bands_periodic:
            return None
        fluid = self.needed(self.stage(stage, "fluid"))
        wet = []
        if "wetWall" in self.kinds:
            ts = [t for t in self.stage(stage, "wetWall") if t.pair or t.init or t.final]
            if [t for t in ts if not t.on_demand]:
                wet = self.needed(ts)
        own = [t for t in fluid + wet if not t.on_demand]
        if not own:
            return None
        for t in fluid + wet:
            if t.on_demand or t.corrects:
                if not t.parity or set(t.corrects) - T.PAIR_QUANTITIES:
                    return None
            elif t.final or (t.pair and not t.reaction):
                return None
        if wet:
            # the pair quantities are made once per pair, for both particles: a corrector
            # must act for fluid and wet-wall particles alike
            f_ids, w_ids = {id(t) for t in fluid}, {id(t) for t in wet}
            if any(t.corrects and (id(t) in f_ids) != (id(t) in w_ids) for t in fluid + wet):
                return None
        return fluid, wet

    def counts_self(self) -> bool:
        """The count pass's row walk counts particle a itself (once: the rows are distinct
        where y is not periodic) and the caller subtracts it: without the test b != a per
        candidate the compiler vectorises the count (3.4 against 12.6 ms at 89 k
        particles, one thread, issue 12)."""
        return not self.sel.any_periodic

    # --- the checks of every loop, before any code is written ------------------------------
    def _check_loops(self) -> None:
        """Contract errors of the loops themselves: a loop whose terms cannot share its
        neighbour dispatch (one sees every neighbour, another only some kinds), and a
        prepass term for wet walls where the boundary defines none."""
        loops = []
        for stage in ("step", "rates", "density", "filter"):
            for applies in ("fluid", "wetWall"):
                loops.append(self.stage(stage, applies))
        for ts in self._prepass_groups():
            loops.append(ts)
            for which in ({"all", "fluid"}, {"all", "wall"}, {"wetWall"}):
                loops.append([t for t in ts if which & set(t.applies)])
            wet = [t for t in ts if "wetWall" in t.applies
                   and not {"all", "wall"} & set(t.applies) and not t.on_demand]
            if wet and "wetWall" not in self.kinds and \
                    not all("all" in t.applies for t in ts):
                raise T.ContractError(f"{wet[0].who()} applies to wet walls, which the "
                                      "selected boundary does not define")
        half = self.prepass_half_terms()
        if half:
            loops.append(half)
        for ts in loops:
            ts = self.needed(ts)
            rest = [t for t in ts if not (t.on_demand or set(t.corrects) & T.PAIR_QUANTITIES)]
            self.check_dispatch(rest)

    def check_dispatch(self, rest: list) -> None:
        """The terms of one neighbour dispatch either all see every neighbour or all see
        only some kinds."""
        sees = {id(t): self.sees(t) for t in rest}
        alls = [t for t in rest if "all" in sees[id(t)]]
        if alls and len(alls) != len(rest):
            a, b = alls[0], next(t for t in rest if t not in alls)
            raise T.ContractError(f"{a.who()} sees every neighbour but {b.who()} in the "
                                  "same loop sees only some kinds; they cannot share a loop")
