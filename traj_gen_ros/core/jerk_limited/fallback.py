"""
Fallbacks of the S-curve backend for requests Ruckig cannot plan, even rescaled.

- :func:`rest_to_rest`: one joint, rest to rest, minimum time: the closed-form seven-phase
  profile (Biagiotti & Melchiorri, *Trajectory Planning for Automatic Machines and
  Robots*, Springer 2008, §3.4.2, with zero boundary velocities), which cannot fail.
- :func:`composed`: several joints: each planned alone, then brought to the common
  duration (a joint at rest time-stretched, a moving one holding its goal at the end).

Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

from collections.abc import Callable
import math

import numpy as np
from traj_gen_ros.core.jerk_limited.problem import DURATION_TOLERANCE, Move
from traj_gen_ros.core.trajectory import JerkLimitedTrajectory, Trajectory


def rest_to_rest(move: Move) -> tuple[Trajectory, float] | None:
    """
    Plan one joint's time-optimal rest-to-rest S-curve in closed form, or return ``None``.

    With distance ``D``, limits ``v, a, j`` (B&M eqs. 3.30-3.33 for ``v0 = v1 = 0``):
    jerk phases ``Tj = a/j`` if ``v j ≥ a²`` else ``sqrt(v/j)``, acceleration phase
    ``Ta = Tj + v/a`` (or ``2 Tj``), cruise ``Tv = D/v - Ta``; if ``Tv < 0`` the velocity
    limit is not reached: ``Tv = 0`` and ``Tj = a/j``, ``Ta = Tj/2 + sqrt((Tj/2)² + D/a)``
    when ``D ≥ 2a³/j²``, else ``Tj = (D/2j)^(1/3)``, ``Ta = 2 Tj``. Applies only to a
    single joint, at rest at both ends, without a requested duration.
    """
    if (len(move.start) != 1 or move.duration is not None
            or move.v0[0] or move.a0[0] or move.vf[0]):
        return None
    (v,), (a,), (j,) = move.limits
    start, goal = move.start[0], move.goal[0]
    # Python floats: an overflow gives inf (refused below), never an exception.
    distance, sign = abs(goal - start), math.copysign(1.0, goal - start)
    jerk_time = a / j if v * j >= a * a else math.sqrt(v / j)
    ramp = jerk_time + v / a if v * j >= a * a else 2.0 * jerk_time
    cruise = distance / v - ramp
    if cruise < 0.0:
        cruise = 0.0
        if distance >= 2.0 * a * (a / j) * (a / j):
            jerk_time = a / j
            ramp = 0.5 * jerk_time + math.sqrt(0.25 * jerk_time * jerk_time + distance / a)
        else:
            jerk_time = (0.5 * distance / j) ** (1.0 / 3.0)
            ramp = 2.0 * jerk_time
    hold = ramp - 2.0 * jerk_time
    lengths = [jerk_time, hold, jerk_time, cruise, jerk_time, hold, jerk_time]
    jerks = [sign * j, 0.0, -sign * j, 0.0, -sign * j, 0.0, sign * j]
    rows, times = [], [0.0]
    position, velocity, acceleration = start, 0.0, 0.0
    for length, jerk in zip(lengths, jerks, strict=True):
        rows.append([position, velocity, 0.5 * acceleration, jerk / 6.0])
        position += length * (velocity + length * (0.5 * acceleration + length * jerk / 6.0))
        velocity += length * (acceleration + 0.5 * length * jerk)
        acceleration += length * jerk
        times.append(times[-1] + length)
    coefficients = np.array(rows)[:, :, None]
    breakpoints = np.array(times)[:, None]
    if not (np.isfinite(coefficients).all() and np.isfinite(breakpoints).all()):
        return None
    return JerkLimitedTrajectory(breakpoints, coefficients), float(breakpoints[-1, 0])


def composed(move: Move, plan_move: Callable[[Move], tuple[Trajectory, float]]
             ) -> tuple[Trajectory, float] | None:
    """
    Plan each joint alone and bring them to the common duration, when Ruckig cannot.

    ``T`` is the requested duration, or the slowest joint's own minimum time (so the plan
    stays time-optimal). A joint starting at rest runs its own optimal profile slowed by
    ``σ = T/t`` (pieces ``σ`` times longer, coefficients ``c_n/σ^n``: within the limits,
    arriving at ``T``); a moving one runs its own optimum, then holds the goal until
    ``T``. Only for targets at rest; returns ``None`` when it does not apply.
    """
    joints = len(move.start)
    if any(move.vf) or (move.duration is None and joints == 1):
        return None
    try:
        own = [plan_move(move.joint(joint).minimum_time()) for joint in range(joints)]
    except ValueError:
        return None
    duration = move.duration or max(time for _, time in own)
    if max(time for _, time in own) > duration * (1.0 + DURATION_TOLERANCE):
        return None
    columns = []
    for joint, (plan, time) in enumerate(own):
        times, coefficients = plan.breakpoints[:, 0], plan.coefficients[:, :, 0]
        hold = np.array([[move.goal[joint], 0.0, 0.0, 0.0]])
        if time > 0.0 and not (move.v0[joint] or move.a0[joint]):
            stretch = duration / time
            with np.errstate(over='ignore', invalid='ignore'):  # checked finite below
                times = np.minimum(times * stretch, duration)
                coefficients = coefficients / stretch ** np.arange(4.0)
        else:
            times = np.append(times, duration)
            coefficients = np.concatenate([coefficients, hold])
        times[-1] = duration
        columns.append((times, coefficients, hold))
    if not all(np.isfinite(times).all() and np.isfinite(coefficients).all()
               for times, coefficients, _ in columns):
        return None
    pieces = max(len(coefficients) for _, coefficients, _ in columns)
    breakpoints = np.full((pieces + 1, joints), duration)
    table = np.zeros((pieces, 4, joints))
    for joint, (times, coefficients, hold) in enumerate(columns):
        breakpoints[:len(times), joint] = times
        table[:, :, joint] = hold  # zero-length padding at the end holds the goal
        table[:len(coefficients), :, joint] = coefficients
    return JerkLimitedTrajectory(breakpoints, table), duration
