"""
The node's parameters, each with one fixed type, its range and its rule.

Every parameter is declared *statically typed*: its type never changes, so
``ros2 param describe``/``get``/``dump`` always tell the truth. The rules:

* a number given where a double is declared is stored as a double: ``ros2 param set
  /trajectory_generator rate_hz 50`` (an integer on the command line) sets ``rate_hz`` to
  ``50.0``, and an integer in a parameters file is read the same way;
* a per-joint parameter (``max_velocity``, ``max_acceleration``, ``lspb_acceleration``,
  ``max_jerk``, ``min_position``, ``max_position``, ``position_gain``, …: every name in
  :data:`DOUBLE_ARRAYS`) is a double array: one value for all joints or one per joint. A
  single number (integer or double) is stored as a one-element array;
* any other type (a string, a bool, …) is refused by rclpy with
  ``Wrong parameter type, expected 'Type.DOUBLE' got 'Type.STRING'``, and the parameter
  keeps its value.

The conversion is a *pre-set* callback (rclpy calls it before checking the type), and at
start-up each parameter's override is converted before the parameter is declared.
Scalars carry their range in the descriptor (``FloatingPointRange``), which rclpy enforces;
per-joint arrays state their rule in ``description`` and ``additional_constraints``
(rclpy checks no range on arrays; :mod:`traj_gen_ros.node.settings.config` and
:mod:`traj_gen_ros.node.description.robot_description` do).

Units: rad (or m), rad/s, rad/s², rad/s³, Hz; ``position_gain`` 1/s.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import math

from rcl_interfaces.msg import (
    FloatingPointRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
from rclpy.node import Node
from rclpy.parameter import Parameter
from traj_gen_ros.node.settings.config import (
    COMMAND_OUT_INTERFACES,
    COMMAND_OUT_TYPES,
    DEFAULT_MAX_ANGULAR_VELOCITY,
    DEFAULT_MAX_JERK,
    DEFAULT_MAX_LINEAR_ACCELERATION,
    DEFAULT_MAX_LINEAR_VELOCITY,
    DEFAULT_POSITION_GAIN,
    DEFAULT_STATE_TOLERANCE,
    DEFAULT_TIMEOUT,
    FLOAT64_MULTI_ARRAY,
    MAX_BLEND_RADIUS,
    MAX_RATE_HZ,
    MIN_RATE_HZ,
    POSITION,
    PROFILES,
)

DEFAULT_JOINTS = [f'joint_{index}' for index in range(1, 7)]
PER_JOINT = 'one value for all joints or one per joint'
#: Parameters declared as doubles: an integer is stored as a double.
DOUBLES = ('rate_hz', 'joint_topic_timeout', 'allowed_start_tolerance', 'goal_time_tolerance',
           'stopped_velocity_tolerance', 'speed_scaling', 'blend_radius', 'max_linear_velocity',
           'max_linear_acceleration', 'max_angular_velocity')
#: Per-joint parameters, declared as double arrays: one number is stored as ``[number]``.
DOUBLE_ARRAYS = ('initial_positions', 'max_velocity', 'max_acceleration', 'lspb_acceleration',
                 'max_jerk', 'min_position', 'max_position', 'state_tolerance', 'path_tolerance',
                 'goal_tolerance', 'position_gain')

_DOUBLE = Parameter.Type.DOUBLE
_DOUBLE_ARRAY = Parameter.Type.DOUBLE_ARRAY
_TYPE_NAMES = {
    ParameterType.PARAMETER_BOOL: 'a bool', ParameterType.PARAMETER_INTEGER: 'an integer',
    ParameterType.PARAMETER_DOUBLE: 'a number (double)',
    ParameterType.PARAMETER_STRING: 'a string',
    ParameterType.PARAMETER_BYTE_ARRAY: 'a byte array',
    ParameterType.PARAMETER_BOOL_ARRAY: 'a bool array',
    ParameterType.PARAMETER_INTEGER_ARRAY: 'an integer array',
    ParameterType.PARAMETER_DOUBLE_ARRAY: f'a number or a list of numbers ({PER_JOINT})',
    ParameterType.PARAMETER_STRING_ARRAY: 'a list of strings',
}
_NUMBERS = (Parameter.Type.INTEGER, Parameter.Type.DOUBLE)
_NUMBER_ARRAYS = (Parameter.Type.INTEGER_ARRAY, Parameter.Type.DOUBLE_ARRAY)


def _per_joint(description: str, rule: str, unit: str) -> ParameterDescriptor:
    return ParameterDescriptor(
        description=f'{description} ({PER_JOINT}; {rule}; {unit}).',
        type=ParameterType.PARAMETER_DOUBLE_ARRAY,
        additional_constraints=f'{PER_JOINT}; {rule}; {unit}')


def descriptors(joint_count: int) -> dict[str, tuple[object, ParameterDescriptor]]:
    """Return every parameter's default value and descriptor, in declaration order."""
    return {
        'initial_positions': ([0.0] * max(joint_count, 1), ParameterDescriptor(
            description='Start position per joint, rad or m (read only); empty means zeros.',
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, read_only=True,
            additional_constraints='empty, or one finite value per joint; rad or m')),
        'rate_hz': (100.0, ParameterDescriptor(
            description='JointState stream rate and sample rate of ~/trajectory, Hz.',
            type=ParameterType.PARAMETER_DOUBLE,
            floating_point_range=[FloatingPointRange(from_value=MIN_RATE_HZ,
                                                     to_value=MAX_RATE_HZ)])),
        'profile': ('quintic', ParameterDescriptor(
            description='Profile of the next plans.', type=ParameterType.PARAMETER_STRING,
            additional_constraints=' | '.join(PROFILES))),
        'via_velocities': ('heuristic', ParameterDescriptor(
            description='Velocities at via points for cubic/quintic when none are given.',
            type=ParameterType.PARAMETER_STRING,
            additional_constraints='heuristic | continuous')),
        'max_velocity': ([1.0], _per_joint(
            'Velocity limit, used for timing and checked on every plan; a URDF velocity '
            'limit lowers it', 'each finite and > 0', 'rad/s or m/s')),
        'max_acceleration': ([2.0], _per_joint(
            'Acceleration limit, used for timing, checked on every plan, and the braking '
            'rate of ~/stop', 'each finite and > 0', 'rad/s^2 or m/s^2')),
        'max_jerk': ([DEFAULT_MAX_JERK], _per_joint(
            'Jerk limit of profile scurve: used for timing, checked on every scurve plan, and '
            'the jerk bound of ~/stop with scurve', 'each finite and > 0', 'rad/s^3 or m/s^3')),
        'lspb_acceleration': ([0.0], _per_joint(
            'LSPB blend acceleration; 0 means max_acceleration',
            'each 0 <= value <= max_acceleration', 'rad/s^2 or m/s^2')),
        'min_position': ([-math.inf], _per_joint(
            'Lower position limit; the URDF lower limit applies too, the tighter wins',
            '-.inf means none, +inf not allowed', 'rad or m')),
        'max_position': ([math.inf], _per_joint(
            'Upper position limit; the URDF upper limit applies too, the tighter wins',
            '.inf means none, -inf not allowed', 'rad or m')),
        'angle_wraparound': (True, ParameterDescriptor(
            description='Goals and via points of URDF continuous joints without position '
                        'limits are reached the shortest way round (whole turns added).',
            type=ParameterType.PARAMETER_BOOL)),
        'robot_description': ('', ParameterDescriptor(
            description='URDF of the robot (XML); its joint limits apply. A message on the '
                        'robot_description topic replaces it; empty: none.',
            type=ParameterType.PARAMETER_STRING)),
        'base_frame': ('', ParameterDescriptor(
            description='Link whose frame tool poses are given in; empty: the URDF root '
                        'link (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True)),
        'tool_frame': ('', ParameterDescriptor(
            description='Link whose pose pose goals set; empty: the end of the fixed joints '
                        'below the last joint, where there is one (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True)),
        'blend_radius': _non_negative(
            'Corners of ~/cartesian_path are blended by a tangent arc from this distance '
            'before to this distance after each (clipped to half the shorter segment), m; '
            '0: the tool stops at each corner.', 0.0, MAX_BLEND_RADIUS),
        'max_linear_velocity': _positive(
            'Speed limit of the tool point on lines and arcs, m/s.',
            DEFAULT_MAX_LINEAR_VELOCITY),
        'max_linear_acceleration': _positive(
            'Limit of the whole acceleration vector of the tool point (tangential and '
            'centripetal) on lines and arcs, m/s^2.', DEFAULT_MAX_LINEAR_ACCELERATION),
        'max_angular_velocity': _positive(
            "Limit of the tool's angular speed on lines and arcs, rad/s.",
            DEFAULT_MAX_ANGULAR_VELOCITY),
        'publish_tool_pose': (True, ParameterDescriptor(
            description="Publish the setpoint's tool pose on ~/tool_pose at the stream rate "
                        'while a kinematic chain is in force (read only).',
            type=ParameterType.PARAMETER_BOOL, read_only=True)),
        'joint_topic': ('', ParameterDescriptor(
            description='Measured joint state in (sensor_msgs/JointState, e.g. /joint_states '
                        'of a joint_state_broadcaster): the first message is the start, the '
                        'arm is the reference; empty: standalone (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True)),
        'publish_joint_states': (True, ParameterDescriptor(
            description='Publish the setpoint on joint_states; false when a '
                        'joint_state_broadcaster owns joint_states (read only).',
            type=ParameterType.PARAMETER_BOOL, read_only=True)),
        'command_out_topic': ('', ParameterDescriptor(
            description='Commands out to a ros2_control controller, e.g. '
                        '/forward_position_controller/commands; empty: none (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True)),
        'command_out_type': (FLOAT64_MULTI_ARRAY, ParameterDescriptor(
            description='Type of command_out_topic: the setpoint every tick, or each plan '
                        'for a joint_trajectory_controller (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True,
            additional_constraints=' | '.join(COMMAND_OUT_TYPES))),
        'command_out_interface': (POSITION, ParameterDescriptor(
            description='What a std_msgs/Float64MultiArray command carries: the setpoint '
                        'positions, or its velocities (+ position_gain times the position '
                        'error) for a forward_velocity_controller (read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True,
            additional_constraints=' | '.join(COMMAND_OUT_INTERFACES))),
        'position_gain': ([DEFAULT_POSITION_GAIN], ParameterDescriptor(
            description=f'command_out_interface velocity: the command is the setpoint '
                        f'velocity + this times (setpoint - measured position) while the '
                        f'measured state is fresh ({PER_JOINT}; each finite and >= 0, 0: '
                        f'feed-forward only; 1/s; read only).',
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, read_only=True,
            additional_constraints=f'{PER_JOINT}; each finite and >= 0; 1/s')),
        'joint_topic_timeout': (DEFAULT_TIMEOUT, ParameterDescriptor(
            description='No valid measured state for this long, s: brake and refuse '
                        'requests until it returns; 0: never (read only).',
            type=ParameterType.PARAMETER_DOUBLE, read_only=True,
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=3600.0)])),
        'speed_scaling': (1.0, ParameterDescriptor(
            description='Speed override: the running plan advances at this times the clock '
                        '(times ~/speed_scaling_input); 0 pauses, 1 is full speed.',
            type=ParameterType.PARAMETER_DOUBLE,
            additional_constraints='a finite number in [0, 1]',
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1.0)])),
        'speed_scaling_output_topic': ('', ParameterDescriptor(
            description='Forward the speed scaling factor in force (control_msgs/'
                        'SpeedScalingFactor) to a joint_trajectory_controller, e.g. '
                        '/joint_trajectory_controller/speed_scaling_input; empty: none '
                        '(read only).',
            type=ParameterType.PARAMETER_STRING, read_only=True)),
        'state_tolerance': ([DEFAULT_STATE_TOLERANCE], ParameterDescriptor(
            description=f'Measured position farther than this from the held setpoint while '
                        f'idle: hold where the arm is ({PER_JOINT}; each >= 0, 0: never; '
                        f'rad or m; read only).',
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, read_only=True,
            additional_constraints=f'{PER_JOINT}; each >= 0, 0: never; rad or m')),
        **action_descriptors(),
    }


def _non_negative(description: str, default: float, upper: float) -> tuple[float, object]:
    return default, ParameterDescriptor(
        description=description, type=ParameterType.PARAMETER_DOUBLE,
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=upper)])


def _positive(description: str, default: float) -> tuple[float, object]:
    return default, ParameterDescriptor(
        description=description, type=ParameterType.PARAMETER_DOUBLE,
        additional_constraints='finite and > 0',
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)])


def action_descriptors() -> dict[str, tuple[object, ParameterDescriptor]]:
    """Return the ``~/follow_joint_trajectory`` parameters (MoveIt's and JTC's names)."""
    return {
        'allowed_start_tolerance': _non_negative(
            'Largest distance of a goal point at time 0 from where the arm is, rad; 0: not '
            'checked (as MoveIt).', 0.01, 1000.0),
        'goal_time_tolerance': _non_negative(
            'Time after a goal ends within which the arm must be within goal_tolerance and '
            'still, s; 0: no limit (as JTC).', 0.25, 3600.0),
        'stopped_velocity_tolerance': _non_negative(
            'Largest measured |velocity| of a joint at rest at a goal end, rad/s; 0: not '
            'checked.', 0.01, 1000.0),
        'path_tolerance': ([0.0], _per_joint(
            'Largest deviation of the measured state from the setpoint during a goal',
            'each >= 0; 0 means not checked', 'rad or m')),
        'goal_tolerance': ([0.0], _per_joint(
            'Largest deviation of the measured state from a goal end',
            'each >= 0; 0 means not checked', 'rad or m')),
    }


def typed(parameter: Parameter) -> Parameter:
    """
    Return ``parameter`` with a number converted to the type its name is declared with.

    ``rate_hz`` 50 → 50.0; ``max_velocity`` 2 or 2.0 → [2.0]; [1, 2] → [1.0, 2.0]. Other
    parameters and other types are returned unchanged (rclpy then refuses a wrong type).
    """
    kind = parameter.type_
    if parameter.name in DOUBLES and kind == Parameter.Type.INTEGER:
        return Parameter(parameter.name, _DOUBLE, float(parameter.value))
    if parameter.name in DOUBLE_ARRAYS:
        if kind in _NUMBERS:
            return Parameter(parameter.name, _DOUBLE_ARRAY, [float(parameter.value)])
        if kind == Parameter.Type.INTEGER_ARRAY:
            return Parameter(parameter.name, _DOUBLE_ARRAY, [float(v) for v in parameter.value])
        if kind == Parameter.Type.BYTE_ARRAY and len(parameter.value) == 0:
            return Parameter(parameter.name, _DOUBLE_ARRAY, [])  # [] is inferred as bytes
    return parameter


def typed_parameters(parameters: list[Parameter]) -> list[Parameter]:
    """Pre-set callback: convert numbers to the declared types (:func:`typed`)."""
    return [typed(parameter) for parameter in parameters]


def declare_parameters(node: Node) -> None:
    """
    Declare the node's parameters, statically typed, and convert numbers from now on.

    An override (parameters file, ``-p``) is read first and converted with :func:`typed`,
    so ``rate_hz: 50`` in a file is the double 50.0; an empty per-joint array in a file
    means the default. A value of another type raises ``ValueError`` saying what the
    parameter must be (the node exits with status 1 and the reason).
    """
    joints = node.declare_parameter('joints', DEFAULT_JOINTS, ParameterDescriptor(
        description='Joint names: the joint set and its order (read only).', read_only=True,
        type=ParameterType.PARAMETER_STRING_ARRAY)).value
    for name, (default, descriptor) in descriptors(len(joints or [])).items():
        given = typed(node.declare_parameter(  # the override, if any, as it was given
            name, None, ParameterDescriptor(dynamic_typing=True)))
        node.undeclare_parameter(name)
        value = given.value
        if value is not None and given.type_.value != descriptor.type:
            raise ValueError(f'{name} must be {_TYPE_NAMES[descriptor.type]}; got {value!r} '
                             f'({_TYPE_NAMES.get(given.type_.value, given.type_.name)})')
        if value is None or (name in DOUBLE_ARRAYS and given.type_ == _DOUBLE_ARRAY
                             and len(value) == 0):
            value = default
        node.declare_parameter(name, value, descriptor, ignore_override=True)
    node.add_pre_set_parameters_callback(typed_parameters)


@dataclass(frozen=True)
class ParameterUse:
    """
    One party's part in a parameter change: ``check`` it, then ``apply`` it once accepted.

    ``check(parameters)`` returns the reason to refuse the change, or None.
    """

    check: Callable[[list[Parameter]], str | None]
    apply: Callable[[list[Parameter]], None] = lambda parameters: None


def serve_parameters(node: Node, uses: Sequence[ParameterUse]) -> None:
    """
    Register the node's one on-set and one post-set parameter callback, over ``uses``.

    A change is refused with the first reason a ``check`` gives (then nothing changes);
    an accepted one is applied by every ``apply``, in order. Registered once the node is
    built, so no callback reaches a half-built node.
    """
    def check(parameters: list[Parameter]) -> SetParametersResult:
        for use in uses:
            reason = use.check(parameters)
            if reason is not None:
                return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def apply(parameters: list[Parameter]) -> None:
        for use in uses:
            use.apply(parameters)
    node.add_on_set_parameters_callback(check)
    node.add_post_set_parameters_callback(apply)
