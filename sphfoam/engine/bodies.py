"""The loop bodies of a pipeline, assembled from its plan: backend-neutral code.

:class:`LoopBodies` writes, from a :class:`~sphfoam.engine.plan.Plan`, the code of one
particle ``a`` in each loop: its state loaded, the terms' ``init``, the walk over its
neighbour list (``nb_start``/``nb_idx``) with the pair quantities and the terms dispatched by
the neighbour's kind, and the terms' ``final``; and the pair code of the half-list loops
(each pair a < b once, a's terms and b's reactions). The code reads arrays by index and calls
the models' helper functions: it is the same for every backend. What a backend adds is the
loop around it (a ``prange`` over particles or bands of cell rows on the CPU,
:mod:`sphfoam.engine.emit_cpu`; one thread per particle on a GPU), the cell walk that builds
the list, and how its functions are compiled.
"""

from __future__ import annotations

import re
import textwrap

from sphfoam.engine import terms as T


def _block(code: str, indent: int) -> str:
    code = textwrap.dedent(code).strip("\n")
    return textwrap.indent(code, " " * indent) if code else ""


def _indent(code: str, n: int = 4) -> str:
    code = textwrap.dedent(code).strip("\n")
    return textwrap.indent(code, " " * n) if code else " " * n + "pass"


#: per-neighbour loads every pair loop makes (engine quantities; see sphfoam.engine.terms)
_NEIGHBOUR_LOAD = """\
U@_ab = U@a - U@[b]
vdotr = {vdotr}
rhob = rho[b]
pb = p[b]
cb = c[b]
mb = m[b]
kindb = kind[b]
"""

_PARTICLE_LOAD = """\
@a = @[a]
U@a = U@[a]
rhoa = rho[a]
pa = p[a]
ca = c[a]
"""

#: T(3.89) with the (0.1 h)^2 guard of Monaghan (1992) that T(3.32) uses: without it a pair
#: closing to r -> 0 (a particle meeting its own mirror image at a wall) collapses the step
_SIGMA = """\
if want_sigma:
    s_ab = abs(h * vdotr / (r2 + eta2))
    sigma_a = max(sigma_a, s_ab)
"""

#: every pair loop: over the neighbour list of particle ``a`` (built once per step)
_LIST = """\
for k in range(nb_start[a], nb_start[a + 1]):
    b = nb_idx[k]
{rel}{wrap}    r2 = {r2}
    if r2 >= support2 or r2 == 0.0:   # beyond the support now, or coincident (grad W = 0)
        continue
    q = math.sqrt(r2) * inv_h
{body}
"""

#: the half-list loop of particle a: its listed neighbours b > a (from ``half[a]`` on)
_HALF = """\
for k in range(half[a], nb_start[a + 1]):
    b = nb_idx[k]
{rel}{wrap}    r2 = {r2}
    if r2 >= support2 or r2 == 0.0:   # beyond the support now, or coincident (grad W = 0)
        continue
    q = math.sqrt(r2) * inv_h
{body}
"""

#: T(3.89) in the half-list loop: s_ab is the same for (a, b) and (b, a); fluid particles only
_SIGMA_HALF = """\
if want_sigma:
    s_ab = abs(h * vdotr / (r2 + eta2))
    if kinda == FLUID:
        sigma_a = max(sigma_a, s_ab)
    if kindb == FLUID:
        out_sigma[b] = max(out_sigma[b], s_ab)"""

#: T(3.89) where the boundary keeps massless (dormant) particles in the list
#: (``Boundary.massless_ghosts``): a neighbour of mass 0 is no neighbour, in this maximum as
#: in every mass-weighted sum
_SIGMA_MASSIVE = """\
if want_sigma:
    s_ab = abs(h * vdotr / (r2 + eta2)) if mb > 0.0 else 0.0
    sigma_a = max(sigma_a, s_ab)
"""

_SIGMA_HALF_MASSIVE = """\
if want_sigma:
    s_ab = abs(h * vdotr / (r2 + eta2))
    if kinda == FLUID and mb > 0.0:
        sigma_a = max(sigma_a, s_ab)
    if kindb == FLUID and ma > 0.0:
        out_sigma[b] = max(out_sigma[b], s_ab)"""

#: the same for a fluid pair
_SIGMA_FF = """\
if want_sigma:
    s_ab = abs(h * vdotr / (r2 + eta2))
    sigma_a = max(sigma_a, s_ab)
    out_sigma[b] = max(out_sigma[b], s_ab)"""


#: the components of each dimension: (axis, velocity)
COMPONENTS = (("x", "u"), ("y", "v"), ("z", "w"))


def components(dim: int):
    """(axis, velocity) of each component in ``dim`` dimensions."""
    if dim not in (2, 3):
        raise ValueError(f"dimension {dim}: valid are 2, 3")
    return COMPONENTS[:dim]


def expand(code: str, dim: int = 2) -> str:
    """``code`` with its ``@`` lines written once per component (``sphfoam.engine.terms``)."""
    return T.expand_components(code, components(dim)) if code else ""


def sum_over(template: str, dim: int = 2) -> str:
    """``template`` summed over the components, left to right: ``sum_over("U@_ab * d@_ab")``
    is ``u_ab * dx_ab + v_ab * dy_ab`` in two dimensions."""
    return " + ".join(template.replace("U@", vel).replace("@", ax)
                      for ax, vel in components(dim))


def particle_load(dim: int = 2) -> str:
    """a's state, loaded once per particle."""
    return expand(_PARTICLE_LOAD, dim)


def neighbour_load(dim: int = 2) -> str:
    """b's state and the pair's velocity difference, loaded once per neighbour."""
    return expand(_NEIGHBOUR_LOAD.format(vdotr=sum_over("U@_ab * d@_ab", dim)), dim) + "\n"


def cell_range(sel, axis: str, i: str, n: str, name: str):
    """(first, end, cell) of the loop ``for <name>0 in range(first, end): <name> = cell``
    over the cells of ``axis`` around index ``i``. Along a periodic axis the three cells
    wrap; along one the half lists' bands do not follow (:attr:`Selection.band_axis`) they
    are visited in increasing index, i - 1, i, i + 1 with the wrapped one moved to its
    place, so that the list, like the walk over particles sorted by cell, holds each
    particle's b < a before its b > a (:func:`sphfoam.engine.neighbours.half_lists`)."""
    if not sel.periodic(axis):
        return f"max({i} - 1, 0)", f"min({i} + 2, {n})", f"{name}0"
    if axis == sel.band_axis:
        return f"{i} - 1", f"{i} + 2", f"{name}0 % {n}"
    turn = f"(1 if {i} == 0 else 2 if {i} == {n} - 1 else 0)"
    return "0", "3", f"({i} - 1 + ({name}0 + {turn}) % 3) % {n}"


class LoopBodies:
    """The code of each loop's body for one particle ``a``, from ``plan``."""

    def __init__(self, plan, precision: str = "double"):
        if precision not in ("double", "single"):
            raise ValueError(f"precision {precision!r}: valid are double, single")
        self.plan = plan
        #: the dimension of the case: every ``@`` is expanded to its components
        self.dim = plan.sel.dim
        #: "single": the pairs' relative positions, formed from double positions, are
        #: rounded to float32 (``F4``) where the loops form them
        self.precision = precision

    def _x(self, code: str) -> str:
        """``code`` expanded to the components of the case's dimension."""
        return expand(code, self.dim)

    def _code(self, t, part: str) -> str:
        """The ``part`` code of term ``t`` in the case's dimension (every term's code is read
        here: a term may give it per dimension, see ``Term.code``)."""
        return t.code(part, self.dim)

    def _pair_geometry(self) -> dict:
        """The relative position of the pair (one line per component, in the working
        precision) and r2, for the list loop templates."""
        rel = "".join(f"    d{ax}_ab = {self.relative(ax)}\n" for ax, _ in components(self.dim))
        return dict(rel=rel, r2=sum_over("d@_ab * d@_ab", self.dim))

    def relative(self, axis: str) -> str:
        """The relative position of the pair along ``axis`` (x[a] - x[b]), in the working
        precision."""
        d = f"{axis}a - {axis}[b]"
        return f"F4({d})" if self.precision == "single" else d

    def _cond(self, k: str, i: str) -> str:
        kind = "kindb" if i == "b" else f"kind[{i}]"
        c = self.plan.kinds[k]
        if c == "else":
            others = [self._cond(j, i) for j in self.plan.kinds if j != k]
            c = "not (" + " or ".join(others) + ")" if others else "True"
            return c
        return c.format(i=i, kind=kind)

    # --- code ------------------------------------------------------------------------------
    def neighbour_body(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """Pair code of ``terms`` for one neighbour b: the definers and correctors of pair
        quantities first, for every neighbour, then the others by neighbour kind.
        ``cache`` "store" (in the prepass) also defines the cached pair scalars and stores
        them in ``pc[J_<name>, k]``; "read" (in the loops after it) reads them from there."""
        terms = self.plan.needed(terms)
        if cache == "store":
            extra = [t for t in self.plan.terms if t.on_demand and set(t.cache) & set(self.plan.cache)
                     and t not in terms]
            terms = extra + terms
        pre = [t for t in terms if t.on_demand or set(t.corrects) & T.PAIR_QUANTITIES]
        rest = [t for t in terms if t not in pre]
        pre_code = []
        for t in pre:
            code = self._code(t, "pair")
            if cache == "read" and code:
                for n in t.cache:
                    if n in self.plan.cache:
                        code = re.sub(rf"(?m)^{re.escape(n)} = .*$", f"{n} = pc[J_{n}, k]",
                                      code)
            pre_code.append(self._x(code) if code else "")
        if cache == "store":
            pre_code += [f"pc[J_{n}, k] = {n}" for n in self.plan.cache]
        code = neighbour_load(self.dim) + "\n".join(x for x in pre_code if x)
        disp = self._dispatch(rest)
        if disp:
            code += "\n" + disp
        if sigma:
            code += "\n" + (_SIGMA_MASSIVE if self.plan.massless_ghosts else _SIGMA)
        return code

    def _dispatch(self, rest: list, i: str = "b", part: str = "pair") -> str:
        """The ``part`` code of ``rest`` by the kind of neighbour ``i`` ("b"; "a" for the
        reactions of the half-list loops, where a is b's neighbour)."""
        if not rest:
            return ""
        self.plan.check_dispatch(rest)      # (the plan checked every loop's terms)
        sees = {id(t): self.plan.sees(t) for t in rest}
        alls = [t for t in rest if "all" in sees[id(t)]]
        if alls:
            return "\n".join(self._x(self._code(t, part)) for t in rest
                             if self._code(t, part))
        per_kind = {k: [t for t in rest if k in sees[id(t)] and self._code(t, part)]
                    for k in self.plan.kinds}
        groups: list[tuple[list[str], list]] = []
        for k, ts in per_kind.items():
            for g in groups:
                if [id(t) for t in g[1]] == [id(t) for t in ts]:
                    g[0].append(k)
                    break
            else:
                groups.append(([k], ts))
        groups = [g for g in groups if g[1]]
        if not groups:
            return ""
        if len(groups) == 1 and set(groups[0][0]) == set(self.plan.kinds) and self.plan.complete:
            return "\n".join(self._x(self._code(t, part)) for t in groups[0][1])
        order = list(self.plan.kinds)
        out = []
        for gi, (ks, ts) in enumerate(groups):
            later = [j for g in groups[gi + 1:] for j in g[0]]
            conds = []
            for k in ks:
                c = self._cond(k, i)
                excl = [self._cond(j, i) for j in later if order.index(j) < order.index(k)]
                if excl:
                    c = f"({c}) and not ({' or '.join(excl)})"
                conds.append(c)
            body = "\n".join(self._x(self._code(t, part)) for t in ts)
            kw = "if" if gi == 0 else "elif"
            covered = {j for g in groups for j in g[0]} == set(self.plan.kinds)
            if gi == len(groups) - 1 and gi > 0 and covered and self.plan.complete:
                out.append("else:\n" + _indent(body))
            else:
                out.append(f"{kw} {' or '.join(conds)}:\n" + _indent(body))
        return "\n".join(out)

    def _wrap(self) -> str:
        """The relative position wrapped to the nearest image along each periodic axis."""
        wrap = ""
        for ax, _ in components(self.dim):
            if self.plan.sel.periodic(ax):
                wrap += (f"if d{ax}_ab > half_l{ax}:\n    d{ax}_ab -= l{ax}\n"
                         f"elif d{ax}_ab < -half_l{ax}:\n    d{ax}_ab += l{ax}\n")
        return wrap

    def _wrap_block(self) -> str:
        """:meth:`_wrap` indented for the list loop templates."""
        wrap = self._wrap()
        return _block(wrap, 4) + ("\n" if wrap else "")

    def pair_loop(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """The loop over the neighbour list of particle ``a`` with ``terms`` for each b."""
        cache = cache if self.plan.cache else None
        return _LIST.format(**self._pair_geometry(), wrap=self._wrap_block(),
                            body=_block(self.neighbour_body(terms, sigma, cache), 4))

    def particle_code(self, terms: list, part: str) -> str:
        return "\n".join(self._x(self._code(t, part)) for t in terms
                         if self._code(t, part))

    def gather(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """init, the neighbour loop and final of ``terms`` for one particle a (no loop where
        none but the on-demand ones, the kernel's, has pair code)."""
        loop = self.pair_loop(terms, sigma, cache) if any(
            self._code(t, "pair") for t in terms if not t.on_demand) else ""
        return "\n".join(x for x in (self.particle_code(terms, "init"), loop,
                                     self.particle_code(terms, "final")) if x)

    def prepass_loops(self) -> list[str]:
        """The body of each prange loop of the prepass, in order: first the terms that set
        a particle's state in place (``p``, ``c``, ``rho``, ``u``), so every other term
        reads the value they set and none reads it while it is written; then the others.
        Terms that apply to every particle run unbranched; otherwise fluid and wall
        particles each run the terms that apply to them."""
        store = self.plan._unbranched_prepass() if self.plan.cache else None
        return [self._prepass_body(ts, "store" if i == store else None)
                for i, ts in enumerate(self.plan._prepass_groups())]

    def prepass_half_loop(self) -> str:
        """Body of the half-list prepass loop of particle a: for each listed b > a the kernel
        (stored in the pair cache at a's entry), a's sums and b's (the reactions), added to
        b's in ``hs``; then a's sums added to its own."""
        ts = self.plan.prepass_half_terms()
        sums = self.plan.prepass_half_sums()
        body = [self.neighbour_body(ts, cache="store" if self.plan.cache else None),
                "\n".join(f"{n}_b = 0.0" for n in sums),
                "\n".join(self._x(self._code(t, "reaction")) for t in ts if t.reaction),
                "\n".join(f"hs[S_{n}, b] += {n}_b" for n in sums)]
        loop = _HALF.format(**self._pair_geometry(), wrap=self._wrap_block(),
                            body=_block("\n".join(body), 4))
        return "\n".join((self.particle_code(ts, "init"), loop,
                          "\n".join(f"hs[S_{n}, a] += {n}" for n in sums)))

    def prepass_half_final(self) -> str:
        """The prepass's ``final`` code of particle a, its sums read back from ``hs``."""
        ts = self.plan.prepass_half_terms()
        return "\n".join(["\n".join(f"{n} = hs[S_{n}, a]" for n in self.plan.prepass_half_sums()),
                          self.particle_code(ts, "final")])

    def _prepass_body(self, ts: list, cache: str | None = None) -> str:
        if all("all" in t.applies for t in ts):
            return self.gather(ts, cache=cache)
        fluid = [t for t in ts if {"all", "fluid"} & set(t.applies)]
        wall = [t for t in ts if {"all", "wall"} & set(t.applies)]
        wet = [t for t in ts if "wetWall" in t.applies and not {"all", "wall"} & set(t.applies)]
        out = "if kind[a] == FLUID:\n" + _indent(self._gather_or_pass(fluid))
        wall_code = self._gather_or_pass(wall)
        if [t for t in wet if not t.on_demand]:
            # (the plan refused wet-wall terms where the boundary defines no wet walls)
            wet_code = self.gather([t for t in ts if t.on_demand] + wet)
            if self.plan.kinds["wetWall"] != "else":
                wet_code = f"if {self._cond('wetWall', 'a')}:\n" + _indent(wet_code)
            wall_code = wet_code if wall_code == "pass" else wall_code + "\n" + wet_code
        return out + "\nelse:\n" + _indent(wall_code)

    def _gather_or_pass(self, ts: list) -> str:
        return self.gather(ts) if [t for t in ts if not t.on_demand] else "pass"

    def wall_gather(self, stage: str) -> str:
        """The code of ``stage`` for a wall particle a: terms applying to wet walls, when a
        is wet ("pass" where no model defines wet walls)."""
        if "wetWall" not in self.plan.kinds:
            return "pass"
        ts = [t for t in self.plan.stage(stage, "wetWall") if t.pair or t.init or t.final]
        if not [t for t in ts if not t.on_demand]:
            return "pass"
        body = self.gather(ts, cache=None if stage == "step" else self.plan.cache_mode(stage))
        cond = self._cond("wetWall", "a")
        if self.plan.kinds["wetWall"] == "else":
            return body
        return f"if {cond}:\n" + _indent(body)

    def half_loop(self, stage: str, sigma: bool = False) -> str | None:
        """Body of the half-list loop of particle a (see ``rates_half``): for each listed
        b > a the pair quantities once, a's terms (by the kind of b) into a's sums, b's
        reactions (by the kind of a) into ``acc_b_@``/``drho_b``, added to b's outputs."""
        sel = self.plan.half_terms(stage)
        if sel is None:
            return None
        fluid, wet = sel
        ids = {id(t) for t in fluid + wet}
        terms = [t for t in self.plan.terms if id(t) in ids]          # the global order
        pre = [t for t in terms if t.on_demand or t.corrects]    # (correctors: with parity)
        cache = self.plan.cache_mode(stage)
        pre_code = []
        for t in pre:
            code = self._code(t, "pair")
            if cache and code:
                for n in t.cache:
                    if n in self.plan.cache:
                        code = re.sub(rf"(?m)^{re.escape(n)} = .*$", f"{n} = pc[J_{n}, k]",
                                      code)
            if code:
                pre_code.append(self._x(code))
        own = [t for t in fluid if not t.on_demand and not t.corrects]
        own_wet = [t for t in wet if not t.on_demand and not t.corrects]
        common = []
        if wet and self.plan.kinds["wetWall"] == "else":
            # every particle that is not fluid is a wet wall: the terms of both run for
            # every particle, outside the branch on its kind
            wet_ids = {id(t) for t in own_wet}
            common = [t for t in own if id(t) in wet_ids]
            own = [t for t in own if id(t) not in wet_ids]
            own_wet = [t for t in own_wet if id(t) not in {id(c) for c in common}]
        side_a, side_b = [], []
        if common:
            side_a.append(self._dispatch(common))
            side_b.append(self._dispatch(common, "a", "reaction"))
        if own or own_wet:
            for side, i, part in ((side_a, "b", "pair"), (side_b, "a", "reaction")):
                kind = "kinda" if i == "b" else "kindb"
                code = f"if {kind} == FLUID:\n" + _indent(self._dispatch(own, i, part)
                                                          or "pass")
                if own_wet:
                    wet_code = self._dispatch(own_wet, i, part) or "pass"
                    if self.plan.kinds["wetWall"] != "else":
                        wet_code = (f"if {self._cond('wetWall', 'a' if i == 'b' else 'b')}:\n"
                                    + _indent(wet_code))
                    code += "\nelse:\n" + _indent(wet_code)
                side.append(code)
        side_a, side_b = "\n".join(x for x in side_a if x), "\n".join(x for x in side_b if x)
        pair_code = (side_a or "pass") + "\n" + (side_b or "pass")
        if sigma:
            pair_code += "\n" + (_SIGMA_HALF_MASSIVE if self.plan.massless_ghosts else _SIGMA_HALF)
        ff = self._fluid_fluid(common, own, sigma)
        if ff is not None:
            # the common case, a fluid pair, in straight-line code of its own: the same terms
            # in the same order (the same sums), with no branch on the kinds between a's
            # terms and b's reactions, so the compiler shares what they have in common
            # (rho_a rho_b, Pi_ab, the reciprocals)
            pair_code = ("if kinda == FLUID and kindb == FLUID:\n" + _indent(ff)
                         + "\nelse:\n" + _indent(pair_code))
        body = [neighbour_load(self.dim) + "\n".join(pre_code),
                self._x("acc_b_@ = 0.0\ndrho_b = 0.0"), pair_code]
        if stage == "rates":
            body.append(self._x("out_a@[b] += acc_b_@"))
        body.append("out_drho[b] += drho_b")
        loop = _HALF.format(**self._pair_geometry(), wrap=self._wrap_block(),
                            body=_block("\n".join(body), 4))
        init = self.particle_code(terms, "init")
        return "\n".join(x for x in (init, loop) if x)

    def _fluid_fluid(self, common: list, own: list, sigma: bool) -> str | None:
        """The half-list pair code of a fluid particle a and a fluid neighbour b: a's terms
        that see fluid, then b's reactions, in the order of the general branches."""
        ts = [t for t in common + own if {"fluid", "all"} & self.plan.sees(t)]
        if not ts:
            return None
        # the force coefficients (Term.force, F_ab = F_ba) summed into one, applied once per
        # side, where the first of them stood
        forces = [t for t in ts if t.force]
        fold_a = self._x("f_ab = " + " + ".join(f"({t.force})" for t in forces)
                                   + "\nacc_@ -= mb * f_ab * gW@") if len(forces) > 1 else ""
        fold_b = self._x("acc_b_@ += ma * f_ab * gW@") if fold_a else ""
        code, code_b = [], []
        for t in ts:
            folded = fold_a and t.force
            if t.pair and not folded:
                code.append(self._x(self._code(t, "pair")))
            elif folded and t is forces[0]:
                code.append(fold_a)
            if t.reaction and not folded:
                code_b.append(self._x(self._code(t, "reaction")))
            elif folded and t is forces[0]:
                code_b.append(fold_b)
        code += code_b
        if sigma:
            code.append(_SIGMA_FF)
        return "\n".join(code)

