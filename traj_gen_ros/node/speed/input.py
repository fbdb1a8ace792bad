"""
The speed override's ROS side: the ``speed_scaling`` parameter, ``~/speed_scaling_input``.

The logic (the inputs, the ramp, the plan clock) is :mod:`traj_gen_ros.node.speed.time_map`;
this module reads the inputs and hands their product to the stream
(:meth:`traj_gen_ros.node.stream.speed_view.SpeedView.set_factor`):

* ``speed_scaling`` (double in [0, 1], run-time changeable): checked in the node's
  parameter callback (:meth:`SpeedScalingInput.check`: a value outside [0, 1] or not
  finite is refused with the reason), applied after it (:meth:`SpeedScalingInput.apply`);
* ``~/speed_scaling_input`` (``control_msgs/msg/SpeedScalingFactor``, as a
  ``joint_trajectory_controller`` names it) where control_msgs is importable: three
  subscriptions (:data:`SUBSCRIPTIONS`), so that a publisher of any reliability and
  durability is heard, a reliable one without loss, a latched value too; a message that
  several deliver is taken once (a message no newer by its source timestamp than the
  last taken is skipped). A factor outside [0, 1] or not finite is ignored, logged and
  counted on ``/diagnostics``;
* each change of the factor asked for is logged (INFO), at most once a second
  (:class:`~traj_gen_ros.node.speed.factor.ChangeReport`: the first of a burst at once,
  the value at its end a second after the last line);
* a delayed motion (a future ``header.stamp``) that a change drops is answered: its
  request gets an ERROR ``~/status`` saying why (:data:`DROPPED`), an action goal is
  aborted with it (:meth:`RequestHandler.dropped`);
* ``speed_scaling_output_topic`` (read only, '' = none): the effective factor, as it
  ramps, forwarded as ``SpeedScalingFactor`` (reliable, transient local) to a
  ``joint_trajectory_controller``'s ``speed_scaling_input`` when the commands out are
  its plans (``command_out_type`` ``trajectory_msgs/JointTrajectory``).

Why three subscriptions (the DDS request/offered rules: a reliable reader matches no
best-effort writer, a transient-local reader no volatile writer; a best-effort or a
volatile reader matches either): the best-effort one alone hears everyone, but loses
what a writer sends before this node has matched it, which is what ``ros2 topic pub
--once`` does (it publishes as soon as *it* sees a subscription, then exits); the
reliable volatile one hears every reliable publisher and gets such a sample repaired by
the reliable protocol once matched; only a transient-local reader gets the value a
latched publisher wrote before the node started. A publisher that one of the two
reliable subscriptions cannot match is expected, as the other ones hear it: that
incompatibility is logged at debug level instead of rclpy's warning; any other is
warned about (the best-effort subscription keeps rclpy's warning: it asks the least, so
a publisher it cannot match is heard by none).
"""

from __future__ import annotations

from collections.abc import Callable
import time

from rclpy.clock import Clock, ClockType
from rclpy.event_handler import QoSRequestedIncompatibleQoSInfo, SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import (
    DurabilityPolicy,
    qos_policy_name_from_kind,
    QoSPolicyKind,
    QoSProfile,
    ReliabilityPolicy,
)
from traj_gen_ros.node.messages.wire import factor_cdr
from traj_gen_ros.node.speed.factor import (
    ChangeReport,
    check_factor,
    FactorInputs,
    FactorSink,
    REPORT_PERIOD,
)

try:
    from control_msgs.msg import SpeedScalingFactor
except ImportError:  # control_msgs not built: the parameter alone
    SpeedScalingFactor = None

INPUT_TOPIC = '~/speed_scaling_input'
#: Every reliable publisher, volatile or transient local; a sample sent before this node
#: matched its writer is repaired (``ros2 topic pub --once``).
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
#: A transient-local publisher's latched value, also one written before the node started;
#: the output's QoS too.
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Every publisher, best-effort ones too (their only subscription); no repair.
BEST_EFFORT = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT,
                         durability=DurabilityPolicy.VOLATILE)
#: The subscriptions in the order they are created, each with the policies in which a
#: publisher it cannot match is expected to differ (another subscription hears it), or
#: None: rclpy's warning. The reliable volatile one comes first: the node announces its
#: subscriptions in that order, so a publisher that publishes at its first match (as
#: ``ros2 topic pub --once``) has matched the one that repairs a lost sample.
SUBSCRIPTIONS = (
    ('reliable', RELIABLE, {QoSPolicyKind.RELIABILITY}),
    ('transient-local', LATCHED, {QoSPolicyKind.RELIABILITY, QoSPolicyKind.DURABILITY}),
    ('best-effort', BEST_EFFORT, None),
)
#: Why a delayed motion is dropped (its request's ERROR status, its action goal's abort).
DROPPED = ('the speed scaling factor changed before its delayed start (header.stamp) '
           'and moved the state it was planned from: not executed (it would jump); '
           'resend it')


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
        self._asked = self.inputs.product  # the factor asked for, as last reported
        self._report = ChangeReport()
        # The report's held line, a period after it was held (steady: not sim time).
        self._report_timer = node.create_timer(
            REPORT_PERIOD, self._say_held, clock=Clock(clock_type=ClockType.STEADY_TIME),
            autostart=False)
        if self.available:
            for name, qos, expected in SUBSCRIPTIONS:
                events = (SubscriptionEventCallbacks(
                    incompatible_qos=self._incompatible(name, expected))
                    if expected is not None else None)
                node.create_subscription(SpeedScalingFactor, INPUT_TOPIC, self._on_message,
                                         qos, event_callbacks=events)
        self._apply()

    def _incompatible(self, name: str, expected: set[QoSPolicyKind]
                      ) -> Callable[[QoSRequestedIncompatibleQoSInfo], None]:
        """Say a publisher the ``name`` subscription cannot match: debug if ``expected``."""
        def callback(info: QoSRequestedIncompatibleQoSInfo) -> None:
            policy = qos_policy_name_from_kind(info.last_policy_kind)
            line = (f'a publisher on {INPUT_TOPIC} differs from its {name} subscription in '
                    f'{policy} ({info.total_count} so far)')
            if info.last_policy_kind in expected:
                self._node.get_logger().debug(f'{line}: heard by another one')
            else:
                self._node.get_logger().warning(f'{line}: not heard there')
        return callback

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
            return  # the same message through another subscription, or an older one
        self._last_source_ns = max(self._last_source_ns, source_ns)
        ignored = self.inputs.take_message(message.factor)
        if ignored is not None:
            self._node.get_logger().warning(f'{ignored}: ignored',
                                            throttle_duration_sec=1.0)
            return
        self._apply()

    def _apply(self) -> None:
        dropped = self._stream.set_factor(self.inputs.product)
        if self.inputs.product != self._asked:
            self._asked = self.inputs.product
            self._log_change()
        if dropped:
            self._node.get_logger().warning(
                f'speed scaling changed before {len(dropped)} delayed motion(s) started '
                'from a state the change moved: dropped (they would jump); resend them')
            if self._on_dropped is not None:
                self._on_dropped([tag for _, tag in dropped], DROPPED)

    def _log_change(self) -> None:
        """Log the factor asked for now, or hold the line for :meth:`_say_held`."""
        inputs = self.inputs
        line = self._report.change(
            time.monotonic(), f'speed scaling factor {inputs.product:g} (speed_scaling '
            f'{inputs.parameter:g} × {INPUT_TOPIC} {inputs.topic:g})')
        if line is not None:
            self._node.get_logger().info(line)
        elif self._report_timer.is_canceled():
            self._report_timer.reset()  # fires a period from now: after the line due

    def _say_held(self) -> None:
        """Log the held line once due; stop the timer when none is held."""
        line = self._report.due(time.monotonic())
        if line is not None:
            self._node.get_logger().info(line)
        if self._report.held is None:
            self._report_timer.cancel()

    def values(self) -> list[tuple[str, str]]:
        """Give the ``/diagnostics`` key/values: both inputs, the factor in force."""
        values = self.inputs.values(self._stream.factor_in_force())
        if not self.available:
            values.append(('speed_scaling_input', 'control_msgs not importable: no topic'))
        return values
