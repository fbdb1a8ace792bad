"""
``/diagnostics``: the node's health about once a second, as ``rqt_robot_monitor`` shows it.

One ``diagnostic_msgs/DiagnosticArray`` per second on the absolute topic ``/diagnostics``
(as ``diagnostic_updater`` publishes), holding one ``DiagnosticStatus`` named
``<node name>: Trajectory generator`` with an empty ``hardware_id``. Its content is built
by :func:`traj_gen_ros.node.diagnostics.status.node_status`: achieved stream rate, ``rate_hz``, the
motion in progress, the limits in force and where they came from, the counts of
accepted, refused and superseded requests, and the joints of the setpoint outside their
position range (:func:`~traj_gen_ros.node.planning.position_checks.outside_ranges`: WARN, and a
warning in the log when that changes, at start-up at once), and the late ticks (a warning
in the log, at once and then at most every :data:`LATE_LOG_PERIOD` s for those since:
the stream thread itself does not log).

The timer runs on the executor thread and only reads counters and formats a few strings
(the limits' text is formatted once per change of the limits), so it cannot disturb the
stream thread. :class:`CountingAnswers` is the node's
:class:`~traj_gen_ros.node.requests.answers.Answers`
that also counts each answer and notes each accepted motion.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import math
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header
from traj_gen_ros.node.description.joint_limits import describe_sources
from traj_gen_ros.node.description.robot_description import NodeLimits
from traj_gen_ros.node.diagnostics.status import MotionLog, node_status, RateMeter, RequestCounts
from traj_gen_ros.node.planning.motion import PlannedMotion
from traj_gen_ros.node.planning.position_checks import outside_ranges
from traj_gen_ros.node.requests.answers import Answers
from traj_gen_ros.node.requests.request import Request
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.clock import LATE_PERIODS

#: Seconds between two ``/diagnostics`` messages (diagnostic_updater's default).
PERIOD = 1.0
TOPIC = '/diagnostics'
#: Late ticks are logged at most this often (s): on a busy machine they can come every second.
LATE_LOG_PERIOD = 10.0


class CountingAnswers(Answers):
    """:class:`Answers` that counts every answer and notes every accepted motion."""

    def __init__(self, node: Node, *args: object, **kwargs: object) -> None:
        """Create the publishers (:class:`Answers`) and empty counts."""
        super().__init__(node, *args, **kwargs)
        self.counts = RequestCounts()
        self.motions = MotionLog()

    def accepted(self, request: Request, motion: PlannedMotion, now_ns: int,
                 start_ns: int) -> None:
        """Note the motion and its start (ns), then answer OK."""
        self.motions.record(start_ns, motion.profile, motion.plan.duration)
        super().accepted(request, motion, now_ns, start_ns)

    def report(self, level: bytes, text: str, values: dict[str, str], log: bool = True) -> None:
        """Count the answer, then publish it."""
        self.counts.count(level[0] if isinstance(level, bytes) else int(level), values)
        super().report(level, text, values, log)


class NodeDiagnostics:
    """The ``/diagnostics`` publisher and its timer."""

    def __init__(self, node: Node, config: Callable[[], Config], limits: NodeLimits,
                 answers: CountingAnswers, meter: RateMeter,
                 setpoint: Callable[[], Sequence[float]],
                 measured: Callable[[], tuple[int, str, list[tuple[str, str]]]] | None = None,
                 time_left: Callable[[int], float] | None = None) -> None:
        """
        Publish the node's status every :data:`PERIOD` s from the node's parts.

        :param setpoint: returns the position last published (rad or m).
        :param measured: gives the measured state's status (``joint_topic`` set), else None.
        :param time_left: the plan time (s) the motion in effect at a node time (ns) has
            left, on the plan clock (speed scaling); None: unscaled.
        """
        self._time_left = time_left
        self._node = node
        self._setpoint = setpoint
        self._outside = ''
        self._measured = measured
        self._config = config
        self._limits = limits
        self._answers = answers
        self._meter = meter
        self._name = f'{node.get_name()}: Trajectory generator'
        self._limits_text: tuple[object, str] = (None, 'none')
        self._late_logged = -math.inf  # when late ticks were last logged (monotonic s)
        self._publisher = node.create_publisher(
            DiagnosticArray, TOPIC, QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self._timer = node.create_timer(PERIOD, self.publish)

    def _limits_summary(self, config: Config) -> str:
        if config.limits is None:
            return 'none'
        if self._limits_text[0] is not config.limits:
            self._limits_text = (config.limits, describe_sources(config.limits))
        return self._limits_text[1]

    def check_ranges(self) -> str:
        """
        Return which joints of the setpoint are outside their range ('' if none).

        Logs a warning when that changes to a joint outside (an INFO when all are back in).
        """
        outside = outside_ranges(self._config().limits, self._setpoint())
        if outside != self._outside:
            logger = self._node.get_logger()
            if outside:
                logger.warning(f'{outside}: it may hold there or move toward its range; a '
                               'goal that takes it further out is refused')
            else:
                logger.info('every joint is within its position range')
            self._outside = outside
        return outside

    def publish(self) -> None:
        """Publish one ``DiagnosticArray`` with the node's status (a failure is logged)."""
        try:
            self._publish()
        except Exception as error:  # noqa: BLE001 - diagnostics must not stop the node
            self._node.get_logger().error(f'/diagnostics: {error!r}',
                                          throttle_duration_sec=60.0)

    def _log_late(self) -> None:
        """Warn of the late ticks since the last warning, if any (:data:`LATE_LOG_PERIOD`)."""
        now = time.monotonic()
        if now - self._late_logged < LATE_LOG_PERIOD:
            return
        ticks, gap_ns, held_ns = self._meter.late_report()
        if ticks:
            self._late_logged = now
            self._node.get_logger().warning(
                f'stream: {ticks} late tick{"s" if ticks > 1 else ""} (the longest '
                f'{gap_ns * 1e-6:.1f} ms after the setpoint before it, more than '
                f'{LATE_PERIODS} periods): the motion was held back {held_ns * 1e-6:.1f} ms, '
                f'to continue from the last setpoint without a jump (late ticks since '
                f'start: {self._meter.late_ticks})')

    def _publish(self) -> None:
        now = self._node.get_clock().now()
        config = self._config()
        level, message, values = node_status(
            rate=self._meter.rate(now.nanoseconds * 1e-9), rate_hz=config.rate_hz,
            joints=len(config.joints), profile=config.profile,
            motion=self._answers.motions.describe(now.nanoseconds, self._time_left),
            limits=self._limits_summary(config), urdf_source=self._limits.source,
            urdf_problem=self._limits.problem, counts=self._answers.counts,
            outside=self.check_ranges(),
            feedback=self._measured() if self._measured else None,
            late=(self._meter.late_ticks, self._meter.held_back_ns),
            kinematics='' if self._limits.source == 'none' else config.kinematics.describe())
        self._log_late()
        status = DiagnosticStatus(level=bytes([level]), name=self._name, message=message,
                                  hardware_id='',
                                  values=[KeyValue(key=k, value=v) for k, v in values])
        self._publisher.publish(DiagnosticArray(header=Header(stamp=now.to_msg()),
                                                status=[status]))
