"""
The messages the node reads and writes in CDR, with numpy: its wire format in and out.

Out: ``JointTrajectory``, ``JointState``, ``Float64MultiArray``, ``PoseStamped`` and
``nav_msgs/Path``. In: a goal's
``frame_id``, names and positions (:func:`read_goal`), the measured state of
``joint_topic`` (the same and its velocities: :func:`read_joint_state`), and a via
request's point count (:func:`peek_via_points`), so a huge message is refused before
it is deserialised.

Building a 1000-point ``JointTrajectory`` as rclpy message objects costs tens of
milliseconds (one Python object per point, one check per float). Its wire form is plain:
little-endian CDR (XCDR1, as rmw_fastrtps writes it) where every point of an ``n``-joint
plan has the same layout. The stream's ``JointState`` is small but sent 100s of times a
second: its bytes cost a few microseconds here against tens as an rclpy message. This
module writes those bytes directly; rclpy's
``Publisher.publish`` sends ``bytes`` as they are. No ROS import: the layout is the
message definition's, checked field by field against ``rclpy.serialization`` in the tests.

CDR rules used: a 4-byte encapsulation header (``00 01 00 00``: CDR, little endian), then
every primitive aligned to its size relative to the end of that header; a string is a
``uint32`` length (with the terminating NUL) and its bytes; a sequence is a ``uint32``
count and its elements.
"""

from __future__ import annotations

from collections.abc import Sequence
import struct

import numpy as np

_ENCAPSULATION = b'\x00\x01\x00\x00'
_NANOSECONDS_PER_SECOND = 1_000_000_000


def _point_dtype(joint_count: int, starts_on_eight: bool,
                 with_accelerations: bool = True) -> np.dtype:
    """
    Give the packed layout of one ``JointTrajectoryPoint``.

    A point starting 8-aligned pads after its first count; one starting 4 past an
    8-boundary does not. Either way each double array lands 8-aligned. Effort is empty,
    and so are accelerations unless ``with_accelerations``.
    """
    doubles = ('<f8', (joint_count,))
    fields = [('positions_count', '<u4')]
    if starts_on_eight:
        fields.append(('positions_pad', '<u4'))
    fields += [('positions', *doubles),
               ('velocities_count', '<u4'), ('velocities_pad', '<u4'),
               ('velocities', *doubles)]
    if with_accelerations:
        fields += [('accelerations_count', '<u4'), ('accelerations_pad', '<u4'),
                   ('accelerations', *doubles)]
    else:
        fields += [('accelerations_count', '<u4')]
    fields += [('effort_count', '<u4'), ('sec', '<i4'), ('nanosec', '<u4')]
    return np.dtype(fields)


def _write_string(text: str, offset: int) -> bytes:
    """
    Encode a CDR string written at payload ``offset`` (a multiple of 4).

    Cut at the first NUL, as rclpy's conversion to a C string cuts it, so the bytes match
    what ``serialize_message`` writes for the same text.
    """
    encoded = text.split('\x00', 1)[0].encode() + b'\x00'
    padding = (-(offset + 4 + len(encoded))) % 4
    return len(encoded).to_bytes(4, 'little') + encoded + b'\x00' * padding


def joint_trajectory_cdr(
    stamp_ns: int,
    joint_names: Sequence[str],
    time_from_start_ns: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    accelerations: np.ndarray | None,
    frame_id: str = '',
) -> bytes:
    """
    Serialise a ``JointTrajectory`` whose points are rows of ``(points, joints)`` arrays.

    :param stamp_ns: ``header.stamp`` in nanoseconds.
    :param joint_names: the joint names, in column order.
    :param time_from_start_ns: each point's ``time_from_start`` in nanoseconds, ``(points,)``.
    :param positions: rad, ``(points, joints)``; likewise velocities (rad/s) and
        accelerations (rad/s²; ``None``: left empty, as effort is).
    :param frame_id: ``header.frame_id``.
    """
    seconds, nanoseconds = divmod(int(stamp_ns), _NANOSECONDS_PER_SECOND)
    head = bytearray(seconds.to_bytes(4, 'little', signed=True)
                     + nanoseconds.to_bytes(4, 'little'))
    head += _write_string(frame_id, len(head))
    head += len(joint_names).to_bytes(4, 'little')
    for name in joint_names:
        head += _write_string(name, len(head))
    point_count, joint_count = positions.shape
    head += point_count.to_bytes(4, 'little')
    if point_count == 0:
        return _ENCAPSULATION + bytes(head)
    first_on_eight = len(head) % 8 == 0
    with_accelerations = accelerations is not None
    first = np.zeros(1, _point_dtype(joint_count, first_on_eight, with_accelerations))
    # Every later point starts where the first ended (each has a multiple of 8 bytes).
    rest_on_eight = (len(head) + first.itemsize) % 8 == 0
    rest = np.zeros(point_count - 1,
                    _point_dtype(joint_count, rest_on_eight, with_accelerations))
    time_ns = np.asarray(time_from_start_ns, dtype=np.int64)
    if time_ns.min() < 0 or time_ns.max() >= 2**31 * _NANOSECONDS_PER_SECOND:
        raise ValueError('time_from_start must lie in [0, 2**31) s to fit a Duration message')
    for points, rows in ((first, slice(0, 1)), (rest, slice(1, None))):
        for field, values in (('positions', positions), ('velocities', velocities),
                              ('accelerations', accelerations)):
            if values is not None:
                points[f'{field}_count'] = joint_count
                points[field] = values[rows]
        points['sec'], points['nanosec'] = np.divmod(time_ns[rows], _NANOSECONDS_PER_SECOND)
    return _ENCAPSULATION + bytes(head) + first.tobytes() + rest.tobytes()


def float64_multi_array_cdr(data: np.ndarray) -> bytes:
    """
    Serialise a ``std_msgs/Float64MultiArray`` with an empty layout and ``data``.

    Layout: ``layout.dim`` (uint32 count 0), ``layout.data_offset`` (uint32 0), ``data``
    (uint32 count, 4 bytes of padding to the 8-aligned float64s).
    """
    values = np.asarray(data, dtype='<f8')
    return b''.join((_ENCAPSULATION, b'\x00' * 8, len(values).to_bytes(4, 'little'),
                     b'\x00' * 4, values.tobytes()))


def joint_state_cdr(stamp_ns: int, names_cdr: bytes, position: np.ndarray,
                    velocity: np.ndarray) -> bytes:
    """
    Serialise a ``sensor_msgs/JointState`` with positions and velocities (effort empty).

    :param stamp_ns: ``header.stamp`` in nanoseconds.
    :param names_cdr: the empty ``frame_id`` and ``name`` as :func:`joint_names_cdr` wrote
        them (they do not change between messages).
    :param position: rad, ``(joints,)``; ``velocity`` rad/s, ``(joints,)``.
    """
    seconds, nanoseconds = divmod(int(stamp_ns), _NANOSECONDS_PER_SECOND)
    count = len(position)
    # position's count lands on a 4-boundary: pad to 8 if it is not 4 past an 8-boundary.
    pad = b'\x00' * 4 if (8 + len(names_cdr)) % 8 == 0 else b''
    count_bytes = count.to_bytes(4, 'little')
    return b''.join((
        _ENCAPSULATION, seconds.to_bytes(4, 'little', signed=True),
        nanoseconds.to_bytes(4, 'little'), names_cdr, count_bytes, pad,
        np.asarray(position, dtype='<f8').tobytes(), count_bytes, b'\x00' * 4,
        np.asarray(velocity, dtype='<f8').tobytes(), b'\x00' * 8))  # effort: 0, padding


def joint_names_cdr(joint_names: Sequence[str]) -> bytes:
    """Encode the empty ``frame_id`` and the ``name`` of a ``JointState``, without stamp."""
    head = bytearray(8)  # the stamp, written per message
    head += _write_string('', len(head))
    head += len(joint_names).to_bytes(4, 'little')
    for name in joint_names:
        head += _write_string(name, len(head))
    return bytes(head[8:])


def _read_string(data: bytes, offset: int, errors: str = 'strict') -> tuple[str, int]:
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


def _read_count(data: bytes, offset: int) -> tuple[int, int]:
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
    fields = read_joint_state(data)
    return None if fields is None else fields[:3]


def read_joint_state(data: bytes) -> tuple[str, list[str], np.ndarray, np.ndarray] | None:
    """
    Read ``header.frame_id``, ``name``, ``position`` and ``velocity`` of a CDR ``JointState``.

    As :func:`read_goal`, and ``velocity`` after the positions (uint32 count, float64s
    aligned to 8; often empty: a driver that reports none).
    """
    if data[:2] != b'\x00\x01':
        return None
    try:
        frame_id, offset = _read_string(data, 8)
        count, offset = _read_count(data, offset)
        names = []
        for _ in range(count):
            name, offset = _read_string(data, offset)
            names.append(name)
        positions, offset = _read_doubles(data, offset)
        velocities, offset = _read_doubles(data, offset)
    except (ValueError, struct.error):  # UnicodeDecodeError is a ValueError
        return None
    return frame_id, names, positions, velocities


def _read_doubles(data: bytes, offset: int) -> tuple[np.ndarray, int]:
    """Read a CDR ``float64[]`` at ``offset`` (from the encapsulation's end); ValueError."""
    count, offset = _read_count(data, offset)
    offset = (offset + 7) & ~7 if count else offset
    values = np.frombuffer(data, '<f8', count, 4 + offset).astype(float)
    return values, offset + 8 * count


def peek_via_points(data: bytes) -> tuple[str, int]:
    """
    Read ``header.frame_id`` and the number of points of a CDR ``JointTrajectory``.

    Layout after the 4-byte encapsulation header: stamp (2 x 4 bytes), ``frame_id``
    (uint32 length with the NUL, bytes), ``joint_names`` (uint32 count, strings), then the
    uint32 point count; each uint32 aligned to 4 from the end of the encapsulation header.
    A message too short to hold them gives ``('', 0)``: deserialising it then refuses it.
    """
    try:
        frame_id, offset = _read_string(data, 8, 'replace')
        names, offset = _read_count(data, offset)
        for _ in range(names):
            offset = _read_string(data, offset, 'replace')[1]
        count = _read_count(data, offset)[0]
    except (ValueError, struct.error):
        return '', 0
    return frame_id, count


def peek_path_poses(data: bytes) -> tuple[str, int]:
    """
    Read ``header.frame_id`` and the number of poses of a CDR ``nav_msgs/Path``.

    Its header as :func:`peek_via_points` reads it, then the uint32 pose count. A message
    too short to hold them gives ``('', 0)``.
    """
    try:
        frame_id, offset = _read_string(data, 8, 'replace')
        count = _read_count(data, offset)[0]
    except (ValueError, struct.error):
        return '', 0
    return frame_id, count


def factor_cdr(factor: float) -> bytes:
    """Serialise a ``control_msgs/SpeedScalingFactor`` (one float64) to CDR bytes."""
    return _ENCAPSULATION + struct.pack('<d', factor)


def pose_stamped_cdr(stamp_ns: int, frame_id: str, position: np.ndarray,
                     quaternion: np.ndarray) -> bytes:
    """
    Serialise a ``geometry_msgs/PoseStamped``: ``position`` (m), ``quaternion`` (x, y, z, w).

    :param stamp_ns: ``header.stamp`` in nanoseconds.
    """
    seconds, nanoseconds = divmod(int(stamp_ns), _NANOSECONDS_PER_SECOND)
    frame = _write_string(frame_id, 8)
    pad = b'\x00' * ((-(8 + len(frame))) % 8)  # the doubles on an 8-boundary
    return b''.join((_ENCAPSULATION, seconds.to_bytes(4, 'little', signed=True),
                     nanoseconds.to_bytes(4, 'little'), frame, pad,
                     np.asarray(position, dtype='<f8').tobytes(),
                     np.asarray(quaternion, dtype='<f8').tobytes()))


def path_cdr(stamp_ns: int, frame_id: str, positions: np.ndarray,
             quaternions: np.ndarray) -> bytes:
    """
    Serialise a ``nav_msgs/Path``: ``positions`` (m, ``(poses, 3)``), ``quaternions`` (x, y, z, w).

    Every pose's header is the path's (``stamp_ns`` in nanoseconds, ``frame_id``). Layout:
    the header, the uint32 pose count, then each ``PoseStamped`` (:func:`pose_stamped_cdr`'s
    fields, aligned from where it starts: the first after the count, each later one on an
    8-boundary where the one before ended). An rclpy ``Path`` costs tens of microseconds
    per pose to build and convert; this, a few.
    """
    seconds, nanoseconds = divmod(int(stamp_ns), _NANOSECONDS_PER_SECOND)
    stamp = seconds.to_bytes(4, 'little', signed=True) + nanoseconds.to_bytes(4, 'little')
    points = np.asarray(positions, dtype='<f8').reshape(-1, 3)
    rotations = np.asarray(quaternions, dtype='<f8').reshape(-1, 4)
    head = bytearray(stamp)
    head += _write_string(frame_id, len(head))
    head += len(points).to_bytes(4, 'little')
    parts, offset = [_ENCAPSULATION, bytes(head)], len(head)
    for point, rotation in zip(points, rotations, strict=True):
        header = stamp + _write_string(frame_id, offset + 8)
        pad = b'\x00' * ((-(offset + len(header))) % 8)  # the doubles on an 8-boundary
        parts += [header, pad, point.tobytes(), rotation.tobytes()]
        offset += len(header) + len(pad) + 56
    return b''.join(parts)
