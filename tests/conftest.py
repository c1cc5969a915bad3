"""Shared helpers: copy a tutorial into a temporary directory and edit its dictionaries."""

from __future__ import annotations

from pathlib import Path

import pytest

from sphfoam.case.edit import clone_case, set_entry  # noqa: F401  (re-exported)

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"


@pytest.fixture
def tutorial(tmp_path):
    """``tutorial(name, **{"system/controlDict:endTime": 0.1})`` -> a fresh copy."""

    def make(name: str, edits: dict | None = None) -> Path:
        return clone_case(TUTORIALS / name, tmp_path / name, edits)

    return make
