"""Tait equation of state, T(3.27), with the speed of sound of T(3.29)-(3.31)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sphfoam import registry
from sphfoam.models.base import CaseContext
from sphfoam.models.eos import tait_pressure, tait_sound_speed

CTX = CaseContext(dx=0.01, h=0.013, rho0=1000.0, nu=1e-6, g=(0.0, -9.81), fluid_height=0.5)


def test_b_from_vmax_is_t331():
    eos = registry.build("equationOfState", {"type": "tait", "vmax": 2.0})
    # T(3.31): B = 100 rho0 vmax^2 / gamma  <=>  c0 = 10 vmax for |drho/rho| = 1 %
    assert eos.B(CTX) == pytest.approx(100 * 1000 * 2.0**2 / 7)
    assert eos.c0(CTX) == pytest.approx(20.0)
    # T(3.29): c0^2 = gamma B / rho0
    assert eos.c0(CTX) ** 2 == pytest.approx(7 * eos.B(CTX) / 1000)


def test_auto_vmax_and_explicit_speed_of_sound():
    auto = registry.build("equationOfState", {"type": "tait"})
    assert auto.vmax(CTX) == pytest.approx(math.sqrt(2 * 9.81 * 0.5))
    fixed = registry.build("equationOfState", {"type": "tait", "speedOfSound": 35.0})
    assert fixed.c0(CTX) == 35.0


def test_pressure_sound_speed_and_inverse():
    eos = registry.build("equationOfState", {"type": "tait", "vmax": 3.0})
    B, c0 = eos.B(CTX), eos.c0(CTX)
    assert tait_pressure(1000.0, 1000.0, B, 7.0) == 0.0
    rho = 1010.0
    p = tait_pressure(rho, 1000.0, B, 7.0)
    assert p == pytest.approx(B * ((rho / 1000.0) ** 7 - 1))
    # c = sqrt(dp/drho) by finite differences
    d = 1e-4
    dpdrho = (tait_pressure(rho + d, 1000.0, B, 7.0) - tait_pressure(rho - d, 1000.0, B, 7.0)) / (2 * d)
    assert tait_sound_speed(rho, 1000.0, c0, 7.0) == pytest.approx(math.sqrt(dpdrho), rel=1e-6)
    ps = np.array([0.0, 1e3, 5e4])
    rhos = eos.density(ps, CTX)
    np.testing.assert_allclose([tait_pressure(r, 1000.0, B, 7.0) for r in rhos], ps, atol=1e-6)
