"""The contract between a model and the engine: named terms with declared stages and data.

A model contributes :class:`Term` objects (``PipelineModel.terms``). Each term says

* **where** it runs: its ``stages`` (see :data:`STAGES`), the kinds of particle ``a`` it
  ``applies`` to and the kinds of neighbour ``b`` it ``sees`` (see :data:`PARTICLE_KINDS`,
  :data:`NEIGHBOUR_KINDS`);
* **what** it runs: ``init`` (per particle a, before its neighbour loop), ``pair`` (per
  neighbour b) and ``final`` (per particle a, after the loop), numba-compatible Python;
* **what it touches**: ``reads`` and ``writes``, from :data:`QUANTITIES` or ``aux.<name>``
  (a per-particle auxiliary field, ``aux[I_<name>, i]`` in the code) or ``field.<name>`` (a
  per-particle field written by the set-up, ``fld[F_<name>, i]``).

The generator assembles each stage from these declarations alone (the plan,
``sphfoam.engine.plan``; the loop bodies, ``sphfoam.engine.bodies``; a backend's emitter):
which terms enter which loop, in which order (a term that defines or corrects a pair quantity
comes before the terms reading it), whether the kernel value is computed (only if a term of
that loop reads ``W``), which auxiliary fields exist. :func:`check` rejects, before anything
compiles, a quantity defined or corrected by two models, and a quantity or field read that
nothing provides, naming the models involved.

Vector components. A line containing ``@`` is written once per spatial component with ``@``
replaced by ``x``, ``y`` (and ``z`` in three dimensions), and ``U@`` by the velocity
component ``u``, ``v`` (``w``): ``acc_@ -= pterm * gW@`` is ``acc_x -= pterm * gWx`` and
``acc_y -= pterm * gWy``. Reductions: ``dot(A@, B@)`` is ``(A_x * B_x + A_y * B_y [+ A_z *
B_z])`` and ``sum@(E@)`` is ``(E_x + E_y [+ E_z])``; a line whose only ``@`` are inside them
is written once. A term whose algebra is per dimension gives its code per dimension
(``pair={2: "...", 3: "..."}``) or says ``dims=(2,)``; the plan refuses it in any other
dimension. A backend for another dimension or device expands the same text with its own
components (see docs/developing.md).
"""

from __future__ import annotations

import re

import textwrap
from dataclasses import dataclass, field, replace

#: per-particle fields that exist in three dimensions only (read as ``fld[F_n@, b]`` expands
#: them: a 2-D case neither sets them up nor reads them)
THREE_D_FIELDS = ("nz", "ghostZ")

#: stages of a time step, in the order of the generated module
STAGES = {
    "particle": "per particle, no neighbours (the equation of state: p, c from rho)",
    "step": "once per step after the neighbour update, with a neighbour loop "
            "(e.g. the wet/dry state of wall particles, the free surface of fluid ones)",
    "prepass": "before every evaluation of the rates, with a neighbour loop: per-particle "
               "auxiliary fields the pair terms read (XSPH, C-SPH, velocity gradients)",
    "rates": "dv/dt and drho/dt (and sigma of T(3.89)) of every particle, gathered over "
             "neighbours",
    "density": "drho/dt alone (the last stage of Monaghan's 2007 scheme, T(3.96))",
    "filter": "a periodic density pass setting rho_new of each particle (densityFilter)",
}

#: the stages with a neighbour loop
LOOP_STAGES = ("step", "prepass", "rates", "density", "filter")

#: kinds of neighbour b; each neighbour is of at most one kind. ``fluid`` is the engine's
#: (kind FLUID); the others exist only where a model defines them (``neighbour_kinds``);
#: a neighbour of no kind is seen only by terms that see ``all``
NEIGHBOUR_KINDS = ("fluid", "ghost", "wetWall", "dryWall")
#: what a term may name in ``sees``: the kinds above, ``all`` (every neighbour, whatever its
#: kind) and ``viscousWall`` (the dry walls that enter viscous terms: those of a no-slip
#: boundary, none of a free-slip one)
SEES = (*NEIGHBOUR_KINDS, "viscousWall", "all")
#: kinds of particle a a term may apply to: ``fluid``, ``wall`` (any wall particle),
#: ``wetWall`` (a wall particle the boundary treats as fluid), ``all``
PARTICLE_KINDS = ("fluid", "wall", "wetWall", "all")

#: quantities of a neighbour pair or of a particle a term may define, correct or read besides
#: the engine's loads (x, u, rho, p, c, m of a and b, dx_ab, r2, q, u_ab, vdotr, h, inv_h,
#: eta2, gravity), with the names they have in the code
QUANTITIES = {
    "W": "Wab, the kernel value W(r_ab, h)",
    "gradW": "gWx, gWy (gWz): grad_a W_ab",
    "uc": "uc_ab, vc_ab (wc_ab): the velocity difference the continuity equation uses",
    "acc": "acc_x, acc_y (acc_z): dv_a/dt (accumulated)",
    "drho": "drho_a: drho_a/dt (accumulated)",
    "rho_new": "rho_new: the filtered density of a (filter stage)",
    "rho": "rho[a]: the density of a, set in place (step stage)",
    "p": "p[a]: pressure (particle stage)",
    "c": "c[a]: sound speed (particle stage)",
    "u": "u[a], v[a]: the velocity of a wall particle, set in place (prepass stage)",
}
#: quantities of a pair (defined and corrected per neighbour, before the terms reading them)
PAIR_QUANTITIES = {"W", "gradW", "uc"}
#: quantities of a particle's state a prepass term may set in place (p, c corrected after the
#: equation of state, rho, u written): such terms run in a prepass loop of their own, before
#: every other prepass term, so that no term reads them while they are written
STATE_QUANTITIES = ("p", "c", "rho", "u")
#: quantities each of which exactly one model defines (another may correct it)
EXCLUSIVE = ("W", "gradW", "uc", "rho_new", "p", "c")


@dataclass(frozen=True)
class Term:
    """One term a model contributes to the generated pipeline (see the module docstring)."""

    name: str
    stages: tuple[str, ...]
    pair: str = ""
    init: str = ""
    final: str = ""
    applies: tuple[str, ...] = ("fluid",)
    sees: tuple[str, ...] = ("fluid", "ghost", "wetWall")
    reads: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()
    #: quantities this term changes after their definer (e.g. a kernel correction of gradW)
    corrects: tuple[str, ...] = ()
    #: per-pair scalars an on-demand term defines on a line of their own (``name = ...``)
    #: from the pair's geometry (r2, q, d@_ab) and coefficients alone: the engine may compute
    #: them once per evaluation, in the prepass, and let the later loops of that evaluation
    #: read them from a per-pair array instead (the kernel value and gradient factor)
    cache: tuple[str, ...] = ()
    #: the half-list evaluation (each pair a < b once, for both particles): the pair code of
    #: this term's contribution to particle b, i.e. its ``pair`` code for the pair (b, a),
    #: accumulated into ``acc_b_@`` / ``drho_b`` and written with the quantities of (a, b)
    #: (``gW@`` = grad_a W_ab, ``u_ab``, ``d@_ab``, b's neighbour a: ``ma``, ``rhoa``, ...);
    #: the quantities of (b, a) follow from their definers' ``parity``. A stage whose terms
    #: with pair code do not all have one (or that has ``final`` code) keeps the gather
    reaction: str = ""
    #: of a prepass term: the per-particle sums its ``init`` sets to 0.0 and its ``pair`` code
    #: adds to. With a ``reaction`` (adding to ``<name>_b`` the pair (b, a)'s contribution to
    #: b's sum) the prepass can run over half lists too (``prepass_half``): the sums are then
    #: kept per particle in an array, and ``final`` reads them back
    sums: tuple[str, ...] = ()
    #: of a definer or corrector of pair quantities: "even" when those of the pair (b, a)
    #: equal those of (a, b) (the kernel value), "odd" when they are their negatives (grad W,
    #: uc, XSPH's corrected uc); "" (e.g. a kernel correction, which depends on a's moment
    #: matrix alone) keeps the gather
    parity: str = ""
    #: False when the pair code adds to a sum something that does not vanish for a neighbour
    #: of mass 0 (a neighbour count, a maximum, an unweighted kernel sum). A boundary that
    #: keeps massless particles in the list (dormant mirror ghosts, ``massless_ghosts``)
    #: keeps them out of the support of every particle such a term sees them from (by
    #: rebuilding the list). The definers of pair quantities (W, gradW, uc) count as weighted:
    #: what reads them is
    weighted: bool = True
    #: of a prepass term: True when what it makes is computed once per step, from the step's
    #: first state, and held through the step's later stages (e.g. XSPH's velocity with
    #: ``evaluation oncePerStep``); False (the default) when afresh before every evaluation.
    #: The prepass is one loop: its terms must agree
    per_step: bool = False
    #: True when what the term sums for a non-fluid particle a is discarded (its ``final``
    #: code writes a fixed value for such a particle, e.g. XSPH's dv = 0 for walls): a pair
    #: of two non-fluid particles then adds nothing this term keeps, and the neighbour list
    #: may leave such pairs out (``Plan.fluid_pairs_only``)
    nonfluid_discarded: bool = False
    #: True for a momentum diffusion term (a viscosity's pair term, the SPS stress): wet wall
    #: particles enter it only at a no-slip boundary (``Plan.viscous_wet_walls``)
    viscous: bool = False
    #: True when the pair code is a multiple of the pair's relative velocity (``U@c_ab``, e.g.
    #: the continuity equation's v_ab . grad W): it adds exactly 0 for two particles of one
    #: velocity, so with every wall still (``Selection.still_walls``) a pair of two wall
    #: particles adds nothing and the neighbour list may leave it out
    relative: bool = False
    #: a pair force coefficient F_ab equal to F_ba (an expression of the pair and of
    #: a's ``init`` names): the term adds -m_b F_ab grad_a W_ab to dv_a/dt and, over half
    #: lists, +m_a F_ab grad_a W_ab to dv_b/dt. Its ``pair`` and ``reaction`` code are
    #: written from it (give neither); where a fluid particle meets a fluid neighbour, the
    #: coefficients of all such terms of the loop are summed first and the gradient applied
    #: once (e.g. a pressure gradient and a viscous term along grad W: one product per
    #: component and side instead of one per term)
    force: str = ""
    #: the dimensions the term has code for: those every per-dimension code field
    #: (``{2: "...", 3: "..."}``) and per-dimension name field (``writes={2: (...), 3:
    #: (...)}``) names, (2, 3) where every such field is a plain string or tuple (written
    #: once with ``@``, ``dot``, ``sum@``). A plan of another dimension refuses it
    dims: tuple[int, ...] = ()
    #: the model that contributed it (set by :func:`collect`)
    owner: object = field(default=None, compare=False)

    def __post_init__(self):
        dims = {2, 3}
        for part in CODE_PARTS:
            code = getattr(self, part)
            if isinstance(code, dict):
                code = tuple(sorted(code.items()))
                object.__setattr__(self, part, code)
            if isinstance(code, tuple):
                dims &= {d for d, _ in code}
        for part in NAME_PARTS:
            names = getattr(self, part)
            if isinstance(names, dict):
                # names per dimension: one entry (dim, names) per dimension, which
                # expand_names picks (e.g. the six entries of a 3 x 3 stress tensor)
                names = tuple((d, tuple(v)) for d, v in sorted(names.items()))
                object.__setattr__(self, part, names)
                dims &= {d for d, _ in names}
        if not self.dims:
            object.__setattr__(self, "dims", tuple(sorted(dims)))
        if self.force:
            f = f"f_{self.name}"
            pair = f"{f} = {self.force}\nacc_@ -= mb * {f} * gW@"
            reaction = f"{f}_b = {self.force}\nacc_b_@ += ma * {f}_b * gW@"
            if (self.pair or self.reaction) and (self.pair, self.reaction) != (pair, reaction):
                raise ContractError(f"term {self.name!r}: a force term's pair and reaction "
                                    "code are written from its force; give neither")
            object.__setattr__(self, "pair", pair)
            object.__setattr__(self, "reaction", reaction)

    def code(self, part: str, dim: int = 2) -> str:
        """The ``part`` code (``pair``, ``init``, ``final``, ``reaction``, ``force``) of
        the ``dim``-dimensional form: a plain string, or the entry of ``dim`` of a code given
        per dimension ("" where it has none: the plan refuses such a term in ``dim``)."""
        code = getattr(self, part)
        return dict(code).get(dim, "") if isinstance(code, tuple) else code

    @property
    def on_demand(self) -> bool:
        """A term that only defines pair quantities is emitted where some term reads them."""
        return bool(self.writes) and all(w in ("W", "gradW", "uc") for w in self.writes) \
            and not self.corrects

    def who(self) -> str:
        o = self.owner
        return f"{o.family} {o.name!r} (term {self.name!r})" if o is not None else self.name


#: the code fields of a :class:`Term`, each a string or a mapping {dimension: string}
CODE_PARTS = ("pair", "init", "final", "reaction")
#: the declared names of a :class:`Term`, each a tuple of names or a mapping {dimension:
#: names} (a term whose fields differ per dimension: a 3 x 3 tensor's six entries, a 4 x 4
#: moment matrix's ten)
NAME_PARTS = ("reads", "writes", "corrects", "sums")


class ContractError(ValueError):
    """A selection whose terms do not fit together (raised before anything compiles)."""


_REDUCTION = re.compile(r"(?<![\w.])(dot|sum@)\(")
_ATOM = re.compile(r"^(?:[A-Za-z_]\w*(?:\[[^\[\]]*\])?|\d+(?:\.\d*)?(?:e[-+]?\d+)?)$")


def _close(text: str, start: int) -> int:
    """The index of the parenthesis closing the one opened just before ``start``."""
    depth = 1
    for i in range(start, len(text)):
        if text[i] in "([{":
            depth += 1
        elif text[i] in ")]}":
            depth -= 1
            if depth == 0:
                return i
    raise ContractError(f"unbalanced parentheses in {text!r}")


def _top_level(text: str) -> list[str]:
    """``text`` split at its commas outside parentheses and brackets."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return [p.strip() for p in parts + [text[start:]]]


def _product(text: str) -> bool:
    """Whether ``text`` is a product of factors (no operator binding looser than ``*``, ``/``
    outside parentheses): such a term of a sum needs no parentheses of its own."""
    depth = 0
    for i, ch in enumerate(text):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif depth == 0 and (ch in "+-<>=!,%" or (ch == " " and re.match(
                r" (if|else|and|or|not|for|in) ", text[i:]))):
            return False
    return True


def _component(text: str, axis: str, vel: str) -> str:
    return text.replace("U@", vel).replace("@", axis)


def _reductions(line: str, dims) -> str:
    """``dot(A, B)`` and ``sum@(E)`` of ``line`` written out over the components."""
    while True:
        m = _REDUCTION.search(line)
        if m is None:
            return line
        end = _close(line, m.end())
        inner = _reductions(line[m.end():end], dims)
        if m.group(1) == "dot":
            args = _top_level(inner)
            if len(args) != 2:
                raise ContractError(f"dot takes two vectors: {line!r}")
            a, b = (x if _ATOM.match(_component(x, "x", "u")) else f"({x})" for x in args)
            out = " + ".join(f"{_component(a, ax, v)} * {_component(b, ax, v)}"
                             for ax, v in dims)
        else:
            e = inner.strip()
            e = e if _product(e) else f"({e})"
            out = " + ".join(_component(e, ax, v) for ax, v in dims)
        line = f"{line[:m.start()]}({out}){line[end + 1:]}"


_ASSIGNED = re.compile(r"^\s*([A-Za-z_][\w@]*)\s*(?:[-+*/]?=)(?!=)", re.M)


def _check_names(code: str, dims) -> None:
    """A name assigned with ``@`` must not become, written out over the components, one
    other name the code also assigns without it (``sU@`` in 3-D is ``su``, ``sv``, ``sw``:
    a weight sum ``sw`` beside it would be overwritten by its w component). Assigning
    every component by name (a vector written row by row, ``nx = ...``, ``ny = ...``, then
    ``n@`` in another branch) is the same vector, not a clash."""
    targets = set(_ASSIGNED.findall(code))
    plain = {t for t in targets if "@" not in t}
    for t in targets - plain:
        components = {_component(t, ax, v) for ax, v in dims}
        clash = plain & components
        if clash and clash != components:
            raise ContractError(f"{t!r} written out over {', '.join(ax for ax, _ in dims)} "
                                f"gives {', '.join(sorted(clash))}, a name the code also "
                                "assigns: rename one of them")


def expand_components(code: str, dims=(("x", "u"), ("y", "v"))) -> str:
    """Write every line holding ``@`` once per component, after writing out its reductions
    ``dot(A@, B@)`` (A_x * B_x + A_y * B_y ...) and ``sum@(E@)`` (E_x + E_y ...); a line
    whose only ``@`` are in reductions is written once (see the module docstring). A
    component name that clashes with one the code assigns is refused (:func:`_check_names`)."""
    _check_names(code, dims)
    out = []
    for line in textwrap.dedent(code).strip("\n").splitlines():
        if "@" not in line:
            out.append(line)
            continue
        line = _reductions(line, dims)
        if "@" not in line:
            out.append(line)
            continue
        for axis, vel in dims:
            out.append(_component(line, axis, vel))
    return "\n".join(out)


#: (axis, velocity) of each component, x, y, z
AXES = (("x", "u"), ("y", "v"), ("z", "w"))


def expand_names(names: tuple, dim: int = 2) -> tuple[str, ...]:
    """Declared names (``reads``, ``writes``, ``corrects``, ``sums``) with each one holding
    ``@`` written once per component: ``aux.name_dU@`` is ``aux.name_du``, ``aux.name_dv``;
    an entry ``(dim, names)`` (names given per dimension, ``writes={2: (...), 3: (...)}``)
    stands for its names in its own dimension and for nothing in another."""
    out = []
    for n in names:
        if isinstance(n, tuple):
            d, given = n
            out += expand_names(given, dim) if d == dim else []
            continue
        out += [n.replace("U@", v).replace("@", ax) for ax, v in AXES[:dim]] if "@" in n \
            else [n]
    return tuple(out)


def collect(models, dim: int = 2) -> list[Term]:
    """Every term of the selected models, in selection order, with its owner and its declared
    names written out for ``dim`` dimensions (see :func:`expand_names`)."""
    terms = []
    for m in models:
        for t in m.terms():
            unknown = [s for s in t.stages if s not in STAGES]
            bad_sees = [s for s in t.sees if s not in SEES]
            bad_applies = [s for s in t.applies if s not in PARTICLE_KINDS]
            if unknown or bad_sees or bad_applies:
                raise ContractError(
                    f"{m.family} {m.name!r}, term {t.name!r}: unknown "
                    + "; ".join(f"{what} {vals}" for what, vals in
                                (("stage", unknown), ("neighbour kind", bad_sees),
                                 ("particle kind", bad_applies)) if vals))
            terms.append(replace(t, owner=m, **{
                k: expand_names(getattr(t, k), dim)
                for k in ("reads", "writes", "corrects", "sums")}))
    return terms


def check(terms: list[Term], fields: set[str], kinds_defined: dict[str, object],
          dim: int = 2) -> None:
    """Conflicts and missing inputs, naming the models involved (``terms`` as
    :func:`collect` wrote them out for ``dim`` dimensions)."""
    definers: dict[str, Term] = {}
    correctors: dict[str, Term] = {}
    aux_writers: dict[str, Term] = {}
    for t in terms:
        for w in t.writes:
            if w in EXCLUSIVE:
                other = definers.get(w)
                if other is not None and other.owner is not t.owner:
                    raise ContractError(f"{t.who()} and {other.who()} both define {w!r} "
                                        f"({QUANTITIES[w]}); select one of them")
                definers.setdefault(w, t)
            elif w.startswith("aux."):
                other = aux_writers.get(w)
                if other is not None and other.owner is not t.owner:
                    raise ContractError(f"{t.who()} and {other.who()} both write the "
                                        f"auxiliary field {w[4:]!r}")
                aux_writers.setdefault(w, t)
            elif w not in QUANTITIES:
                raise ContractError(f"{t.who()} writes {w!r}, which is neither a quantity "
                                    f"({', '.join(QUANTITIES)}) nor aux.<name>")
        for c in t.corrects:
            other = correctors.get(c)
            if other is not None and other.owner is not t.owner:
                raise ContractError(f"{t.who()} and {other.who()} both correct {c!r} "
                                    f"({QUANTITIES.get(c, c)}); select one of them")
            correctors[c] = t
    for c, t in correctors.items():
        if c not in definers:
            raise ContractError(f"{t.who()} corrects {c!r}, which no selected model defines")
    for t in terms:
        pair_q = t.on_demand or bool(set(t.corrects) & PAIR_QUANTITIES)
        if t.parity not in ("", "even", "odd") or (t.parity and not pair_q):
            raise ContractError(f"{t.who()} declares parity {t.parity!r}: only a definer or "
                                "corrector of pair quantities may, as 'even' or 'odd'")
        if t.reaction and (t.on_demand or not t.pair):
            raise ContractError(f"{t.who()} declares a reaction but has no pair code of its "
                                "own to mirror")
        for name in t.sums:
            if "prepass" not in t.stages or \
                    not re.search(rf"(?m)^{re.escape(name)} = 0\.0$",
                                  expand_components(t.code("init", dim), AXES[:dim])):
                raise ContractError(f"{t.who()} declares the sum {name!r}: only a prepass term "
                                    f"whose init sets it ('{name} = 0.0') may")
    pre = [t for t in terms if "prepass" in t.stages and not t.on_demand]
    for t in pre:
        if t.per_step != pre[0].per_step:
            once, each = (t, pre[0]) if t.per_step else (pre[0], t)
            raise ContractError(f"{once.who()} is computed once per step but {each.who()} "
                                "before every evaluation, and they share the prepass: "
                                "select the former's evaluation everyStage")
    for t in terms:
        for name in t.cache:
            if not t.on_demand or t.reads:
                raise ContractError(f"{t.who()} caches {name!r} but is not a definer of pair "
                                    "quantities from the geometry alone (on demand, no reads)")
            if not all(re.search(rf"(?m)^{re.escape(name)} = ",
                                 expand_components(t.code("pair", d), AXES[:d]))
                       for d in t.dims):
                raise ContractError(f"{t.who()} caches {name!r}, which its pair code does not "
                                    f"define on a line of its own ('{name} = ...')")
    for t in terms:
        for r in t.reads:
            if r.startswith("aux."):
                if r not in aux_writers:
                    raise ContractError(f"{t.who()} reads the auxiliary field {r[4:]!r}, "
                                        "which no selected model writes")
            elif r.startswith("field."):
                if r[6:] not in fields and (dim == 3 or r[6:] not in THREE_D_FIELDS):
                    raise ContractError(f"{t.who()} reads the particle field {r[6:]!r}, "
                                        "which the selected boundary does not set up")
            elif r in EXCLUSIVE:
                if r not in definers:
                    raise ContractError(f"{t.who()} reads {r!r} ({QUANTITIES[r]}), which "
                                        "no selected model defines")
            elif r not in QUANTITIES:
                raise ContractError(f"{t.who()} reads {r!r}: not a quantity "
                                    f"({', '.join(QUANTITIES)}), aux.<name> or field.<name>")
        if "viscousWall" in t.sees and "dryWall" in t.sees:
            raise ContractError(f"{t.who()} sees both dryWall and viscousWall")
    del kinds_defined


def order(terms: list[Term]) -> list[Term]:
    """Definers of a quantity, then its correctors, then its readers; otherwise selection
    order (stable)."""
    def rank(t: Term) -> int:
        if t.on_demand:
            return {"W": 0, "gradW": 1, "uc": 3}[t.writes[0]]
        if t.corrects:
            return 2 if "gradW" in t.corrects else 4
        return 5
    return sorted(terms, key=rank)
