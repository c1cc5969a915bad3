"""Generated modules, for every backend: the working precision of their loops, and their
cache on disk.

A backend's emitter writes a module's source; :func:`load_generated` writes it once under
``<cache>/<kind>s/<key>/`` (``key`` hashes the source with the package's models and
engine, so an edit of a model or of the engine makes a new module) and imports it once per
process. :func:`working_precision` puts the loops of a module in float32 by an AST pass
(the same for the CPU's ``@njit`` functions and the CUDA kernels).
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import os
import sys
from pathlib import Path

from sphfoam._version import __version__
from sphfoam.cachedir import cache_root

#: the folders whose sources a generated module depends on (it imports models and engine)
_SOURCES = ("models", "engine", "engine/cuda")


def package_fingerprint() -> str:
    """Hash of the sources a generated module imports from (models, engine)."""
    root = Path(__file__).resolve().parent.parent
    hsh = hashlib.sha256(__version__.encode())
    for sub in _SOURCES:
        for f in sorted((root / sub).glob("*.py")):
            hsh.update(f.name.encode())
            hsh.update(f.read_bytes())
    return hsh.hexdigest()


def load_generated(src: str, kind: str):
    """(module, path) of generated source ``src``: written once under
    ``<cache>/<kind>s/<key>/`` and imported once per process."""
    key = hashlib.sha256((src + package_fingerprint()).encode()).hexdigest()[:20]
    folder = cache_root() / f"{kind}s" / key
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"sphfoam_{kind}_{key}.py"
    if not path.exists() or path.read_text() != src:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(src)
        os.replace(tmp, path)
    modname = f"sphfoam_{kind}_{key}"
    if modname in sys.modules:
        return sys.modules[modname], path
    spec = importlib.util.spec_from_file_location(modname, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module
    spec.loader.exec_module(module)
    return module, path


class Float32Literals(ast.NodeTransformer):
    """Float literals as ``F4(literal)`` and the results of the models' jitted helpers (the
    kernel) as ``F4(call)``: with float32 arrays and coefficients numba then keeps the
    arithmetic in float32 (a Python float literal is a float64 to numba)."""

    def __init__(self, helpers: set[str]):
        self.helpers = helpers

    def visit_Constant(self, node):
        if isinstance(node.value, float):
            return ast.Call(ast.Name("F4", ast.Load()), [node], [])
        return node

    def visit_Call(self, node):
        self.generic_visit(node)
        if isinstance(node.func, ast.Name) and node.func.id in self.helpers:
            return ast.Call(ast.Name("F4", ast.Load()), [node], [])
        return node


def helper_names(imports) -> set[str]:
    """The names the models' import lines bind (their jitted helpers)."""
    names = set()
    for line in imports:
        if " import " in line:
            for item in line.split(" import ", 1)[1].split(","):
                names.add(item.split(" as ")[-1].strip())
    return names


def working_precision(src: str, helpers: set[str], working) -> str:
    """``src`` with the functions for which ``working(name)`` is true in float32: their
    literals and helper results typed by :class:`Float32Literals`; ``F4 = np.float32``
    defined before ``FLUID``."""
    tree = ast.parse(src)
    typer = Float32Literals(helpers)
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and working(node.name):
            node.body = [typer.visit(stmt) for stmt in node.body]
    at = next(i for i, n in enumerate(tree.body) if isinstance(n, ast.Assign)
              and getattr(n.targets[0], "id", None) == "FLUID")
    tree.body.insert(at, ast.parse("F4 = np.float32").body[0])
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n"
