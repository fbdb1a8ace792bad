"""
A jerk-limited brake *along* a tool path: from a moving state on it to rest, on it.

The S-curve profile's ``~/stop`` on a line or an arc (the acceleration-limited one is
:mod:`.path_brake`). From ``(s_0, ṡ_0, s̈_0)`` the path parameter brakes as the core's
:func:`~traj_gen_ros.core.jerk_limited.brake.scurve_brake` brakes one axis (``s̈`` ramps
at ``-J`` to ``-A``, holds, ramps back to 0: the time-optimal stop) within constant
``(A, J)`` that keep every joint and the tool within their limits
(:func:`.jerk_bounds.brake_bounds`, the bounds of :mod:`.jerk_bounds` over the rest of
the piece). The joints ``q(s(t))`` are sampled into quintics as the timing's
(:func:`.jerk_limited_timing.sample_motion`) and checked exactly, jerk included; where
they overshoot, the bounds are chosen again in rows scaled by what that brake used of
each limit (its start cannot be slowed down).

Units: units of path, s; rad (or m), rad/s, rad/s², rad/s³.
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.cartesian.bound_report import Bound
from traj_gen_ros.core.cartesian.jerk_bounds import Bounds, brake_bounds, piece_rows
from traj_gen_ros.core.cartesian.jerk_limited_sampling import (
    sample_motion,
    scaled,
    used_limits,
)
from traj_gen_ros.core.cartesian.jerk_limited_timing import JerkLimitedTimedPath
from traj_gen_ros.core.cartesian.path_constraints import merge_values, ToolLimits
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.jerk_limited.brake import scurve_brake
from traj_gen_ros.core.kinematic_limits import LIMIT_TOLERANCE
from traj_gen_ros.core.sequences import concatenate
from traj_gen_ros.core.trajectory import Trajectory

#: The brake is planned within the acceleration and jerk bounds times this (the
#: quintics' rounding is ~1e-9 of the jerk).
MARGIN = 1.0 - 1e-6
#: How soon (s) a timing's own braking must begin for :func:`brake_from_timing` to use it.
_SOON = 0.05
#: Attempts before the brake is refused (the caller then brakes each joint).
ATTEMPTS = 5


def brake_along_jerk_limited(
    path: IdealPath, joint_path: JointPath, max_velocity: np.ndarray,
    max_acceleration: np.ndarray, max_jerk: np.ndarray, tool: ToolLimits, s0: float,
    speed: float, path_acceleration: float = 0.0, *,
    timed: JerkLimitedTimedPath | None = None,
) -> tuple[Trajectory, float]:
    """
    Return the jerk-limited brake from ``s0`` at ``(ṡ, s̈)`` to rest, and where it rests.

    The trajectory is in local time from 0 (joints, as ``joint_path``, quintic pieces); it
    starts at ``q(s0)`` with velocity ``q' ṡ`` and acceleration ``q' s̈ + q'' ṡ²`` and ends at
    rest at or before the next knot of the path, every joint within ``max_velocity``,
    ``max_acceleration`` and ``max_jerk`` (``(joints,)``, rad/s, rad/s², rad/s³) exactly.
    The bounds are first chosen in the rows the piece of ``timed`` (the timing the state
    comes from, if given) was planned in (:attr:`~.jerk_limited_timing.
    JerkLimitedTimedPath.models`: its state is within them), else in the conservative
    ones; after an attempt above a limit, in those rows with the rows of the limits it
    exceeded scaled up by what it used of them (:meth:`~.jerk_bounds.Rows.refined`).

    :raises ValueError: ``speed`` < 0, nothing to brake (at rest, or at the end), or no
        brake within the limits before the next knot (the caller brakes each joint).
    """
    if not speed >= 0.0:
        raise ValueError(f'brake_along_jerk_limited: speed {speed!r} must be >= 0')
    length = float(path.length)
    s0 = min(max(float(s0), 0.0), length)
    rests = merge_values(length, path.knots, path.stops, joint_path.knots, joint_path.stops)
    ahead = rests[rests > s0 + 1e-12 * length]
    if (speed == 0.0 and path_acceleration <= 0.0) or ahead.size == 0:
        raise ValueError('brake_along_jerk_limited: nothing to brake (at rest, or at the '
                         'end)')
    start, end = float(rests[rests <= s0].max(initial=0.0)), float(ahead[0])
    joints = joint_path.joints.joint_count
    limits = [np.broadcast_to(np.asarray(value, dtype=float), (joints,))
              for value in (max_velocity, max_acceleration, max_jerk)]
    conservative = piece_rows(path, joint_path, s0, end, *limits, tool.as_array())
    rows = conservative
    if timed is not None and timed.models:
        piece = int(np.searchsorted(rests, s0, side='right')) - 1
        rows = timed.models[min(max(piece, 0), len(timed.models) - 1)]
    fallback = rows is not conservative
    for _ in range(ATTEMPTS):
        choice = brake_bounds(rows, speed, path_acceleration, end - s0, MARGIN)
        if choice is None:
            if not fallback:
                break
            rows, fallback = conservative, False
            continue
        acceleration, jerk = choice
        attempt = _attempt(path, joint_path, (s0, speed, path_acceleration), choice,
                           (start, end), limits, tool.as_array())
        if attempt is None:
            break
        plan, rest, used = attempt
        if max(used.values()) <= 1.0 + LIMIT_TOLERANCE:
            return plan, rest
        peak = speed + max(path_acceleration, 0.0) ** 2 / (2.0 * jerk)
        rows = rows.refined(Bounds(peak, acceleration, jerk, *(Bound('jerk'),) * 3), used,
                            tighten=True)
    raise ValueError(f'brake_along_jerk_limited: no brake within the limits from s = '
                     f'{s0:.6g} before the next knot at {end:.6g}')


def _attempt(path: IdealPath, joint_path: JointPath, state: tuple[float, float, float],
             choice: tuple[float, float], piece: tuple[float, float],
             limits: list[np.ndarray], tool: np.ndarray
             ) -> tuple[Trajectory, float, dict[Bound, float]] | None:
    """Plan the brake of ``choice`` ``(A, J)``: it, its rest, its use; None: off the piece."""
    brake = scurve_brake(*state, *choice)
    breaks, coefficients = brake.shared_pieces
    moving = np.flatnonzero(np.diff(breaks) > 0.0)
    if not moving.size:
        return None
    profile = Trajectory(breaks[:moving[-1] + 2], coefficients[:moving[-1] + 1])
    rest = float(profile.sample(profile.duration)[0][0, 0])
    lowest = float(profile.position_extrema().minimum[0])
    start, end = piece
    slack = 1e-9 * path.length
    if rest > end + slack or lowest < start - slack:
        return None
    times, s, _, trajectory = sample_motion(joint_path, profile, start, end)
    return trajectory, min(rest, end), used_limits(path, profile, times, s, trajectory,
                                                   limits, tool)


def brake_from_timing(
    timed: JerkLimitedTimedPath, path: IdealPath, joint_path: JointPath,
    limits: tuple[np.ndarray, np.ndarray, np.ndarray], tool: ToolLimits, time: float,
    speed: float, path_acceleration: float,
) -> tuple[Trajectory, float]:
    """
    Brake a motion of ``timed`` from its ``time`` (s) at the commanded ``(ṡ, s̈)``, on the path.

    1. :func:`brake_along_jerk_limited` from there (in the rows of the timing first);
    2. else, while the timing still speeds up (``s̈ > 0``: a brake would have to ramp its
       acceleration down harder than the jerk allows where the path bends), its own
       motion until its acceleration is back at 0 (the end of its S-curve's ramp), then
       the brake from there, or its own rest of the way;
    3. else, where it brakes already (as hard as its bounds allow: ``s̈ < 0`` now or
       within :data:`_SOON`), its own rest of the way.

    The timing's own motion runs ``ṡ_plan / ṡ`` times slower (a speed override below 1),
    so the velocity and acceleration continue the commanded ones. ``limits`` are
    ``max_velocity``, ``max_acceleration``, ``max_jerk`` (``(joints,)``).

    :raises ValueError: nothing to brake, or no brake (the caller brakes each joint).
    """
    s0, planned, planned_acceleration = (float(value) for value in timed.path_state(time))
    slower = max(planned / speed, 1.0) if speed > 0.0 else 1.0
    try:
        return brake_along_jerk_limited(path, joint_path, *limits, tool, s0, speed,
                                        path_acceleration, timed=timed)
    except ValueError:
        if not 0.0 <= time < timed.duration or speed <= 0.0:
            raise
    if path_acceleration <= 0.0:
        soon = float(timed.path_state(min(time + _SOON, timed.duration))[2])
        if planned_acceleration < 0.0 or soon < 0.0:
            return rest_of_piece(timed, time, slower)
        raise ValueError(f'brake_from_timing: no brake within the limits from s = {s0:.6g}')
    level = _level(timed, time)
    head = scaled(_between(timed.trajectory, time, level), slower)
    s1, speed1, _ = (float(value) for value in timed.path_state(level))
    try:
        tail, rest = brake_along_jerk_limited(path, joint_path, *limits, tool, s1,
                                              speed1 / slower, 0.0, timed=timed)
    except ValueError:
        tail, rest = rest_of_piece(timed, level, slower)
    return concatenate([head, tail]), rest


def _level(timed: JerkLimitedTimedPath, time: float) -> float:
    """Return the first phase boundary of the S-curve after ``time`` where ``s̈`` is 0."""
    breaks = timed.profile.breakpoints
    after = breaks[breaks > time + 1e-12 * max(timed.duration, 1.0)]
    accelerations = np.abs(timed.profile.sample(after)[2][:, 0])
    scale = np.abs(timed.profile.sample(breaks)[2][:, 0]).max(initial=0.0)
    level = after[accelerations <= 1e-9 * scale]
    return float(level[0]) if level.size else timed.duration


def rest_of_piece(timed: JerkLimitedTimedPath, time: float, slower: float = 1.0
                  ) -> tuple[Trajectory, float]:
    """
    Return the timing's own motion from ``time`` (s) to its next rest, ``slower`` times slower.

    The brake when :func:`brake_along_jerk_limited` finds none before the next knot (the
    timing already brakes as hard as its bounds allow to rest there): the same
    polynomials from ``time`` on (re-expanded about it), their time times ``slower``
    (>= 1: a speed override below 1 runs them so; every limit then holds with room),
    and the ``s`` where it rests.

    :raises ValueError: ``time`` outside the motion, or ``slower`` below 1.
    """
    if not (0.0 <= time < timed.duration) or not (math.isfinite(slower) and slower >= 1.0):
        raise ValueError(f'rest_of_piece: time {time!r} must be in [0, {timed.duration}) '
                         f'and slower {slower!r} >= 1')
    rest = float(timed.rest_times[np.searchsorted(timed.rest_times, time, side='right')])
    return scaled(_between(timed.trajectory, time, rest), slower), \
        float(timed.path_parameter(rest)[0])


def _between(trajectory: Trajectory, start: float, end: float) -> Trajectory:
    """Return ``trajectory`` from ``start`` to ``end`` (s) in local time from 0."""
    breaks, coefficients = trajectory.breakpoints, trajectory.coefficients
    first = int(np.searchsorted(breaks, start, side='right')) - 1
    last = max(int(np.searchsorted(breaks, end, side='left')), first + 1)
    head = _shifted(coefficients[first], start - float(breaks[first]))
    pieces = np.concatenate([head[None], coefficients[first + 1:last]])
    inner = breaks[first + 1:last]
    return Trajectory(np.concatenate([[start], inner, [end]]) - start, pieces)


def _shifted(coefficients: np.ndarray, offset: float) -> np.ndarray:
    """Re-expand ascending ``(n + 1, joints)`` coefficients about ``offset`` (Taylor)."""
    size = coefficients.shape[0]
    shifted = np.zeros_like(coefficients)
    for power in range(size):
        for higher in range(power, size):
            shifted[power] += (math.comb(higher, power) * coefficients[higher]
                               * offset ** (higher - power))
    return shifted
