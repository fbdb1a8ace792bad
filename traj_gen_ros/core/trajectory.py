"""
One result type for every profile: a piecewise polynomial in local time, per joint.

Cubic and quintic segments, LSPB blends (parabolas) and linear parts (lines) all fit the
same representation, in the manner of scipy's ``PPoly``: breakpoints plus an ascending
coefficient array. One vectorised evaluator then serves every profile, joint and sample.

Units: seconds for time, radians (or metres) for position.
"""

from __future__ import annotations

from functools import cached_property
import math
from typing import NamedTuple

import numpy as np
from traj_gen_ros.core.exact.piece_extrema import (
    derivative,
    peak_abs,
    peak_bounds,
    peaks_above,
    position_extrema,
)

# Samples per piece above which each piece is evaluated as one matrix product.
_SAMPLES_PER_PIECE_FOR_MATMUL = 16
_SAMPLES_PER_PRODUCT = 4096  # keeps each product's operands in cache
# Dense sampling merges per-joint breakpoints (joints² work) up to this many joints.
_JOINTS_FOR_MERGING = 16
# Per-joint breakpoints up to this many are compared at once; more use searchsorted.
_PIECES_FOR_COMPARISON = 16


class PositionExtrema(NamedTuple):
    """Per joint lowest and highest position (rad or m) and their times (s), ``(joints,)``."""

    minimum: np.ndarray
    maximum: np.ndarray
    time_of_minimum: np.ndarray
    time_of_maximum: np.ndarray


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
        Sample positions, velocities and accelerations at ``times`` (s).

        Each result is ``(samples, joints)``. Times before 0 or after ``duration`` give the
        boundary state at 0 or ``duration``. Vectorised, with no loop over samples: dense
        sampling evaluates every piece's run of (sorted) samples as one matrix product
        ``[1, τ, τ², …] @ coefficients``; sparse sampling gathers each sample's
        coefficients and runs Horner's rule on all of them at once.
        """
        times = np.asarray(times, dtype=float).reshape(-1)
        if np.count_nonzero(np.isfinite(times)) != times.size:
            raise ValueError(f'times must be finite: sample {np.argmin(np.isfinite(times))} '
                             f'is {times[np.argmin(np.isfinite(times))]}')
        times = np.clip(times, 0.0, self.duration)
        dense = times.size >= _SAMPLES_PER_PIECE_FOR_MATMUL * self.breakpoints.size
        if self.breakpoints.ndim == 2 and not (dense and
                                               self.joint_count <= _JOINTS_FOR_MERGING):
            return self._sample_per_joint(times)
        breakpoints, coefficients = self.shared_pieces
        if times.size < _SAMPLES_PER_PIECE_FOR_MATMUL * len(coefficients):
            piece = np.searchsorted(breakpoints[1:-1], times, side='right')
            local_time = (times - breakpoints[piece])[:, None]
            return _horner(coefficients[piece], local_time, self.degree)
        order = None
        if np.any(times[1:] < times[:-1]):
            order = np.argsort(times, kind='stable')
            times = times[order]
        states = self._sample_sorted(times)
        if order is not None:
            unsorted = np.empty_like(states)
            unsorted[:, order] = states
            states = unsorted
        return states[0], states[1], states[2]

    def peaks(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Find the largest ``|velocity|`` and ``|acceleration|`` per joint, ``(joints,)`` each.

        Extrema from the closed-form roots of the next derivative
        (:func:`~traj_gen_ros.core.exact.piece_extrema.peak_abs`): exact
        to rounding, not sampled estimates.
        """
        peak_velocity, peak_acceleration = self._peaks(2)
        return peak_velocity, peak_acceleration

    def peaks_with_jerk(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Largest ``|velocity|``, ``|acceleration|`` and ``|jerk|`` per joint, in one pass."""
        peak_velocity, peak_acceleration, peak_jerk = self._peaks(3)
        return peak_velocity, peak_acceleration, peak_jerk

    def peak_bounds(self, orders: int = 2) -> list[np.ndarray]:
        """
        Upper bounds of ``|velocity|``, ``|acceleration|`` (and ``|jerk|``, ``orders`` 3).

        ``(joints,)`` each, never below :meth:`peaks`' values: the largest Bernstein
        coefficient of each piece (:func:`~traj_gen_ros.core.exact.piece_extrema.
        peak_bounds`); :meth:`peaks_above` uses them to skip the pieces within a limit.
        """
        return peak_bounds(self._piece_durations(self.joint_count), *self._series(orders))

    def peaks_above(self, limits: list[np.ndarray]) -> list[np.ndarray]:
        """
        Peaks of ``|velocity|``, ``|acceleration|`` (and ``|jerk|``: one limit per order).

        Exact wherever above ``limits`` (``(joints,)`` each), else a bound within them
        (:func:`~traj_gen_ros.core.exact.piece_extrema.peaks_above`): the roots are found
        only on pieces whose Bernstein bound is above the limit.
        """
        return peaks_above(self._piece_durations(self.joint_count), limits,
                           *self._series(len(limits)))

    def _peaks(self, orders: int) -> list[np.ndarray]:
        """Exact peaks of the first ``orders`` derivatives, in one call."""
        return peak_abs(self._piece_durations(self.joint_count), *self._series(orders))

    def _series(self, orders: int) -> list[np.ndarray]:
        """Coefficients of the first ``orders`` derivatives."""
        series = [derivative(self.coefficients)]
        for _ in range(orders - 1):
            series.append(derivative(series[-1]))
        return series

    def _piece_durations(self, joint_count: int) -> np.ndarray:
        """Each piece's length (s) per joint, ``(pieces, joints)``."""
        lengths = np.diff(self.breakpoints, axis=0)
        return np.broadcast_to(lengths if lengths.ndim == 2 else lengths[:, None],
                               (len(self.coefficients), joint_count))

    def peak_jerk(self) -> np.ndarray:
        """Largest ``|jerk|`` (rad/s³) per joint, ``(joints,)``: exact, from the coefficients."""
        jerk = derivative(derivative(derivative(self.coefficients)))
        return peak_abs(self._piece_durations(self.joint_count), jerk)[0]

    def position_extrema(self) -> PositionExtrema:
        """
        Find each joint's lowest and highest position and when it is reached, exactly.

        As Ruckig's ``Trajectory::get_position_extrema``: every extremum of a polynomial
        piece lies at one of its ends or at a real root of its velocity
        (:func:`traj_gen_ros.core.exact.piece_extrema.position_extrema`). On a tie the
        earliest time is given. Positions in rad (or m), times in s, ``(joints,)`` each.
        """
        joints = self.joint_count
        return PositionExtrema(*position_extrema(
            np.broadcast_to(self.breakpoints[:-1].reshape(self.piece_count, -1),
                            (self.piece_count, joints)),
            self._piece_durations(joints), self.coefficients))

    def _sample_per_joint(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Sample pieces whose breakpoints differ per joint (LSPB, S-curve): linear in joints.

        Each sample's piece is found per joint (a comparison with the few interior
        breakpoints, or one ``searchsorted`` per joint when there are many), then every
        sample and joint runs Horner's rule on its own piece at once.
        """
        interior = self.breakpoints[1:-1]
        joints = np.arange(self.joint_count)
        if len(interior) <= _PIECES_FOR_COMPARISON:
            piece = np.count_nonzero(times[:, None, None] >= interior[None], axis=1)
        else:
            piece = np.empty((times.size, self.joint_count), dtype=np.intp)
            for joint in joints:
                piece[:, joint] = np.searchsorted(interior[:, joint], times, side='right')
        flat = piece * self.joint_count + joints  # index into (pieces * joints)
        local_time = times[:, None] - self.breakpoints[:-1].reshape(-1)[flat]
        gathered = [self.coefficients[:, power].reshape(-1)[flat]
                    for power in range(self.degree + 1)]
        states = []
        for order in range(3):
            value = np.zeros_like(local_time)
            for power in range(self.degree, order - 1, -1):
                value *= local_time
                value += _falling_factorial(power, order) * gathered[power]
            states.append(value)
        return states[0], states[1], states[2]

    @cached_property
    def shared_pieces(self) -> tuple[np.ndarray, np.ndarray]:
        """
        Give breakpoints shared by every joint, ``(pieces + 1,)``, with coefficients on them.

        Per-joint breakpoints (LSPB, S-curve) are merged into their union and each joint's
        polynomial is re-expanded about the start of every union interval (Taylor shift:
        ``c'_k = Σ_m C(m, k) c_m d^(m-k)``). This costs joints² × pieces, so it serves only
        dense sampling of a few joints (``_JOINTS_FOR_MERGING``), where one matrix product
        per union piece beats gathering every sample's coefficients.
        """
        if self.breakpoints.ndim == 1:
            return self.breakpoints, self.coefficients
        union = np.sort(self.breakpoints, axis=None)  # sorted, repeats dropped below
        union = union[np.concatenate([[True], union[1:] != union[:-1]])]
        if union.size == 1:  # zero duration: one zero-length piece, each joint's last
            union = np.repeat(union, 2)
        starts = union[:-1]
        joints = np.arange(self.joint_count)
        piece = np.empty((starts.size, self.joint_count), dtype=np.intp)
        for joint in joints:
            piece[:, joint] = np.searchsorted(self.breakpoints[1:-1, joint], starts, 'right')
        offset = starts[:, None] - self.breakpoints[piece, joints]
        source = self.coefficients[piece, :, joints].transpose(0, 2, 1)
        shifted = np.zeros_like(source)
        for power in range(self.degree + 1):
            for higher in range(power, self.degree + 1):
                shifted[:, power] += (math.comb(higher, power) * source[:, higher]
                                      * offset ** (higher - power))
        return union, shifted

    @cached_property
    def _state_tables(self) -> np.ndarray:
        """Position, velocity, acceleration coefficients, ``(pieces, 3, n + 1, joints)``."""
        coefficients = self.shared_pieces[1]
        tables = np.zeros((len(coefficients), 3) + coefficients.shape[1:])
        series = coefficients
        for order in range(3):
            tables[:, order, :series.shape[1]] = series
            series = derivative(series)
        return tables

    def _sample_sorted(self, times: np.ndarray) -> np.ndarray:
        """Evaluate ascending ``times`` piece by piece: ``(3, samples, joints)``."""
        breakpoints = self.shared_pieces[0]
        states = np.zeros((3, times.size, self.joint_count))
        edges = np.searchsorted(times, breakpoints, side='left')
        edges[0], edges[-1] = 0, times.size
        for piece in np.flatnonzero(edges[1:] > edges[:-1]):
            table = self._state_tables[piece]
            for first in range(edges[piece], edges[piece + 1], _SAMPLES_PER_PRODUCT):
                run = slice(first, min(first + _SAMPLES_PER_PRODUCT, edges[piece + 1]))
                local_time = times[run] - breakpoints[piece]
                states[:, run] = np.vander(local_time, self.degree + 1, True) @ table
        return states


class JerkLimitedTrajectory(Trajectory):
    """A jerk-limited (S-curve) trajectory of cubic pieces: ``peaks()`` also gives jerk."""

    def peaks(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Find the largest ``|velocity|``, ``|acceleration|`` and ``|jerk|`` per joint."""
        return self.peaks_with_jerk()

    def peaks_with_jerk(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """
        Largest ``|velocity|``, ``|acceleration|`` and ``|jerk|`` per joint, in closed form.

        On a cubic piece ``c0 + c1 t + c2 t² + c3 t³`` of length ``L`` the jerk ``6 c3`` is
        constant, the acceleration ``2 c2 + 6 c3 t`` is linear (its peak is at an end) and
        the velocity ``c1 + 2 c2 t + 3 c3 t²`` peaks at an end or where the acceleration
        is zero, ``t = -c2 / (3 c3)`` inside the piece: exact, and a quarter of the
        general :meth:`Trajectory.peaks_with_jerk`'s numpy calls (the node checks every
        S-curve plan with it).
        """
        if self.degree != 3:
            return super().peaks_with_jerk()
        c1, c2, c3 = self.coefficients[:, 1], self.coefficients[:, 2], self.coefficients[:, 3]
        lengths = self._piece_durations(self.joint_count)
        slope = 3.0 * c3
        end_acceleration = 2.0 * (c2 + slope * lengths)
        end_velocity = c1 + (2.0 * c2 + slope * lengths) * lengths
        # The acceleration's zero: a piece with c3 = 0 has none (it is left at t = 0).
        with np.errstate(divide='ignore', invalid='ignore'):
            turn = -c2 / slope
        turn[~((turn > 0.0) & (turn < lengths))] = 0.0
        turn_velocity = c1 + (2.0 * c2 + slope * turn) * turn
        velocity = np.maximum(np.maximum(np.abs(c1), np.abs(end_velocity)),
                              np.abs(turn_velocity))
        acceleration = np.maximum(np.abs(c2), 0.5 * np.abs(end_acceleration))
        return (np.maximum.reduce(velocity), 2.0 * np.maximum.reduce(acceleration),
                6.0 * np.maximum.reduce(np.abs(c3)))


def state_at(trajectory: Trajectory, time: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Position, velocity and acceleration at one ``time`` (s, clipped to the plan), ``(joints,)``.

    The stream's path: a setpoint every tick, and the start state of every new plan. The
    same polynomials as :meth:`Trajectory.sample` (the same piece at a breakpoint: the one
    starting there), evaluated as the pieces' coefficients times the powers ``τᵏ`` of local
    time and their derivatives ``k τᵏ⁻¹``, ``k (k - 1) τᵏ⁻²``: a handful of numpy calls
    instead of Horner's rule's three dozen. Agrees with :meth:`Trajectory.sample` to
    rounding (the sums run in another order).
    """
    time = min(max(float(time), 0.0), trajectory.duration)
    breakpoints, coefficients = trajectory.breakpoints, trajectory.coefficients
    size = coefficients.shape[1]
    if breakpoints.ndim == 1:
        piece = int(np.searchsorted(breakpoints[1:-1], time, side='right'))
        local = time - float(breakpoints[piece])
        powers = [1.0]
        for _ in range(size - 1):
            powers.append(powers[-1] * local)
        rows = np.zeros((3, size))
        rows[0] = powers
        rows[1, 1:] = _ORDERS[1:size] * powers[:-1]
        rows[2, 2:] = _SECOND_ORDERS[2:size] * powers[:-2]
        state = rows @ coefficients[piece]
        return state[0], state[1], state[2]
    joints = np.arange(trajectory.joint_count)
    piece = np.count_nonzero(breakpoints[1:-1] <= time, axis=0)
    local = time - breakpoints[piece, joints]
    gathered = coefficients[piece, :, joints].T  # (size, joints)
    powers = np.empty((size, joints.size))
    powers[0] = 1.0
    powers[1:] = local
    np.multiply.accumulate(powers, axis=0, out=powers)
    position = np.add.reduce(gathered * powers)
    velocity = np.add.reduce(gathered[1:] * _ORDERS[1:size, None] * powers[:-1])
    acceleration = np.add.reduce(gathered[2:] * _SECOND_ORDERS[2:size, None] * powers[:-2])
    return position, velocity, acceleration


_ORDERS = np.arange(8.0)  # d/dτ τᵏ = k τᵏ⁻¹
_SECOND_ORDERS = _ORDERS * (_ORDERS - 1.0)  # d²/dτ² τᵏ = k (k - 1) τᵏ⁻²


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
