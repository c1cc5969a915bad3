"""Shared helpers: copy a tutorial into a temporary directory and edit its dictionaries."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sphfoam.case.edit import clone_case, set_entry  # noqa: F401  (re-exported)

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"

# pytest-xdist gives its workers COLUMNS=80, and the CLI's rich console (made when sphfoam.cli
# is imported, at collection) would fix its width from it: tests that ask CliRunner for a
# wider console would not get one. The workers run as one process does, without it.
os.environ.pop("COLUMNS", None)

#: P's set-up of the wall case (P section 4: the finite Gaussian, XSPH, MLS every 20 steps, the
#: mirrored bed's p_G = p_a, the KdV2 wave, P's predictor-corrector), the wall tutorial's
#: default until issue 35's convergence study; as the study dictionaries' set blocks
P_WALL = {
    "constant/sphProperties:kernel": {"type": "gaussian", "hdx": 1.3333333},
    "constant/sphProperties:velocityCorrection": {"type": "xsph", "epsilon": 0.5},
    "constant/sphProperties:densityFilter": {"type": "mlsReinitialisation", "every": 20},
    "constant/sphProperties:particleShifting": {"type": "none"},
    "constant/sphProperties:boundary.pressure": "mirror",
    "constant/waveProperties:waves.incident.theory": "kdv2",
    "system/sphSchemes:integrator": {"type": "predictorCorrector"},
}


@pytest.fixture
def p_wall() -> dict:
    """The edits that give the wall tutorial P's set-up (:data:`P_WALL`)."""
    return dict(P_WALL)


@pytest.fixture
def tutorial(tmp_path):
    """``tutorial(name, **{"system/controlDict:endTime": 0.1})`` -> a fresh copy."""

    def make(name: str, edits: dict | None = None) -> Path:
        return clone_case(TUTORIALS / name, tmp_path / name, edits)

    return make
