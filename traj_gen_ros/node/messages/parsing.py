"""
Step 2 of a request, *parse*: message fields into a checked request (no ROS here).

:func:`parse_goal` turns the ``name``/``position`` fields of a ``sensor_msgs/JointState``
into a :class:`GoalRequest`; :func:`parse_via` turns the points of a
``trajectory_msgs/JointTrajectory`` into a :class:`ViaRequest`. Each check that fails
raises :class:`RequestError` saying what is wrong and what is valid: known joints, each
named once, matching lengths, finite numbers, strictly increasing times, bounded sizes.
(The wire bytes are read in :mod:`traj_gen_ros.node.messages.wire`.)

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np

#: Most via points one request may carry (planning time grows with the count).
MAX_VIA_POINTS = 1000
#: Longest plan (and largest ``time_from_start``) accepted, seconds.
MAX_DURATION = 3600.0

#: One via point as read from the message: positions, velocities, accelerations, time (s).
ViaPoint = tuple[Sequence[float], Sequence[float], Sequence[float], float]


class RequestError(ValueError):
    """A request the generator refuses; ``str(error)`` says what is wrong and what is valid."""


class JointNameError(RequestError):
    """A request naming no joint, an unknown one or one twice (the action's INVALID_JOINTS)."""


@dataclass(frozen=True)
class GoalRequest:
    """Move ``joints`` (indices into the joint set) to ``positions`` (rad)."""

    joints: np.ndarray
    positions: np.ndarray


@dataclass(frozen=True)
class ViaRequest:
    """
    Pass ``joints`` through ``positions`` (rad, ``(points, len(joints))``) at ``times`` (s).

    ``times`` are seconds from the start of execution; ``auto_timed`` means they were all
    zero ("time it for me from the limits"). ``velocities`` (rad/s) and ``accelerations``
    (rad/s²) are given for every point or are ``None``.
    """

    joints: np.ndarray
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None
    accelerations: np.ndarray | None
    auto_timed: bool


def joint_indices(joints: Sequence[str], names: Sequence[str], what: str) -> np.ndarray:
    """
    Return the indices of ``names`` in the joint set ``joints``; :class:`JointNameError` if not.

    Each name must be known and named once, and at least one must be given; ``what``
    names the request in the reason.
    """
    joints = list(joints)
    if len(names) == 0:
        raise JointNameError(f'{what} names no joint: give a subset of {joints}')
    seen = set()
    indices = []
    for name in names:
        if name not in joints:
            raise JointNameError(f'{what} names unknown joint {name!r}; known joints: '
                                 f'{joints}')
        if name in seen:
            raise JointNameError(f'{what} names joint {name!r} more than once')
        seen.add(name)
        indices.append(joints.index(name))
    return np.asarray(indices, dtype=int)


def check_no_effort(efforts: Sequence[Sequence[float]], what: str) -> None:
    """
    Refuse points that carry ``effort``: the node commands positions (and velocities) only.

    As ``joint_trajectory_controller`` refuses them without an effort command interface.
    ``efforts`` are the points' ``effort`` fields, in order.
    """
    for number, effort in enumerate(efforts):
        if len(effort):
            raise RequestError(f'{what} point {number} has {len(effort)} effort values: this '
                               'node commands positions only (no effort command interface); '
                               'leave effort empty')


def _finite_row(values: Sequence[float], names: Sequence[str], what: str) -> np.ndarray:
    row = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(row))
    if bad.size:
        index = bad[0]
        raise RequestError(f'{what} for joint {names[index]!r} is {row[index]}: '
                           f'every value must be finite')
    return row


def parse_goal(joints: Sequence[str], names: Sequence[str],
               positions: Sequence[float]) -> GoalRequest:
    """Check a goal (``JointState`` name/position fields) against the joint set."""
    joints = list(joints)
    indices = joint_indices(joints, list(names), 'goal')
    if len(positions) != len(names):
        raise RequestError(f'goal has {len(names)} names but {len(positions)} positions: '
                           f'give exactly one position per name')
    return GoalRequest(indices, _finite_row(positions, list(names), 'goal position'))


def parse_via(joints: Sequence[str], names: Sequence[str],
              points: Sequence[ViaPoint], what: str = 'via_points') -> ViaRequest:
    """
    Check via points given as ``(positions, velocities, accelerations, time_from_start)``.

    Velocities and accelerations are boundary conditions: each is given for every point
    (with one value per name) or for none, as ``joint_trajectory_controller`` requires.
    ``what`` names the request in the reasons (``via_points``, or an action goal's).
    """
    joints = list(joints)
    names = list(names)
    indices = joint_indices(joints, names, what)
    if len(points) == 0:
        raise RequestError(f'{what} has no points: give at least one point')
    if len(points) > MAX_VIA_POINTS:
        raise RequestError(too_many_points(len(points)))
    count = len(names)
    positions, velocities, accelerations, times = [], [], [], []
    for number, (pos, vel, acc, time) in enumerate(points):
        where = f'point {number}'
        if len(pos) != count:
            raise RequestError(f'{where} has {len(pos)} positions but joint_names has '
                               f'{count}: give one position per joint name')
        for field, values, store in (('velocities', vel, velocities),
                                     ('accelerations', acc, accelerations)):
            if len(values) not in (0, count):
                raise RequestError(f'{where} has {len(values)} {field} but joint_names has '
                                   f'{count}: give one per joint name or leave it empty')
            if len(values):
                store.append(_finite_row(values, names, f'{where} {field[:-3]}y'))
        positions.append(_finite_row(pos, names, f'{where} position'))
        if not math.isfinite(time) or time < 0.0:
            raise RequestError(f'{where} has time_from_start {time} s: must be >= 0')
        if time > MAX_DURATION:
            raise RequestError(f'{where} has time_from_start {time:g} s, above the limit of '
                               f'{MAX_DURATION:g} s')
        times.append(time)
    for field, store in (('velocities', velocities), ('accelerations', accelerations)):
        if store and len(store) != len(points):
            raise RequestError(f'{field} are given for {len(store)} of {len(points)} points: '
                               f'give them for every point or for none')
    if accelerations and not velocities:
        raise RequestError('accelerations are given without velocities: give both or '
                           'velocities only')
    times_array = np.asarray(times, dtype=float)
    auto = bool(np.all(times_array == 0.0))
    if not auto:
        steps = np.diff(times_array)
        bad = np.flatnonzero(steps <= 0.0)
        if bad.size:
            index = bad[0] + 1
            raise RequestError(f'time_from_start must be strictly increasing: point {index} '
                               f'({times_array[index]:g} s) is not after point {index - 1} '
                               f'({times_array[index - 1]:g} s)')
    return ViaRequest(indices, times_array, np.asarray(positions),
                      np.asarray(velocities) if velocities else None,
                      np.asarray(accelerations) if accelerations else None, auto)


def seconds(duration: object) -> float:
    """Return a ``builtin_interfaces/Duration`` (``sec``, ``nanosec``) in seconds."""
    return duration.sec + duration.nanosec * 1e-9


def too_many_points(count: int) -> str:
    """Give the refusal of a request with ``count`` > :data:`MAX_VIA_POINTS` points."""
    return (f'via_points has {count} points, above the limit of {MAX_VIA_POINTS}: split the '
            'path into several requests')
