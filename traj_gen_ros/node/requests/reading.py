"""
Step 2 of a request, *read*: a serialised message into a :class:`Request`, or its refusal.

``~/goal`` (``sensor_msgs/JointState``, its fields read off the CDR bytes), ``~/via_points``
(``trajectory_msgs/JointTrajectory``, its point count read before it is built) and
``~/pose_goal`` (``geometry_msgs/PoseStamped``), ``~/cartesian_path`` and ``~/circular_goal``
(``nav_msgs/Path``). A malformed request is answered ERROR at once and changes nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from geometry_msgs.msg import Pose, PoseStamped
from nav_msgs.msg import Path
import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.core.kinematics import pose_matrix
from traj_gen_ros.node.messages.parsing import (
    check_no_effort,
    MAX_VIA_POINTS,
    parse_goal,
    parse_via,
    RequestError,
    seconds,
    too_many_points,
)
from traj_gen_ros.node.messages.wire import peek_path_poses, peek_via_points, read_goal
from traj_gen_ros.node.planning.pose_goal import PoseRequest
from traj_gen_ros.node.planning.tool_motion import CIRCULAR_GOAL, ToolPathRequest
from traj_gen_ros.node.requests.answers import Answers
from traj_gen_ros.node.requests.request import Request
from trajectory_msgs.msg import JointTrajectory


def goal_request(data: bytes, received: int, joints: Sequence[str],
                 answers: Answers) -> Request | None:
    """
    Read a serialised goal into a :class:`Request`, or refuse it (ERROR) and return ``None``.

    ``received`` (ns, system clock) goes into its answers; ``joints`` is the joint set.
    """
    fields = read_goal(data)
    if fields is None:  # not the usual little-endian CDR: let rclpy read it
        try:
            message = deserialize_message(data, JointState)
        except Exception as error:  # noqa: BLE001 - wire bytes must never kill the node
            answers.refused(Request('goal', answers.values('goal', '', received), 0, None),
                            f'malformed message: {error}')
            return None
        fields = message.header.frame_id, message.name, message.position
    frame_id, names, positions = fields
    request = Request('goal', answers.values('goal', frame_id, received), 0, None)
    try:
        request.parsed = parse_goal(joints, names, positions)
    except RequestError as error:
        answers.refused(request, str(error))
        return None
    return request


def via_request(data: bytes, received: int, joints: Sequence[str],
                answers: Answers) -> Request | None:
    """:func:`goal_request` for a serialised ``JointTrajectory``; a huge one is not built."""
    frame_id, count = peek_via_points(data)
    values = answers.values('via_points', frame_id, received)
    if count > MAX_VIA_POINTS:  # refused before one Python object per point is made
        answers.refused(Request('via_points', values, 0, None), too_many_points(count))
        return None
    try:
        message = deserialize_message(data, JointTrajectory)
    except Exception as error:  # noqa: BLE001 - bytes from the wire must never kill the node
        answers.refused(Request('via_points', values, 0, None), f'malformed message: {error}')
        return None
    stamp = message.header.stamp
    stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec  # 0 or past: "now"
    request = Request('via_points', values, stamp_ns, None)
    points = [(p.positions, p.velocities, p.accelerations, seconds(p.time_from_start))
              for p in message.points]
    try:
        check_no_effort([p.effort for p in message.points], 'via_points')
        request.parsed = parse_via(joints, message.joint_names, points)
    except RequestError as error:
        answers.refused(request, str(error))
        return None
    return request


def pose_request(data: bytes, received: int, joints: Sequence[str],
                 answers: Answers) -> Request | None:
    """
    :func:`goal_request` for a serialised ``PoseStamped``: the tool pose to reach.

    Its quaternion must have norm 1 within 1e-3 (then it is normalised); what the pose is
    relative to (``header.frame_id``) is resolved when it is planned
    (:mod:`traj_gen_ros.node.planning.pose_goal`).
    """
    del joints  # every joint of the chain moves
    try:
        message = deserialize_message(data, PoseStamped)
    except Exception as error:  # noqa: BLE001 - bytes from the wire must never kill the node
        answers.refused(Request('pose_goal', answers.values('pose_goal', '', received), 0,
                                None), f'malformed message: {error}')
        return None
    frame_id = message.header.frame_id
    values = answers.values('pose_goal', frame_id, received)
    stamp = message.header.stamp
    request = Request('pose_goal', values, stamp.sec * 1_000_000_000 + stamp.nanosec, None)
    try:
        pose = _matrix(message.pose)
    except ValueError as error:
        answers.refused(request, f'pose: {error}')
        return None
    request.parsed = PoseRequest(frame_id, pose, values)
    return request


#: Most poses one ``~/cartesian_path`` may have.
MAX_PATH_POSES = 1000


#: Largest |coordinate| (m) of a pose: beyond any arm's reach, and far from float64's range.
MAX_COORDINATE = 1.0e4


def _matrix(pose: Pose) -> np.ndarray:
    """Return a message's pose as ``(4, 4)``; its quaternion checked (norm 1 within 1e-3)."""
    position, orientation = pose.position, pose.orientation
    values = (position.x, position.y, position.z)
    if not all(abs(value) <= MAX_COORDINATE for value in values):  # NaN fails too
        raise ValueError(f'position ({", ".join(f"{v:g}" for v in values)}) m: each '
                         f'coordinate must be finite and at most {MAX_COORDINATE:g} m')
    return pose_matrix([position.x, position.y, position.z],
                       [orientation.x, orientation.y, orientation.z, orientation.w])


def tool_path_request(kind: str) -> Callable[[bytes, int, Sequence[str], Answers],
                                             Request | None]:
    """
    Return the reader of ``kind`` (``cartesian_path`` or ``circular_goal``): a ``nav_msgs/Path``.

    The path's ``header.frame_id`` applies to every pose; a pose's own non-empty
    ``frame_id`` must be the same, else the request is refused naming the pose. Each
    quaternion as for pose goals. ``~/circular_goal`` takes exactly two poses (the interim
    point and the goal), ``~/cartesian_path`` one to :data:`MAX_PATH_POSES`.
    """
    def read(data: bytes, received: int, joints: Sequence[str],
             answers: Answers) -> Request | None:
        del joints  # every joint of the chain moves
        frame_id, count = peek_path_poses(data)
        if count > MAX_PATH_POSES:  # refused before one Python object per pose is made
            answers.refused(Request(kind, answers.values(kind, frame_id, received), 0, None),
                            f'{kind} has {count} poses: give 1 to {MAX_PATH_POSES}')
            return None
        try:
            message = deserialize_message(data, Path)
        except Exception as error:  # noqa: BLE001 - wire bytes must never kill the node
            answers.refused(Request(kind, answers.values(kind, '', received), 0, None),
                            f'malformed message: {error}')
            return None
        frame_id = message.header.frame_id
        stamp = message.header.stamp
        request = Request(kind, answers.values(kind, frame_id, received),
                          stamp.sec * 1_000_000_000 + stamp.nanosec, None)
        try:
            poses = _path_poses(kind, frame_id, message.poses)
        except ValueError as error:
            answers.refused(request, str(error))
            return None
        request.parsed = ToolPathRequest(kind, frame_id, poses, request.values)
        return request
    return read


def _path_poses(kind: str, frame_id: str, stamped: Sequence[PoseStamped]
                ) -> tuple[np.ndarray, ...]:
    """Read a Path's poses, each checked; ``ValueError`` naming the pose."""
    count = len(stamped)
    if kind == CIRCULAR_GOAL and count != 2:
        raise ValueError(f'circular_goal has {count} poses: give exactly two, the interim '
                         'point and the goal')
    if not 1 <= count <= MAX_PATH_POSES:
        raise ValueError(f'cartesian_path has {count} poses: give 1 to {MAX_PATH_POSES}')
    poses = []
    for index, pose in enumerate(stamped):
        own = pose.header.frame_id
        if own and own != frame_id:
            raise ValueError(f'poses[{index}] has frame_id {own!r} but the path has '
                             f'{frame_id!r}: leave it empty or give the same frame')
        try:
            poses.append(_matrix(pose.pose))
        except ValueError as error:
            raise ValueError(f'poses[{index}]: {error}') from None
    return tuple(poses)
