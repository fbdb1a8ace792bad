"""
One result type for every profile: a piecewise polynomial in local time, per joint.

Cubic and quintic segments, LSPB blends (parabolas) and linear parts (lines) all fit the
same representation, in the manner of scipy's ``PPoly``: breakpoints plus an ascending
coefficient array. One vectorised evaluator then serves every profile, joint and sample.

Units: seconds for time, radians (or metres) for position.
"""

from __future__ import annotations

import numpy as np

_PEAK_SEED_SAMPLES = 17  # samples per segment that seed the Newton search for extrema
_PEAK_NEWTON_STEPS = 6


class Trajectory:
    """
    A joint trajectory made of polynomial pieces in local time.

    :ivar breakpoints: piece boundaries in seconds, ``(pieces + 1,)`` when every joint shares
        them, ``(pieces + 1, joints)`` when each joint has its own (LSPB blends).
    :ivar coefficients: ascending polynomial coefficients ``a0 … an`` of each piece in local
        time ``t - breakpoints[piece]``, shaped ``(pieces, n + 1, joints)``. For a single
        cubic, ``coefficients[0, :, j]`` are Craig's ``a0, a1, a2, a3`` for joint ``j``.
    :ivar duration: total duration in seconds.
    :ivar joint_count: number of joints.

    """

    def __init__(self, breakpoints: np.ndarray, coefficients: np.ndarray) -> None:
        self.breakpoints = breakpoints
        self.coefficients = coefficients
        # Per-joint breakpoints all end at the same total duration.
        self.duration = float(breakpoints[-1] if breakpoints.ndim == 1 else breakpoints[-1, 0])
        self.joint_count = int(coefficients.shape[2])

    @property
    def degree(self) -> int:
        """Polynomial degree of the pieces (3 for cubic, 5 for quintic, 2 for LSPB)."""
        return self.coefficients.shape[1] - 1

    @property
    def piece_count(self) -> int:
        """Count the polynomial pieces (segments, or blends and linear parts)."""
        return self.coefficients.shape[0]

    def sample(self, times: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Positions, velocities and accelerations at ``times`` (s), each ``(samples, joints)``.

        Times before 0 or after ``duration`` return the boundary state at 0 or ``duration``.
        Vectorised: one ``searchsorted`` and one Horner pass for all samples and joints.
        """
        times = np.clip(np.asarray(times, dtype=float).reshape(-1), 0.0, self.duration)
        coefficients, local_time = self._locate(times)
        return _horner(coefficients, local_time, self.degree)

    def peaks(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Largest ``|velocity|`` and ``|acceleration|`` over the whole motion, per joint.

        Each piece is searched from a few seed samples, refined by Newton steps on the next
        derivative, so the values are exact extrema to rounding, not sampled estimates.
        """
        velocity = _derivative(self.coefficients)
        acceleration = _derivative(velocity)
        durations = np.diff(self.breakpoints, axis=0)
        if durations.ndim == 1:
            durations = np.broadcast_to(durations[:, None], velocity[:, 0].shape)
        return _peak_abs(velocity, durations), _peak_abs(acceleration, durations)

    def _locate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Coefficients ``(samples, n + 1, joints)`` and local times for each sample."""
        if self.piece_count == 1:
            return self.coefficients, times[:, None]
        if self.breakpoints.ndim == 1:
            piece = np.searchsorted(self.breakpoints[1:-1], times, side='right')
            return self.coefficients[piece], (times - self.breakpoints[piece])[:, None]
        joints = np.arange(self.joint_count)
        piece = np.empty((times.size, self.joint_count), dtype=np.intp)
        for joint in joints:
            piece[:, joint] = np.searchsorted(self.breakpoints[1:-1, joint], times, 'right')
        coefficients = self.coefficients[piece, :, joints].transpose(0, 2, 1)
        return coefficients, times[:, None] - self.breakpoints[piece, joints]


def _horner(
    coefficients: np.ndarray, local_time: np.ndarray, degree: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of ascending coefficients, by Horner's rule."""
    shape = np.broadcast_shapes(coefficients[:, 0].shape, local_time.shape)
    result = []
    for order in range(3):
        value = np.zeros(shape)
        for power in range(degree, order - 1, -1):
            factor = _falling_factorial(power, order)
            value *= local_time
            value += factor * coefficients[:, power] if factor != 1 else coefficients[:, power]
        result.append(value)
    return result[0], result[1], result[2]


def _falling_factorial(power: int, order: int) -> int:
    """``power * (power - 1) * … `` with ``order`` factors: d^order/dt^order of t^power."""
    factor = 1
    for step in range(order):
        factor *= power - step
    return factor


def _derivative(coefficients: np.ndarray) -> np.ndarray:
    """Ascending coefficients of the time derivative, same layout ``(pieces, n, joints)``."""
    powers = np.arange(1, coefficients.shape[1], dtype=float)[None, :, None]
    return coefficients[:, 1:] * powers


def _polyval(coefficients: np.ndarray, local_time: np.ndarray) -> np.ndarray:
    """Evaluate ``(pieces, n + 1, joints)`` coefficients at ``(pieces, k, joints)`` times."""
    value = np.zeros_like(local_time)
    for power in range(coefficients.shape[1] - 1, -1, -1):
        value = value * local_time + coefficients[:, power][:, None, :]
    return value


def _peak_abs(coefficients: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """Exact largest ``|p(t)|`` over every piece, per joint: ``(joints,)``."""
    if coefficients.shape[1] == 0:
        return np.zeros(coefficients.shape[2])
    fractions = np.linspace(0.0, 1.0, _PEAK_SEED_SAMPLES)[None, :, None]
    seeds = fractions * durations[:, None, :]
    values = np.abs(_polyval(coefficients, seeds))
    best = np.take_along_axis(seeds, values.argmax(axis=1)[:, None, :], axis=1)
    slope = _derivative(coefficients)
    if slope.shape[1] >= 2:
        curvature = _derivative(slope)
        upper = durations[:, None, :]
        for _ in range(_PEAK_NEWTON_STEPS):
            second = _polyval(curvature, best)
            safe = np.where(second == 0.0, 1.0, second)
            step = np.where(second == 0.0, 0.0, _polyval(slope, best) / safe)
            best = np.clip(best - step, 0.0, upper)
    refined = np.abs(_polyval(coefficients, best))[:, 0, :]
    return np.maximum(values.max(axis=1), refined).max(axis=0)
