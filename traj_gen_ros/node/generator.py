"""
The ``trajectory_generator`` node: plans from its current setpoint and streams it.

A thin ROS layer: this module declares the parameters and creates the subscriptions, the
service and the publishers; the work is done by

* :mod:`traj_gen_ros.node.requests.handler`: a request from its callback to the stream, in the
  order parse (:mod:`~traj_gen_ros.node.messages.parsing`) → validate and plan
  (:mod:`~traj_gen_ros.node.planning.pipeline`) → sample → splice into the schedule;
* :mod:`traj_gen_ros.node.requests.thread`: the thread that waits on ``~/goal`` and
  ``~/via_points`` alone and runs their callbacks (the executor serves the rest);
* :mod:`traj_gen_ros.node.stream.stream`: the thread that publishes the schedule's setpoint
  (:mod:`~traj_gen_ros.node.stream.schedule`) every period;
* :mod:`traj_gen_ros.node.requests.answers`: ``~/status`` and ``~/trajectory``;
* :mod:`traj_gen_ros.node.settings.config`: parameters → a validated ``Config``;
  :mod:`~traj_gen_ros.node.settings.parameters` declares them, statically typed;
* :mod:`traj_gen_ros.node.description.robot_description`: the URDF and
  ``min_position``/``max_position`` → the
  limits in force (``Config.limits``);
* :mod:`traj_gen_ros.node.diagnostics.publisher`: ``/diagnostics`` about once a second.

Interface (all names relative, so namespaces and remapping work):

* ``joint_states`` (``sensor_msgs/JointState``, reliable, depth 10): setpoint at ``rate_hz``.
* ``~/trajectory`` (``trajectory_msgs/JointTrajectory``, reliable, transient local, depth 1):
  each accepted plan sampled every ``1/rate_hz`` s.
* ``~/status`` (``diagnostic_msgs/DiagnosticStatus``): OK or ERROR with a reason, per request.
* ``~/goal`` (``sensor_msgs/JointState``), ``~/via_points`` (``trajectory_msgs/JointTrajectory``),
  ``~/pose_goal`` (``geometry_msgs/PoseStamped``), ``~/cartesian_path`` and ``~/circular_goal``
  (``nav_msgs/Path``): the requests (:data:`~traj_gen_ros.node.requests.handler.READERS`).
* ``~/tool_pose`` (``geometry_msgs/PoseStamped``): the setpoint's tool pose every tick;
  ``~/tool_path`` (``nav_msgs/Path``, transient local): the last planned tool path.
* ``~/stop`` (``std_srvs/Trigger``): brake within ``max_acceleration`` (and ``max_jerk``
  with profile ``scurve``) and hold.
* ``~/follow_joint_trajectory`` (``control_msgs/action/FollowJointTrajectory``), where
  control_msgs is importable: :mod:`traj_gen_ros.node.action.server`.
* ``robot_description`` (``std_msgs/String``, transient local): the robot's URDF, in.
* ``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``): the node's health, about 1 Hz.
* ``joint_topic`` (``sensor_msgs/JointState``, best effort): the measured state, in
  (:mod:`~traj_gen_ros.node.robot.joint_feedback`); ``command_out_topic``
  (``std_msgs/Float64MultiArray`` every tick, positions or velocities, or
  ``trajectory_msgs/JointTrajectory`` per plan:
  :mod:`~traj_gen_ros.node.robot.command_publisher`), out.
"""

from __future__ import annotations

from collections.abc import Callable
import dataclasses
import functools
import gc
import os
import signal
import sys
import threading
import time

import numpy as np
import numpy.ma  # noqa: F401 - np.unique's first call imports it: loaded before gc.freeze()
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from traj_gen_ros.node.action.server import create_server
from traj_gen_ros.node.action.tolerance_parameters import ToleranceParameters
from traj_gen_ros.node.description.held_joints import HeldJoints
from traj_gen_ros.node.description.robot_description import NodeLimits
from traj_gen_ros.node.diagnostics.publisher import CountingAnswers, NodeDiagnostics
from traj_gen_ros.node.diagnostics.status import RateMeter
from traj_gen_ros.node.planning.motion import held
from traj_gen_ros.node.requests.handler import READERS, REQUEST_DEPTH, RequestHandler
from traj_gen_ros.node.requests.thread import NotForTheExecutor, RequestThread
from traj_gen_ros.node.robot.command_publisher import CommandOutput
from traj_gen_ros.node.robot.joint_feedback import JointFeedback
from traj_gen_ros.node.robot.measured_state import MeasuredState
from traj_gen_ros.node.robot.tool_pose import each_setpoint, ToolPoseOutput
from traj_gen_ros.node.settings.config import Config, initial_state, make_config
from traj_gen_ros.node.settings.parameters import (
    declare_parameters,
    ParameterUse,
    serve_parameters,
)
from traj_gen_ros.node.speed.input import SpeedScalingInput
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.realtime import (
    choose_priority,
    EXECUTOR_FIFO_PRIORITY,
    favour_calling_thread,
    realtime_calling_thread,
)
from traj_gen_ros.node.stream.stream import Stream
from traj_gen_ros.node.stream.transport import choose_transport

NODE_NAME = 'trajectory_generator'
CONFIG_PARAMETERS = ('joints', 'rate_hz', 'profile', 'via_velocities', 'max_velocity',
                     'max_acceleration', 'lspb_acceleration', 'max_jerk', 'angle_wraparound',
                     'blend_radius', 'max_linear_velocity', 'max_linear_acceleration',
                     'max_angular_velocity')
#: A thread waiting for the GIL asks its holder for it after this long (s) without a
#: switch: the stream thread gets it from a planning thread within about this (plus the
#: hand-over). Each time the holder lets the GIL go and takes it back (numpy on more than
#: 500 elements, LAPACK) the wait starts again, so planning kept the stream waiting for
#: several 0.1 ms intervals; at 20 µs the 500 Hz p99 period while lines are planned fell
#: from 2.35–2.45 to 2.14–2.20 ms (benchmarks/panda_stream.py, docs/node-design.md).
SWITCH_INTERVAL = 0.00002
#: The spin loop checks this often (s) whether SIGINT/SIGTERM asked it to end.
SIGNAL_POLL = 0.1


class TrajectoryGenerator(Node):
    """Plan smooth joint motions from the current setpoint and stream the setpoint."""

    def __init__(self, **kwargs: object) -> None:
        """Declare parameters, check them, and create the interface; ValueError if invalid."""
        super().__init__(NODE_NAME, **kwargs)
        self._declare_parameters()
        # The URDF's joints outside `joints`: measured (joint_topic) in, the chains hold them.
        self._held = HeldJoints()
        self._limits = NodeLimits(self, self._held)
        self._config = self._read_config()
        initial = initial_state(self._config.joints,
                                self.get_parameter('initial_positions').value)
        publish_states = self.get_parameter('publish_joint_states').value
        measured = self._measured_state(publish_states)
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        publish = (self.create_publisher(JointState, 'joint_states', reliable).publish
                   if publish_states else _nothing)
        self._commands = CommandOutput(self, lambda: self._config, measured, reliable)
        self._node_clock = self.get_clock()  # ROS time: use_sim_time makes it follow /clock
        self._rate_meter = RateMeter(self._now_ns() * 1e-9)  # for /diagnostics
        # Speed scaling: the plan clock (node/speed/time_map.py), its inputs (speed_input.py).
        self._time_map = TimeMap(self._config.max_acceleration, self._config.jerk_limit,
                                 origin_ns=self._now_ns())
        self._stream = Stream(held(initial), self._config.joints, self._now_ns,
                              lambda: self._config.period_ns,
                              self._rate_meter.wrap(publish), self.get_logger().error,
                              waiting=measured is not None,
                              publish_command=each_setpoint(
                                  self._commands.stream_command,
                                  ToolPoseOutput(self, lambda: self._config.kinematics,
                                                 self._now_ns, reliable)
                                  if self.get_parameter('publish_tool_pose').value else None),
                              time_map=self._time_map,
                              publish_factor=SpeedScalingInput.output(self),
                              on_late=self._rate_meter.late,
                              # A JTC runs the plans sent to it on its own clock.
                              hold_back=not self._commands.own_clock,
                              simulated=lambda: self._node_clock.ros_time_is_active)
        self.context.on_shutdown(self._stream.stopping.set)  # SIGINT/SIGTERM: stream ends
        self._answers = CountingAnswers(self, lambda: self._config.joints)
        self._requests = RequestHandler(
            lambda: self._config, self._stream, self._answers, self._now_ns,
            self.get_logger().error, refusal=measured.refusal if measured else lambda: None,
            on_plan=self._commands.on_plan)
        #: The measured state in (``joint_topic``), or None (standalone).
        self.feedback = (JointFeedback(self, measured, self._stream, self._requests)
                         if measured else None)
        # Served by the request thread, not the executor (request_thread).
        requests_only = NotForTheExecutor()
        # Raw: a goal's names and positions are read off the wire (microseconds, against
        # tens for an rclpy message), and a via request's point count, so a huge message is
        # refused without building one Python object per point.
        self._request_subscriptions = {
            topic: self.create_subscription(
                reader.message_type, f'~/{topic}', functools.partial(self._on_request, topic),
                REQUEST_DEPTH, raw=True, callback_group=requests_only)
            for topic, reader in READERS.items()}
        self._request_thread = RequestThread(
            self.context, list(self._request_subscriptions.values()), self.get_logger().error)
        self.create_service(Trigger, '~/stop', self._on_stop)
        # ~/follow_joint_trajectory where control_msgs is importable (action/server.py)
        tolerances = ToleranceParameters(self, lambda: len(self._config.joints))
        self.follow_joint_trajectory = create_server(
            self, self._requests, self._stream, self._answers, lambda: self._config,
            self._now_ns, tolerances=tolerances,
            arrival_ns=lambda: self._request_thread.ready_ns, arm=self.feedback,
            callback_group=requests_only)
        if self.follow_joint_trajectory is not None:
            self._request_thread.serve(self.follow_joint_trajectory.action_server)
            if self.feedback is not None:
                self.feedback.add_listener(self.follow_joint_trajectory.monitor)
        self.speed_scaling = SpeedScalingInput(self, self._stream.speed, self._requests.dropped)
        # Every party's parameter checks and changes, registered once the node is built.
        serve_parameters(self, [ParameterUse(self._check_config, self._apply_config),
                                ParameterUse(self._limits.check),
                                ParameterUse(tolerances.check, tolerances.apply),
                                ParameterUse(self.speed_scaling.check,
                                             self.speed_scaling.apply)])
        self._limits.add_listener(lambda: self._apply_config([]))
        self._diagnostics = NodeDiagnostics(
            self, lambda: self._config, self._limits, self._answers, self._rate_meter,
            lambda: self._stream.setpoint(self._stream.last_published()).position,
            self._status_with_speed(measured), self._stream.speed.time_left)
        self._diagnostics.check_ranges()  # a start outside the limits is said at once
        self._answers.trajectory(0, held(initial), self._config.rate_hz)  # warm up
        priority = self._stream.start()
        self._request_thread.start()
        waiting = f', waiting for the measured state on {measured.topic}' if measured else ''
        self.get_logger().info(
            f'streaming {len(self._config.joints)} joints at {self._config.rate_hz:g} Hz '
            f'({priority}), profile {self._config.profile}{waiting}')

    def _measured_state(self, publish_states: bool) -> MeasuredState | None:
        """Check the ``joint_topic`` parameters; None when standalone; ValueError if bad."""
        topic = self.get_parameter('joint_topic').value
        if not topic:
            return None
        resolved = self.resolve_topic_name(topic)
        if publish_states and resolved == self.resolve_topic_name('joint_states'):
            raise ValueError(f'joint_topic {topic!r} is {resolved}, where this node publishes '
                             'its own setpoint: it would read it back as the measured state. '
                             'Remap joint_states, or set publish_joint_states false when a '
                             'joint_state_broadcaster publishes it')
        return MeasuredState(self._config.joints, resolved,
                             self.get_parameter('state_tolerance').value,
                             self.get_parameter('joint_topic_timeout').value, self._held)

    def _status_with_speed(self, measured: MeasuredState | None
                           ) -> Callable[[], tuple[int, str, list[tuple[str, str]]]]:
        """Give the ``/diagnostics`` part after the limits: the measured state's, the speed's."""
        def status() -> tuple[int, str, list[tuple[str, str]]]:
            level, problem, values = measured.status() if measured else (0, '', [])
            return level, problem, values + self.speed_scaling.values()
        return status

    # ------------------------------------------------------------------ requests

    def _on_request(self, topic: str, data: bytes, info: dict) -> None:
        """Take a request off ``~/<topic>`` (on the request thread)."""
        self._requests.take(self._request_subscriptions[topic], topic, (data, info))

    def _on_stop(self, request: Trigger.Request, response: Trigger.Response
                 ) -> Trigger.Response:
        del request
        return self._requests.stop(response)

    def _now_ns(self) -> int:
        """
        Read the node clock (ns): ROS time, the system time unless ``/clock`` drives it.

        The stream reads it several times a tick and a request several times: without sim
        time, ``time.time_ns()`` (the same ``CLOCK_REALTIME``) costs 0.1 µs and checking
        that costs 1.5, against 4.8 µs for ``Clock.now()`` (each holding the GIL).
        """
        clock = self._node_clock
        if clock.ros_time_is_active:
            return clock.now().nanoseconds
        return time.time_ns()

    # ------------------------------------------------------------------ parameters

    def _declare_parameters(self) -> None:
        declare_parameters(self)  # statically typed; numbers converted (node_parameters)

    def _parameter_values(self) -> dict[str, object]:
        return {name: self.get_parameter(name).value for name in CONFIG_PARAMETERS}

    def _read_config(self) -> Config:
        config = make_config(**self._parameter_values())
        limits = self._limits.in_force(config.max_velocity)
        return dataclasses.replace(config, max_velocity=np.array(limits.velocity),
                                   limits=limits, kinematics=self._limits.kinematics)

    def _check_config(self, parameters: list[Parameter]) -> str | None:
        """Say why the changed ``CONFIG_PARAMETERS`` make no valid ``Config``, or None."""
        values = self._parameter_values()
        values.update({p.name: p.value for p in parameters if p.name in CONFIG_PARAMETERS})
        try:
            make_config(**values)
        except ValueError as error:
            return str(error)
        return None

    def _apply_config(self, parameters: list[Parameter]) -> None:
        """Rebuild the ``Config`` in force (after a change, or a new URDF on the topic)."""
        del parameters  # every change can change the limits in force: rebuilt whole
        self._config = config = self._read_config()  # the stream reads the period every tick
        self._stream.speed.set_scaling_limits(config.max_acceleration, config.jerk_limit)

    def destroy_node(self) -> None:
        """Stop the request and stream threads, send a last zero velocity command, destroy."""
        self._request_thread.stop()
        self._stream.stop()
        self._commands.send_zero()  # the stream's last tick is out: nothing follows it
        if self.follow_joint_trajectory is not None:
            self.follow_joint_trajectory.destroy()
        super().destroy_node()


def _nothing(data: bytes) -> None:
    """Publish nothing (``publish_joint_states`` false)."""
    del data


def main(args: list[str] | None = None) -> int:
    """
    Run the generator until SIGINT/SIGTERM; return the exit status.

    The signal handlers only set a flag that the spin loop checks every ``SIGNAL_POLL``
    s: a signal that arrives while the node or the executor is being built interrupts
    nothing half-made, and the node is then destroyed in order (exit status 0).
    """
    try:
        choose_priority(os.environ)  # before rclpy starts its threads
    except ValueError as error:
        print(f'{NODE_NAME}: {error}', file=sys.stderr)
        return 1
    transport = choose_transport(os.environ)  # before rclpy creates the DDS participant
    favour_calling_thread()  # before rclpy starts its threads: they inherit it
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    sys.setswitchinterval(SWITCH_INTERVAL)
    node = None
    status = 0
    # Before the stream runs: a full collection holds the GIL for ~30 ms. numpy.ma is loaded
    # by now (imported above): np.unique's first call would take 14 ms importing it on the
    # request thread, in the node's first line or arc (benchmarks/panda_stream.py).
    gc.collect()
    try:
        node = TrajectoryGenerator()
        node.get_logger().info(transport)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        # What exists now lives as long as the node: out of the collector's sight, later
        # full collections (which hold the GIL, so the stream waits) stay short.
        gc.freeze()
        # The executor thread holds the GIL while it plans: preempted by a normal process
        # then, it would keep the stream waiting. Below the stream's priority; set after
        # rclpy started its DDS threads, which stay normal (nice -10) threads.
        realtime_calling_thread(EXECUTOR_FIFO_PRIORITY)
        while not stop.is_set():
            executor.spin_once(timeout_sec=SIGNAL_POLL)
    except ExternalShutdownException:
        pass  # the context was shut down by someone else
    except (ValueError, ParameterException) as error:
        print(f'{NODE_NAME}: invalid parameters: {error}', file=sys.stderr)
        status = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
