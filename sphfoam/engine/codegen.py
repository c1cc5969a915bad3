"""Generate, cache and compile the pipeline for exactly the models a case selects.

The source is assembled from the snippets of the selected models (see
``sphfoam.models.base``): there is no branch for a model the case did not select. The module
is written to ``<cache>/pipelines/<key>/`` where ``key`` hashes the generated source together
with the source of sphfoam's models and engine, then imported; its functions are compiled by
numba with ``cache=True``, so a second run of the same selection loads machine code from disk.
(Closures over jitted functions never reach numba's disk cache; generated modules do.)
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

import sphfoam
from sphfoam.cachedir import cache_root
from sphfoam.engine import terms as T
from sphfoam.engine.fastmath import FASTMATH_SOURCE
from sphfoam.engine.neighbours import deal_bands, half_lists

#: bands of cell rows of the half-list loops (about equal particle counts, but never less than
#: a row, so a shallow tank has about as many as it has rows of water, and one band for the
#: near-empty rows above): numba's prange hands each thread a contiguous share of a colour's
#: bands, so they are listed dealt in turn (``deal_bands``: thread t's share holds the
#: colour's bands t, t + T, ...), not in row order, which gave the bed's rows to one thread
#: and the rows above the water to the other; a fixed number (not one per thread) keeps
#: every sum's order, and so the results, the same whatever the thread count
HALF_BANDS = 64

#: the fixed scalar slots every pipeline reads from ``prm`` before the models' own
CORE_PARAMS = ("h", "inv_h", "support2", "eta2", "gx", "gy")


def _package_fingerprint() -> str:
    """Hash of the sources the generated module imports from (models, engine)."""
    root = Path(sphfoam.__file__).parent
    hsh = hashlib.sha256(sphfoam.__version__.encode())
    for sub in ("models", "engine"):
        for f in sorted((root / sub).glob("*.py")):
            hsh.update(f.name.encode())
            hsh.update(f.read_bytes())
    return hsh.hexdigest()


def _block(code: str, indent: int) -> str:
    code = textwrap.dedent(code).strip("\n")
    return textwrap.indent(code, " " * indent) if code else ""


#: the loop of the half-list functions over the particles of each band of cell rows, in two
#: colours (see ``rates_half``'s docstring), with a's state loaded
_HALF_BANDS = """\
n = x.shape[0]
nb = int(half[half.shape[0] - 1])
for colour in range(2):
    dealt = n + nb + 1 + colour * ((nb + 1) // 2)
    for j in prange((nb + 1 - colour) // 2):
        ib = n + int(half[dealt + j])
        for a in range(half[ib], half[ib + 1]):
{body}"""


def _half_bands(*parts: str) -> str:
    """``_HALF_BANDS`` with ``parts`` (code of particle a) as the body."""
    body = "\n".join([_block(_PARTICLE_LOAD, 0), "ma = m[a]\nkinda = kind[a]",
                      *(_block(x, 0) for x in parts)])
    return _HALF_BANDS.format(body=_block(body, 12))


def _indent(code: str, n: int = 4) -> str:
    code = textwrap.dedent(code).strip("\n")
    return textwrap.indent(code, " " * n) if code else " " * n + "pass"


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
    #: ``sphSchemes`` ``precision``: "double", or "single" (float32 velocities, density,
    #: pressure, aux, coefficients and pair arithmetic; positions in double)
    precision: str = "double"

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
        per = "".join(a for a, on in (("x", self.periodic_x), ("y", self.periodic_y)) if on)
        txt += f", periodic={per}" if per else ""
        return txt + (", precision=single" if self.precision == "single" else "")

    def assembly(self) -> "Assembly":
        return Assembly(self)

    def aux_names(self) -> list[str]:
        return self.assembly().aux

    def field_names(self) -> list[str]:
        """Per-particle persistent fields the generated code reads as ``fld[F_<name>, i]``."""
        return self.assembly().fields

    def hooks(self, name: str) -> list:
        """The selected models' implementations of the run-time hook ``name`` (see
        ``sphfoam.models.base``), in selection order."""
        return [getattr(m, name) for m in self.models() if m.implements(name)]


#: per-neighbour loads every pair loop makes (engine quantities; see sphfoam.engine.terms)
_NEIGHBOUR_LOAD = """\
u_ab = ua - u[b]
v_ab = va - v[b]
vdotr = u_ab * dx_ab + v_ab * dy_ab
rhob = rho[b]
pb = p[b]
cb = c[b]
mb = m[b]
kindb = kind[b]
"""

_PARTICLE_LOAD = """\
xa = x[a]
ya = y[a]
ua = u[a]
va = v[a]
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

#: the 3 x 3 cell walk around particle ``a``, run once per step to build the neighbour list
_CELLS = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
for cy0 in range({ylo}, {yhi}):
    cy = {cy}
    for cx0 in range({xlo}, {xhi}):
        cx = {cx}
        cc = cy * ncx + cx
        for b in range(cell_start[cc], cell_start[cc + 1]):
            dx_ab = xa - x[b]
            dy_ab = ya - y[b]
{wrap}            r2 = dx_ab * dx_ab + dy_ab * dy_ab
            if r2 >= reach2 or b == a{keep}:
                continue
{body}
"""

#: the same walk where the x axis is not periodic: the three cells of a row are consecutive,
#: so their particles are one range of the sorted arrays (the same candidates in the same
#: order); ``ok`` says whether b is listed, with no branch to mispredict (about 1/3 of the
#: candidates in the 3 x 3 cells are within the cell side)
_CELLS_ROWS = """\
ix = min(max(int((xa - x0) * inv_cell), 0), ncx - 1)
iy = min(max(int((ya - y0) * inv_cell), 0), ncy - 1)
cx_lo = max(ix - 1, 0)
cx_hi = min(ix + 2, ncx)
for cy0 in range({ylo}, {yhi}):
    row = {cy} * ncx
    lo = cell_start[row + cx_lo]
    hi = cell_start[row + cx_hi]
    xs = x[lo:hi]
    ys = y[lo:hi]
{kslice}    for j in range(hi - lo):
        b = lo + j
        dx_ab = xa - xs[j]
        dy_ab = ya - ys[j]
{wrap}        r2 = dx_ab * dx_ab + dy_ab * dy_ab
        ok = (r2 < reach2){notself}{keep}
{body}
"""

#: every pair loop: over the neighbour list of particle ``a`` (built once per step)
_LIST = """\
for k in range(nb_start[a], nb_start[a + 1]):
    b = nb_idx[k]
    dx_ab = xa - x[b]
    dy_ab = ya - y[b]
{wrap}    r2 = dx_ab * dx_ab + dy_ab * dy_ab
    if r2 >= support2 or r2 == 0.0:   # beyond the support now, or coincident (grad W = 0)
        continue
    q = math.sqrt(r2) * inv_h
{body}
"""


#: the half-list loop of particle a: its listed neighbours b > a (from ``half[a]`` on)
_HALF = """\
for k in range(half[a], nb_start[a + 1]):
    b = nb_idx[k]
    dx_ab = xa - x[b]
    dy_ab = ya - y[b]
    r2 = dx_ab * dx_ab + dy_ab * dy_ab
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


class Assembly:
    """The selected models' terms, checked, and the code of each loop assembled from them."""

    def __init__(self, sel: Selection):
        self.sel = sel
        #: the boundary keeps particles of mass 0 in the neighbour list (dormant mirror
        #: ghosts): the maximum of T(3.89), the one sum not weighted by mass, skips them
        self.massless_ghosts = bool(getattr(sel.boundary, "massless_ghosts", False))
        self.models = sel.models()
        self.terms = T.order(T.collect(self.models))
        self.kinds, self.viscous_dry_walls = self._kinds()
        self.fields = []
        for m in self.models:
            for f in m.particle_fields:
                if f not in self.fields:
                    self.fields.append(f)
        T.check(self.terms, set(self.fields), self.kinds)
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

    # --- kinds ---------------------------------------------------------------------------
    def _kinds(self):
        kinds: dict[str, str] = {"fluid": "{kind} == FLUID"}
        owners: dict[str, object] = {}
        viscous_dry = False
        for m in self.models:
            for k, cond in m.neighbour_kinds().items():
                if k == "viscousWall":
                    viscous_dry = bool(cond)
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
        return {k: kinds[k] for k in present}, viscous_dry

    def _cond(self, k: str, i: str) -> str:
        kind = "kindb" if i == "b" else f"kind[{i}]"
        c = self.kinds[k]
        if c == "else":
            others = [self._cond(j, i) for j in self.kinds if j != k]
            c = "not (" + " or ".join(others) + ")" if others else "True"
            return c
        return c.format(i=i, kind=kind)

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
        neighbours and keeps what it sums there (``Term.nonfluid_discarded``): no term
        then keeps anything such a pair adds (7 % of the pairs of P's wall case)."""
        nonfluid = {"all", "wall"} | ({"wetWall"} if "wetWall" in self.kinds else set())
        for t in self.terms:
            if t.on_demand or t.nonfluid_discarded or not t.pair:
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

    # --- code ------------------------------------------------------------------------------
    def neighbour_body(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """Pair code of ``terms`` for one neighbour b: the definers and correctors of pair
        quantities first, for every neighbour, then the others by neighbour kind.
        ``cache`` "store" (in the prepass) also defines the cached pair scalars and stores
        them in ``pc[J_<name>, k]``; "read" (in the loops after it) reads them from there."""
        terms = self.needed(terms)
        if cache == "store":
            extra = [t for t in self.terms if t.on_demand and set(t.cache) & set(self.cache)
                     and t not in terms]
            terms = extra + terms
        pre = [t for t in terms if t.on_demand or set(t.corrects) & T.PAIR_QUANTITIES]
        rest = [t for t in terms if t not in pre]
        pre_code = []
        for t in pre:
            code = t.pair
            if cache == "read" and code:
                for n in t.cache:
                    if n in self.cache:
                        code = re.sub(rf"(?m)^{re.escape(n)} = .*$", f"{n} = pc[J_{n}, k]",
                                      code)
            pre_code.append(expand_components(code) if code else "")
        if cache == "store":
            pre_code += [f"pc[J_{n}, k] = {n}" for n in self.cache]
        code = _NEIGHBOUR_LOAD + "\n".join(x for x in pre_code if x)
        disp = self._dispatch(rest)
        if disp:
            code += "\n" + disp
        if sigma:
            code += "\n" + (_SIGMA_MASSIVE if self.massless_ghosts else _SIGMA)
        return code

    def _dispatch(self, rest: list, i: str = "b", part: str = "pair") -> str:
        """The ``part`` code of ``rest`` by the kind of neighbour ``i`` ("b"; "a" for the
        reactions of the half-list loops, where a is b's neighbour)."""
        if not rest:
            return ""
        sees = {id(t): self.sees(t) for t in rest}
        alls = [t for t in rest if "all" in sees[id(t)]]
        if alls:
            if len(alls) != len(rest):
                a, b = alls[0], next(t for t in rest if t not in alls)
                raise T.ContractError(f"{a.who()} sees every neighbour but {b.who()} in the "
                                      "same loop sees only some kinds; they cannot share a "
                                      "loop")
            return "\n".join(expand_components(getattr(t, part)) for t in rest
                             if getattr(t, part))
        per_kind = {k: [t for t in rest if k in sees[id(t)] and getattr(t, part)]
                    for k in self.kinds}
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
        if len(groups) == 1 and set(groups[0][0]) == set(self.kinds) and self.complete:
            return "\n".join(expand_components(getattr(t, part)) for t in groups[0][1])
        order = list(self.kinds)
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
            body = "\n".join(expand_components(getattr(t, part)) for t in ts)
            kw = "if" if gi == 0 else "elif"
            covered = {j for g in groups for j in g[0]} == set(self.kinds)
            if gi == len(groups) - 1 and gi > 0 and covered and self.complete:
                out.append("else:\n" + _indent(body))
            else:
                out.append(f"{kw} {' or '.join(conds)}:\n" + _indent(body))
        return "\n".join(out)

    def _wrap(self) -> str:
        sel = self.sel
        wrap = ""
        if sel.periodic_x:
            wrap += ("if dx_ab > half_lx:\n    dx_ab -= lx\nelif dx_ab < -half_lx:\n"
                     "    dx_ab += lx\n")
        if sel.periodic_y:
            wrap += ("if dy_ab > half_ly:\n    dy_ab -= ly\nelif dy_ab < -half_ly:\n"
                     "    dy_ab += ly\n")
        return wrap

    def counts_self(self) -> bool:
        """The count pass's row walk counts particle a itself (once: the rows are distinct
        where y is not periodic) and the caller subtracts it: without the test b != a per
        candidate the compiler vectorises the count (3.4 against 12.6 ms at 89 k
        particles, one thread, issue 12)."""
        return not self.sel.periodic_x and not self.sel.periodic_y

    def cell_walk(self, body: str, rows: str | None = None, count: bool = False) -> str:
        """The 3 x 3 cell gather around particle ``a`` (within ``reach2``), for the list:
        ``body`` for each b within reach, or, where x is not periodic, ``rows`` for every
        candidate of the three row ranges (contiguous slices of the sorted particles), with
        ``ok`` true for those within reach (and, for ``count`` where ``counts_self``, for a
        itself)."""
        sel = self.sel
        if rows is not None and not sel.periodic_x:
            ylo, yhi, cy = (("iy - 1", "iy + 2", "(cy0 % ncy)") if sel.periodic_y
                            else ("max(iy - 1, 0)", "min(iy + 2, ncy)", "cy0"))
            wrap = self._wrap()
            notself = "" if count and self.counts_self() else " & (b != a)"
            fo = self.fluid_pairs_only
            return _CELLS_ROWS.format(ylo=ylo, yhi=yhi, cy=cy, notself=notself,
                                      keep=" & (fluid_a | (ks[j] == FLUID))" if fo else "",
                                      kslice="    ks = kind[lo:hi]\n" if fo else "",
                                      wrap=_block(wrap, 8) + ("\n" if wrap else ""),
                                      body=_block(rows, 8))

        def axis(per, i, n, name):
            if per:
                return f"{i} - 1", f"{i} + 2", f"{name}0 % {n}"
            return f"max({i} - 1, 0)", f"min({i} + 2, {n})", f"{name}0"

        xlo, xhi, cx = axis(sel.periodic_x, "ix", "ncx", "cx")
        ylo, yhi, cy = axis(sel.periodic_y, "iy", "ncy", "cy")
        wrap = self._wrap()
        return _CELLS.format(xlo=xlo, xhi=xhi, ylo=ylo, yhi=yhi, cx=cx, cy=cy,
                             keep=(" or not (fluid_a or kind[b] == FLUID)"
                                   if self.fluid_pairs_only else ""),
                             wrap=_block(wrap, 12) + ("\n" if wrap else ""),
                             body=_block(body, 12))

    def pair_loop(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """The loop over the neighbour list of particle ``a`` with ``terms`` for each b."""
        wrap = self._wrap()
        cache = cache if self.cache else None
        return _LIST.format(wrap=_block(wrap, 4) + ("\n" if wrap else ""),
                            body=_block(self.neighbour_body(terms, sigma, cache), 4))

    def particle_code(self, terms: list, part: str) -> str:
        return "\n".join(expand_components(getattr(t, part)) for t in terms
                         if getattr(t, part))

    def gather(self, terms: list, sigma: bool = False, cache: str | None = None) -> str:
        """init, the neighbour loop and final of ``terms`` for one particle a."""
        return "\n".join(x for x in (self.particle_code(terms, "init"),
                                     self.pair_loop(terms, sigma, cache),
                                     self.particle_code(terms, "final")) if x)

    def prepass_loops(self) -> list[str]:
        """The body of each prange loop of the prepass, in order: first the terms that set
        a particle's state in place (``p``, ``c``, ``rho``, ``u``), so every other term
        reads the value they set and none reads it while it is written; then the others.
        Terms that apply to every particle run unbranched; otherwise fluid and wall
        particles each run the terms that apply to them."""
        store = self._unbranched_prepass() if self.cache else None
        return [self._prepass_body(ts, "store" if i == store else None)
                for i, ts in enumerate(self._prepass_groups())]

    def prepass_half_terms(self) -> list | None:
        """The terms of the prepass when it can run over half lists (``prepass_half``), else
        None: a single loop of terms that apply to and see every particle and declare their
        per-particle ``sums`` and the ``reaction`` that adds to b's; the kernel's pair
        quantities with their parity; no periodic axis; and every loop that reads what the
        prepass makes, or its pair cache (stored for each pair once, at a's entry, where the
        half-list loops read it), is a half-list loop itself."""
        if self.sel.periodic_x or self.sel.periodic_y:
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

    def prepass_half_loop(self) -> str:
        """Body of the half-list prepass loop of particle a: for each listed b > a the kernel
        (stored in the pair cache at a's entry), a's sums and b's (the reactions), added to
        b's in ``hs``; then a's sums added to its own."""
        ts = self.prepass_half_terms()
        sums = self.prepass_half_sums()
        body = [self.neighbour_body(ts, cache="store" if self.cache else None),
                "\n".join(f"{n}_b = 0.0" for n in sums),
                "\n".join(expand_components(t.reaction) for t in ts if t.reaction),
                "\n".join(f"hs[S_{n}, b] += {n}_b" for n in sums)]
        loop = _HALF.format(body=_block("\n".join(body), 4))
        return "\n".join((self.particle_code(ts, "init"), loop,
                          "\n".join(f"hs[S_{n}, a] += {n}" for n in sums)))

    def prepass_half_final(self) -> str:
        """The prepass's ``final`` code of particle a, its sums read back from ``hs``."""
        ts = self.prepass_half_terms()
        return "\n".join(["\n".join(f"{n} = hs[S_{n}, a]" for n in self.prepass_half_sums()),
                          self.particle_code(ts, "final")])

    def _prepass_groups(self) -> list[list]:
        pre = [t for t in self.terms if "prepass" in t.stages]
        state = [t for t in pre if not t.on_demand and
                 (set(t.writes) | set(t.corrects)) & set(T.STATE_QUANTITIES)]
        rest = [t for t in pre if t not in state]
        if state:
            state = [t for t in pre if t.on_demand] + state
        return [ts for ts in (state, rest) if [t for t in ts if not t.on_demand]]

    def _prepass_body(self, ts: list, cache: str | None = None) -> str:
        if all("all" in t.applies for t in ts):
            return self.gather(ts, cache=cache)
        fluid = [t for t in ts if {"all", "fluid"} & set(t.applies)]
        wall = [t for t in ts if {"all", "wall"} & set(t.applies)]
        wet = [t for t in ts if "wetWall" in t.applies and not {"all", "wall"} & set(t.applies)]
        out = "if kind[a] == FLUID:\n" + _indent(self._gather_or_pass(fluid))
        wall_code = self._gather_or_pass(wall)
        if [t for t in wet if not t.on_demand]:
            if "wetWall" not in self.kinds:
                t = next(t for t in wet if not t.on_demand)
                raise T.ContractError(f"{t.who()} applies to wet walls, which the selected "
                                      "boundary does not define")
            wet_code = self.gather([t for t in ts if t.on_demand] + wet)
            if self.kinds["wetWall"] != "else":
                wet_code = f"if {self._cond('wetWall', 'a')}:\n" + _indent(wet_code)
            wall_code = wet_code if wall_code == "pass" else wall_code + "\n" + wet_code
        return out + "\nelse:\n" + _indent(wall_code)

    def _gather_or_pass(self, ts: list) -> str:
        return self.gather(ts) if [t for t in ts if not t.on_demand] else "pass"

    def wall_gather(self, stage: str) -> str:
        """The code of ``stage`` for a wall particle a: terms applying to wet walls, when a
        is wet ("pass" where no model defines wet walls)."""
        if "wetWall" not in self.kinds:
            return "pass"
        ts = [t for t in self.stage(stage, "wetWall") if t.pair or t.init or t.final]
        if not [t for t in ts if not t.on_demand]:
            return "pass"
        body = self.gather(ts, cache=None if stage == "step" else self.cache_mode(stage))
        cond = self._cond("wetWall", "a")
        if self.kinds["wetWall"] == "else":
            return body
        return f"if {cond}:\n" + _indent(body)

    # --- half lists ------------------------------------------------------------------------
    def half_terms(self, stage: str):
        """(fluid terms, wet-wall terms) of ``stage`` when each of its pairs can be evaluated
        once for both particles (every term with pair code declares its ``reaction``, none
        has ``final`` code, every definer of a pair quantity its ``parity``; no periodic
        axis), else None: then the stage is only the gather over full lists."""
        if self.sel.periodic_x or self.sel.periodic_y:
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

    def half_loop(self, stage: str, sigma: bool = False) -> str | None:
        """Body of the half-list loop of particle a (see ``rates_half``): for each listed
        b > a the pair quantities once, a's terms (by the kind of b) into a's sums, b's
        reactions (by the kind of a) into ``acc_b_@``/``drho_b``, added to b's outputs."""
        sel = self.half_terms(stage)
        if sel is None:
            return None
        fluid, wet = sel
        ids = {id(t) for t in fluid + wet}
        terms = [t for t in self.terms if id(t) in ids]          # the global order
        pre = [t for t in terms if t.on_demand or t.corrects]    # (correctors: with parity)
        cache = self.cache_mode(stage)
        pre_code = []
        for t in pre:
            code = t.pair
            if cache and code:
                for n in t.cache:
                    if n in self.cache:
                        code = re.sub(rf"(?m)^{re.escape(n)} = .*$", f"{n} = pc[J_{n}, k]",
                                      code)
            if code:
                pre_code.append(expand_components(code))
        own = [t for t in fluid if not t.on_demand and not t.corrects]
        own_wet = [t for t in wet if not t.on_demand and not t.corrects]
        common = []
        if wet and self.kinds["wetWall"] == "else":
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
                    if self.kinds["wetWall"] != "else":
                        wet_code = (f"if {self._cond('wetWall', 'a' if i == 'b' else 'b')}:\n"
                                    + _indent(wet_code))
                    code += "\nelse:\n" + _indent(wet_code)
                side.append(code)
        side_a, side_b = "\n".join(x for x in side_a if x), "\n".join(x for x in side_b if x)
        pair_code = (side_a or "pass") + "\n" + (side_b or "pass")
        if sigma:
            pair_code += "\n" + (_SIGMA_HALF_MASSIVE if self.massless_ghosts else _SIGMA_HALF)
        ff = self._fluid_fluid(common, own, sigma)
        if ff is not None:
            # the common case, a fluid pair, in straight-line code of its own: the same terms
            # in the same order (the same sums), with no branch on the kinds between a's
            # terms and b's reactions, so the compiler shares what they have in common
            # (rho_a rho_b, Pi_ab, the reciprocals)
            pair_code = ("if kinda == FLUID and kindb == FLUID:\n" + _indent(ff)
                         + "\nelse:\n" + _indent(pair_code))
        body = [_NEIGHBOUR_LOAD + "\n".join(pre_code),
                "acc_b_x = 0.0\nacc_b_y = 0.0\ndrho_b = 0.0", pair_code]
        if stage == "rates":
            body.append("out_ax[b] += acc_b_x\nout_ay[b] += acc_b_y")
        body.append("out_drho[b] += drho_b")
        loop = _HALF.format(body=_block("\n".join(body), 4))
        init = self.particle_code(terms, "init")
        return "\n".join(x for x in (init, loop) if x)

    def _fluid_fluid(self, common: list, own: list, sigma: bool) -> str | None:
        """The half-list pair code of a fluid particle a and a fluid neighbour b: a's terms
        that see fluid, then b's reactions, in the order of the general branches."""
        ts = [t for t in common + own if {"fluid", "all"} & self.sees(t)]
        if not ts:
            return None
        # the force coefficients (Term.force, F_ab = F_ba) summed into one, applied once per
        # side, where the first of them stood
        forces = [t for t in ts if t.force]
        fold_a = expand_components("f_ab = " + " + ".join(f"({t.force})" for t in forces)
                                   + "\nacc_@ -= mb * f_ab * gW@") if len(forces) > 1 else ""
        fold_b = expand_components("acc_b_@ += ma * f_ab * gW@") if fold_a else ""
        code, code_b = [], []
        for t in ts:
            folded = fold_a and t.force
            if t.pair and not folded:
                code.append(expand_components(t.pair))
            elif folded and t is forces[0]:
                code.append(fold_a)
            if t.reaction and not folded:
                code_b.append(expand_components(t.reaction))
            elif folded and t is forces[0]:
                code_b.append(fold_b)
        code += code_b
        if sigma:
            code.append(_SIGMA_FF)
        return "\n".join(code)


def expand_components(code: str) -> str:
    return T.expand_components(code) if code else ""


_ARGS_BASE = "x, y, u, v, rho, p, c, m, kind, nb_start, nb_idx, prm, aux, fld"


def generate_source(sel: Selection, param_names: list[str]) -> str:
    """Python source of the pipeline module for ``sel``, assembled by stage from the terms
    the selected models declare (see :mod:`sphfoam.engine.terms`)."""
    asm = Assembly(sel)
    imports = sorted({line for m in asm.models for line in m.imports()})
    bind = "\n".join(f"{name} = prm[{i}]" for i, name in enumerate(param_names))
    aux = asm.aux
    aux_const = "\n".join(f"I_{a} = {i}" for i, a in enumerate(aux))
    fields = asm.fields
    fld_const = "\n".join(f"F_{a} = {i}" for i, a in enumerate(fields))
    cache = asm.cache
    cache_const = "".join(f"\nJ_{a} = {i}" for i, a in enumerate(cache))
    #: the arguments of every loop over pairs (``pc``: the per-pair cache, when there is one)
    _ARGS = _ARGS_BASE + (", pc" if cache else "")
    eos = asm.particle_code(asm.stage("particle", "all"), "final")
    # the passes the prepass runs before (rates always; see Assembly.needs_prepass)
    prepass_before = ("\n#: the passes the prepass runs before (the rates always)\nPREPASS_BEFORE = "
                      + repr(tuple(x for x in ("rates", "density", "filter")
                                   if x == "rates" or asm.needs_prepass(x)))
                      + "\n#: the prepass runs once per step, before the step's first evaluation"
                      + f"\nPREPASS_ONCE = {asm.prepass_once()}"
                      if asm.has_stage("prepass") else "")

    # the sums of the half-list prepass, one row each of its array ``hs``
    hsums = asm.prepass_half_sums()
    half_sums = ("\n#: the per-particle sums of prepass_half (rows of its array hs)\nPREPASS_SUMS = "
                 + repr(tuple(hsums)) + "".join(f"\nS_{n} = {i}" for i, n in enumerate(hsums))
                 if hsums else "")
    parts = [f'''"""sphfoam pipeline, generated for: {sel.describe()}; adjustTimeStep={sel.adjust_time_step}.

Generated by sphfoam {sphfoam.__version__} (sphfoam.engine.codegen); do not edit.
"""
import math

import numpy as np
from numba import njit, prange

{chr(10).join(imports)}

FLUID = 0
WALL = 1
GHOST = 2
PARAMS = {tuple(param_names)!r}
AUX = {tuple(aux)!r}
{aux_const}
FIELDS = {tuple(fields)!r}
{fld_const}
PAIR_CACHE = {tuple(cache)!r}{cache_const}{prepass_before}{half_sums}
#: the neighbour list may leave out pairs of two non-fluid particles (Assembly.fluid_pairs_only)
FLUID_PAIRS_ONLY = {asm.fluid_pairs_only}


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def equation_of_state(rho, p, c, prm):
{_block(bind, 4)}
    for a in prange(rho.shape[0]):
{_block(eos or "pass", 8)}
''']
    parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def count_neighbours(x, y, kind, skip, cell_start, x0, y0, inv_cell, ncx, ncy, prm, reach2,
                     count):
    """Neighbours of every particle within sqrt(reach2) (the cell side), from the cells;
    with ``skip``, none of a non-fluid particle's non-fluid neighbours."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
        xa = x[a]
        ya = y[a]
        fluid_a = (not skip) or kind[a] == FLUID
        n_a = 0
{_block(asm.cell_walk("n_a += 1", "n_a += ok", count=True), 8)}
        count[a] = n_a{_self_count(asm)}


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def fill_neighbours(x, y, kind, skip, cell_start, x0, y0, inv_cell, ncx, ncy, prm, reach2,
                    nb_start, nb_idx):
    """The neighbour list: b of particle a in nb_idx[nb_start[a]:nb_start[a + 1]], in the
    order of the cell walk (cells by row, particles by cell); with ``skip``, no pair of two
    non-fluid particles."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
        xa = x[a]
        ya = y[a]
        fluid_a = (not skip) or kind[a] == FLUID
        k = nb_start[a]
        k_end = nb_start[a + 1]
{_block(asm.cell_walk("if k < k_end:" + chr(10) + "    nb_idx[k] = b" + chr(10) + "    k += 1",
                     "if k < k_end:" + chr(10) + "    nb_idx[k] = b" + chr(10) + "k += ok"), 8)}
        while k < k_end:            # (never: the count pass walked the same cells)
            nb_idx[k] = a
            k += 1
''')
    if asm.has_stage("prepass"):
        loops = "".join(f'''
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
{_block(body, 8)}''' for body in asm.prepass_loops())
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def prepass({_ARGS}):
    """Per-particle quantities the pair terms need: {", ".join(aux)}."""
{_block(bind, 4)}{loops}
''')
    fluid_rates = asm.stage("rates", "fluid")
    parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def rates({_ARGS}, out_ax, out_ay, out_drho, out_sigma):
    """dv/dt, drho/dt and sigma of T(3.89) for every particle (gather over neighbours);
    an empty out_sigma: no sigma (an evaluation whose time step is not taken from it)."""
{_block(bind, 4)}
    want_sigma = out_sigma.shape[0] > 0
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        acc_x = 0.0
        acc_y = 0.0
        drho_a = 0.0
        sigma_a = 0.0
        if kind[a] == FLUID:
{_block(asm.gather(fluid_rates, sigma=sel.adjust_time_step, cache="read"), 12)}
            acc_x += gx
            acc_y += gy
        else:
{_block(asm.wall_gather("rates"), 12)}
        out_ax[a] = acc_x
        out_ay[a] = acc_y
        out_drho[a] = drho_a
        if want_sigma:
            out_sigma[a] = sigma_a


@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def density_rate({_ARGS}, out_drho):
    """drho/dt alone (the last stage of Monaghan's 2007 scheme, T(3.96))."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        drho_a = 0.0
        if kind[a] == FLUID:
{_block(asm.gather(asm.stage("density", "fluid"), cache=asm.cache_mode("density")), 12)}
        else:
{_block(asm.wall_gather("density"), 12)}
        out_drho[a] = drho_a
''')
    if asm.has_stage("step"):
        step = asm.stage("step", "wall")
        fluid_step = asm.stage("step", "fluid")
        if not any(not t.on_demand for t in fluid_step):
            parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def step_pass({_ARGS}):
    """Once per step, after the re-sort: per-step state of wall particles."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
        if kind[a] != FLUID:
{_block(_PARTICLE_LOAD, 12)}
{_block(asm.gather(step), 12)}
''')
        else:
            # step terms that apply to fluid particles (e.g. a free-surface detection)
            wall_part = (asm.gather(step) if any(not t.on_demand for t in step)
                         else "pass")
            parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def step_pass({_ARGS}):
    """Once per step, after the re-sort: per-step state of fluid and wall particles."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        if kind[a] == FLUID:
{_block(asm.gather(fluid_step), 12)}
        else:
{_block(wall_part, 12)}
''')
    if asm.has_stage("filter"):
        filt = asm.stage("filter", "fluid")
        owner = next(t.owner for t in filt if not t.on_demand)
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def density_filter({_ARGS}, out_rho):
    """{owner.doc}"""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        rho_new = rhoa
        if kind[a] == FLUID:
{_block(asm.gather(filt), 12)}
        out_rho[a] = rho_new
''')
    for stage, name, outs in (("rates", "rates_half", "out_ax, out_ay, out_drho, out_sigma"),
                              ("density", "density_half", "out_drho")):
        body = asm.half_loop(stage, sigma=stage == "rates" and sel.adjust_time_step)
        if body is None:
            continue
        zero = "\n".join(f"{o}[a] = 0.0" for o in outs.split(", ") if o != "out_sigma")
        if stage == "rates":
            zero += "\nif want_sigma:\n    out_sigma[a] = 0.0"
            start = "acc_x = 0.0\nacc_y = 0.0\ndrho_a = 0.0\nsigma_a = 0.0"
            end = ("if kinda == FLUID:\n    acc_x += gx\n    acc_y += gy\n"
                   "out_ax[a] += acc_x\nout_ay[a] += acc_y\nout_drho[a] += drho_a\n"
                   "if want_sigma and sigma_a > out_sigma[a]:\n    out_sigma[a] = sigma_a")
        else:
            start = "drho_a = 0.0"
            end = "out_drho[a] += drho_a"
        want = "\n    want_sigma = out_sigma.shape[0] > 0" if stage == "rates" else ""
        sigma_doc = ("\n    An empty out_sigma: no sigma (an evaluation whose time step is not "
                     "taken from it).") if stage == "rates" else ""
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def {name}({_ARGS}, half, {outs}):
    """{"rates" if stage == "rates" else "density_rate"} over half lists, the same sums in another order: each
    listed pair a < b once, for both particles (the terms' reactions). half[a] (a < n) is
    where the neighbours b > a start in a's list and half[n + i] the first particle of band
    i (consecutive cell rows): the bands run in two colours, so that no two threads write
    the same particle (a's neighbours b > a lie in a's band or the next).{sigma_doc}"""
{_block(bind, 4)}{want}
    for a in prange(x.shape[0]):
{_block(zero, 8)}
{_block(_half_bands(start, body, end), 4)}
''')
    if asm.prepass_half_terms() is not None:
        zero = "\n".join(f"hs[S_{n}, a] = 0.0" for n in asm.prepass_half_sums())
        parts.append(f'''

@njit(parallel=True, fastmath={FASTMATH_SOURCE}, cache=True)
def prepass_half({_ARGS}, half, hs):
    """The prepass over half lists, the same sums in another order: each listed pair a < b
    once, for both particles (the terms' reactions), in the two colours of bands of
    ``rates_half``; the sums {", ".join(asm.prepass_half_sums())} in ``hs`` (one row each),
    then each particle's final code."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(zero, 8)}
{_block(_half_bands(asm.prepass_half_loop()), 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
{_block(asm.prepass_half_final(), 8)}
''')
    src = "".join(parts)
    if sel.precision == "single":
        src = single_precision(src, imports)
    elif sel.precision != "double":
        raise ValueError(f"precision {sel.precision!r}: valid are double, single")
    return src


_FLOAT_LITERAL = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][-+]?\d+)?|\d+[eE][-+]?\d+|\.\d+)"
                            r"(?![\w.])")
#: functions whose loops run in the working precision (not the cell walk, which bins and
#: measures positions in double)
_SINGLE_FUNCS = ("equation_of_state", "prepass", "rates", "density_rate", "step_pass",
                 "density_filter", "rates_half", "density_half", "prepass_half")


def single_precision(src: str, imports) -> str:
    """The pipeline source in single precision: in the pair and particle loops every float
    literal becomes ``F4(literal)`` and every result of an imported jitted function (the
    kernel) is rounded to float32, and the relative position of a pair is formed in double
    and then rounded (``dx_ab = F4(xa - x[b])``), so that, with float32 arrays and
    coefficients, numba keeps the arithmetic in float32 instead of promoting it to float64
    (Python float literals are float64 to numba)."""
    names = []
    for line in imports:
        if " import " in line:
            for item in line.split(" import ", 1)[1].split(","):
                names.append(item.split(" as ")[-1].strip())
    calls = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\(([^()]*)\)") \
        if names else None
    out = []
    blocks = re.split(r"(?m)^(?=@njit)", src)
    for blk in blocks:
        m = re.search(r"(?m)^def (\w+)\(", blk)
        if m and m.group(1) in _SINGLE_FUNCS:
            head, body = blk.split("\n", 1)[0], blk.split("\n", 1)[1]
            body = _FLOAT_LITERAL.sub(r"F4(\1)", body)
            if calls is not None:
                body = calls.sub(r"F4(\1(\2))", body)
            body = body.replace("dx_ab = xa - x[b]", "dx_ab = F4(xa - x[b])")
            body = body.replace("dy_ab = ya - y[b]", "dy_ab = F4(ya - y[b])")
            blk = head + "\n" + body
        out.append(blk)
    src = "".join(out)
    return src.replace("\nFLUID = 0\n", "\nF4 = np.float32\nFLUID = 0\n", 1)


def core_parameters(sel: Selection, ctx, domain_lo=(0.0, 0.0), domain_hi=(1.0, 1.0)) -> dict:
    """h, 1/h, the squared support radius, the eta^2 guard of T(3.32), gravity and, for periodic
    axes, the periods: the single source of these for the pipeline, set-up, sampling and
    benchmarks (all from the selected kernel and the case context)."""
    h = ctx.h
    support = ctx.support or sel.kernel.support_radius(h)   # the case context's, if set
    core = dict(h=h, inv_h=1.0 / h, support2=support * support, eta2=ctx.eta2,
                gx=ctx.g[0], gy=ctx.g[1])
    if sel.periodic_x:
        core["lx"] = float(domain_hi[0] - domain_lo[0])
    if sel.periodic_y:
        core["ly"] = float(domain_hi[1] - domain_lo[1])
    return core


@dataclass
class Pipeline:
    """The compiled functions of one selection and the coefficient vector they read."""

    module: object
    prm: np.ndarray
    source_path: Path
    compile_seconds: float
    cache_hit: bool
    selection: Selection
    #: h, support radius (m) and the rest of :func:`core_parameters`
    core: dict | None = None
    #: list no pair of two non-fluid particles (the module's FLUID_PAIRS_ONLY; False lists
    #: every pair within reach, as before: the same results, a longer list)
    fluid_pairs_only: bool = False

    @property
    def h(self) -> float:
        if self.core is not None:
            return float(self.core["h"])
        return float(self.prm[CORE_PARAMS.index("h")])

    @property
    def support_radius(self) -> float:
        if self.core is not None:
            return float(np.sqrt(self.core["support2"]))
        return float(np.sqrt(self.prm[CORE_PARAMS.index("support2")]))

    @property
    def dtype(self):
        """The numpy type of the state arrays, ``aux`` and ``prm`` the functions take."""
        return self.prm.dtype

    @property
    def equation_of_state(self):
        return self.module.equation_of_state

    @property
    def rates(self):
        return self.module.rates

    @property
    def density_rate(self):
        return self.module.density_rate

    def neighbour_list(self, x, y, kind, cells, reach: float, start=None, idx=None):
        """(nb_start, nb_idx): the neighbours of every particle within ``reach`` (at most
        the cell side), found by one walk of the cells; ``start``/``idx`` are reused when
        large enough. Where ``fluid_pairs_only``, no pair of two non-fluid particles."""
        n = x.shape[0]
        count = np.empty(n, dtype=np.int64)
        args = (x, y, kind, bool(self.fluid_pairs_only), cells.cell_start, cells.x0,
                cells.y0, 1.0 / cells.cell_size, cells.ncx, cells.ncy, self.prm,
                reach * reach)
        self.module.count_neighbours(*args, count)
        if start is None or start.shape[0] != n + 1:
            start = np.empty(n + 1, dtype=np.int64)
        start[0] = 0
        np.cumsum(count, out=start[1:])
        total = int(start[-1])
        if idx is None or idx.shape[0] < total:
            idx = np.empty(int(total * 1.1) + 16, dtype=np.uint32)
        self.module.fill_neighbours(*args, start, idx)
        return start, idx

    def deal_bands(self, half, threads: int):
        """Deal the bands of ``half`` to ``threads`` threads anew (``deal_bands``)."""
        deal_bands(half, half.shape[0] - 2 * int(half[-1]) - 2, threads)

    def half_lists(self, nb_start, nb_idx, cells, half=None):
        """The array ``half`` of the half-list loops ``rates_half``/``density_half``: where
        each particle's neighbours b > a start in its list, the first particle of each band
        of cell rows (see :func:`sphfoam.engine.neighbours.half_lists`), the order the loops
        run each colour's bands in, dealt to numba's threads now
        (:func:`~sphfoam.engine.neighbours.deal_bands`), and the number of bands; None when the selection
        has no such loops or the list does not allow them. ``half`` is reused if it fits.
        (One array, not two: the loops then take 19 arguments, and CPython keeps freed
        tuples of up to 20 items, which the no-allocation check of tests/test_speed.py
        would count.)"""
        if self.rates_half is None and self.density_half is None:
            return None
        n = nb_start.shape[0] - 1
        size = n + 2 * cells.ncy + 2
        if nb_start[-1] >= 2 ** 32:
            return None
        if half is None or half.base is None or half.base.shape[0] != size:
            buf = np.empty(size, dtype=np.uint32)
        else:
            buf = half.base
        nb = half_lists(nb_start, nb_idx, cells.cell_start, cells.ncx, cells.ncy,
                        HALF_BANDS, buf[:n], buf[n:n + cells.ncy + 1])
        if not nb:
            return None
        half = buf[:n + 2 * nb + 2]
        half[-1] = nb
        deal_bands(half, n, numba.get_num_threads())
        return half

    @property
    def rates_half(self):
        """``rates`` over half lists, or None when a selected term has no reaction."""
        return getattr(self.module, "rates_half", None)

    @property
    def density_half(self):
        """``density_rate`` over half lists, or None."""
        return getattr(self.module, "density_half", None)

    @property
    def prepass(self):
        """None when no selected model needs per-particle auxiliary fields."""
        return getattr(self.module, "prepass", None)

    @property
    def prepass_once(self) -> bool:
        """Whether the prepass runs once per step (``Assembly.prepass_once``)."""
        return bool(getattr(self.module, "PREPASS_ONCE", False))

    @property
    def prepass_half(self):
        """``prepass`` over half lists, or None (see ``Assembly.prepass_half_terms``)."""
        return getattr(self.module, "prepass_half", None)

    @property
    def prepass_sums(self) -> int:
        """Rows of the array of per-particle sums ``prepass_half`` takes."""
        return len(getattr(self.module, "PREPASS_SUMS", ()))

    @property
    def density_filter(self):
        return getattr(self.module, "density_filter", None)

    @property
    def step_pass(self):
        """None unless a selected model keeps a per-step state (the ``step`` stage)."""
        return getattr(self.module, "step_pass", None)

    @property
    def fields(self) -> tuple[str, ...]:
        return tuple(self.module.FIELDS)

    @property
    def pair_cache(self) -> tuple[str, ...]:
        """Pair scalars the prepass stores per listed pair for the later loops of an
        evaluation (``pc[J_<name>, k]``, an extra last argument of every pair loop)."""
        return tuple(getattr(self.module, "PAIR_CACHE", ()))

    def prepass_before(self, stage: str) -> bool:
        """Whether the prepass runs before the pass ``stage`` ("rates", "density",
        "filter"): always before the rates, before the others where they read what it
        makes."""
        return self.prepass is not None and stage in self.module.PREPASS_BEFORE

    @property
    def n_aux(self) -> int:
        return len(self.module.AUX)

    def aux_index(self, name: str) -> int:
        return list(self.module.AUX).index(name)


def build_pipeline(sel: Selection, ctx, core: dict[str, float] | None = None, *,
                   domain_lo=(0.0, 0.0), domain_hi=(1.0, 1.0)) -> Pipeline:
    """Generate (or reuse) the module for ``sel``, import it and compile it.

    ``core`` (h, inv_h, support2, eta2, gx, gy and, for periodic axes, lx and ly) defaults to
    :func:`core_parameters` of ``sel`` and ``ctx``; given, it must agree with them.
    """
    derived = core_parameters(sel, ctx, domain_lo, domain_hi)
    if core is None:
        core = derived
    else:
        for k in CORE_PARAMS:
            if not np.isclose(float(core[k]), derived[k], rtol=1e-12, atol=0.0):
                raise ValueError(f"core parameter {k} = {core[k]!r} differs from the one the "
                                 f"selection and case context give ({derived[k]!r})")
    params: dict[str, float] = {k: float(core[k]) for k in CORE_PARAMS}
    for axis, on in (("x", sel.periodic_x), ("y", sel.periodic_y)):
        if on:
            params[f"l{axis}"] = float(core[f"l{axis}"])
            params[f"half_l{axis}"] = 0.5 * float(core[f"l{axis}"])
    for mdl in sel.models():
        for k, val in mdl.params(ctx).items():
            if not k.startswith(mdl.prefix):
                raise ValueError(f"{mdl!r}: parameter {k!r} must start with {mdl.prefix!r}")
            params[k] = float(val)
    names = list(params)
    src = generate_source(sel, names)
    key = hashlib.sha256((src + _package_fingerprint()).encode()).hexdigest()[:20]
    folder = cache_root() / "pipelines" / key
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"sphfoam_pipeline_{key}.py"
    if not path.exists() or path.read_text() != src:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(src)
        os.replace(tmp, path)
    modname = f"sphfoam_pipeline_{key}"
    if modname in sys.modules:
        module = sys.modules[modname]
    else:
        spec = importlib.util.spec_from_file_location(modname, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[modname] = module
        spec.loader.exec_module(module)
    prm = np.array([params[k] for k in names], dtype=sel.dtype)
    t0 = time.perf_counter()
    funcs = _warm_up(module, prm)
    seconds = time.perf_counter() - t0
    hits = sum(len(f.stats.cache_hits) for f in funcs)
    return Pipeline(module, prm, path, seconds, hits > 0, sel, dict(core),
                    fluid_pairs_only=bool(getattr(module, "FLUID_PAIRS_ONLY", False)))


def _self_count(asm) -> str:
    """What the count pass subtracts for particle a itself where its row walk counts it
    (``counts_self``): 1, or, where the list leaves out pairs of two non-fluid particles, 1
    for a fluid particle only (a non-fluid one does not count itself)."""
    if not asm.counts_self():
        return ""
    return " - (1 if fluid_a else 0)" if asm.fluid_pairs_only else " - 1"


def _warm_up(module, prm):
    """Compile (or load from numba's cache) every function with the real argument types."""
    n = 2
    dt = prm.dtype               # the working precision (positions and fields: double)
    f = np.zeros(n, dtype=dt)
    x = np.array([0.0, 0.5 * float(prm[0])])
    y = np.zeros(n)
    kind = np.zeros(n, dtype=np.int64)
    m = np.ones(n, dtype=dt)
    rho = np.full(n, 1000.0, dtype=dt)
    cell_start = np.array([0, 2], dtype=np.int64)
    aux = np.zeros((len(module.AUX), n), dtype=dt)
    fld = np.zeros((len(module.FIELDS), n))
    module.equation_of_state(rho, f.copy(), f.copy(), prm)
    count = np.zeros(n, dtype=np.int64)
    grid = (x, y, kind, False, cell_start, -1.0, -1.0, 1e-3, 1, 1, prm,
            float(prm[0]) ** 2 * 16.0)
    module.count_neighbours(*grid, count)
    # sized from the count: with periodic axes the single cell is walked 3 x 3 times, so
    # each particle finds its neighbour up to nine times (a fixed list of two overflowed)
    nb_start = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    nb_idx = np.zeros(int(nb_start[-1]), dtype=np.uint32)
    module.fill_neighbours(*grid, nb_start, nb_idx)
    args = (x, y, f, f, rho, f, f, m, kind, nb_start, nb_idx, prm, aux, fld)
    if getattr(module, "PAIR_CACHE", ()):
        args += (np.zeros((len(module.PAIR_CACHE), nb_idx.shape[0]), dtype=dt),)
    funcs = [module.equation_of_state, module.count_neighbours, module.fill_neighbours,
             module.rates, module.density_rate]
    module.rates(*args, f.copy(), f.copy(), f.copy(), f.copy())
    module.density_rate(*args, f.copy())
    if hasattr(module, "prepass"):
        module.prepass(*args)
        funcs.append(module.prepass)
    if hasattr(module, "density_filter"):
        module.density_filter(*args, f.copy())
        funcs.append(module.density_filter)
    if hasattr(module, "step_pass"):
        module.step_pass(*args)
        funcs.append(module.step_pass)
    # [nb_mid | band starts | the bands' dealt order | nb]: one band of both particles
    half = np.array([0] * n + [0, n, 0, 1], dtype=np.uint32)
    if hasattr(module, "rates_half"):
        module.rates_half(*args, half, f.copy(), f.copy(), f.copy(), f.copy())
        funcs.append(module.rates_half)
    if hasattr(module, "density_half"):
        module.density_half(*args, half, f.copy())
        funcs.append(module.density_half)
    if hasattr(module, "prepass_half"):
        module.prepass_half(*args, half, np.zeros((len(module.PREPASS_SUMS), n), dtype=dt))
        funcs.append(module.prepass_half)
    return funcs
