"""Shared helpers: copy a tutorial into a temporary directory and edit its dictionaries."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from sphfoam.case import foamdict

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"


def set_entry(case: Path, rel: str, key: str, value) -> None:
    """Set ``a.b.c`` in ``case/rel`` (written back in OpenFOAM syntax)."""
    path = case / rel
    d = foamdict.read(path)
    header = d.pop("FoamFile", None)
    node = d
    *parents, last = key.split(".")
    for k in parents:
        node = node.setdefault(k, {})
    if value is None:
        node.pop(last, None)
    else:
        node[last] = value
    foamdict.write(path, d, header=header)


@pytest.fixture
def tutorial(tmp_path):
    """``tutorial(name, **{"system/controlDict:endTime": 0.1})`` -> a fresh copy."""

    def make(name: str, edits: dict | None = None) -> Path:
        dst = tmp_path / name
        shutil.copytree(TUTORIALS / name, dst, ignore=shutil.ignore_patterns(
            "[1-9]*", "0.*", "postProcessing", "VTK", "log.*", "lagrangian", "uniform"))
        for where, value in (edits or {}).items():
            rel, key = where.split(":")
            set_entry(dst, rel, key, value)
        return dst

    return make
