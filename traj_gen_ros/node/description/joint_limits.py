"""
Joint limits from a URDF robot description, merged with the node's parameters.

No ROS import: the URDF is an XML string (what ``robot_description`` holds), read by
:func:`traj_gen_ros.node.description.urdf_joints.read_joints` (only each joint's ``name``,
``type``,
``<limit>`` and ``<mimic>``, with urdfdom's rules). For the trajectory joints:

- ``revolute`` and ``prismatic`` joints must have a ``<limit>``; its ``lower`` and
  ``upper`` default to 0 (so a joint whose limit gives neither cannot move), its
  ``velocity`` must be > 0. Units: rad and rad/s (revolute), m and m/s (prismatic).
- ``continuous`` joints have no position limits (a ``lower``/``upper`` there is ignored,
  as KDL and MoveIt do); a ``<limit>`` on them gives a velocity.
- a mimic joint (``<mimic>``) follows another one and is never commanded, and ``fixed``,
  ``floating`` and ``planar`` joints have no single coordinate to plan: naming one as a
  trajectory joint is an error.
- A joint absent from the URDF has no URDF limits.

The limits in force are the tighter of the URDF and the parameters ``min_position``,
``max_position`` (±inf: none) and ``max_velocity``; for every joint and bound the source
is recorded: :data:`URDF`, :data:`PARAMETER` or :data:`NONE` (on a tie, the URDF).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.validation import per_joint
from traj_gen_ros.node.description.urdf_joints import read_joints, UrdfJoint

URDF = 'urdf'
PARAMETER = 'parameter'
NONE = 'none'
ABSENT = 'absent'  # the joint type recorded for a joint the URDF does not have
_MOVABLE = ('revolute', 'continuous', 'prismatic')
_SOURCE_TEXT = {URDF: 'URDF', NONE: 'none'}
_PARAMETER_NAME = {'lower': 'min_position', 'upper': 'max_position',
                   'velocity': 'max_velocity'}
#: Slack on a position bound (relative to ``max(1, |bound|)``): rounding, not an excess.
POSITION_TOLERANCE = 1e-9


def _frozen(values: Sequence[float]) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class UrdfLimits:
    """
    What a URDF says about an ordered list of joints (±inf where it says nothing).

    :ivar joints: the joint names, in the caller's order.
    :ivar lower: lower position limits, rad or m, ``(joints,)``.
    :ivar upper: upper position limits, rad or m, ``(joints,)``.
    :ivar velocity: velocity limits, rad/s or m/s, ``(joints,)``.
    :ivar types: each joint's URDF type, or :data:`ABSENT`.
    """

    joints: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    types: tuple[str, ...]

    @classmethod
    def unlimited(cls, joints: Sequence[str]) -> UrdfLimits:
        """Return the limits of joints without a URDF: none at all."""
        count = len(joints)
        return cls(tuple(joints), _frozen([-math.inf] * count), _frozen([math.inf] * count),
                   _frozen([math.inf] * count), (ABSENT,) * count)


@dataclass(frozen=True)
class PositionLimits:
    """
    Position limits in force, rad or m, ``(joints,)``, and where each bound came from.

    :ivar lower_source: per joint :data:`URDF`, :data:`PARAMETER` or :data:`NONE`.
    :ivar upper_source: likewise for ``upper``.
    """

    lower: np.ndarray
    upper: np.ndarray
    lower_source: tuple[str, ...]
    upper_source: tuple[str, ...]


@dataclass(frozen=True)
class JointLimits:
    """
    The limits in force for an ordered list of joints (see :func:`merge_limits`).

    :ivar joints: the joint names.
    :ivar position: position limits and their sources.
    :ivar velocity: velocity limits, rad/s or m/s, ``(joints,)``; inf: none.
    :ivar velocity_source: per joint :data:`URDF`, :data:`PARAMETER` or :data:`NONE`.
    :ivar units: per joint ``'rad'``, or ``'m'`` for a prismatic joint.
    :ivar types: per joint its URDF type, or :data:`ABSENT`.
    """

    joints: tuple[str, ...]
    position: PositionLimits
    velocity: np.ndarray
    velocity_source: tuple[str, ...]
    units: tuple[str, ...]
    types: tuple[str, ...] = ()


def urdf_limits(urdf_xml: str | bytes, joints: Sequence[str]) -> UrdfLimits:
    """
    Read the position and velocity limits of ``joints`` from a URDF.

    :param urdf_xml: the URDF document (e.g. the ``robot_description`` string).
    :param joints: the trajectory's joint names, in order.
    :return: per joint lower/upper (rad or m) and velocity (rad/s or m/s) limits, ±inf
        where the URDF has none (continuous joints' positions, absent joints).
    :raises ValueError: an invalid URDF (:func:`read_joints`), a revolute or prismatic
        joint without ``<limit>``, a fixed/floating/planar or mimic trajectory joint, a
        NaN limit, ``lower > upper`` or a velocity limit that is not > 0.
    """
    by_name = read_joints(urdf_xml)
    lower, upper, velocity, types = [], [], [], []
    for name in joints:
        joint = by_name.get(name)
        if joint is None:
            bounds, kind = (-math.inf, math.inf, math.inf), ABSENT
        else:
            bounds, kind = _joint_bounds(joint), joint.type
        lower.append(bounds[0])
        upper.append(bounds[1])
        velocity.append(bounds[2])
        types.append(kind)
    return UrdfLimits(tuple(joints), _frozen(lower), _frozen(upper), _frozen(velocity),
                      tuple(types))


def _joint_bounds(joint: UrdfJoint) -> tuple[float, float, float]:
    """Return ``(lower, upper, velocity)`` of one URDF trajectory joint (urdfdom semantics)."""
    name, kind, limit = joint.name, joint.type, joint.limit
    if kind not in _MOVABLE:
        raise ValueError(f"URDF joint '{name}' is {kind}: only revolute, continuous and "
                         'prismatic joints can be trajectory joints')
    if joint.mimic is not None:
        raise ValueError(f"URDF joint '{name}' mimics joint '{joint.mimic}' (<mimic>): it "
                         'follows that joint and is not commanded; remove it from joints')
    if limit is None:
        if kind == 'continuous':
            return -math.inf, math.inf, math.inf
        raise ValueError(f"invalid URDF: {kind} joint '{name}' has no <limit> element "
                         '(required for revolute and prismatic joints)')
    for key in ('lower', 'upper', 'velocity'):
        if math.isnan(limit[key]):
            raise ValueError(f"invalid URDF: joint '{name}' has {key} limit NaN")
    if not limit['velocity'] > 0:
        raise ValueError(f"URDF joint '{name}' has velocity limit {limit['velocity']:g}: "
                         'it must be > 0 for the joint to move')
    if kind == 'continuous':
        return -math.inf, math.inf, limit['velocity']
    lower, upper = limit['lower'], limit['upper']
    if lower > upper or lower == math.inf or upper == -math.inf:
        raise ValueError(f"invalid URDF: joint '{name}' has lower limit {lower:g} and upper "
                         f'limit {upper:g}: lower must be <= upper')
    return lower, upper, limit['velocity']


def merge_limits(urdf: UrdfLimits, *, min_position: float | Sequence[float] = -math.inf,
                 max_position: float | Sequence[float] = math.inf,
                 max_velocity: float | Sequence[float] = math.inf) -> JointLimits:
    """
    Merge URDF limits with the parameters: the tighter bound wins, its source is kept.

    :param urdf: from :func:`urdf_limits`, or :meth:`UrdfLimits.unlimited` without a URDF.
    :param min_position: lower position limit, rad or m, one or one per joint; -inf: none.
    :param max_position: upper position limit, likewise; +inf: none.
    :param max_velocity: velocity limit, rad/s or m/s, one or one per joint, > 0; inf: none.
    :return: the limits in force, with a source per joint and bound.
    :raises ValueError: wrong lengths, NaN, ``min_position`` of +inf or ``max_position`` of
        -inf, ``max_velocity <= 0``, or a joint whose merged range is empty.
    """
    count = len(urdf.joints)
    names = urdf.joints
    parameter_lower = per_joint('min_position', min_position, count, 'any', infinite=True,
                                joints=names)
    parameter_upper = per_joint('max_position', max_position, count, 'any', infinite=True,
                                joints=names)
    parameter_velocity = per_joint('max_velocity', max_velocity, count, infinite=True,
                                   joints=names)
    if (parameter_lower == math.inf).any() or (parameter_upper == -math.inf).any():
        raise ValueError('min_position cannot be +inf nor max_position -inf (use -inf and '
                         '+inf respectively for no limit)')

    lower = np.maximum(urdf.lower, parameter_lower)
    upper = np.minimum(urdf.upper, parameter_upper)
    velocity = np.minimum(urdf.velocity, parameter_velocity)
    lower_source = _sources(urdf.lower, parameter_lower, -math.inf, prefer_urdf=np.greater_equal)
    upper_source = _sources(urdf.upper, parameter_upper, math.inf, prefer_urdf=np.less_equal)
    velocity_source = _sources(urdf.velocity, parameter_velocity, math.inf,
                               prefer_urdf=np.less_equal)
    units = tuple('m' if kind == 'prismatic' else 'rad' for kind in urdf.types)
    for index in np.flatnonzero(lower > upper):
        unit = units[index]
        raise ValueError(
            f"joint '{urdf.joints[index]}' has no valid position: the URDF allows "
            f'[{urdf.lower[index]:g}, {urdf.upper[index]:g}] {unit} and the parameters '
            f'[{parameter_lower[index]:g}, {parameter_upper[index]:g}] {unit}')
    return JointLimits(urdf.joints, PositionLimits(_frozen(lower), _frozen(upper),
                                                   lower_source, upper_source),
                       _frozen(velocity), velocity_source, units, urdf.types)


def _sources(from_urdf: np.ndarray, from_parameter: np.ndarray, unlimited: float,
             prefer_urdf: np.ufunc) -> tuple[str, ...]:
    """Return per joint which bound is in force (the URDF's on a tie)."""
    result = []
    for urdf_value, parameter_value in zip(from_urdf, from_parameter, strict=True):
        if urdf_value == unlimited and parameter_value == unlimited:
            result.append(NONE)
        elif prefer_urdf(urdf_value, parameter_value):
            result.append(URDF)
        else:
            result.append(PARAMETER)
    return tuple(result)


def _origin(source: str, bound: str) -> str:
    """Name where a bound came from: ``URDF``, the parameter's name, or ``none``."""
    if source == PARAMETER:
        return _PARAMETER_NAME[bound]
    return _SOURCE_TEXT[source]


def _describe_origin(source: str, bound: str) -> str:
    """Name a bound's origin in a sentence: ``URDF`` or ``parameter max_position``."""
    origin = _origin(source, bound)
    return f'parameter {origin}' if source == PARAMETER else origin


def describe_sources(limits: JointLimits) -> str:
    """
    Summarise the limits in force and their sources in one line (a log line, a status).

    Example: ``joint_1: [-2.9, 2.9] rad (URDF), 2 rad/s (max_velocity); joint_2: position
    unlimited, 3 rad/s (URDF); joint_3: [0, 0.4] m (lower URDF, upper max_position), …``.
    """
    parts = []
    position = limits.position
    for index, name in enumerate(limits.joints):
        unit = limits.units[index]
        lower = _origin(position.lower_source[index], 'lower')
        upper = _origin(position.upper_source[index], 'upper')
        if position.lower_source[index] == position.upper_source[index] == NONE:
            text = 'position unlimited'
        else:
            origin = lower if lower == upper else f'lower {lower}, upper {upper}'
            text = (f'[{position.lower[index]:.6g}, {position.upper[index]:.6g}] {unit} '
                    f'({origin})')
        if limits.velocity_source[index] == NONE:
            text += ', velocity unlimited'
        else:
            text += (f', {limits.velocity[index]:.6g} {unit}/s '
                     f"({_origin(limits.velocity_source[index], 'velocity')})")
        parts.append(f'{name}: {text}')
    return '; '.join(parts)


def describe_range(limits: JointLimits, index: int) -> str:
    """
    Say a joint's position range and where each bound came from.

    E.g. ``[-2.9, 2.9] rad (lower from URDF; upper from parameter max_position)``.
    """
    position, unit = limits.position, limits.units[index]
    origins = '; '.join(
        f'{bound} from {_describe_origin(sources[index], bound)}'
        for bound, sources in (('lower', position.lower_source),
                               ('upper', position.upper_source)))
    return f'[{position.lower[index]:.6g}, {position.upper[index]:.6g}] {unit} ({origins})'


def check_positions(names: Sequence[str], positions: Sequence[float] | np.ndarray,
                    limits: JointLimits, what: str = 'goal position',
                    start: Sequence[float] | np.ndarray | None = None) -> str | None:
    """
    Check positions of named joints against their position limits.

    The one position check: the node refuses a goal or via point with it
    (:func:`traj_gen_ros.node.planning.position_checks.check_request`). A position may exceed a
    bound by :data:`POSITION_TOLERANCE` (relative to ``max(1, |bound|)``: rounding).

    :param names: joint names, any subset of ``limits.joints`` in any order.
    :param positions: one position per name, rad or m; or rows of them, ``(points, names)``.
    :param limits: the limits in force (:func:`merge_limits`).
    :param what: what the positions are, for the sentence (e.g. ``'via point 2 position'``);
        ``{point}`` in it is replaced by the row of a 2-D ``positions``.
    :param start: each named joint's current position (rad or m), or ``None``. A joint
        that starts outside its range may stay there or move toward or into its range:
        its positions must lie within ``[min(start, lower), max(start, upper)]``, the
        range widened to the start; only further out is refused.
    :return: ``None`` when every position is within its range (bounds included); otherwise
        one sentence for the first offending point and, in it, the first offending joint,
        naming it, the value, the valid range and where each bound came from, e.g. ``goal
        position 3.2 rad for joint 'joint_2' is outside its range [-2.9, 2.9] rad (lower
        from URDF; upper from URDF)``.
    :raises ValueError: ``names`` and ``positions`` differ in length.
    """
    rows = np.asarray(positions, dtype=float)
    rows = rows.reshape(1, -1) if rows.ndim < 2 else rows
    if rows.shape[1] != len(names):
        raise ValueError(f'{len(names)} names but {rows.shape[1]} positions')
    index_of = {name: index for index, name in enumerate(limits.joints)}
    for name in names:
        if name not in index_of:
            return (f"{what.format(point=0)} names joint '{name}', which has no limits; "
                    f'known joints: {list(limits.joints)}')
    indices = np.array([index_of[name] for name in names], dtype=int)
    lower, upper = limits.position.lower[indices], limits.position.upper[indices]
    range_lower, range_upper = lower, upper
    if start is not None:  # the range widened to the start
        start = np.asarray(start, dtype=float)
        lower, upper = np.minimum(lower, start), np.maximum(upper, start)
    finite = np.isfinite(rows)
    outside = ~finite | (rows < lower - POSITION_TOLERANCE * np.maximum(1.0, np.abs(lower))) \
        | (rows > upper + POSITION_TOLERANCE * np.maximum(1.0, np.abs(upper)))
    if not outside.any():
        return None
    point, column = (int(i) for i in np.argwhere(outside)[0])  # first point, first joint
    index, value, label = indices[column], rows[point, column], what.format(point=point)
    unit = limits.units[index]
    if not finite[point, column]:
        return f"{label} {value:g} {unit} for joint '{names[column]}' is not finite"
    reason = (f"{label} {value:.6g} {unit} for joint '{names[column]}' is outside its range "
              f'{describe_range(limits, index)}')
    if lower[column] != range_lower[column] or upper[column] != range_upper[column]:
        reason += (f'; it is at {start[column]:.6g} {unit}, outside its range: only positions '
                   f'in [{lower[column]:.6g}, {upper[column]:.6g}] {unit} (toward or into '
                   'its range) are allowed')
    return reason
