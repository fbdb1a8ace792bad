"""
``command_out_topic`` out: its publisher and what goes on it (the ROS side of commands_out).

The parameters ``command_out_topic``, ``command_out_type``, ``command_out_interface`` and
``position_gain`` are read once, at start-up (read only); a bad value raises
``ValueError`` saying why (the node exits with status 1). Then, with a topic set:

* ``std_msgs/Float64MultiArray``: :attr:`CommandOutput.stream_command`, which the stream
  calls each tick with the setpoint, publishes its positions, or with ``velocity`` the
  :class:`~traj_gen_ros.node.robot.commands_out.VelocityCommand` (corrected toward the
  measured state of ``joint_topic`` while it is fresh:
  :meth:`~traj_gen_ros.node.robot.measured_state.MeasuredState.fresh_position`);
* ``trajectory_msgs/JointTrajectory``: :attr:`CommandOutput.on_plan`, which the request
  handler calls with every plan spliced in, publishes the plan as a JTC takes it
  (:func:`~traj_gen_ros.node.robot.commands_out.controller_points`);
* :meth:`CommandOutput.send_zero` (``velocity`` only): one all-zero command, the last,
  when the node ends (SIGINT/SIGTERM), after the stream thread has stopped.
"""

from __future__ import annotations

from collections.abc import Callable
import time

import numpy as np
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile
from std_msgs.msg import Float64MultiArray
from traj_gen_ros.node.messages.wire import joint_trajectory_cdr
from traj_gen_ros.node.planning.motion import PlannedMotion
from traj_gen_ros.node.robot.commands_out import (
    controller_points,
    position_command,
    VelocityCommand,
)
from traj_gen_ros.node.robot.measured_state import MeasuredState
from traj_gen_ros.node.settings.config import (
    check_command_out_interface,
    check_command_out_type,
    check_position_gain,
    Config,
    FLOAT64_MULTI_ARRAY,
    VELOCITY,
)
from trajectory_msgs.msg import JointTrajectory

#: How long the last (zero) command waits for the subscribers' acknowledgement (s): see
#: :meth:`CommandOutput.send_zero`.
ZERO_ACK_WAIT = 0.5


def _no_plan(start_ns: int, motion: PlannedMotion) -> None:
    """Publish no plan (no ``JointTrajectory`` command output)."""
    del start_ns, motion


class CommandOutput:
    """The ``command_out_topic`` publisher: the stream's command each tick, or each plan."""

    def __init__(self, node: Node, config: Callable[[], Config],
                 measured: MeasuredState | None, qos: QoSProfile) -> None:
        """
        Read the command parameters of ``node``; create the publisher if a topic is set.

        :param config: the parameters in force (read every tick: limits and the period
            may change at run time).
        :param measured: the measured state (``joint_topic``), or None (standalone: a
            velocity command is then the setpoint velocity alone).
        """
        parameter = node.get_parameter
        self.command_type = check_command_out_type(parameter('command_out_type').value)
        self.interface = check_command_out_interface(
            parameter('command_out_interface').value, self.command_type)
        joints = config().joints
        gain = check_position_gain(joints, parameter('position_gain').value)
        topic = parameter('command_out_topic').value
        self._config = config
        self._logger = node.get_logger()
        self._publisher = None
        #: The velocity command (``command_out_interface`` velocity), else None.
        self.velocity: VelocityCommand | None = None
        #: For ``Stream(publish_command=)``: called with each tick's setpoint, or None.
        self.stream_command: Callable[[np.ndarray, np.ndarray], None] | None = None
        #: For ``RequestHandler(on_plan=)``: called with every plan spliced in.
        self.on_plan: Callable[[int, PlannedMotion], None] = _no_plan
        #: Whether a controller runs the plans sent to it on its own clock (a JTC's
        #: ``JointTrajectory``): then the stream's clock is never held back.
        self.own_clock = bool(topic) and self.command_type != FLOAT64_MULTI_ARRAY
        if not topic:
            return
        array = self.command_type == FLOAT64_MULTI_ARRAY
        self._publisher = node.create_publisher(
            Float64MultiArray if array else JointTrajectory, topic, qos)
        if not array:
            self.on_plan = self._publish_plan
            return
        write = position_command
        if self.interface == VELOCITY:
            fresh = (lambda: None) if measured is None else (
                lambda: measured.fresh_position(time.monotonic()))
            self.velocity = write = VelocityCommand(
                gain, lambda: self._config().max_velocity,
                lambda: self._config().max_acceleration,
                lambda: self._config().period_ns * 1e-9, fresh)
            if measured is None and np.any(gain > 0.0):
                self._logger.warning('position_gain has no effect without joint_topic: '
                                     'the velocity commands are the setpoint velocities')
        publish = self._publisher.publish

        def send(position: np.ndarray, velocity: np.ndarray) -> None:
            publish(write(position, velocity))
        self.stream_command = send

    def _publish_plan(self, start_ns: int, motion: PlannedMotion) -> None:
        """Publish a plan spliced in as a JTC's ``JointTrajectory`` (``command_out_type``)."""
        times_ns, *values = controller_points(motion)
        if not all(np.isfinite(v).all() for v in values if v is not None):
            self._logger.error('command_out_topic: a non-finite point: not sent')
            return
        self._publisher.publish(joint_trajectory_cdr(start_ns, self._config().joints,
                                                     times_ns, *values))

    def send_zero(self) -> None:
        """
        Publish one all-zero velocity command and wait until it is acknowledged.

        Call it once the stream thread has stopped (no tick sends another after it) and
        before the context shuts down; nothing with ``command_out_interface`` position.
        rmw_fastrtps publishes synchronously by default: the command is on the wire when
        ``publish`` returns. The wait (at most :data:`ZERO_ACK_WAIT` s) covers an
        asynchronous publication mode, whose thread sends it later; an acknowledgement
        may also wait for the writer's next heartbeat (Fast DDS: every 3 s), so a wait
        that ends without one is usual and only logged at debug level.
        """
        if self.velocity is None or self._publisher is None:
            return
        try:
            self._publisher.publish(self.velocity.zero())
            if not self._publisher.wait_for_all_acked(Duration(seconds=ZERO_ACK_WAIT)):
                self._logger.debug('command_out_topic: the last (zero) velocity command '
                                   f'was not acknowledged within {ZERO_ACK_WAIT:g} s')
        except Exception as error:  # noqa: BLE001 - the context may be gone already
            self._logger.error(f'command_out_topic: the last (zero) velocity command '
                               f'could not be sent: {error!r}')
