"""
Position limits applied to requests and plans: commanded positions and exact plan extrema.

No ROS here. The limits in force
(:class:`traj_gen_ros.node.description.joint_limits.JointLimits`, the
tighter of the URDF and the ``min_position``/``max_position`` parameters) ride on the
node's :class:`~traj_gen_ros.node.settings.config.Config` (``Config.limits``). Two checks, each
raising :class:`~traj_gen_ros.node.messages.parsing.RequestError` that names the joint by its ROS
name, the value and the range:

* :func:`check_request`: a goal position or via point outside the range, before planning
  (:func:`traj_gen_ros.node.description.joint_limits.check_positions`, the one position check);
* :func:`check_plan`: a plan that would leave the range between its points (a spline's
  overshoot, a moving start that must brake past the target), from the plan's exact
  position extrema (:meth:`~traj_gen_ros.core.trajectory.Trajectory.position_extrema`).

A joint may be outside its range already: ``initial_positions`` (or a measured state)
there, or limits narrowed while it was there. :func:`outside_ranges` says so (the node
logs it and reports WARN on ``/diagnostics``). Such a joint may hold where it is while
the others move, and move toward or into its range: for both checks the positions of a
joint that starts at ``s`` must stay within ``[min(s, lower), max(s, upper)]`` (its
range, widened to the start), so only a goal, via point or plan that takes it further
out is refused. ``~/stop`` is never checked.

Units: rad or m, s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.description.joint_limits import (
    check_positions,
    describe_range,
    JointLimits,
    POSITION_TOLERANCE,
)
from traj_gen_ros.node.messages.parsing import GoalRequest, RequestError, ViaRequest


def _outside(limits: JointLimits, index: int, value: float) -> str | None:
    """Say which bound ``value`` breaks (``'lower'``/``'upper'``), or None."""
    lower = limits.position.lower[index]
    upper = limits.position.upper[index]
    if value < lower - POSITION_TOLERANCE * max(1.0, abs(lower)):
        return 'lower'
    if value > upper + POSITION_TOLERANCE * max(1.0, abs(upper)):
        return 'upper'
    return None


def outside_ranges(limits: JointLimits | None, positions: Sequence[float]) -> str:
    """
    Say which joints are outside their position range at ``positions`` (rad or m).

    :return: '' when all are within (bounds included, with ``POSITION_TOLERANCE``);
        otherwise one clause per joint, joined by ``'; '``, e.g. ``joint 'joint_4' is at 0
        rad, outside its range [0.194395, 2.29440] rad (lower from URDF; upper from
        URDF)``.
    """
    if limits is None:
        return ''
    parts = []
    for index, value in enumerate(np.asarray(positions, dtype=float)):
        if _outside(limits, index, float(value)) is not None:
            parts.append(f'joint {limits.joints[index]!r} is at {value:.6g} '
                         f'{limits.units[index]}, outside its range '
                         f'{describe_range(limits, index)}')
    return '; '.join(parts)


def check_request(limits: JointLimits, request: GoalRequest | ViaRequest,
                  start: Sequence[float]) -> None:
    """
    Refuse a goal or via point outside its joint's position range.

    A joint whose ``start`` (rad or m) is outside its range may be sent anywhere between
    its start and its range, not further out
    (:func:`traj_gen_ros.node.description.joint_limits.check_positions`, the one position check).

    :raises RequestError: e.g. ``goal position 3.2 rad for joint 'joint_2' is outside its
        range [-2.9, 2.9] rad (lower from URDF; upper from URDF)``; for a joint outside
        already, ``…; it is at 0 rad, outside its range: only positions in [0, 2.29] rad
        (toward or into its range) are allowed``.
    """
    joints = np.asarray(request.joints, dtype=int)
    what = 'goal position' if isinstance(request, GoalRequest) else \
        'via point {point} position'
    reason = check_positions([limits.joints[joint] for joint in joints], request.positions,
                             limits, what, start=np.asarray(start, dtype=float)[joints])
    if reason is not None:
        raise RequestError(reason)


def check_plan(limits: JointLimits, plan: Trajectory, start: Sequence[float]) -> None:
    """
    Refuse a plan whose exact positions leave a joint's range widened to its ``start``.

    :param start: where the plan starts, rad or m, ``(joints,)``.
    :raises RequestError: e.g. ``the plan would take joint 'joint_2' to 2.95 rad, outside
        its range [-2.9, 2.9] rad (…): …``.
    """
    if not (np.isfinite(limits.position.lower).any()
            or np.isfinite(limits.position.upper).any()):
        return  # no position limit at all: nothing to find
    extrema = plan.position_extrema()
    lowest, highest = extrema.minimum, extrema.maximum
    start = np.asarray(start, dtype=float)
    for index in range(len(limits.joints)):
        for value, bound in ((lowest[index], 'lower'), (highest[index], 'upper')):
            broken = _outside(limits, index, float(value))
            if broken != bound:
                continue
            slack = POSITION_TOLERANCE * max(1.0, abs(start[index]))
            if (bound == 'lower' and value >= start[index] - slack) or \
                    (bound == 'upper' and value <= start[index] + slack):
                continue  # a start outside the range may stay there or come back
            raise RequestError(
                f'the plan would take joint {limits.joints[index]!r} to {value:.6g} '
                f'{limits.units[index]}, outside its range '
                f'{describe_range(limits, index)}: the motion overshoots between its points '
                'or must brake past the target; choose other points or times, or send it '
                'when the joint moves slower')
