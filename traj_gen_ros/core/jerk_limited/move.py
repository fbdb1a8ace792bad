"""
Jerk-limited (S-curve) joint motion: the seven-phase, third-order profile, synchronised.

Each joint's motion is the classic seven-phase S-curve (Biagiotti & Melchiorri,
*Trajectory Planning for Automatic Machines and Robots*, Springer 2008, §3.4): jerk
``±j_max`` or 0 in each phase, so acceleration is piecewise linear and velocity piecewise
quadratic; phases whose limit is not reached have zero length. A start beyond the limits
(``|v0| > v_max``, ``|a0| > a_max``, or a velocity that ``a0`` will carry past ``v_max``)
is first brought back by up to two braking phases. The time-optimal synchronised
solution comes from Ruckig (L. Berscheid and T. Kröger, "Jerk-limited Real-time
Trajectory Generation with Arbitrary Target States", RSS 2021; the ``ruckig`` package,
MIT), read phase by phase into the package's piecewise cubic :class:`Trajectory`.

Ruckig refuses some valid requests (synchronised durations above ~7.6e3 s, numerically
extreme ratios); :mod:`traj_gen_ros.core.jerk_limited.ruckig_backend`, the backend, then solves
them again
in exactly rescaled units or composed per joint, and otherwise raises ``ValueError``
naming the input.

Units: rad (or m), rad/s, rad/s², rad/s³, s. Only the ``scurve*`` modules import ruckig,
so the other profiles do not need it.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.jerk_limited.problem import DURATION_TOLERANCE, LIMIT_NAMES, Move
from traj_gen_ros.core.jerk_limited.ruckig_backend import plan_move, scurve_minimum_duration
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike


def scurve_min_time(
    start: np.ndarray,
    goal: np.ndarray,
    start_velocity: np.ndarray,
    start_acceleration: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray,
) -> Trajectory:
    """
    Plan the time-optimal synchronised jerk-limited move from ``(q0, v0, a0)`` to rest.

    All arguments are validated float arrays shaped ``(joints,)``: positions (rad), start
    velocity (rad/s) and acceleration (rad/s²), limits (rad/s, rad/s², rad/s³, > 0). The
    slowest joint sets the duration (s); every other joint runs a seven-phase profile of
    exactly that duration (Ruckig's time synchronisation), so all arrive together. The
    result has per-joint breakpoints ``(pieces + 1, joints)`` and cubic pieces: 7, or 9
    with braking first when the start state is beyond (or will overshoot) the limits.
    Raises ``ValueError`` when no plan can be found, naming the joint and its input.

    Where Ruckig cannot synchronise even in rescaled units (a joint whose own time is a
    tiny fraction of the common one), the duration is still the optimum, but a joint that
    starts moving may reach its goal early and hold it
    (:mod:`traj_gen_ros.core.jerk_limited.ruckig_backend`).
    """
    move = Move(start.tolist(), goal.tolist(), start_velocity.tolist(),
                start_acceleration.tolist(), [0.0] * start.size,
                (max_velocity.tolist(), max_acceleration.tolist(), max_jerk.tolist()), None)
    return plan_move(move)[0]


@validation.refuses_overflow('scurve')
def scurve(
    q0: ArrayLike,
    qf: ArrayLike,
    duration: float,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
) -> Trajectory:
    """
    Plan a jerk-limited move from ``(q0, v0, a0)`` to rest at ``qf`` in exactly ``duration``.

    :param q0: start position (rad), scalar or one per joint.
    :param qf: goal position (rad), scalar or one per joint.
    :param duration: the move's duration (s).
    :param max_velocity: velocity limit (rad/s), scalar or one per joint.
    :param max_acceleration: acceleration limit (rad/s²), scalar or one per joint.
    :param max_jerk: jerk limit (rad/s³), scalar or one per joint.
    :param v0: start velocity (rad/s).
    :param a0: start acceleration (rad/s²).

    Every joint runs a seven-phase S-curve (Ruckig with ``minimum_duration``). Raises
    ``ValueError`` giving the minimum duration when ``duration`` is shorter; a joint that
    cannot arrive at exactly ``duration`` although longer and shorter times work (a
    blocked interval: from a moving start it would stop short or overshoot) is named, with
    the next duration that works.
    """
    rows = validation.per_joint_rows(q0=q0, qf=qf, v0=v0, a0=a0, max_velocity=max_velocity,
                                     max_acceleration=max_acceleration, max_jerk=max_jerk)
    validation.require_positive(rows[4:], LIMIT_NAMES)
    duration = validation.duration_of(duration)
    start, goal, start_velocity, start_acceleration = (row.tolist() for row in rows[:4])
    limits = tuple(row.tolist() for row in rows[4:])
    move = Move(start, goal, start_velocity, start_acceleration, [0.0] * len(start),
                limits, duration)
    return fixed_duration(move, 'scurve', 'duration')


def fixed_duration(move: Move, caller: str, what: str) -> Trajectory:
    """
    Plan ``move`` in exactly ``move.duration`` or raise ``ValueError`` saying why not.

    ``caller`` and ``what`` (e.g. ``'segment 2'``) start the message.
    """
    trajectory, reached = plan_move(move)
    if reached <= move.duration * (1.0 + DURATION_TOLERANCE):
        return trajectory
    fastest = scurve_minimum_duration(move)
    if fastest > move.duration * (1.0 + DURATION_TOLERANCE):
        raise ValueError(f'{caller}: {what} {move.duration:g} s is too short for the limits; '
                         f'the minimum duration is {validation.round_up(fastest, 9)} s')
    blocked = [joint for joint in range(len(move.start))
               if plan_move(move.joint(joint))[1] > move.duration * (1 + DURATION_TOLERANCE)]
    names = ('the joints together' if not blocked else
             f'joint{"s" if len(blocked) > 1 else ""} '
             + ', '.join(str(joint) for joint in blocked))
    raise ValueError(f'{caller}: {what} {move.duration:g} s is in a blocked duration interval '
                     f'of {names} (from its start state it would stop short or overshoot); '
                     f'the minimum duration is {validation.round_up(fastest, 9)} s and the next '
                     f'one that works is {validation.round_up(reached, 9)} s')
