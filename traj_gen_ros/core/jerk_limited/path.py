"""
Jerk-limited (S-curve) paths through via points, and their durations from the limits.

Each segment is one fixed-duration, state-to-state seven-phase S-curve (Ruckig with
``minimum_duration`` and a target velocity; see :mod:`traj_gen_ros.core.jerk_limited.move`) from
``(θ_k, θ̇_k, 0)`` to ``(θ_k+1, θ̇_k+1, 0)``: the path passes through every via point at its
time, with zero acceleration there, so position, velocity and acceleration are
continuous and jerk, acceleration and velocity stay within their limits. Via velocities
are Craig's heuristic (§7.3, :func:`traj_gen_ros.core.polynomial.heuristic_velocities`) or
given. To the heuristic a step within Ruckig's precision (:data:`PRECISION`, 1e-8) is no
motion, as it is to Ruckig: its slope is zero, so the velocity at both its ends is zero,
as at a repeated point (counted as a slope, a step of, say, 1e-262 rad beside one of 1 rad
with the same sign asks for their mean at the point between, which the tiny segment must
reach with no distance to do it in: hours for a 1 rad path at unit limits).

Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.jerk_limited.move import fixed_duration
from traj_gen_ros.core.jerk_limited.problem import LIMIT_NAMES, Move, PRECISION
from traj_gen_ros.core.jerk_limited.ruckig_backend import plan_move, scurve_minimum_duration
from traj_gen_ros.core.polynomial import heuristic_velocities
from traj_gen_ros.core.trajectory import JerkLimitedTrajectory, Trajectory
from traj_gen_ros.core.validation import ArrayLike

_SCALE_STEPS = 200  # bound on the halvings/doublings of the duration search
_BISECTION_TOLERANCE = 1e-12
_FIXED_POINT_STEPS = 30


class Start(NamedTuple):
    """The path's start velocity (rad/s) and acceleration (rad/s²), per joint or scalar."""

    velocity: np.ndarray | float
    acceleration: np.ndarray | float


REST = Start(0.0, 0.0)


@validation.refuses_overflow('scurve_via')
def scurve_via(
    points: ArrayLike,
    durations: ArrayLike,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
    velocities: str | ArrayLike = 'heuristic',
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
) -> Trajectory:
    """
    Plan a jerk-limited path through every via point at its time.

    :param points: positions (rad), ``(points,)`` or ``(points, joints)``.
    :param durations: time between consecutive points (s), one per segment.
    :param max_velocity: velocity limit (rad/s), scalar or one per joint.
    :param max_acceleration: acceleration limit (rad/s²), scalar or one per joint.
    :param max_jerk: jerk limit (rad/s³), scalar or one per joint.
    :param velocities: ``"heuristic"`` (Craig's rule: mean of the neighbouring slopes,
        0 where the slope changes sign; rest at both ends) or the velocity at every point
        (rad/s), ``(points, joints)``.
    :param v0: start velocity (rad/s) for the heuristic (given velocities include it).
    :param a0: start acceleration (rad/s²): the first segment starts from it (replanning
        a moving joint); the path ends at rest.

    Acceleration is zero at every via point after the start. Raises ``ValueError`` naming
    the segment and the smallest duration that works for it when a segment cannot be planned (with
    heuristic velocities, which change with the segment's duration, the smallest one a
    fixed-point iteration finds, checked to work), or naming the point and joint whose
    via velocity exceeds ``max_velocity``.
    """
    path, durations, limits, spec = _validated(points, durations, max_velocity,
                                               max_acceleration, max_jerk, velocities)
    start = Start(*validation.per_joint_rows(v0=v0, a0=a0, like=path[0]))
    via = _via_velocities(path, durations, spec, start)
    if spec is None:
        _check_heuristic(path, durations, limits, via, start)
    else:
        _check_velocities(via, limits[0], spec)
    pieces = []
    for segment in range(len(durations)):
        move = _segment(path, via, durations, limits, segment, start)
        try:
            pieces.append(fixed_duration(
                move, 'scurve_via', f'segment {segment} (points {segment} to {segment + 1}): '
                'duration'))
        except ValueError as error:
            if 'no jerk-limited plan' in str(error):
                raise ValueError(f'scurve_via: segment {segment} (points {segment} to '
                                 f'{segment + 1}): {error}') from None
            if spec is not None:
                raise
            smallest = _smallest_heuristic(path, durations, limits, segment, start)
            raise ValueError(
                f'scurve_via: segment {segment} (points {segment} to {segment + 1}) cannot '
                f'take {durations[segment]:g} s with the heuristic via velocities '
                f'{via[segment].tolist()} and {via[segment + 1].tolist()}; the smallest '
                f'duration that works for it is {smallest}') from None
    return _concatenate(pieces, durations)


def _check_heuristic(path: np.ndarray, durations: np.ndarray, limits: tuple,
                     via: np.ndarray, start: Start) -> None:
    """
    Refuse a heuristic via velocity above ``max_velocity``.

    The message names the steeper neighbouring segment (lengthening it lowers the
    velocity most) and the smallest duration that works for it.
    """
    over = np.abs(via) > limits[0]
    if not np.count_nonzero(over):
        return
    point, joint = (int(index) for index in np.argwhere(over)[0])
    with np.errstate(over='ignore'):  # a huge step over a short segment: inf, the steepest
        slopes = np.abs(np.diff(path[:, joint]) / durations)
    segment = max((s for s in (point - 1, point) if 0 <= s < len(durations)),
                  key=lambda s: slopes[s])
    smallest = _smallest_heuristic(path, durations, limits, segment, start)
    raise ValueError(
        f'scurve_via: segment {segment} (points {segment} to {segment + 1}) is too short: '
        f'the heuristic via velocity at point {point}, joint {joint} is '
        f'{via[point, joint]:g}, above max_velocity {limits[0][joint]:g}; the smallest '
        f'duration that works for segment {segment} is {smallest}')


def scurve_via_durations(
    path: ArrayLike,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
    velocities: str | ArrayLike = 'heuristic',
) -> np.ndarray:
    """
    Segment durations (s) for which :func:`scurve_via` is feasible, ``(segments,)``.

    With given ``velocities`` (rad/s, ``(points, joints)``) each segment's boundary
    states are fixed, so every duration is exact: the segment's time-optimal synchronised
    duration (Ruckig). With ``"heuristic"`` velocities every duration changes every via
    velocity, so the segments' own rest-to-rest minimum times ``T0`` are scaled by the
    smallest common factor ``c`` that is feasible, found by bisection. This search cannot
    skip a feasible answer: scaling every duration by ``c`` scales the heuristic
    velocities by ``1/c``, so segment ``k`` at scale ``c`` is feasible exactly when the
    segment of duration ``T0_k`` with via velocities ``w`` (those at ``c = 1``) is
    feasible under the limits ``(c v_max, c² a_max, c³ j_max)``; those admit more motions
    as ``c`` grows, so the feasible factors form one interval ``[c*, ∞)`` (a step within
    :data:`PRECISION` has slope zero at every ``c``; the backend keeps a plan longer than
    asked only when no attempt meets the duration:
    :func:`traj_gen_ros.core.jerk_limited.ruckig_backend.plan_move`).
    """
    path = validation.path_points(path)
    _, _, limits, spec = _validated(path, np.ones(len(path) - 1), max_velocity,
                                    max_acceleration, max_jerk, velocities)
    segments = len(path) - 1
    if spec is not None:
        via = spec
        _check_velocities(via, limits[0], spec)
        ones = np.ones(segments)
        times = np.array([_shortest(path, via, ones, limits, segment)
                          for segment in range(segments)])
        if not times.any():
            raise ValueError('scurve_via_durations: the path never moves: every point equals '
                             'the start and every velocity is 0')
        # A segment that stays at rest takes any time: a short one (durations are > 0).
        return np.where(times > 0.0, times, 1e-9 * times.max())
    rest = np.zeros_like(path)
    ones = np.ones(segments)
    base = np.array([_shortest(path, rest, ones, limits, segment)
                     for segment in range(segments)])
    if not base.any():
        raise ValueError('scurve_via_durations: every via point equals the start: there is '
                         'nothing to move')
    base = np.maximum(base, 1e-6 * base.max())
    low, high = 1.0, 1.0
    if _feasible(path, base, limits):
        for _ in range(_SCALE_STEPS):
            low *= 0.5
            if not _feasible(path, base * low, limits):
                break
            high = low
    else:
        for _ in range(_SCALE_STEPS):
            high *= 2.0
            if not math.isfinite(float(base.max()) * high):  # Python floats: no warning
                raise ValueError('scurve_via_durations: no finite scaling of the segment '
                                 'durations keeps the heuristic path within the limits')
            if _feasible(path, base * high, limits):
                break
            low = high
        else:
            raise ValueError('scurve_via_durations: no common scaling of the segment '
                             'durations keeps the heuristic path within the limits')
    while high - low > _BISECTION_TOLERANCE * high:
        middle = 0.5 * (low + high)
        if _feasible(path, base * middle, limits):
            high = middle
        else:
            low = middle
    return base * high


def _validated(points: ArrayLike, durations: ArrayLike, max_velocity: ArrayLike,
               max_acceleration: ArrayLike, max_jerk: ArrayLike,
               velocities: str | ArrayLike) -> tuple:
    """Validate a via request: path, durations, limits and the given velocities or None."""
    path = validation.path_points(points)
    durations = validation.segment_durations(durations, len(path) - 1)
    joints = path.shape[1]
    limits = tuple(validation.per_joint(name, value, joints) for name, value in
                   zip(LIMIT_NAMES, (max_velocity, max_acceleration, max_jerk), strict=True))
    if isinstance(velocities, str):
        if velocities != 'heuristic':
            raise ValueError(f'velocities must be "heuristic" or an array (points, joints), '
                             f'got "{velocities}"')
        return path, durations, limits, None
    return path, durations, limits, validation.per_point('velocities', velocities, path.shape)


def _via_velocities(path: np.ndarray, durations: np.ndarray,
                    spec: np.ndarray | None, start: Start = REST) -> np.ndarray:
    """Velocities at every point (rad/s): the given ones, or Craig's heuristic."""
    return _heuristic(path, durations, start) if spec is None else spec


def _heuristic(path: np.ndarray, durations: np.ndarray, start: Start = REST) -> np.ndarray:
    """
    Craig's heuristic velocities from ``start``; an overflowing slope gives ``inf``.

    A step within :data:`PRECISION` has slope zero (Ruckig cannot tell it from none).
    """
    with np.errstate(over='ignore', invalid='ignore'):  # inf slopes, inf - inf: made inf
        velocities = heuristic_velocities(path, durations, start.velocity, PRECISION)
    return np.where(np.isnan(velocities), np.inf, velocities)


def _check_velocities(via: np.ndarray, max_velocity: np.ndarray,
                      spec: np.ndarray | None) -> None:
    """Refuse a via velocity above ``max_velocity``, naming the point and joint."""
    over = np.abs(via) > max_velocity
    if np.count_nonzero(over):
        point, joint = (int(index) for index in np.argwhere(over)[0])
        source = 'given' if spec is not None else 'heuristic (lengthen the segments around it)'
        raise ValueError(f'scurve_via: point {point}, joint {joint}: via velocity '
                         f'{via[point, joint]:g} ({source}) exceeds max_velocity '
                         f'{max_velocity[joint]:g}')


def _segment(path: np.ndarray, via: np.ndarray, durations: np.ndarray, limits: tuple,
             segment: int, start: Start = REST) -> Move:
    """Return segment ``segment`` as a fixed-duration state-to-state move."""
    acceleration = start.acceleration if segment == 0 else 0.0
    return Move(path[segment].tolist(), path[segment + 1].tolist(), via[segment].tolist(),
                np.broadcast_to(acceleration, path.shape[1]).tolist(), via[segment + 1].tolist(),
                tuple(limit.tolist() for limit in limits), float(durations[segment]))


def _shortest(path: np.ndarray, via: np.ndarray, durations: np.ndarray, limits: tuple,
              segment: int) -> float:
    """Return a segment's minimum time (s); a failure names the segment."""
    try:
        return scurve_minimum_duration(_segment(path, via, durations, limits, segment))
    except ValueError as error:
        raise ValueError(f'scurve_via_durations: segment {segment} (points {segment} to '
                         f'{segment + 1}): {error}') from None


def _segment_feasible(path: np.ndarray, durations: np.ndarray, limits: tuple,
                      segment: int, start: Start = REST) -> bool:
    """Tell whether ``segment`` meets its duration with the heuristic velocities."""
    via = _heuristic(path, durations, start)
    ends = np.abs(via[segment:segment + 2]) <= limits[0]
    if not validation.every(ends):
        return False
    move = _segment(path, via, durations, limits, segment, start)
    try:
        return plan_move(move)[1] == move.duration
    except ValueError:
        return False


def _feasible(path: np.ndarray, durations: np.ndarray, limits: tuple) -> bool:
    """Tell whether every segment meets its duration with the heuristic velocities."""
    via = _heuristic(path, durations)
    if not validation.every(np.abs(via) <= limits[0]):
        return False
    return all(_segment_feasible(path, durations, limits, segment)
               for segment in range(len(durations)))


def _smallest_heuristic(path: np.ndarray, durations: np.ndarray, limits: tuple,
                        segment: int, start: Start = REST) -> str:
    """
    Find a small duration of ``segment`` that works, the others unchanged, as text.

    The segment's minimum time with the via velocities of the current durations is
    iterated to a fixed point, each candidate checked; then doubling and bisection from
    the given duration. Returns the duration rounded up, or why none works.
    """
    trial = durations.copy()
    for _ in range(_FIXED_POINT_STEPS):
        via = _heuristic(path, trial, start)
        if not validation.every(np.abs(via[segment:segment + 2]) <= limits[0]):
            break
        try:
            shortest = scurve_minimum_duration(_segment(path, via, trial, limits, segment, start))
        except ValueError:
            break
        if shortest <= 0.0:
            break
        trial[segment] = shortest
        if _segment_feasible(path, trial, limits, segment, start):
            return f'{validation.round_up(shortest, 9)} s'
    low = high = float(durations[segment])
    for _ in range(_SCALE_STEPS):
        high *= 2.0
        trial[segment] = high
        if _segment_feasible(path, trial, limits, segment, start):
            break
        low = high
    else:
        return ('none: a via velocity from a neighbouring segment exceeds the limits; '
                'lengthen that segment')
    while high - low > _BISECTION_TOLERANCE * high:
        trial[segment] = 0.5 * (low + high)
        if _segment_feasible(path, trial, limits, segment, start):
            high = trial[segment]
        else:
            low = trial[segment]
    return f'{validation.round_up(high, 9)} s'


def _concatenate(pieces: list[Trajectory], durations: np.ndarray) -> Trajectory:
    """Join segment trajectories end to end, per-joint breakpoints shifted by each start."""
    starts = np.concatenate([[0.0], np.cumsum(durations)])
    breakpoints = [np.minimum(piece.breakpoints[:-1] + starts[index], starts[index + 1])
                   for index, piece in enumerate(pieces)]
    breakpoints.append(np.full((1, pieces[0].joint_count), starts[-1]))
    coefficients = np.concatenate([piece.coefficients for piece in pieces])
    return JerkLimitedTrajectory(np.concatenate(breakpoints), coefficients)
