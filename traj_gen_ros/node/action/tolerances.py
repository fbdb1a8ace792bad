"""
Path and goal tolerances of a ``FollowJointTrajectory`` goal, with JTC's meaning (no ROS).

The node's defaults are the parameters ``path_tolerance`` and ``goal_tolerance`` (rad, one
per joint or one for all; 0 = not checked), ``goal_time_tolerance`` (s; 0 = no time limit:
the goal waits until within its tolerance) and ``stopped_velocity_tolerance`` (rad/s; 0 =
not checked). A goal's own ``JointTolerance`` entries override them by joint name
(``position`` field; 0 = the node's default, -1 = not checked), and its non-zero
``goal_time_tolerance`` overrides the node's, as ``joint_trajectory_controller`` does
(ros2_controllers, ``tolerances.hpp``). Only the joints a goal names are checked, and only
against a measured state: without one, the end of the trajectory reached is success.

Units: rad, rad/s, s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.validation import per_joint
from traj_gen_ros.node.action.goal_points import (
    GOAL_TOLERANCE_VIOLATED,
    GoalError,
    INVALID_GOAL,
    INVALID_JOINTS,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
)

#: A ``JointTolerance`` value that turns the check off for that joint.
NOT_CHECKED = -1.0
#: How a goal ends.
SUCCEEDED, ABORTED, CANCELED = 'succeeded', 'aborted', 'canceled'
#: The parameters that give the node's defaults (:func:`read_defaults`).
TOLERANCE_PARAMETERS = ('allowed_start_tolerance', 'goal_time_tolerance',
                        'stopped_velocity_tolerance', 'path_tolerance', 'goal_tolerance')


@dataclass(frozen=True)
class Tolerances:
    """Per joint of the joint set: ``path`` and ``goal`` (rad, 0 = not checked); times."""

    path: np.ndarray
    goal: np.ndarray
    goal_time: float
    stopped_velocity: float


def default_tolerances(joint_count: int, path: object, goal: object, goal_time: float,
                       stopped_velocity: float) -> Tolerances:
    """Return the node's defaults from the parameters; ``ValueError`` naming a bad one."""
    for name, value in (('goal_time_tolerance', goal_time),
                        ('stopped_velocity_tolerance', stopped_velocity)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f'{name} is {value!r}: must be finite and >= 0')
    return Tolerances(per_joint('path_tolerance', path, joint_count, 'non-negative'),
                      per_joint('goal_tolerance', goal, joint_count, 'non-negative'),
                      float(goal_time), float(stopped_velocity))


def read_defaults(value: Callable[[str], object], joint_count: int,
                  changed: dict[str, object]) -> tuple[float, Tolerances]:
    """
    Return ``(allowed_start_tolerance, Tolerances)`` from the parameters; ``ValueError``.

    ``value(name)`` gives a parameter's value; ``changed`` (name: value) the ones being set.
    """
    values = {name: changed[name] if name in changed else value(name)
              for name in TOLERANCE_PARAMETERS}
    return values['allowed_start_tolerance'], default_tolerances(
        joint_count, values['path_tolerance'], values['goal_tolerance'],
        values['goal_time_tolerance'], values['stopped_velocity_tolerance'])


def _override(values: np.ndarray, joints: Sequence[str],
              entries: Sequence[tuple[str, float]], field: str) -> np.ndarray:
    values = values.copy()
    for name, value in entries:
        if name not in joints:
            raise GoalError(INVALID_JOINTS, f'{field} names unknown joint {name!r}; known '
                            f'joints: {list(joints)}')
        if value == NOT_CHECKED:
            values[joints.index(name)] = 0.0
        elif not (math.isfinite(value) and value >= 0.0):
            raise GoalError(INVALID_GOAL, f'{field} for joint {name!r} is {value!r} rad: give '
                            '> 0, 0 for the default or -1 for not checked')
        elif value > 0.0:
            values[joints.index(name)] = value
    return values


def goal_tolerances(defaults: Tolerances, joints: Sequence[str],
                    path: Sequence[tuple[str, float]], goal: Sequence[tuple[str, float]],
                    goal_time: float) -> Tolerances:
    """
    Apply a goal's ``(joint name, position tolerance)`` entries and ``goal_time`` (s).

    Raises :class:`GoalError`: INVALID_JOINTS for an unknown name, INVALID_GOAL for a
    value that is not finite, or negative other than -1.
    """
    joints = list(joints)
    if not (math.isfinite(goal_time) and goal_time >= 0.0):
        raise GoalError(INVALID_GOAL, f'goal_time_tolerance is {goal_time!r} s: must be >= 0')
    return Tolerances(_override(defaults.path, joints, path, 'path_tolerance'),
                      _override(defaults.goal, joints, goal, 'goal_tolerance'),
                      goal_time if goal_time > 0.0 else defaults.goal_time,
                      defaults.stopped_velocity)


def path_violation(tolerances: Tolerances, named: np.ndarray, desired: np.ndarray,
                   actual: np.ndarray, joints: Sequence[str]) -> str | None:
    """Say which named joint is farther than its path tolerance from ``desired``, or None."""
    return _beyond(tolerances.path, named, desired, actual, joints, 'path_tolerance')


def goal_violation(tolerances: Tolerances, named: np.ndarray, target: np.ndarray,
                   actual: np.ndarray, velocity: np.ndarray | None,
                   joints: Sequence[str]) -> str | None:
    """
    Say why the arm is not at the goal yet (position beyond ``goal`` or still moving).

    ``velocity`` is the measured one (rad/s), or None when the measured state has none.
    """
    problem = _beyond(tolerances.goal, named, target, actual, joints, 'goal_tolerance')
    if problem is not None or velocity is None or tolerances.stopped_velocity <= 0.0:
        return problem
    speeds = np.abs(velocity[named])
    worst = int(np.argmax(speeds))
    if speeds[worst] > tolerances.stopped_velocity:
        return (f'joint {joints[int(named[worst])]!r} still moves at {speeds[worst]:.6g} '
                f'rad/s, above stopped_velocity_tolerance {tolerances.stopped_velocity:g} '
                'rad/s')
    return None


def _beyond(limit: np.ndarray, named: np.ndarray, wanted: np.ndarray, actual: np.ndarray,
            joints: Sequence[str], field: str) -> str | None:
    errors = np.abs(actual[named] - wanted[named])
    limits = limit[named]
    over = np.where(limits > 0.0, errors - limits, -np.inf)
    worst = int(np.argmax(over))
    if over[worst] <= 0.0:
        return None
    joint = int(named[worst])
    return (f'joint {joints[joint]!r} is at {actual[joint]:.6g} rad, {errors[worst]:.6g} rad '
            f'from {wanted[joint]:.6g} rad: above {field} {limits[worst]:g} rad')


def outcome(tolerances: Tolerances, named: np.ndarray, joints: Sequence[str],
            times_ns: tuple[int, int, int, int], desired: np.ndarray, target: np.ndarray,
            measured: np.ndarray | None, measured_velocities: Callable[[], np.ndarray | None],
            slowed: str) -> tuple[str, int, str] | None:
    """
    Say how a running goal ends now, ``(status, error code, error string)``, or None.

    ``times_ns`` are its start and end, now and the last setpoint published (ns, node
    clock); ``desired`` the setpoint now and ``target`` the end (rad); ``measured`` where
    the arm is (rad) or None. ``slowed`` (the slow-down, if any) goes into the text.
    """
    start_ns, end_ns, now_ns, published_ns = times_ns
    if measured is not None and start_ns <= now_ns < end_ns:
        problem = path_violation(tolerances, named, desired, measured, joints)
        if problem is not None:
            return ABORTED, PATH_TOLERANCE_VIOLATED, problem
    if published_ns < end_ns:
        return None
    if measured is None:
        return SUCCEEDED, SUCCESSFUL, slowed
    problem = goal_violation(tolerances, named, target, measured, measured_velocities(),
                             joints)
    if problem is None:
        return SUCCEEDED, SUCCESSFUL, slowed
    if tolerances.goal_time > 0.0 and now_ns > end_ns + tolerances.goal_time * 1e9:
        return (ABORTED, GOAL_TOLERANCE_VIOLATED, f'{problem} {tolerances.goal_time:g} s '
                f'after the end{"; " + slowed if slowed else ""}')
    return None
