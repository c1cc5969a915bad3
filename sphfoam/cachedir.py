"""Where sphfoam keeps compiled code: ``SPHFOAM_CACHE_DIR``, else ``$XDG_CACHE_HOME/sphfoam``,
else ``~/.cache/sphfoam``.

numba's on-disk cache (``cache=True``) checks only the source file of the function it
compiled, not the functions it calls in other modules: after an upgrade or an edit of a
callee, a caller's cached machine code would silently keep the old callee. sphfoam
therefore gives numba a cache folder per version of its own sources (a hash of every
``sphfoam/**/*.py``), unless the user has set ``NUMBA_CACHE_DIR``.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path


def cache_root() -> Path:
    env = os.environ.get("SPHFOAM_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sphfoam"


def sources_fingerprint() -> str:
    """Hash of every source file of the package (names and contents)."""
    root = Path(__file__).parent
    hsh = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        hsh.update(str(f.relative_to(root)).encode())
        hsh.update(f.read_bytes())
    return hsh.hexdigest()[:16]


def use_numba_cache_dir() -> None:
    """Point numba's cache at ``cache_root()/numba/<sources_fingerprint()>`` unless
    ``NUMBA_CACHE_DIR`` is set (numba reads it at import; its config is set too in case
    numba was imported first)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    folder = str(cache_root() / "numba" / sources_fingerprint())
    os.environ["NUMBA_CACHE_DIR"] = folder
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = folder
