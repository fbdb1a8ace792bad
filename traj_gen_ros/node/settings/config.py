"""
The node's parameters, checked together into one :class:`Config` (no ROS here).

``make_config`` takes the parameter values as the node reads them and either returns a
:class:`Config` with one value per joint for every limit, or raises ``ValueError`` naming
the parameter and saying what is valid. The node calls it at start-up (a bad value ends
the node with exit status 1) and before every parameter change (a bad value is refused).

Units: rad/s, rad/s², rad/s³, Hz; ``position_gain`` 1/s; the tool's m, m/s, m/s², rad/s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.timing import PROFILES  # the core's: the node offers every profile
from traj_gen_ros.core.validation import per_joint
from traj_gen_ros.node.description.joint_limits import JointLimits
from traj_gen_ros.node.description.kinematics import RobotKinematics

#: Jerk limit (rad/s³) when ``max_jerk`` is not given: the S-curve's.
DEFAULT_MAX_JERK = 20.0
VIA_VELOCITIES = ('heuristic', 'continuous')
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 1000.0
#: Default ``state_tolerance`` (rad): farther than this from the held setpoint re-seeds it.
DEFAULT_STATE_TOLERANCE = 0.05
#: Default ``joint_topic_timeout`` (s); 0 means never.
DEFAULT_TIMEOUT = 0.5
#: ``command_out_type``: a position array every tick, or a JTC's trajectory per plan.
FLOAT64_MULTI_ARRAY = 'std_msgs/Float64MultiArray'
JOINT_TRAJECTORY = 'trajectory_msgs/JointTrajectory'
COMMAND_OUT_TYPES = (FLOAT64_MULTI_ARRAY, JOINT_TRAJECTORY)
#: ``command_out_interface``: what a ``Float64MultiArray`` command carries.
POSITION = 'position'
VELOCITY = 'velocity'
COMMAND_OUT_INTERFACES = (POSITION, VELOCITY)
#: Default ``position_gain`` (1/s): velocity commands are the setpoint's velocity alone.
DEFAULT_POSITION_GAIN = 0.0
#: Defaults of the tool's limits on lines and arcs: UR's default tool speed and
#: acceleration (250 mm/s, 1.2 m/s²; the ISO 10218-1 reduced speed is 250 mm/s too) and
#: a quarter turn per second, Pilz's default max_rot_vel (π/2 rad/s).
DEFAULT_MAX_LINEAR_VELOCITY = 0.25
DEFAULT_MAX_LINEAR_ACCELERATION = 1.2
DEFAULT_MAX_ANGULAR_VELOCITY = 1.5707963267948966
#: Largest ``blend_radius`` (m).
MAX_BLEND_RADIUS = 10.0


@dataclass(frozen=True)
class Config:
    """
    Validated generator parameters; per-joint arrays have one entry per joint.

    ``max_velocity`` is the tighter of the parameter and the URDF when ``limits`` are set
    (:mod:`traj_gen_ros.node.description.robot_description`).
    """

    joints: tuple[str, ...]
    rate_hz: float
    profile: str
    via_velocities: str
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    lspb_acceleration: np.ndarray
    #: Jerk limit (rad/s³) of the ``scurve`` profile and of its ``~/stop``.
    max_jerk: np.ndarray
    #: Position (and velocity) limits in force, with their sources; None: no position limits.
    limits: JointLimits | None = None
    #: Targets of URDF continuous joints without position limits are reached the shortest
    #: way round (:mod:`traj_gen_ros.node.planning.continuous_joints`).
    angle_wraparound: bool = True
    #: The kinematic chain in force, or why there is none (tool-frame requests).
    kinematics: RobotKinematics = RobotKinematics()
    #: Corners of ``~/cartesian_path`` blended within this distance (m); 0: stop at each.
    blend_radius: float = 0.0
    #: The tool's limits on lines and arcs: speed (m/s), the whole acceleration vector of
    #: the tool point (m/s²), angular speed (rad/s).
    max_linear_velocity: float = DEFAULT_MAX_LINEAR_VELOCITY
    max_linear_acceleration: float = DEFAULT_MAX_LINEAR_ACCELERATION
    max_angular_velocity: float = DEFAULT_MAX_ANGULAR_VELOCITY

    @property
    def profile_acceleration(self) -> np.ndarray:
        """Acceleration limit used for timing (rad/s²): the LSPB blend one for ``lspb``."""
        return self.lspb_acceleration if self.profile == 'lspb' else self.max_acceleration

    @property
    def jerk_limit(self) -> np.ndarray | None:
        """Jerk limit (rad/s³) the plans are checked against: ``max_jerk`` for ``scurve``."""
        return self.max_jerk if self.profile == 'scurve' else None

    @property
    def keeps_acceleration(self) -> bool:
        """Whether plans start from the current acceleration (quintic, scurve) or from 0."""
        return self.profile in ('quintic', 'scurve')

    @property
    def period_ns(self) -> int:
        """Stream period in integer nanoseconds."""
        return int(1e9 / self.rate_hz)


def check_joint_names(joints: Sequence[str]) -> tuple[str, ...]:
    """Check the ``joints`` parameter: non-empty, non-empty names, no duplicates."""
    names = tuple(joints)
    if not names:
        raise ValueError('joints is empty: list the joint names, e.g. [joint_1, joint_2]')
    for index, name in enumerate(names):
        if not name:
            raise ValueError(f'joints[{index}] is an empty name')
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise ValueError(f'joints lists {duplicates} more than once')
    return names


def initial_state(joints: Sequence[str], initial_positions: Sequence[float]) -> np.ndarray:
    """Check ``initial_positions`` (rad; empty means zeros) and return one per joint."""
    values = list(initial_positions)
    if not values:
        return np.zeros(len(joints))
    if len(values) != len(joints):
        raise ValueError(f'initial_positions has {len(values)} values but joints has '
                         f'{len(joints)}: give one position per joint (or none for zeros)')
    array = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f'initial_positions[{bad[0]}] is {array[bad[0]]}: must be finite')
    return array


def make_config(joints: Sequence[str], rate_hz: float, profile: str, via_velocities: str,
                max_velocity: object, max_acceleration: object,
                lspb_acceleration: object, max_jerk: object = DEFAULT_MAX_JERK,
                angle_wraparound: object = True, blend_radius: object = 0.0,
                max_linear_velocity: object = DEFAULT_MAX_LINEAR_VELOCITY,
                max_linear_acceleration: object = DEFAULT_MAX_LINEAR_ACCELERATION,
                max_angular_velocity: object = DEFAULT_MAX_ANGULAR_VELOCITY) -> Config:
    """
    Validate the node parameters together; raise ``ValueError`` with the reason.

    Limits in rad/s (``max_velocity``), rad/s² (``max_acceleration``,
    ``lspb_acceleration``) and rad/s³ (``max_jerk``), one value or one per joint;
    ``angle_wraparound`` a bool. The tool's: ``blend_radius`` (m, >= 0),
    ``max_linear_velocity`` (m/s), ``max_linear_acceleration`` (m/s²),
    ``max_angular_velocity`` (rad/s), each > 0.
    """
    names = check_joint_names(joints)
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, (int, float)) \
            or not MIN_RATE_HZ <= rate_hz <= MAX_RATE_HZ:
        raise ValueError(f'rate_hz must be a number in [{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}] Hz, '
                         f'got {rate_hz!r}')
    if profile not in PROFILES:
        raise ValueError(f'profile must be one of {", ".join(PROFILES)}; got {profile!r}')
    if via_velocities not in VIA_VELOCITIES:
        raise ValueError(f'via_velocities must be one of {", ".join(VIA_VELOCITIES)}; '
                         f'got {via_velocities!r}')
    count = len(names)
    v_max = per_joint('max_velocity', max_velocity, count, joints=names)
    a_max = per_joint('max_acceleration', max_acceleration, count, joints=names)
    a_lspb = per_joint('lspb_acceleration', lspb_acceleration, count, 'non-negative',
                       joints=names)
    j_max = per_joint('max_jerk', max_jerk, count, joints=names)
    too_high = np.flatnonzero(a_lspb > a_max)
    if too_high.size:
        index = too_high[0]
        raise ValueError(f'lspb_acceleration for {names[index]} is {a_lspb[index]:g} rad/s^2, '
                         f'above max_acceleration {a_max[index]:g}: use a value <= '
                         f'max_acceleration, or 0 to use max_acceleration')
    a_lspb = np.where(a_lspb == 0.0, a_max, a_lspb)
    if not isinstance(angle_wraparound, bool):
        raise ValueError(f'angle_wraparound must be true or false, got {angle_wraparound!r}')
    tool = {name: _tool_number(name, value, name == 'blend_radius') for name, value in (
        ('blend_radius', blend_radius), ('max_linear_velocity', max_linear_velocity),
        ('max_linear_acceleration', max_linear_acceleration),
        ('max_angular_velocity', max_angular_velocity))}
    return Config(names, float(rate_hz), profile, via_velocities, v_max, a_max, a_lspb, j_max,
                  angle_wraparound=angle_wraparound, **tool)


_TOOL_UNITS = {'blend_radius': 'm', 'max_linear_velocity': 'm/s',
               'max_linear_acceleration': 'm/s^2', 'max_angular_velocity': 'rad/s'}


def _tool_number(name: str, value: object, zero: bool) -> float:
    """Check one of the tool's parameters: finite, > 0 (``zero``: >= 0, at most 10 m)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value < 0.0 or (value == 0.0 and not zero) \
            or (zero and value > MAX_BLEND_RADIUS):
        rule = (f'in [0, {MAX_BLEND_RADIUS:g}] (0: stop at each corner)' if zero
                else 'finite and > 0')
        raise ValueError(f'{name} must be a number {rule}, {_TOOL_UNITS[name]}; '
                         f'got {value!r}')
    return float(value)


def check_command_out_type(value: str) -> str:
    """Check ``command_out_type``; ``ValueError`` naming the valid values."""
    if value not in COMMAND_OUT_TYPES:
        raise ValueError(f'command_out_type must be one of {", ".join(COMMAND_OUT_TYPES)}; '
                         f'got {value!r}')
    return value


def check_command_out_interface(value: str, command_type: str) -> str:
    """
    Check ``command_out_interface`` against ``command_out_type``; ``ValueError`` if bad.

    ``velocity`` needs ``std_msgs/Float64MultiArray`` (a ``forward_velocity_controller``):
    a ``JointTrajectory`` for a JTC carries positions and velocities already.
    """
    if value not in COMMAND_OUT_INTERFACES:
        raise ValueError(f'command_out_interface must be one of '
                         f'{", ".join(COMMAND_OUT_INTERFACES)}; got {value!r}')
    if value == VELOCITY and command_type != FLOAT64_MULTI_ARRAY:
        raise ValueError(f'command_out_interface velocity needs command_out_type '
                         f'{FLOAT64_MULTI_ARRAY} (the commands of a forward_velocity_controller), '
                         f'got {command_type} (a joint_trajectory_controller takes the plan '
                         f'itself: use command_out_interface position)')
    return value


def check_position_gain(joints: Sequence[str], value: object) -> np.ndarray:
    """
    Check ``position_gain`` (1/s): one value or one per joint, each finite and >= 0.

    Returns one gain per joint; ``ValueError`` naming the first joint out of range.
    """
    return per_joint('position_gain', value, len(joints), 'non-negative', joints=tuple(joints))
