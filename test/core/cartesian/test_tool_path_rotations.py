"""
SO(3)'s exponential, logarithm, slerp and rates against scipy and finite differences.

scipy's Rotation (from_rotvec, as_rotvec) and Slerp are the oracles for the values; the
rates of exp(v(s)) are checked against central differences of the rotations themselves.
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from traj_gen_ros.core.cartesian.rotations import (
    exp_rates,
    rodrigues_coefficients,
    rotation_exp,
    rotation_log,
    SERIES_ANGLE,
    slerp,
)

RNG = np.random.default_rng(20240530)
DIRECTIONS = RNG.normal(size=(60, 3))
DIRECTIONS /= np.linalg.norm(DIRECTIONS, axis=1)[:, None]
ANGLES = np.concatenate([[0.0, 1e-12, 1e-6, 0.01, SERIES_ANGLE, 0.7, 2.0, 3.0, math.pi - 1e-7],
                         RNG.uniform(0.0, math.pi, 51)])
VECTORS = DIRECTIONS * ANGLES[:, None]


def test_exp_and_log_agree_with_scipy_from_zero_to_half_a_turn():
    rotations = rotation_exp(VECTORS)
    assert np.abs(rotations - Rotation.from_rotvec(VECTORS).as_matrix()).max() < 1e-15
    logs = np.array([rotation_log(rotation) for rotation in rotations])
    assert np.abs(logs - VECTORS).max() < 2e-9  # 2e-9 near π: |R − I| loses the axis there
    assert np.abs(logs[:-52] - VECTORS[:-52]).max() < 1e-15
    assert rotation_exp(VECTORS[3]).shape == (3, 3)


@pytest.mark.parametrize('axis', [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, -2, 2)])
def test_log_of_a_half_turn_is_pi_about_its_axis(axis):
    axis = np.array(axis, dtype=float) / np.linalg.norm(axis)
    vector = rotation_log(Rotation.from_rotvec(math.pi * axis).as_matrix())
    assert np.linalg.norm(vector) == pytest.approx(math.pi, abs=1e-15)
    assert abs(vector @ axis) == pytest.approx(math.pi, abs=1e-14)


def test_rodrigues_coefficients_meet_their_closed_forms_and_limits():
    assert rodrigues_coefficients(0.0) == pytest.approx([1, 1 / 2, 1 / 6, -1 / 12, -1 / 60],
                                                        abs=1e-17)
    for theta in (0.3, SERIES_ANGLE, 1.1):
        s, c = math.sin(theta), math.cos(theta)
        closed = [s / theta, (1 - c) / theta ** 2, (theta - s) / theta ** 3,
                  (theta * s - 2 * (1 - c)) / theta ** 4,
                  (theta * (1 - c) - 3 * (theta - s)) / theta ** 5]
        assert rodrigues_coefficients(theta) == pytest.approx(closed, rel=1e-11, abs=0)
    # Continuous across the switch from series to closed form.
    below, above = rodrigues_coefficients(np.array([SERIES_ANGLE * (1 - 1e-12),
                                                    SERIES_ANGLE])).T
    assert np.abs(below - above).max() < 1e-13


def test_slerp_agrees_with_scipy():
    first, second = Rotation.from_rotvec([[0.3, -0.2, 0.1], [-1.0, 2.0, 0.5]])
    fraction = np.linspace(0.0, 1.0, 13)
    expected = Slerp([0, 1], Rotation.concatenate([first, second]))(fraction).as_matrix()
    actual = slerp(first.as_matrix(), second.as_matrix(), fraction)
    assert np.abs(actual - expected).max() < 1e-15


@pytest.mark.parametrize('scale', [1e-3, 0.3, 1.5])
def test_exp_rates_match_differences_of_the_rotations(scale):
    """v(s) = a + b s + c s² crossing small and large angles; R = exp(v) R0."""
    a, b, c = RNG.normal(size=(3, 3)) * scale
    origin = Rotation.from_rotvec([0.5, 0.1, -0.3]).as_matrix()
    s = np.linspace(-1.0, 1.0, 41)

    def rotation(x):
        return rotation_exp(a + np.outer(x, b) + np.outer(x * x, c)) @ origin

    def difference(x, h=1e-4):
        turn = rotation(x + h) @ np.swapaxes(rotation(x - h), 1, 2)
        return Rotation.from_matrix(turn).as_rotvec() / (2 * h)

    omega, omega_rate = exp_rates(a + np.outer(s, b) + np.outer(s * s, c),
                                  b + 2 * np.outer(s, c), np.tile(2 * c, (len(s), 1)))
    assert np.abs(omega - difference(s, 1e-5)).max() < 1e-9 * max(1.0, scale ** 2)
    h = 2e-3
    rate = (4 * (difference(s + h / 2) - difference(s - h / 2)) / h
            - (difference(s + h) - difference(s - h)) / (2 * h)) / 3
    assert np.abs(omega_rate - rate).max() < 1e-7 * max(1.0, np.abs(rate).max())
