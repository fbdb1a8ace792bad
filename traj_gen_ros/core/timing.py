"""
Minimum-time timing from velocity and acceleration limits, all joints synchronised.

For each joint the shortest duration that keeps ``|velocity| ≤ max_velocity`` and
``|acceleration| ≤ max_acceleration`` is found; the slowest joint sets the duration and
every joint starts and arrives together.

Rest-to-rest peaks (distance ``D``, duration ``T``), used in closed form:
- LSPB: the time-optimal trapezoid, ``T = D/v + v/a`` when ``D ≥ v²/a``, else the
  triangle ``T = 2 sqrt(D/a)``.
- cubic eq. (6): peak velocity ``1.5 D/T``, peak acceleration ``6 D/T²``.
- quintic: peak velocity ``15/8 D/T``, peak acceleration ``10/sqrt(3) D/T²``.
From a moving start (an extension for replanning) the duration is computed exactly:
LSPB in closed form (:mod:`traj_gen_ros.core.exact.second_order`), cubic and quintic from
each joint's set of feasible durations
(:mod:`traj_gen_ros.core.exact.polynomial_durations`). Via-point paths are timed by
:func:`traj_gen_ros.core.paths.via_durations`, stretched by one factor found by bisection
on exact peaks (:func:`shortest_duration`).
"""

from __future__ import annotations

from collections.abc import Callable
import math

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.blends import three_pieces
from traj_gen_ros.core.exact import second_order
from traj_gen_ros.core.exact.polynomial_durations import (
    polynomial_minimum_duration,
    SHORTEST_POLYNOMIAL,
)
from traj_gen_ros.core.jerk_limited.move import scurve_min_time
from traj_gen_ros.core.kinematic_limits import JointError, within_limits
from traj_gen_ros.core.polynomial import cubic, quintic, to_rest
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike

PROFILES = ('lspb', 'cubic', 'quintic', 'scurve')
# (peak velocity, peak acceleration) of a rest-to-rest unit move in unit time.
_POLYNOMIAL_PEAKS = {'cubic': (1.5, 6.0), 'quintic': (15.0 / 8.0, 10.0 / np.sqrt(3.0))}
_BISECTION_STEPS = 60


def check_profile(profile: str) -> None:
    """Raise ``ValueError`` unless ``profile`` is one of :data:`PROFILES`."""
    if profile not in PROFILES:
        raise ValueError(f'profile must be one of {", ".join(PROFILES)}, got "{profile}"')


@validation.refuses_overflow('min_time')
def min_time(
    q0: ArrayLike,
    qf: ArrayLike,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    profile: str = 'lspb',
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
    max_jerk: ArrayLike | None = None,
) -> Trajectory:
    """
    Plan the shortest synchronised ``profile`` trajectory from ``q0`` to rest at ``qf``.

    The one entry point for a move from a state ``(q0, v0, a0)``: the node and
    ``traj-gen`` both plan goals with it.

    :param q0: start position (rad), scalar or one per joint.
    :param qf: goal position (rad), scalar or one per joint.
    :param max_velocity: velocity limit (rad/s), scalar or one per joint.
    :param max_acceleration: acceleration limit (rad/s²), scalar or one per joint.
    :param profile: ``"lspb"`` (time-optimal trapezoid, triangular when the velocity limit is
        never reached), ``"cubic"`` or ``"quintic"`` (the duration at which the
        binding limit is just met), ``"scurve"`` (jerk-limited, seven phases:
        :func:`traj_gen_ros.core.jerk_limited.move.scurve_min_time`).
    :param v0: start velocity (rad/s), extension for replanning a moving joint.
    :param a0: start acceleration (rad/s²), used by the quintic and the S-curve.
    :param max_jerk: jerk limit (rad/s³), scalar or one per joint: the S-curve's, required
        by it and unused by the other profiles.

    For LSPB from rest every other joint runs its own optimal trapezoid stretched in time
    to the common duration (acceleration scaled by ``(T_joint/T)²``, velocity by
    ``T_joint/T``), so none exceeds a limit and all arrive together. A motion of zero
    length gives a zero-duration trajectory that holds ``q0``.

    """
    check_profile(profile)
    if profile == 'scurve':
        if max_jerk is None:
            raise ValueError('profile scurve needs max_jerk (rad/s^3, > 0)')
        return _scurve_min_time(q0, qf, max_velocity, max_acceleration, v0, a0, max_jerk)
    rows = validation.per_joint_rows(q0=q0, qf=qf, v0=v0, a0=a0, max_velocity=max_velocity,
                                     max_acceleration=max_acceleration)
    validation.require_positive(rows[4:], ('max_velocity', 'max_acceleration'))
    # Overflow and underflow are looked for in the result, which names the joint.
    with np.errstate(over='ignore', under='ignore', divide='ignore', invalid='ignore'):
        try:
            plan = _plan(profile, *rows)
        except (OverflowError, ZeroDivisionError):
            plan = None
    return require_finite(plan, rows)


def _scurve_min_time(q0: ArrayLike, qf: ArrayLike, max_velocity: ArrayLike,
                     max_acceleration: ArrayLike, v0: ArrayLike, a0: ArrayLike,
                     max_jerk: ArrayLike) -> Trajectory:
    """Validate and plan the time-optimal S-curve (it checks its own results)."""
    rows = validation.per_joint_rows(q0=q0, qf=qf, v0=v0, a0=a0, max_velocity=max_velocity,
                                     max_acceleration=max_acceleration, max_jerk=max_jerk)
    validation.require_positive(rows[4:], ('max_velocity', 'max_acceleration', 'max_jerk'))
    return scurve_min_time(*rows)


def _plan(profile: str, start: np.ndarray, goal: np.ndarray, start_velocity: np.ndarray,
          start_acceleration: np.ndarray, max_velocity: np.ndarray,
          max_acceleration: np.ndarray) -> Trajectory | None:
    """Dispatch :func:`min_time` on validated ``(joints,)`` rows; ``None`` if it overflows."""
    # Only the quintic starts from an acceleration.
    if np.count_nonzero(start_velocity) or \
            (profile == 'quintic' and np.count_nonzero(start_acceleration)):
        if profile != 'quintic':
            start_acceleration = np.zeros_like(start_acceleration)
        return _moving_min_time(
            start, goal, max_velocity, max_acceleration, profile, start_velocity,
            start_acceleration)
    displacement = goal - start
    if profile == 'lspb':
        return _min_time_lspb(start, goal, displacement, max_velocity, max_acceleration)
    distance = np.abs(displacement)
    joint_times = rest_to_rest_times(distance, max_velocity, max_acceleration, profile)
    duration = float(joint_times.max())
    if duration == 0.0:
        return hold(start)
    if not np.isfinite(duration):
        return None
    polynomial = cubic if profile == 'cubic' else quintic
    return polynomial(start, goal, max(duration, SHORTEST_POLYNOMIAL))


def require_finite(plan: Trajectory | None, rows: np.ndarray) -> Trajectory:
    """
    Return ``plan`` if its duration and coefficients are finite, else raise ``ValueError``.

    ``rows`` are the validated inputs ``(q0, qf, v0, a0, v_max, a_max)``; the message names
    the joint whose numbers overflowed (or the one with the longest move) and its inputs.
    """
    if plan is not None and math.isfinite(plan.duration) and \
            validation.every(np.isfinite(plan.coefficients)):
        return plan
    start, goal, start_velocity, start_acceleration, max_velocity, max_acceleration = rows
    if plan is not None and not validation.every(np.isfinite(plan.coefficients)):
        joint = int(np.argmin(np.isfinite(plan.coefficients).all(axis=(0, 1))))
    else:  # the joint with the longest rough duration; it may be infinite itself
        with np.errstate(over='ignore'):
            joint = int(np.argmax(np.abs(goal - start) / max_velocity
                                  + (max_velocity + np.abs(start_velocity)) / max_acceleration))
    raise JointError(
        f'{{joint}}: moving {goal[joint] - start[joint]:g} rad from velocity '
        f'{start_velocity[joint]:g} rad/s and acceleration {start_acceleration[joint]:g} '
        f'rad/s^2 with max_velocity {max_velocity[joint]:g} rad/s and max_acceleration '
        f'{max_acceleration[joint]:g} rad/s^2 overflows: no finite plan; use limits and '
        'distances within about 1e-100..1e100 of each other', joint)


def _min_time_lspb(
    start: np.ndarray,
    goal: np.ndarray,
    displacement: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
) -> Trajectory:
    """
    Plan every joint's time-optimal trapezoid, stretched to the slowest joint's duration.

    Peak velocity ``v_p = min(v_max, sqrt(D a_max))`` (the triangle when ``v_max`` is not
    reached), duration ``T_j = D/v_p + v_p/a_max``, blend time ``v_p/a_max``. Stretching
    by ``k = T/T_j`` gives blend ``k v_p/a_max``, cruise ``v_p/k``, acceleration ``a_max/k²``.
    """
    distance = np.abs(displacement)
    peak = np.minimum(max_velocity, np.sqrt(distance * max_acceleration))
    moving = peak > 0.0
    ramp = peak / max_acceleration
    joint_times = distance / np.where(moving, peak, 1.0) + ramp
    duration = max(joint_times.tolist())
    if duration == 0.0:
        return hold(start)
    shrink = np.where(moving, joint_times, duration) / duration  # 1/k
    blend = ramp / shrink
    acceleration = np.sign(displacement) * max_acceleration * (shrink * shrink)
    cruise = acceleration * blend
    move = 0.5 * cruise * blend
    return three_pieces(start, goal, duration, (blend, blend), (move, move), cruise, 0.0,
                        (acceleration, -acceleration))


def rest_to_rest_times(
    distance: np.ndarray, max_velocity: np.ndarray, max_acceleration: np.ndarray, profile: str
) -> np.ndarray:
    """Each joint's own shortest rest-to-rest duration (s) for ``distance`` (rad)."""
    if profile == 'lspb':
        peak = np.minimum(max_velocity, np.sqrt(distance * max_acceleration))
        return distance / np.where(peak > 0.0, peak, 1.0) + peak / max_acceleration
    velocity_peak, acceleration_peak = _POLYNOMIAL_PEAKS[profile]
    return np.maximum(velocity_peak * distance / max_velocity,
                      np.sqrt(acceleration_peak * distance / max_acceleration))


@validation.refuses_overflow('hold')
def hold(positions: ArrayLike) -> Trajectory:
    """Return a zero-duration trajectory that holds ``positions`` (rad) at rest."""
    positions = validation.per_joint_rows(positions=positions)[0]
    coefficients = np.zeros((1, 1, positions.size))
    coefficients[0, 0] = positions
    return Trajectory(np.zeros(2), coefficients)


def shortest_duration(
    plan: Callable[[float], Trajectory],
    lower: float,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
) -> Trajectory:
    """
    Find the shortest-duration ``plan(duration)`` within limits, by doubling then bisection.

    ``lower`` (s, > 0) is a duration no feasible plan is shorter than. A plan that raises
    ``ValueError`` (a blend that cannot fit) counts as infeasible.
    """
    def feasible(duration: float) -> Trajectory | None:
        try:
            candidate = plan(duration)
        except ValueError:
            return None
        return candidate if within_limits(candidate, max_velocity, max_acceleration) else None

    best = feasible(lower)
    if best is not None:
        return best
    low, high = lower, 2.0 * lower
    while (best := feasible(high)) is None:
        low, high = high, 2.0 * high
        if high > 1e9:
            raise ValueError('no duration up to 1e9 s keeps the motion within its limits')
    for _ in range(_BISECTION_STEPS):
        middle = 0.5 * (low + high)
        candidate = feasible(middle)
        if candidate is None:
            low = middle
        else:
            high, best = middle, candidate
        if high - low <= 1e-9 * high:
            break
    return best


def _moving_min_time(
    start: np.ndarray,
    goal: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    profile: str,
    start_velocity: np.ndarray,
    start_acceleration: np.ndarray,
) -> Trajectory:
    """
    Shortest synchronised plan from a moving state to rest at ``goal``, computed exactly.

    LSPB: :mod:`traj_gen_ros.core.exact.second_order` in closed form. Cubic and quintic: each
    joint's
    exact set of feasible durations (:mod:`traj_gen_ros.core.exact.polynomial_durations`), then the
    smallest duration in all of them. A polynomial start already beyond a limit (limits
    lowered mid-motion) may stay at that level while it slows down: the polynomial cannot
    leave it at once. ``ValueError`` when no duration works, saying for which joint.
    """
    if profile == 'lspb':
        return _moving_lspb(start, goal, max_velocity, max_acceleration, start_velocity)
    speed = np.abs(start_velocity)
    max_velocity = np.maximum(max_velocity, speed)
    if profile == 'quintic':
        magnitude = np.abs(start_acceleration)
        max_acceleration = np.maximum(max_acceleration, magnitude)
    else:
        start_acceleration = magnitude = np.zeros_like(start_velocity)
    # Start terms far below their limits (1e-12) only blur the candidate polynomials' degree.
    duration, hopeless = polynomial_minimum_duration(
        profile, goal - start,
        start_velocity * (speed >= 1e-12 * max_velocity),
        start_acceleration * (magnitude >= 1e-12 * max_acceleration),
        max_velocity, max_acceleration)
    if hopeless is not None:
        raise JointError(
            f'{{joint}}: no {profile} from velocity {start_velocity[hopeless]:g} and '
            f'acceleration {start_acceleration[hopeless]:g} stays within the limits, however '
            'long; stop first or choose another profile', hopeless)
    if duration is None:
        raise ValueError(f'no {profile} duration suits every joint at once (their feasible '
                         'durations do not overlap); stop first or choose another profile')
    return to_rest(profile, start, goal, duration, start_velocity, start_acceleration)


def _moving_lspb(
    start: np.ndarray,
    goal: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    start_velocity: np.ndarray,
) -> Trajectory:
    """
    Time-optimal synchronised LSPB from ``v0`` (second order), every joint at ``a_max``.

    A joint faster than its limit first brakes to it (a fourth, leading piece); every joint
    then runs blend, line, blend over the common duration with the cruise velocity of
    :func:`traj_gen_ros.core.exact.second_order.cruise_velocity`.
    """
    brake_time, brake_move, velocity = second_order.brake_to_limit(
        start_velocity, max_velocity, max_acceleration)
    displacement = goal - start - brake_move
    joint_times = brake_time + second_order.minimum_times(
        displacement, velocity, max_velocity, max_acceleration)
    duration = float(joint_times.max())
    if duration == 0.0:
        return hold(start)
    remaining = duration - brake_time
    low = np.maximum(0.5 * (velocity - max_acceleration * remaining), -max_velocity)
    high = np.minimum(0.5 * (velocity + max_acceleration * remaining), max_velocity)
    cruise = np.clip(second_order.cruise_velocity(displacement, velocity, remaining,
                                                  max_acceleration), low, high)
    first = np.abs(cruise - velocity) / max_acceleration
    last = np.minimum(np.abs(cruise) / max_acceleration, remaining - first)
    moves = (0.5 * (velocity + cruise) * first, 0.5 * cruise * last)
    accelerations = (np.sign(cruise - velocity) * max_acceleration,
                     -np.sign(cruise) * max_acceleration)
    # Blend, line, blend fill the time after each joint's brake (``remaining``, per joint).
    blended = three_pieces(start + brake_move, goal, remaining, (first, last), moves, cruise,
                           velocity, accelerations)
    if not np.count_nonzero(brake_time):
        return blended
    return _with_brake(start, start_velocity, brake_time, max_acceleration, blended, duration)


def _with_brake(start: np.ndarray, start_velocity: np.ndarray, brake_time: np.ndarray,
                max_acceleration: np.ndarray, blended: Trajectory,
                duration: float) -> Trajectory:
    """Prepend the brake piece to blend, line, blend shifted by ``brake_time``."""
    breakpoints = np.empty((5, start.size))
    breakpoints[0] = 0.0
    breakpoints[1:] = brake_time + blended.breakpoints
    breakpoints[-1] = duration
    coefficients = np.zeros((4, 3, start.size))
    coefficients[0, 0], coefficients[0, 1] = start, start_velocity
    coefficients[0, 2] = -0.5 * np.sign(start_velocity) * max_acceleration * (brake_time > 0)
    coefficients[1:] = blended.coefficients
    return Trajectory(breakpoints, coefficients)
