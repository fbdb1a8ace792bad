"""
Position limits applied to requests and plans: commanded positions and exact plan extrema.

No ROS here. The limits in force (:class:`traj_gen_ros.node.urdf_limits.JointLimits`, the
tighter of the URDF and the ``min_position``/``max_position`` parameters) ride on the
node's :class:`~traj_gen_ros.node.config.Config` (``Config.limits``). Two checks, each
raising :class:`~traj_gen_ros.node.parsing.RequestError` that names the joint by its ROS
name, the value and the range:

* :func:`check_request`: a goal position or via point outside the range, before planning
  (:func:`traj_gen_ros.node.urdf_limits.check_positions`, the one position check);
* :func:`check_plan`: a plan that would leave the range between its points (a spline's
  overshoot, a moving start that must brake past the target), from the plan's exact
  position extrema (:meth:`~traj_gen_ros.core.trajectory.Trajectory.position_extrema`).

A start already outside the range (limits tightened while the setpoint was outside) may
stay where it is: the plan may not go beyond the start, so that moving back in is allowed.
``~/stop`` is never checked.

Units: rad or m, s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.parsing import GoalRequest, RequestError, ViaRequest
from traj_gen_ros.node.urdf_limits import (
    check_positions,
    describe_range,
    JointLimits,
    POSITION_TOLERANCE,
)


def _outside(limits: JointLimits, index: int, value: float) -> str | None:
    """Say which bound ``value`` breaks (``'lower'``/``'upper'``), or None."""
    lower = limits.position.lower[index]
    upper = limits.position.upper[index]
    if value < lower - POSITION_TOLERANCE * max(1.0, abs(lower)):
        return 'lower'
    if value > upper + POSITION_TOLERANCE * max(1.0, abs(upper)):
        return 'upper'
    return None


def check_request(limits: JointLimits, request: GoalRequest | ViaRequest,
                  start: Sequence[float]) -> None:
    """
    Refuse a goal or via point outside its joint's position range.

    The check is :func:`traj_gen_ros.node.urdf_limits.check_positions`: a position within
    ``START_TOLERANCE`` of the joint's ``start`` (rad or m) is allowed even outside the
    range, as the joint may stay where it is.

    :raises RequestError: e.g. ``goal position 3.2 rad for joint 'joint_2' is outside its
        range [-2.9, 2.9] rad (lower from URDF; upper from URDF)``.
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
    Refuse a plan whose exact positions leave a joint's range (beyond ``start``, rad or m).

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
            if (bound == 'lower' and value >= start[index]) or \
                    (bound == 'upper' and value <= start[index]):
                continue  # a start outside the range may stay where it is
            raise RequestError(
                f'the plan would take joint {limits.joints[index]!r} to {value:.6g} '
                f'{limits.units[index]}, outside its range {describe_range(limits, index)}: the '
                'motion overshoots between its points or must brake past the target; '
                'choose other points or times, or send it when the joint moves slower')
