"""
The node's joint limits: the robot's URDF and the ``min_position``/``max_position`` parameters.

The URDF comes from the ``robot_description`` topic (``std_msgs/String``, reliable,
transient local, depth 1, as ``robot_state_publisher`` publishes it) or from the
``robot_description`` parameter; whichever was given last is in force (an empty parameter:
none). Its joints' ``lower``/``upper``/``velocity`` limits are read
(:func:`traj_gen_ros.node.description.joint_limits.urdf_limits`, urdfdom's rules) and merged
with the
parameters
(:func:`~traj_gen_ros.node.description.joint_limits.merge_limits`): the tighter bound wins, and
the URDF
velocity limit lowers ``max_velocity``. Every change of the limits in force is logged
(INFO) with where each bound came from
(:func:`~traj_gen_ros.node.description.joint_limits.describe_sources`).

A URDF that cannot be used (invalid, a trajectory joint that is fixed, a range that the
parameters make empty) is refused: as a parameter with the reason, on the topic with an
error in the log and in ``/diagnostics``; the limits in force stay. An invalid
``robot_description`` parameter at start-up ends the node with status 1, like any other
invalid parameter.

Units: rad or m, rad/s or m/s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
from traj_gen_ros.node.description.held_joints import HeldJoints
from traj_gen_ros.node.description.joint_limits import (
    ABSENT,
    describe_sources,
    JointLimits,
    merge_limits,
    urdf_limits,
    UrdfLimits,
)
from traj_gen_ros.node.description.kinematics import build_kinematics, RobotKinematics

#: What robot_state_publisher offers on ``robot_description``: the last URDF, kept.
DESCRIPTION_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
LIMIT_PARAMETERS = ('min_position', 'max_position', 'max_velocity', 'robot_description')


class NodeLimits:
    """The URDF in force, where it came from, and the limits it gives with the parameters."""

    def __init__(self, node: Node, held: HeldJoints | None = None) -> None:
        """
        Read the ``robot_description`` parameter and subscribe to the topic.

        ``held``: the measured positions of the joints outside ``joints``, at which every
        chain built here holds them (None: at 0).

        :raises ValueError: the ``robot_description`` parameter is not a usable URDF.
        """
        self._node = node
        self._held = HeldJoints() if held is None else held
        self._listeners: list[Callable[[], None]] = []
        self._joints = tuple(node.get_parameter('joints').value)
        self._urdf = UrdfLimits.unlimited(self._joints)
        #: Where the URDF in force came from, e.g. ``topic /robot_description``, or ``none``.
        self.source = 'none'
        #: The last robot_description refused, with the reason ('' if none was).
        self.problem = ''
        self._parameter_text = ''
        self._logged = ''
        self._frames = (node.get_parameter('base_frame').value,
                        node.get_parameter('tool_frame').value)
        #: The kinematic chain of the URDF in force (or why there is none).
        self.kinematics = RobotKinematics()
        self._take_parameter(node.get_parameter('robot_description').value)
        if self.kinematics.chain is None and self.source != 'none' and any(self._frames):
            raise ValueError(f'base_frame {self._frames[0]!r} / tool_frame '
                             f'{self._frames[1]!r}: {self.kinematics.problem}')
        self._subscription = node.create_subscription(
            String, 'robot_description', self._on_description, DESCRIPTION_QOS)

    def add_listener(self, changed: Callable[[], None]) -> None:
        """
        Call ``changed()`` after a new URDF arrived on the topic and was taken.

        The node then rebuilds its ``Config`` (through :meth:`in_force`).
        """
        self._listeners.append(changed)

    # ------------------------------------------------------------------ URDF sources

    def _parse(self, text: str) -> UrdfLimits:
        return urdf_limits(text, self._joints) if text else UrdfLimits.unlimited(self._joints)

    def _take_parameter(self, text: str) -> None:
        self._urdf = self._parse(text)
        self._parameter_text = text
        self.source = 'parameter robot_description' if text else 'none'
        self._report_urdf()
        self._take_kinematics(text)

    def _take_kinematics(self, text: str) -> None:
        """Build the chain of the URDF now in force; log it (INFO) or why none (WARN)."""
        self.kinematics = build_kinematics(text, self._joints, *self._frames, self._held)
        if self.source == 'none':
            return
        logger = self._node.get_logger()
        if self.kinematics.chain is not None:
            logger.info(f'{self.kinematics.describe()} (URDF: {self.source})')
        else:
            logger.warning(f'{self.kinematics.problem} (URDF: {self.source}): tool-frame '
                           'requests are refused')

    def _on_description(self, message: String) -> None:
        topic = self._subscription.topic_name
        try:
            urdf = self._parse(message.data)
            self._merge(urdf, self._parameters())
        except Exception as error:  # noqa: BLE001 - no URDF may stop the node
            self.problem = f'robot_description on {topic} refused: {_reason(error)}'
            self._node.get_logger().error(f'{self.problem}; the limits in force stay')
            return
        self._urdf = urdf
        self.source = f'topic {topic}' if message.data else 'none'
        self.problem = ''
        self._report_urdf()
        self._take_kinematics(message.data)
        for changed in self._listeners:
            changed()

    def _report_urdf(self) -> None:
        logger = self._node.get_logger()
        if self.source != 'none':
            absent = [name for name, kind in zip(self._joints, self._urdf.types, strict=True)
                      if kind == ABSENT]
            if absent:
                logger.warning(f'the URDF ({self.source}) has no joint {absent}: no URDF '
                               'limits for them')

    # ------------------------------------------------------------------ parameters

    def _parameters(self, changes: Sequence[Parameter] = ()) -> dict[str, object]:
        values = {name: self._node.get_parameter(name).value for name in LIMIT_PARAMETERS}
        values.update({p.name: p.value for p in changes if p.name in LIMIT_PARAMETERS})
        return values

    def _merge(self, urdf: UrdfLimits, values: dict[str, object]) -> JointLimits:
        velocity = np.asarray(values['max_velocity'], dtype=float)
        return merge_limits(urdf, min_position=_one_or_all(values['min_position']),
                            max_position=_one_or_all(values['max_position']),
                            max_velocity=velocity if velocity.size != 1 else velocity[0])

    def check(self, parameters: list[Parameter]) -> str | None:
        """Say why limits that cannot be merged, or an unusable URDF, are refused; or None."""
        names = {p.name for p in parameters}
        if not names & {'min_position', 'max_position', 'robot_description'}:
            return None  # max_velocity: make_config checks it
        values = self._parameters(parameters)
        try:
            urdf = self._urdf
            if 'robot_description' in names:
                urdf = self._parse(values['robot_description'])
            self._merge(urdf, values)
        except Exception as error:  # noqa: BLE001 - no URDF may stop the node
            return _reason(error)
        return None

    # ------------------------------------------------------------------ the limits in force

    def in_force(self, max_velocity: np.ndarray) -> JointLimits:
        """
        Return the limits in force: the URDF merged with the parameters and ``max_velocity``.

        ``JointLimits.velocity`` is ``max_velocity`` lowered by the URDF. Takes a changed
        ``robot_description`` parameter first; logs the limits when they changed. Raises
        ``ValueError`` when they cannot be merged (checked before a change).
        """
        text = self._node.get_parameter('robot_description').value
        if text != self._parameter_text:
            self._take_parameter(text)
        values = self._parameters()
        values['max_velocity'] = max_velocity
        limits = self._merge(self._urdf, values)
        summary = describe_sources(limits)
        if summary != self._logged:
            self._logged = summary
            self._node.get_logger().info(f'joint limits (URDF: {self.source}): {summary}')
        return limits


def _reason(error: Exception) -> str:
    """Say why a URDF or limits were refused (a ValueError says it itself)."""
    return str(error) if isinstance(error, ValueError) else f'{type(error).__name__}: {error}'


def _one_or_all(values: Sequence[float]) -> float | np.ndarray:
    array = np.asarray(values, dtype=float).reshape(-1)
    return float(array[0]) if array.size == 1 else array
