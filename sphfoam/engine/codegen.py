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
import sys
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import sphfoam

#: the fixed scalar slots every pipeline reads from ``prm`` before the models' own
CORE_PARAMS = ("h", "inv_h", "support2", "eta2", "gx", "gy")
#: hooks a model may fill (see sphfoam.models.base)
HOOKS = ("prepass_init", "prepass_pair", "prepass_final", "particle_code", "pair_code",
         "continuity_velocity_code", "gradient_code")


def cache_root() -> Path:
    env = os.environ.get("SPHFOAM_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sphfoam"


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
    adjust_time_step: bool = True
    periodic_x: bool = False
    periodic_y: bool = False

    def models(self):
        return [m for m in (self.kernel, self.equationOfState, self.continuity, self.momentum,
                            self.viscosity, self.turbulence, self.densityFilter,
                            self.velocityCorrection, self.kernelCorrection, self.boundary)
                if m is not None]

    def describe(self) -> str:
        txt = ", ".join(f"{m.family}={m.name}" for m in self.models() if m.name != "none")
        per = "".join(a for a, on in (("x", self.periodic_x), ("y", self.periodic_y)) if on)
        return txt + (f", periodic={per}" if per else "")

    def aux_names(self) -> list[str]:
        names: list[str] = []
        for m in self.models():
            for a in getattr(m, "aux", ()):
                if a in names:
                    raise ValueError(f"auxiliary field {a!r} declared twice")
                names.append(a)
        return names

    def field_names(self) -> list[str]:
        """Per-particle persistent fields the generated code reads as ``fld[F_<name>, i]``."""
        return list(getattr(self.boundary, "wall_fields", ()))

    def snippet(self, hook: str) -> str:
        return "\n".join(c for c in (getattr(m, hook, "") for m in self.models()) if c)


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
            if r2 >= support2 or r2 == 0.0:   # itself, or a coincident particle (grad W = 0)
                continue
            q = math.sqrt(r2) * inv_h
{body}
"""

_DEFAULT_GRADIENT = """\
fw = kern_gw * kernel_dfdq_q(q)
gWx = fw * dx_ab
gWy = fw * dy_ab
"""

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
s_ab = abs(h * vdotr / (r2 + eta2))
if s_ab > sigma_a:
    sigma_a = s_ab
"""

_CONTINUITY_VELOCITY = """\
uc_ab = u_ab
vc_ab = v_ab
"""


def _pair_loop(sel: Selection, body: str, gradient: str | None = None) -> str:
    """The 3 x 3 cell gather around particle ``a`` with ``body`` run for each neighbour."""
    grad = gradient if gradient is not None else _DEFAULT_GRADIENT
    pre = grad + _NEIGHBOUR_LOAD
    if "Wab" in body or "Wab" in grad:
        pre = "Wab = kern_w * kernel_f(q)\n" + pre
    full = pre + body

    def axis(per, i, n, name):
        if per:
            return f"{i} - 1", f"{i} + 2", f"{name}0 % {n}"
        return f"max({i} - 1, 0)", f"min({i} + 2, {n})", f"{name}0"

    xlo, xhi, cx = axis(sel.periodic_x, "ix", "ncx", "cx")
    ylo, yhi, cy = axis(sel.periodic_y, "iy", "ncy", "cy")
    wrap = ""
    if sel.periodic_x:
        wrap += ("if dx_ab > half_lx:\n    dx_ab -= lx\nelif dx_ab < -half_lx:\n"
                 "    dx_ab += lx\n")
    if sel.periodic_y:
        wrap += ("if dy_ab > half_ly:\n    dy_ab -= ly\nelif dy_ab < -half_ly:\n"
                 "    dy_ab += ly\n")
    return _CELLS.format(xlo=xlo, xhi=xhi, ylo=ylo, yhi=yhi, cx=cx, cy=cy,
                         wrap=_block(wrap, 12) + ("\n" if wrap else ""), body=_block(full, 12))


_ARGS = ("x, y, u, v, rho, p, c, m, kind, cell_start, x0, y0, inv_cell, ncx, ncy, prm, aux, "
         "fld")


def generate_source(sel: Selection, param_names: list[str]) -> str:
    """Python source of the pipeline module for ``sel``."""
    imports = sorted({line for m in sel.models() for line in m.imports()})
    bind = "\n".join(f"{name} = prm[{i}]" for i, name in enumerate(param_names))
    aux = sel.aux_names()
    aux_const = "\n".join(f"I_{a} = {i}" for i, a in enumerate(aux))
    fields = sel.field_names()
    fld_const = "\n".join(f"F_{a} = {i}" for i, a in enumerate(fields))
    gradient = next((m.gradient_code for m in sel.models()
                     if getattr(m, "gradient_code", "")), None)
    continuity = _CONTINUITY_VELOCITY + sel.snippet("continuity_velocity_code") + "\n" + \
        sel.continuity.pair_code
    others = [m.pair_code for m in sel.models()
              if m is not sel.continuity and getattr(m, "pair_code", "")]
    bnd = sel.boundary
    # the boundary model decides which terms a wall neighbour enters (sphfoam.models.boundaries)
    fluid_body = bnd.fluid_body("\n".join([continuity, *others]), sel.viscosity.pair_code)
    fluid_body += "\n" + (_SIGMA if sel.adjust_time_step else "")
    # every term of drho/dt (continuity, and e.g. delta-SPH diffusion) in the density-only pass
    density_body = bnd.density_body("\n".join([continuity,
                                               *(c for c in others if "drho_a" in c)]))
    wall_code = bnd.wall_body(continuity)
    wall_rates = _pair_loop(sel, wall_code, gradient) if wall_code else "pass"
    particle_code = sel.snippet("particle_code")
    has_prepass = any(sel.snippet(k) for k in ("prepass_init", "prepass_pair", "prepass_final"))

    parts = [f'''"""sphfoam pipeline, generated for: {sel.describe()}; adjustTimeStep={sel.adjust_time_step}.

Generated by sphfoam {sphfoam.__version__} (sphfoam.engine.codegen); do not edit.
"""
import math

import numpy as np
from numba import njit, prange

{chr(10).join(imports)}

FLUID = 0
PARAMS = {tuple(param_names)!r}
AUX = {tuple(aux)!r}
{aux_const}
FIELDS = {tuple(fields)!r}
{fld_const}


@njit(parallel=True, fastmath=True, cache=True)
def equation_of_state(rho, p, c, prm):
{_block(bind, 4)}
    for a in prange(rho.shape[0]):
{_block(sel.equationOfState.eos_code, 8)}
''']
    if has_prepass:
        parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def prepass({_ARGS}):
    """Per-particle quantities the pair terms need: {", ".join(aux)}."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
{_block(sel.snippet("prepass_init"), 8)}
{_block(_pair_loop(sel, sel.snippet("prepass_pair")), 8)}
{_block(sel.snippet("prepass_final"), 8)}
''')
    parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def rates({_ARGS}, out_ax, out_ay, out_drho, out_sigma):
    """dv/dt, drho/dt and sigma of T(3.89) for every particle (gather over neighbours)."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        acc_x = 0.0
        acc_y = 0.0
        drho_a = 0.0
        sigma_a = 0.0
        if kind[a] == FLUID:
{_block(particle_code, 12)}
{_block(_pair_loop(sel, fluid_body, gradient), 12)}
            acc_x += gx
            acc_y += gy
        else:
{_block(wall_rates, 12)}
        out_ax[a] = acc_x
        out_ay[a] = acc_y
        out_drho[a] = drho_a
        out_sigma[a] = sigma_a


@njit(parallel=True, fastmath=True, cache=True)
def density_rate({_ARGS}, out_drho):
    """drho/dt alone (the last stage of Monaghan's 2007 scheme, T(3.96))."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        drho_a = 0.0
        if kind[a] == FLUID:
{_block(_pair_loop(sel, density_body, gradient), 12)}
        else:
{_block(wall_rates, 12)}
        out_drho[a] = drho_a
''')
    if getattr(bnd, "step_pair", ""):
        parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def boundary_step({_ARGS}):
    """Once per step, after the re-sort: {bnd.name} wall-particle state."""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
        if kind[a] != FLUID:
{_block(_PARTICLE_LOAD, 12)}
{_block(bnd.step_init, 12)}
{_block(_pair_loop(sel, bnd.step_pair), 12)}
{_block(bnd.step_final, 12)}
''')
    filt = sel.densityFilter
    if filt is not None and getattr(filt, "filter_pair", ""):
        parts.append(f'''

@njit(parallel=True, fastmath=True, cache=True)
def density_filter({_ARGS}, out_rho):
    """{filt.doc}"""
{_block(bind, 4)}
    for a in prange(x.shape[0]):
{_block(_PARTICLE_LOAD, 8)}
        rho_new = rhoa
        if kind[a] == FLUID:
{_block(filt.filter_init, 12)}
{_block(_pair_loop(sel, filt.filter_pair), 12)}
{_block(filt.filter_final, 12)}
        out_rho[a] = rho_new
''')
    return "".join(parts)


@dataclass
class Pipeline:
    """The compiled functions of one selection and the coefficient vector they read."""

    module: object
    prm: np.ndarray
    source_path: Path
    compile_seconds: float
    cache_hit: bool
    selection: Selection

    @property
    def equation_of_state(self):
        return self.module.equation_of_state

    @property
    def rates(self):
        return self.module.rates

    @property
    def density_rate(self):
        return self.module.density_rate

    @property
    def prepass(self):
        """None when no selected model needs per-particle auxiliary fields."""
        return getattr(self.module, "prepass", None)

    @property
    def density_filter(self):
        return getattr(self.module, "density_filter", None)

    @property
    def boundary_step(self):
        """None unless the boundary keeps a per-step wall state (e.g. hybrid wet/dry)."""
        return getattr(self.module, "boundary_step", None)

    @property
    def fields(self) -> tuple[str, ...]:
        return tuple(self.module.FIELDS)

    @property
    def n_aux(self) -> int:
        return len(self.module.AUX)


def build_pipeline(sel: Selection, ctx, core: dict[str, float]) -> Pipeline:
    """Generate (or reuse) the module for ``sel``, import it and compile it.

    ``core`` holds h, inv_h, support2, eta2, gx, gy and, for periodic axes, lx/half_lx and
    ly/half_ly (see :data:`CORE_PARAMS`).
    """
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
    prm = np.array([params[k] for k in names], dtype=np.float64)
    t0 = time.perf_counter()
    funcs = _warm_up(module, prm)
    seconds = time.perf_counter() - t0
    hits = sum(len(f.stats.cache_hits) for f in funcs)
    return Pipeline(module, prm, path, seconds, hits > 0, sel)


def _warm_up(module, prm):
    """Compile (or load from numba's cache) every function with the real argument types."""
    n = 2
    f = np.zeros(n)
    x = np.array([0.0, 0.5 * prm[0]])
    kind = np.zeros(n, dtype=np.int64)
    m = np.ones(n)
    rho = np.full(n, 1000.0)
    cell_start = np.array([0, 2], dtype=np.int64)
    aux = np.zeros((len(module.AUX), n))
    fld = np.zeros((len(module.FIELDS), n))
    module.equation_of_state(rho, f.copy(), f.copy(), prm)
    args = (x, f, f, f, rho, f, f, m, kind, cell_start, -1.0, -1.0, 1e-3, 1, 1, prm, aux, fld)
    funcs = [module.equation_of_state, module.rates, module.density_rate]
    module.rates(*args, f.copy(), f.copy(), f.copy(), f.copy())
    module.density_rate(*args, f.copy())
    if hasattr(module, "prepass"):
        module.prepass(*args)
        funcs.append(module.prepass)
    if hasattr(module, "density_filter"):
        module.density_filter(*args, f.copy())
        funcs.append(module.density_filter)
    if hasattr(module, "boundary_step"):
        module.boundary_step(*args)
        funcs.append(module.boundary_step)
    return funcs
