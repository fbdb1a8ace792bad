"""
Step 1 of a request, *parse*: message fields into a checked request (no ROS here).

:func:`parse_goal` turns the ``name``/``position`` fields of a ``sensor_msgs/JointState``
into a :class:`GoalRequest`; :func:`parse_via` turns the points of a
``trajectory_msgs/JointTrajectory`` into a :class:`ViaRequest`. Each check that fails
raises :class:`RequestError` saying what is wrong and what is valid: known joints, each
named once, matching lengths, finite numbers, strictly increasing times, bounded sizes.
:func:`peek_via_points` reads a message's point count off the wire, so a huge message is
refused before it is deserialised.

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math
import struct

import numpy as np

#: Most via points one request may carry (planning time grows with the count).
MAX_VIA_POINTS = 1000
#: Longest plan (and largest ``time_from_start``) accepted, seconds.
MAX_DURATION = 3600.0

#: One via point as read from the message: positions, velocities, accelerations, time (s).
ViaPoint = tuple[Sequence[float], Sequence[float], Sequence[float], float]


class RequestError(ValueError):
    """A request the generator refuses; ``str(error)`` says what is wrong and what is valid."""


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


def _joint_indices(joints: Sequence[str], names: Sequence[str], what: str) -> np.ndarray:
    if len(names) == 0:
        raise RequestError(f'{what} names no joint: give a subset of {list(joints)}')
    seen = set()
    indices = []
    for name in names:
        if name in seen:
            raise RequestError(f'{what} names joint {name!r} more than once')
        seen.add(name)
        if name not in joints:
            raise RequestError(f'{what} names unknown joint {name!r}; known joints: '
                               f'{list(joints)}')
        indices.append(joints.index(name))
    return np.asarray(indices, dtype=int)


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
    indices = _joint_indices(joints, list(names), 'goal')
    if len(positions) != len(names):
        raise RequestError(f'goal has {len(names)} names but {len(positions)} positions: '
                           f'give exactly one position per name')
    return GoalRequest(indices, _finite_row(positions, list(names), 'goal position'))


def parse_via(joints: Sequence[str], names: Sequence[str],
              points: Sequence[ViaPoint]) -> ViaRequest:
    """
    Check via points given as ``(positions, velocities, accelerations, time_from_start)``.

    Velocities and accelerations are boundary conditions: each is given for every point
    (with one value per name) or for none, as ``joint_trajectory_controller`` requires.
    """
    joints = list(joints)
    names = list(names)
    indices = _joint_indices(joints, names, 'via_points')
    if len(points) == 0:
        raise RequestError('via_points has no points: give at least one point')
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


def too_many_points(count: int) -> str:
    """Give the refusal of a request with ``count`` > :data:`MAX_VIA_POINTS` points."""
    return (f'via_points has {count} points, above the limit of {MAX_VIA_POINTS}: split the '
            'path into several requests')


def _string(data: bytes, offset: int, errors: str = 'strict') -> tuple[str, int]:
    """
    Read the CDR string at ``offset`` (from the end of the encapsulation header).

    Returns it (UTF-8, decoded with ``errors``) and the offset after it.
    """
    offset = (offset + 3) & ~3
    (length,) = struct.unpack_from('<I', data, 4 + offset)
    if 4 + offset + 4 + length > len(data):
        raise ValueError('string runs past the end of the message')
    text = data[4 + offset + 4:4 + offset + 4 + max(length - 1, 0)].decode('utf-8', errors)
    return text, offset + 4 + length


def _count(data: bytes, offset: int) -> tuple[int, int]:
    """Read the ``uint32`` sequence length at ``offset``, aligned to 4."""
    offset = (offset + 3) & ~3
    return struct.unpack_from('<I', data, 4 + offset)[0], offset + 4


def read_goal(data: bytes) -> tuple[str, list[str], np.ndarray] | None:
    """
    Read ``header.frame_id``, ``name`` and ``position`` of a CDR ``JointState``.

    Little-endian CDR (encapsulation ``00 01``, as rmw_fastrtps writes it), after the
    4-byte encapsulation header: stamp (2 x 4 bytes), ``frame_id`` (uint32 length with
    the NUL, bytes), ``name`` (uint32 count, strings), ``position`` (uint32 count, then
    float64s aligned to 8); ``velocity`` and ``effort`` follow. Each uint32 is aligned to
    4 from the end of the encapsulation header. ``None`` where the bytes are not that
    (another encapsulation, cut short, not UTF-8): the caller deserialises those. Reading
    the three fields costs a few microseconds; an rclpy message, tens.
    """
    if data[:2] != b'\x00\x01':
        return None
    try:
        frame_id, offset = _string(data, 8)
        count, offset = _count(data, offset)
        names = []
        for _ in range(count):
            name, offset = _string(data, offset)
            names.append(name)
        count, offset = _count(data, offset)
        offset = (offset + 7) & ~7 if count else offset
        positions = np.frombuffer(data, '<f8', count, 4 + offset).astype(float)
    except (ValueError, struct.error):  # UnicodeDecodeError is a ValueError
        return None
    return frame_id, names, positions


def peek_via_points(data: bytes) -> tuple[str, int]:
    """
    Read ``header.frame_id`` and the number of points of a CDR ``JointTrajectory``.

    Layout after the 4-byte encapsulation header: stamp (2 x 4 bytes), ``frame_id``
    (uint32 length with the NUL, bytes), ``joint_names`` (uint32 count, strings), then the
    uint32 point count; each uint32 aligned to 4 from the end of the encapsulation header.
    A message too short to hold them gives ``('', 0)``: deserialising it then refuses it.
    """
    try:
        frame_id, offset = _string(data, 8, 'replace')
        names, offset = _count(data, offset)
        for _ in range(names):
            offset = _string(data, offset, 'replace')[1]
        count = _count(data, offset)[0]
    except (ValueError, struct.error):
        return '', 0
    return frame_id, count
