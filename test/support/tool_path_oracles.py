"""
Independent oracles for the tool path tests: poses from scipy, derivatives by differences.

Every derivative here is a central finite difference of the path's own sampled positions
and rotations (scipy's Rotation for the rotation logarithm), never of its derivatives.
"""

import numpy as np
from scipy.spatial.transform import Rotation


def pose(position, rotvec=(0.0, 0.0, 0.0)):
    """Return the (4, 4) pose at position (m) turned by the rotation vector (rad)."""
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    matrix[:3, 3] = position
    return matrix


def angular_difference(path, s, step):
    """Return the angular rate by the central difference of rotations, base axes."""
    later = path.sample(s + step).rotation
    earlier = path.sample(s - step).rotation
    return Rotation.from_matrix(later @ np.swapaxes(earlier, 1, 2)).as_rotvec() / (2 * step)


def differences(path, s, step=1e-5, second_step=2e-4):
    """
    Return dp/ds, d²p/ds², ω_s, dω_s/ds at s by differences of positions and rotations.

    The second derivatives are Richardson's extrapolation of two central differences
    (steps h and h/2: error O(h⁴)).
    """
    s = np.asarray(s, dtype=float)

    def position(x):
        return path.sample(x).position

    def second(h):
        return (position(s + h) - 2 * position(s) + position(s - h)) / h ** 2

    def angular_rate(h):
        return (angular_difference(path, s + h, step)
                - angular_difference(path, s - h, step)) / (2 * h)

    velocity = (position(s + step) - position(s - step)) / (2 * step)
    acceleration = (4 * second(second_step / 2) - second(second_step)) / 3
    angular = angular_difference(path, s, step)
    angular_acceleration = (4 * angular_rate(second_step / 2) - angular_rate(second_step)) / 3
    return velocity, acceleration, angular, angular_acceleration


def assert_derivatives_match_differences(path, s, tolerance=1e-6, steps=(1e-5, 2e-4)):
    """
    Assert the analytic derivatives at s match the differences (relative to their size).

    ``steps``: :func:`differences`' ``step`` and ``second_step`` (shorter ones for tight
    curves: the truncation error grows with step / radius).
    """
    samples = path.sample(s)
    names = ('velocity', 'acceleration', 'angular', 'angular_acceleration')
    for name, expected in zip(names, differences(path, s, *steps), strict=True):
        actual = getattr(samples, name)
        scale = max(1.0, float(np.abs(expected).max()))
        error = float(np.abs(actual - expected).max())
        assert error < tolerance * scale, f'{name}: off by {error:.3g} (scale {scale:.3g})'


def interior(path, count=7, margin=1e-3):
    """Return count values of s inside every piece, margin away from its ends."""
    return np.concatenate([np.linspace(piece.start + margin, piece.end - margin, count)
                           for piece in path.pieces])
