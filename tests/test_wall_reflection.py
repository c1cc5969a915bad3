"""The fully nonlinear wall run-up (sphfoam.reference.wall_reflection): the HOS equations carry
the exact solitary wave unchanged, converge with their order, conserve volume, and meet
Su & Mirie's (1980) third-order run-up as the wave gets small."""

from __future__ import annotations

import numpy as np
import pytest

from sphfoam.reference.wall_reflection import (head_on_collision, propagate, su_mirie,
                                              wall_reflection)


def test_exact_wave_is_carried_unchanged_and_the_error_falls_with_the_order():
    """A/d = 0.3 over 20 sqrt(d/g) (23 depths): the order-M truncation's error falls
    geometrically (measured 8.6e-3, 1.5e-4, 6.6e-6, 4.0e-7 of d at M = 2, 4, 6, 8)."""
    errors = []
    for M in (2, 4, 6, 8):
        x, eta, exact = propagate(0.3, 20.0, order=M, kmax=16.0)
        errors.append(np.max(np.abs(eta - exact)))
    assert errors[-1] < 1e-6
    assert all(a > 10.0 * b for a, b in zip(errors, errors[1:]))


def test_small_wave_meets_su_and_mirie():
    """A/d = 0.1: third-order theory is off by O(a^4) = 1e-4 d at most a few times over."""
    r = wall_reflection(0.1)
    assert abs(r.run_up - su_mirie(0.1)) < 3.0 * 0.1**4
    assert r.run_up > 0.2 + 0.005                   # above linear reflection, 2a, by ~a^2/2


def test_run_up_at_p_s_amplitude_is_converged():
    """A/d = 0.3 (P's wall case): orders 10 (the default) and 12 agree to 2e-5 d, the volume
    is conserved, and the run-up lies between second (2a + a^2/2) and third order
    (Su & Mirie), 0.76 % below the latter."""
    r = wall_reflection(0.3)
    r12 = wall_reflection(0.3, order=12)
    assert abs(r.run_up - r12.run_up) < 2e-5
    assert r.volume_drift < 1e-11
    assert 0.6 + 0.045 < r.run_up < su_mirie(0.3)
    assert r.run_up == pytest.approx(0.66020, abs=1e-4)


@pytest.mark.parametrize("eps, method", [(0.0, None), (-0.1, None), (0.45, "hos"),
                                         (0.0, "bie"), (0.55, None), (0.6, "bie")])
def test_amplitudes_outside_the_method_are_refused(eps, method):
    """HOS above 0.4 (its series diverges; the default then takes the boundary integral),
    the boundary integral above MAX_EPS_BIE = 0.5 (at 0.6 the crest at the wall sharpens and
    the computation blows up)."""
    with pytest.raises(ValueError, match="0 < A/d"):
        wall_reflection(eps, method=method)
    with pytest.raises(ValueError, match="method must be"):
        wall_reflection(0.3, method="spectral")


def test_head_on_collision_of_equal_waves_is_the_wall_and_unequal_meets_third_order():
    """Equal waves: the collision's peak is the wall's run-up (the wall is the plane of
    symmetry). P's collision, a1 = 0.3 and a2 = 0.2: the peak 0.5377 d lies above the linear
    a1 + a2 and within 1 % below the third order of Su & Mirie (1980),
    a1 + a2 + a1 a2 / 2 + 3 a1 a2 (a1 + a2) / 8 = 0.54125."""
    equal = head_on_collision(0.2, 0.2, N=1024)
    assert equal.peak == pytest.approx(wall_reflection(0.2).run_up, abs=1e-9)
    p = head_on_collision(0.3, 0.2)
    third = 0.5 + 0.3 * 0.2 / 2 + 3 * 0.3 * 0.2 * 0.5 / 8
    assert 0.5 < p.peak < third and p.peak > 0.99 * third
    assert p.peak == pytest.approx(0.53771, abs=1e-4)
