"""
Step 6 of a request, *answer*: ``~/status`` and, for an accepted plan, ``~/trajectory``.

Every request gets exactly one answer on ``~/status`` (``diagnostic_msgs/DiagnosticStatus``,
its ``values`` carry ``request``, ``request_id`` and ``frame_id`` so a client can match
it): OK when accepted (with profile, duration and start delay), ERROR with the reason when
refused, WARN when a newer request superseded it before it was planned. The requests a
newer one superseded are answered together, in one status listing them, just before the
newer one's own answer: under a flood one status per batch instead of one per request,
and no request is answered after a newer one.

An accepted plan is published on ``~/trajectory`` sampled every ``1/rate_hz`` s, written
straight to CDR from the sample arrays (:mod:`traj_gen_ros.node.messages.wire`); a line's
or an arc's tool path on ``~/tool_path`` (``nav_msgs/Path``, latched: RViz shows it before
and while the arm moves), written to CDR too.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import json

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from nav_msgs.msg import Path
import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from traj_gen_ros.core.kinematics import pose_quaternion
from traj_gen_ros.node.messages.wire import joint_trajectory_cdr, path_cdr
from traj_gen_ros.node.planning.motion import PlannedMotion
from traj_gen_ros.node.planning.sampling import sample_motion
from traj_gen_ros.node.requests.request import Request
from trajectory_msgs.msg import JointTrajectory

#: Depth of the status publisher: a burst of answers is kept for slow readers.
STATUS_DEPTH = 1000


class Answers:
    """The ``~/status`` and ``~/trajectory`` publishers and what goes on them."""

    def __init__(self, node: Node, joint_names: Callable[[], Sequence[str]]) -> None:
        """Create the ``~/trajectory`` and ``~/status`` publishers."""
        self._node = node
        self._joint_names = joint_names
        self._received = 0
        self._superseded: list[Request] = []
        self._tool_path_shown = False  # whether ~/tool_path holds a path now
        reliable = ReliabilityPolicy.RELIABLE
        self._trajectory = node.create_publisher(
            JointTrajectory, '~/trajectory',
            QoSProfile(depth=1, reliability=reliable, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._status = node.create_publisher(
            DiagnosticStatus, '~/status', QoSProfile(depth=STATUS_DEPTH, reliability=reliable))
        self._tool_path = node.create_publisher(
            Path, '~/tool_path',
            QoSProfile(depth=1, reliability=reliable, durability=DurabilityPolicy.TRANSIENT_LOCAL))

    def values(self, kind: str, frame_id: str, received: int = 0) -> dict[str, str]:
        """
        Give a new request its id; return the values every answer to it carries.

        ``received`` (ns since the epoch, system clock) is when DDS received the request;
        0 (a service call) leaves it out.
        """
        self._received += 1
        values = {'request': kind, 'request_id': str(self._received), 'frame_id': frame_id}
        if received:
            values['received'] = str(received)
        return values

    def trajectory(self, start_ns: int, motion: PlannedMotion, rate_hz: float) -> bytes:
        """
        Sample the plan every ``1/rate_hz`` s into a ``JointTrajectory`` (CDR bytes).

        From its start, stamped ``start_ns``: ``time_from_start`` is time into the plan, as
        a via request gives it, and the first point is the state it was planned from. That
        is the tick where the stream takes it over, or, for a plan planned again from the
        setpoint published last, that setpoint (the plan continues it, and the stream's
        first setpoint from it is the next tick). Raises
        :class:`~traj_gen_ros.node.messages.parsing.RequestError` if a sample is not finite.
        """
        times, positions, velocities, accelerations = sample_motion(motion, rate_hz)
        time_ns = np.round(times * 1e9).astype(np.int64)
        return joint_trajectory_cdr(start_ns, list(self._joint_names()), time_ns, positions,
                                    velocities, accelerations)

    def publish_trajectory(self, message: bytes) -> None:
        """Publish an accepted plan's ``~/trajectory`` (from :meth:`trajectory`)."""
        self._trajectory.publish(message)

    def publish_tool_path(self, start_ns: int, motion: PlannedMotion, frame_id: str) -> None:
        """
        Publish a line's or an arc's tool path (poses in ``frame_id``), stamped ``start_ns``.

        Any other motion that replaces one publishes an empty path once: the latched path
        is no longer the one the arm follows. Written straight to CDR (an rclpy ``Path``
        took 0.3–0.8 ms for three poses in the node while the stream ran).
        """
        if motion.tool_poses is None and not self._tool_path_shown:
            return
        self._tool_path_shown = motion.tool_poses is not None
        # The core's tool path made these poses: rigid transforms, not checked again.
        poses = [pose_quaternion(pose, checked=True) for pose in
                 (() if motion.tool_poses is None else motion.tool_poses)]
        self._tool_path.publish(path_cdr(start_ns, frame_id, [p for p, _ in poses],
                                         [q for _, q in poses]))

    def accepted(self, request: Request, motion: PlannedMotion, now_ns: int,
                 first_ns: int) -> None:
        """Answer OK with the plan's profile, duration and delay to its first setpoint."""
        self._answer_superseded()
        duration = motion.plan.duration
        joints = len(self._joint_names())
        text = f'accepted: profile={motion.profile}, duration={duration:.3f} s, joints={joints}'
        delay = (first_ns - now_ns) * 1e-9
        if request.stamp_ns > now_ns and request.stamp_ns == first_ns:
            text += f', starts in {delay:.3f} s'
        if motion.note:
            text += f' ({motion.note})'
        self.report(DiagnosticStatus.OK, text, {
            **request.values, 'profile': motion.profile, 'duration': f'{duration:.6f}',
            'joints': str(joints), 'start_delay': f'{delay:.6f}'})

    def refused(self, request: Request, reason: str) -> None:
        """Answer ERROR: ``<kind> refused: <reason>`` (kept in ``request.refusal``)."""
        request.refusal = reason
        self._answer_superseded()
        self.report(DiagnosticStatus.ERROR, f'{request.kind} refused: {reason}', request.values)

    def superseded(self, requests: list[Request]) -> None:
        """Answer ``requests`` as superseded, together, before the next request's answer."""
        self._superseded += requests

    def _answer_superseded(self) -> None:
        requests, self._superseded = self._superseded, []
        if len(requests) == 1:
            self.report(DiagnosticStatus.WARN, f'{requests[0].kind} superseded by a newer '
                        'request before it was planned: not executed', requests[0].values,
                        log=False)
        elif requests:
            kinds = sorted({request.kind for request in requests})
            self.report(DiagnosticStatus.WARN, f'{len(requests)} requests superseded by a '
                        'newer request before they were planned: not executed', {
                            'request': ','.join(kinds), 'superseded': str(len(requests)),
                            'request_ids': json.dumps([int(r.values['request_id'])
                                                       for r in requests]),
                            'frame_ids': json.dumps([r.values['frame_id'] for r in requests])},
                        log=False)

    def report(self, level: bytes, text: str, values: dict[str, str], log: bool = True) -> None:
        """Publish one ``~/status``; log it too unless it is OK or ``log`` is False."""
        if log and level != DiagnosticStatus.OK:
            self._node.get_logger().warning(text)
        self._status.publish(DiagnosticStatus(
            level=level, name=self._node.get_fully_qualified_name(), message=text,
            values=[KeyValue(key=key, value=value) for key, value in values.items()]))
