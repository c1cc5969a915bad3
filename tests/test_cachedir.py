"""numba's cache folder follows the package's sources (sphfoam.cachedir): a caller compiled
against an old callee in another module is never reused."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import sphfoam
from sphfoam import cachedir

ROOT = Path(sphfoam.__file__).parent


def _cache_dir_of_fresh_python(env_extra: dict, drop=("NUMBA_CACHE_DIR",)) -> str:
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(env_extra)
    env["PYTHONPATH"] = str(ROOT.parent) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", "import sphfoam, numba; print(numba.config.CACHE_DIR)"],
                         env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_numba_cache_folder_is_named_by_the_sources(tmp_path):
    got = _cache_dir_of_fresh_python({"SPHFOAM_CACHE_DIR": str(tmp_path)})
    assert Path(got) == tmp_path / "numba" / cachedir.sources_fingerprint()


def test_a_users_numba_cache_dir_is_kept(tmp_path):
    mine = str(tmp_path / "mine")
    assert _cache_dir_of_fresh_python({"NUMBA_CACHE_DIR": mine}, drop=()) == mine


def test_fingerprint_changes_with_any_source_file(tmp_path):
    copy = tmp_path / "sphfoam"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))

    def fingerprint():
        spec = importlib.util.spec_from_file_location("cachedir_copy", copy / "cachedir.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod.sources_fingerprint()

    before = fingerprint()
    assert before == cachedir.sources_fingerprint()
    f = copy / "sampling" / "waves.py"          # a callee module, not the caller's file
    f.write_text(f.read_text() + "\n# edited\n")
    assert fingerprint() != before
