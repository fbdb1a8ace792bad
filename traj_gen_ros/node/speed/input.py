"""
The speed override's ROS side: the ``speed_scaling`` parameter, ``~/speed_scaling_input``.

The logic (the inputs, the ramp, the plan clock) is :mod:`traj_gen_ros.node.speed.time_map`;
this module reads the inputs and hands their product to the stream
(:meth:`traj_gen_ros.node.stream.stream.Stream.set_factor`):

* ``speed_scaling`` (double in [0, 1], run-time changeable): checked in the node's
  parameter callback (:meth:`SpeedScalingInput.check`: a value outside [0, 1] or not
  finite is refused with the reason), applied after it (:meth:`SpeedScalingInput.apply`);
* ``~/speed_scaling_input`` (``control_msgs/msg/SpeedScalingFactor``, as a
  ``joint_trajectory_controller`` names it) where control_msgs is importable: two
  subscriptions, one reliable and transient local (it takes a transient-local
  publisher's latched value at start-up; it matches no volatile publisher) and one best
  effort and volatile (it matches every publisher); a message that both deliver is taken
  once (a message no newer by its source timestamp than the last taken is skipped). A
  factor outside [0, 1] or not finite is ignored, logged and counted on ``/diagnostics``;
* a delayed motion (a future ``header.stamp``) that a change drops is answered: its
  request gets an ERROR ``~/status`` saying why (:data:`DROPPED`), an action goal is
  aborted with it (:meth:`RequestHandler.dropped`);
* ``speed_scaling_output_topic`` (read only, '' = none): the effective factor, as it
  ramps, forwarded as ``SpeedScalingFactor`` (reliable, transient local) to a
  ``joint_trajectory_controller``'s ``speed_scaling_input`` when the commands out are
  its plans (``command_out_type`` ``trajectory_msgs/JointTrajectory``).
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from traj_gen_ros.node.messages.wire import factor_cdr
from traj_gen_ros.node.speed.factor import check_factor, FactorInputs, FactorSink

try:
    from control_msgs.msg import SpeedScalingFactor
except ImportError:  # control_msgs not built: the parameter alone
    SpeedScalingFactor = None

INPUT_TOPIC = '~/speed_scaling_input'
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Why a delayed motion is dropped (its request's ERROR status, its action goal's abort).
DROPPED = ('the speed scaling factor changed before its delayed start (header.stamp) '
           'and moved the state it was planned from: not executed (it would jump); '
           'resend it')
ANY = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT,
                 durability=DurabilityPolicy.VOLATILE)


class SpeedScalingInput:
    """The two inputs of the factor, its output, and what ``/diagnostics`` shows of them."""

    def __init__(self, node: Node, stream: FactorSink,
                 on_dropped: Callable[[list[object], str], None] | None = None) -> None:
        """
        Read ``speed_scaling``; subscribe to the topic where control_msgs is importable.

        ``on_dropped(tags, reason)`` answers the delayed motions a change drops (the
        ``tag`` each was spliced with: its request); else they are only logged.
        """
        self._node = node
        self._stream = stream
        self._on_dropped = on_dropped
        self.inputs = FactorInputs(node.get_parameter('speed_scaling').value)
        self.available = SpeedScalingFactor is not None
        self._last_source_ns = -1
        if self.available:
            for qos in (LATCHED, ANY):
                node.create_subscription(SpeedScalingFactor, INPUT_TOPIC, self._on_message,
                                         qos)
        self._apply()

    @staticmethod
    def output(node: Node) -> Callable[[float], None] | None:
        """Return a ``speed_scaling_output_topic`` publish taking a factor, or None."""
        topic = node.get_parameter('speed_scaling_output_topic').value
        if not topic:
            return None
        if SpeedScalingFactor is None:
            raise ValueError(f'speed_scaling_output_topic {topic!r} needs control_msgs, '
                             'which is not importable here')
        publisher = node.create_publisher(SpeedScalingFactor, topic, LATCHED)
        return lambda factor: publisher.publish(factor_cdr(factor))

    @staticmethod
    def check(parameters: list[Parameter]) -> str | None:
        """Say why a ``speed_scaling`` value among ``parameters`` is refused, or None."""
        for parameter in parameters:
            if parameter.name == 'speed_scaling':
                try:
                    check_factor(parameter.value)
                except ValueError as error:
                    return str(error)
        return None

    def apply(self, parameters: list[Parameter]) -> None:
        """Take an accepted ``speed_scaling`` value (after the parameter callback)."""
        for parameter in parameters:
            if parameter.name == 'speed_scaling':
                self.inputs.parameter = float(parameter.value)
                self._apply()

    def _on_message(self, message: object, info: dict) -> None:
        source_ns = info.get('source_timestamp', 0)
        if 0 < source_ns <= self._last_source_ns:
            return  # the same message through the other subscription, or an older one
        self._last_source_ns = max(self._last_source_ns, source_ns)
        ignored = self.inputs.take_message(message.factor)
        if ignored is not None:
            self._node.get_logger().warning(f'{ignored}: ignored',
                                            throttle_duration_sec=1.0)
            return
        self._apply()

    def _apply(self) -> None:
        dropped = self._stream.set_factor(self.inputs.product)
        if dropped:
            self._node.get_logger().warning(
                f'speed scaling changed before {len(dropped)} delayed motion(s) started '
                'from a state the change moved: dropped (they would jump); resend them')
            if self._on_dropped is not None:
                self._on_dropped([tag for _, tag in dropped], DROPPED)

    def values(self) -> list[tuple[str, str]]:
        """Give the ``/diagnostics`` key/values: both inputs, the factor in force."""
        values = self.inputs.values(self._stream.factor_in_force())
        if not self.available:
            values.append(('speed_scaling_input', 'control_msgs not importable: no topic'))
        return values
