"""
The ``trajectory_generator`` node: plans from its current setpoint and streams it.

Thin ROS layer over :mod:`traj_gen_ros.planning` (request checks, plans, schedule) and the
core solver. Each request is parsed, validated, planned, sampled and published by short
functions below; the stream timer only samples the schedule at the current time.

Interface (all names relative, so namespaces and remapping work):

* ``joint_states`` (``sensor_msgs/JointState``, reliable, depth 10): setpoint at ``rate_hz``.
* ``~/trajectory`` (``trajectory_msgs/JointTrajectory``, reliable, transient local, depth 1):
  each accepted plan sampled every ``1/rate_hz`` s.
* ``~/status`` (``diagnostic_msgs/DiagnosticStatus``): OK or ERROR with a reason, per request.
* ``~/goal`` (``sensor_msgs/JointState``), ``~/via_points`` (``trajectory_msgs/JointTrajectory``).
* ``~/stop`` (``std_srvs/Trigger``): brake within ``max_acceleration`` and hold.
"""

from __future__ import annotations

from collections.abc import Callable
import sys

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
import numpy as np
from rcl_interfaces.msg import (
    FloatingPointRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from traj_gen_ros import planning
from traj_gen_ros.trajectory_wire import joint_trajectory_cdr
from trajectory_msgs.msg import JointTrajectory

NODE_NAME = 'trajectory_generator'
DEFAULT_JOINTS = [f'joint_{index}' for index in range(1, 7)]
CONFIG_PARAMETERS = ('joints', 'rate_hz', 'profile', 'via_velocities', 'max_velocity',
                     'max_acceleration', 'lspb_acceleration')
PER_JOINT = 'one value for all joints, or one per joint'


def _descriptor(description: str, **extra: object) -> ParameterDescriptor:
    return ParameterDescriptor(description=description, **extra)


def _seconds(duration: Duration) -> float:
    return duration.sec + duration.nanosec * 1e-9


class TrajectoryGenerator(Node):
    """Plan smooth joint motions from the current setpoint and stream the setpoint."""

    def __init__(self, **kwargs: object) -> None:
        """Declare parameters, check them, and create the interface; ValueError if invalid."""
        super().__init__(NODE_NAME, **kwargs)
        self._declare_parameters()
        self._config = self._read_config()
        initial = planning.initial_state(self._config.joints,
                                         self.get_parameter('initial_positions').value)
        start = planning.PlannedMotion(planning.Hold(initial), 'hold', initial)
        self._schedule = planning.Schedule(start)
        self._names = list(self._config.joints)
        reliable = ReliabilityPolicy.RELIABLE
        self._joint_states = self.create_publisher(
            JointState, 'joint_states', QoSProfile(depth=10, reliability=reliable))
        self._trajectory = self.create_publisher(
            JointTrajectory, '~/trajectory',
            QoSProfile(depth=1, reliability=reliable, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._status = self.create_publisher(
            DiagnosticStatus, '~/status', QoSProfile(depth=10, reliability=reliable))
        self.create_subscription(JointState, '~/goal', self._on_goal, 10)
        self.create_subscription(JointTrajectory, '~/via_points', self._on_via_points, 10)
        self.create_service(Trigger, '~/stop', self._on_stop)
        self._timer = self.create_timer(1.0 / self._config.rate_hz, self._publish_setpoint)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._trajectory_message(0, start)  # warm up the message imports
        self.get_logger().info(
            f'streaming {len(self._names)} joints at {self._config.rate_hz:g} Hz, '
            f'profile {self._config.profile}')

    # ------------------------------------------------------------------ parameters

    def _declare_parameters(self) -> None:
        dynamic = {'dynamic_typing': True}
        joints = self.declare_parameter('joints', DEFAULT_JOINTS, _descriptor(
            'Joint names: the joint set and its order (read only).', read_only=True,
            type=ParameterType.PARAMETER_STRING_ARRAY)).value
        self.declare_parameter('initial_positions', [0.0] * len(joints or []), _descriptor(
            'Start position per joint in rad (read only); empty means zeros.',
            read_only=True, **dynamic))
        self.declare_parameter('rate_hz', 100.0, _descriptor(
            'JointState stream rate and sample rate of ~/trajectory, Hz.',
            floating_point_range=[FloatingPointRange(
                from_value=planning.MIN_RATE_HZ, to_value=planning.MAX_RATE_HZ)], **dynamic))
        self.declare_parameter('profile', 'quintic', _descriptor(
            'Profile of the next plans.', additional_constraints='cubic | quintic | lspb'))
        self.declare_parameter('via_velocities', 'heuristic', _descriptor(
            'Velocities at via points for cubic/quintic when none are given.',
            additional_constraints='heuristic | continuous'))
        self.declare_parameter('max_velocity', 1.0, _descriptor(
            f'Velocity limit in rad/s, > 0: {PER_JOINT}. Used for timing; checked on '
            'every plan.', **dynamic))
        self.declare_parameter('max_acceleration', 2.0, _descriptor(
            f'Acceleration limit in rad/s^2, > 0: {PER_JOINT}. Used for timing, checked '
            'on every plan, and the braking rate of ~/stop.', **dynamic))
        self.declare_parameter('lspb_acceleration', 0.0, _descriptor(
            f'LSPB blend acceleration in rad/s^2, 0..max_acceleration: {PER_JOINT}; '
            '0 means max_acceleration.', **dynamic))

    def _parameter_values(self) -> dict[str, object]:
        return {name: self.get_parameter(name).value for name in CONFIG_PARAMETERS}

    def _read_config(self) -> planning.Config:
        return planning.make_config(**self._parameter_values())

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        values = self._parameter_values()
        values.update({p.name: p.value for p in parameters if p.name in CONFIG_PARAMETERS})
        try:
            planning.make_config(**values)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        del parameters
        rate = self._config.rate_hz
        self._config = self._read_config()
        if self._config.rate_hz != rate:
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(1.0 / self._config.rate_hz, self._publish_setpoint)

    # ------------------------------------------------------------------ stream

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _publish_setpoint(self) -> None:
        now = self.get_clock().now()
        state = self._schedule.state_at(now.nanoseconds)
        message = JointState(name=self._names, position=state.position.tolist(),
                             velocity=state.velocity.tolist())
        message.header.stamp = now.to_msg()
        self._joint_states.publish(message)

    def _trajectory_message(self, start_ns: int, motion: planning.PlannedMotion) -> bytes:
        """
        Serialise the plan, sampled every ``1/rate_hz`` s, as a ``JointTrajectory``.

        Written straight to CDR from the sample arrays (``trajectory_wire``): a 1000-point
        message costs a fraction of a millisecond instead of one rclpy object per point.
        """
        times, positions, velocities, accelerations = planning.sample_motion(
            motion, self._config.rate_hz)
        time_ns = np.round(times * 1e9).astype(np.int64)
        return joint_trajectory_cdr(start_ns, self._names, time_ns, positions, velocities,
                                    accelerations)

    # ------------------------------------------------------------------ requests

    def _on_goal(self, message: JointState) -> None:
        def plan(now_ns: int) -> tuple[int, planning.PlannedMotion]:
            request = planning.parse_goal(self._names, message.name, message.position)
            state = self._schedule.state_at(now_ns)
            hold = self._schedule.end_position(now_ns)
            return now_ns, planning.plan_goal(self._config, state, hold, request)
        self._handle('goal', plan)

    def _on_via_points(self, message: JointTrajectory) -> None:
        def plan(now_ns: int) -> tuple[int, planning.PlannedMotion]:
            points = [(p.positions, p.velocities, p.accelerations, _seconds(p.time_from_start))
                      for p in message.points]
            request = planning.parse_via(self._names, message.joint_names, points)
            start_ns = max(now_ns, Time.from_msg(message.header.stamp).nanoseconds)
            state = self._schedule.state_at(start_ns)
            hold = self._schedule.end_position(start_ns)
            return start_ns, planning.plan_via(self._config, state, hold, request)
        self._handle('via_points', plan)

    def _on_stop(self, request: Trigger.Request, response: Trigger.Response
                 ) -> Trigger.Response:
        del request
        now_ns = self._now_ns()
        motion = planning.plan_stop(self._config, self._schedule.state_at(now_ns))
        self._execute('stop', now_ns, now_ns, motion)
        response.success = True
        response.message = f'stopping: at rest in {motion.plan.duration:.3f} s'
        return response

    def _handle(self, kind: str,
                plan: Callable[[int], tuple[int, planning.PlannedMotion]]) -> None:
        now_ns = self._now_ns()
        try:
            start_ns, motion = plan(now_ns)
        except planning.RequestError as error:
            self._report(DiagnosticStatus.ERROR, f'{kind} refused: {error}', {'request': kind})
            return
        except Exception as error:  # noqa: BLE001 - a bad request must never kill the node
            self.get_logger().error(f'unexpected failure planning {kind}: {error!r}')
            self._report(DiagnosticStatus.ERROR, f'{kind} refused: internal error: {error}',
                         {'request': kind})
            return
        self._execute(kind, now_ns, start_ns, motion)

    def _execute(self, kind: str, now_ns: int, start_ns: int,
                 motion: planning.PlannedMotion) -> None:
        self._schedule.splice(start_ns, motion, now_ns)
        if start_ns == now_ns:  # the new motion's first setpoint goes out at once
            self._publish_setpoint()
            self._timer.reset()
        self._trajectory.publish(self._trajectory_message(start_ns, motion))
        duration = motion.plan.duration
        text = (f'accepted: profile={motion.profile}, duration={duration:.3f} s, '
                f'joints={len(self._names)}')
        if start_ns > now_ns:
            text += f', starts in {(start_ns - now_ns) * 1e-9:.3f} s'
        if motion.note:
            text += f' ({motion.note})'
        self._report(DiagnosticStatus.OK, text, {
            'request': kind, 'profile': motion.profile, 'duration': f'{duration:.6f}',
            'joints': str(len(self._names)), 'start_delay': f'{(start_ns - now_ns) * 1e-9:.6f}'})

    def _report(self, level: bytes, text: str, values: dict[str, str]) -> None:
        if level != DiagnosticStatus.OK:
            self.get_logger().warning(text)
        self._status.publish(DiagnosticStatus(
            level=level, name=self.get_fully_qualified_name(), message=text,
            values=[KeyValue(key=key, value=value) for key, value in values.items()]))


def main(args: list[str] | None = None) -> int:
    """Run the generator until SIGINT/SIGTERM; return the exit status."""
    rclpy.init(args=args)
    node = None
    status = 0
    try:
        node = TrajectoryGenerator()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
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
