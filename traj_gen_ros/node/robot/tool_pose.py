"""
``~/tool_pose``: the setpoint's tool pose in ``base_frame``, at the stream rate.

Published (``geometry_msgs/PoseStamped``, reliable, depth 10, as ``joint_states``) right
after each setpoint while a kinematic chain is in force and ``publish_tool_pose`` is true,
so ``ros2 topic echo`` shows where the tool is. Forward kinematics on the stream thread's
own chain (:meth:`RobotKinematics.for_stream`: held at the latest measured positions of
the joints outside ``joints``, once per tick), written straight to CDR; stamped with the
node clock when published.

Units: m.
"""

from __future__ import annotations

from collections.abc import Callable

from geometry_msgs.msg import PoseStamped
import numpy as np
from rclpy.node import Node
from rclpy.qos import QoSProfile
from traj_gen_ros.core.kinematics import pose_quaternion
from traj_gen_ros.node.description.kinematics import RobotKinematics
from traj_gen_ros.node.messages.wire import pose_stamped_cdr


class ToolPoseOutput:
    """The ``~/tool_pose`` publisher; call it with each setpoint (the stream's thread)."""

    def __init__(self, node: Node, kinematics: Callable[[], RobotKinematics],
                 now_ns: Callable[[], int], qos: QoSProfile) -> None:
        """Create the publisher; ``kinematics()`` is the chain in force (read every tick)."""
        self._kinematics, self._now_ns = kinematics, now_ns
        self._publish = node.create_publisher(PoseStamped, '~/tool_pose', qos).publish

    def __call__(self, position: np.ndarray, velocity: np.ndarray) -> None:
        """Publish the tool pose of setpoint ``position`` (rad or m), if a chain is in force."""
        del velocity
        chain = self._kinematics().for_stream()
        if chain is None:
            return
        point, quaternion = pose_quaternion(chain.forward(position), checked=True)
        self._publish(pose_stamped_cdr(self._now_ns(), chain.base_frame, point, quaternion))


def each_setpoint(*outputs: Callable[[np.ndarray, np.ndarray], None] | None
                  ) -> Callable[[np.ndarray, np.ndarray], None] | None:
    """Return one call that runs every given output with a setpoint, or None if none."""
    given = [output for output in outputs if output is not None]
    if len(given) <= 1:
        return given[0] if given else None

    def every(position: np.ndarray, velocity: np.ndarray) -> None:
        for output in given:
            output(position, velocity)
    return every
