"""
``traj-gen solve line|arc`` and ``plot line|arc``: a tool path planned offline, as the node does.

The chain of ``--urdf`` (:func:`traj_gen_ros.cli.kinematics.load_chain`), the tool pose at
``--start`` (``chain.forward``), and from there what the node's ``~/cartesian_path`` and
``~/circular_goal`` plan (:mod:`traj_gen_ros.node.planning.tool_motion`) with the core:
the ideal path (:func:`~traj_gen_ros.core.cartesian.tool_path.straight_path` with
``--blend-radius``, or :func:`~traj_gen_ros.core.cartesian.tool_path.circular_path`), the
joint path that follows it within the URDF's position limits
(:func:`~traj_gen_ros.core.cartesian.joint_path.follow`) and its time-optimal timing
(:func:`~traj_gen_ros.core.cartesian.path_timing.time_path`). A path the core refuses
(coincident or collinear points, out of reach, a joint limit, a singularity, a
configuration flip) is a :class:`UsageError`: one line, exit 2, saying where.

The tool's speed along the path is ``|dp/ds|·ṡ`` (m/s) and its angular speed ``|ω_s|·ṡ``
(rad/s), from the ideal path at ``s(t)`` (:meth:`TimedPath.path_parameter`).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
import json
import math

import numpy as np
from traj_gen_ros.cli.common import EXIT_OK, report_plot, UsageError
from traj_gen_ros.cli.kinematics import describe_pose, joint_values, load_chain
from traj_gen_ros.cli.tool_path_poses import pose_matrices, tool_poses
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_timing import time_path, TimedPath, ToolLimits
from traj_gen_ros.core.cartesian.samples import JointPath
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path, ToolPath
from traj_gen_ros.core.kinematics import Chain, pose_distance

_DEGREE = math.pi / 180.0


@dataclass(frozen=True)
class ToolPathPlan:
    """
    A line or an arc planned offline: the chain, where it starts, and the core's results.

    :ivar shape: ``'line'`` or ``'arc'``.
    :ivar q_start: ``(joints,)`` rad or m.
    :ivar poses: the ``(4, 4)`` poses given (``--to``), in the base frame.
    :ivar limits: the limits timed under: ``max_velocity``, ``max_acceleration`` (one per
        joint), and the tool's three (:class:`ToolLimits`' fields).
    """

    shape: str
    chain: Chain
    q_start: np.ndarray
    poses: list[np.ndarray]
    blend_radius: float
    path: ToolPath
    joint_path: JointPath
    timed: TimedPath
    limits: dict


def plan_tool_path(args: argparse.Namespace) -> ToolPathPlan:
    """Plan ``solve|plot line|arc``'s arguments; :class:`UsageError` for what the core refuses."""
    shape = args.tool_path
    if shape == 'arc' and args.blend_radius > 0:
        raise UsageError('--blend-radius is for line: an arc has no corners')
    poses = pose_matrices(tool_poses(args.poses, shape, args.degrees))
    chain = load_chain(args)
    q_start = joint_values(args.start, chain, args.degrees, np.zeros(len(chain.joints)),
                           '--start')
    start = chain.forward(q_start)
    velocity = _per_joint(args.max_velocity, chain, '--max-velocity')
    acceleration = _per_joint(args.max_acceleration, chain, '--max-acceleration')
    tool = ToolLimits(args.max_linear_velocity, args.max_linear_acceleration,
                      args.max_angular_velocity)
    try:
        if shape == 'arc':
            path = circular_path(start, poses[0], poses[1])
        else:
            path = straight_path(start, poses, args.blend_radius)
        joint_path = follow(chain, path, q_start)  # PathRefusal is a ValueError
        timed = time_path(path, joint_path, velocity, acceleration, tool,
                          joint_names=chain.joints)
    except ValueError as error:
        raise UsageError(f'{shape}: {error}') from None
    limits = {'max_velocity': velocity.tolist(), 'max_acceleration': acceleration.tolist(),
              'max_linear_velocity': tool.max_linear_velocity,
              'max_linear_acceleration': tool.max_linear_acceleration,
              'max_angular_velocity': tool.max_angular_velocity}
    return ToolPathPlan(shape, chain, q_start, poses, args.blend_radius, path, joint_path,
                        timed, limits)


def _per_joint(values: list[float], chain: Chain, option: str) -> np.ndarray:
    if len(values) == 1:
        return np.full(len(chain.joints), values[0])
    if len(values) != len(chain.joints):
        raise UsageError(f'{option}: {len(values)} limits for the {len(chain.joints)} joints '
                         f'{", ".join(chain.joints)}: give one for all or one per joint')
    return np.array(values, dtype=float)


def tool_speeds(plan: ToolPathPlan, times: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``s``, the tool's speed ``|dp/ds|·ṡ`` (m/s) and ``|ω_s|·ṡ`` (rad/s) at ``times``."""
    s, rate = plan.timed.path_parameter(times)
    samples = plan.path.sample(s)
    return (s, np.linalg.norm(samples.velocity, axis=1) * rate,
            np.linalg.norm(samples.angular, axis=1) * rate)


def bound_runs(plan: ToolPathPlan) -> list[dict]:
    """
    Return the runs of the path one limit bounds: ``{'limit', 'start', 'end'}`` each.

    ``start`` and ``end`` are fractions of the path's length and times (s): the grid
    intervals of :attr:`TimedPath.bounds` with the same limit, merged.
    """
    timed, length = plan.timed, plan.path.length
    runs: list[dict] = []
    for index, bound in enumerate(timed.bounds):
        name = bound.name(plan.chain.joints)
        if runs and runs[-1]['limit'] == name:
            runs[-1].update(end=timed.s[index + 1] / length, end_time=timed.times[index + 1])
            continue
        runs.append({'limit': name, 'start': timed.s[index] / length,
                     'end': timed.s[index + 1] / length, 'start_time': timed.times[index],
                     'end_time': timed.times[index + 1]})
    return [{key: value if isinstance(value, str) else float(value)
             for key, value in run.items()} for run in runs]


def _scales(chain: Chain, degrees: bool) -> np.ndarray:
    """Per joint, what one rad or m is in the user's unit (deg for angular joints)."""
    return np.where(chain.angular & degrees, 1.0 / _DEGREE, 1.0)


def _round(values: object, digits: int = 9) -> object:
    return (np.round(np.asarray(values, dtype=float), digits) + 0.0).tolist()


def describe_plan(plan: ToolPathPlan, rows: int, degrees: bool) -> dict:
    """Return what ``solve line|arc`` prints: the plan, its bounds, peaks and sampled rows."""
    chain, timed = plan.chain, plan.timed
    scales = _scales(chain, degrees)
    times = np.linspace(0.0, timed.duration, rows)
    s, speed, angular = tool_speeds(plan, times)
    positions = timed.trajectory.sample(times)[0] * scales
    dense = np.linspace(0.0, timed.duration, 2001)
    _, dense_speed, dense_angular = tool_speeds(plan, dense)
    peak_velocity, peak_acceleration = timed.trajectory.peaks()
    end = timed.trajectory.sample(timed.duration)[0][0]
    distance, angle = pose_distance(chain.forward(end), plan.poses[-1])
    units = [('deg' if degrees else 'rad') if angular_joint else 'm'
             for angular_joint in chain.angular]
    return {
        'chain': chain.describe(), 'base_frame': chain.base_frame,
        'tool_frame': chain.tool_frame, 'joint_names': list(chain.joints),
        'joint_units': units, 'shape': plan.shape,
        'start': {'joints': _round(plan.q_start * scales),
                  'pose': describe_pose(chain.forward(plan.q_start), degrees)},
        'poses': [describe_pose(pose, degrees) for pose in plan.poses],
        'blend_radius': plan.blend_radius, 'length': float(plan.path.length),
        'pieces': [{'kind': piece.kind, 'start': piece.start, 'end': piece.end,
                    'waypoint': piece.waypoint} for piece in plan.path.pieces],
        'duration': float(timed.duration), 'bounded_by': timed.describe(chain.joints),
        'bounds': bound_runs(plan), 'limits': plan.limits,
        'peaks': {'joint_velocity': _round(peak_velocity * scales),
                  'joint_acceleration': _round(peak_acceleration * scales),
                  'tool_speed': float(dense_speed.max()),
                  'tool_angular_speed': float(dense_angular.max())},
        'rows': [{'t': float(t), 's': float(value), 'fraction': float(value / plan.path.length),
                  'tool_speed': float(v), 'tool_angular_speed': float(w),
                  'positions': _round(row)}
                 for t, value, v, w, row in zip(times, s, speed, angular, positions,
                                                strict=True)],
        'end': {'joints': _round(end * scales), 'position_error_mm': distance * 1e3,
                'orientation_error_mrad': angle * 1e3},
    }


def _cells(values: list[float], width: int, decimals: int) -> str:
    """Return numbers right-aligned in ``width``, with no '-0.000'."""
    return ''.join(f'{0.0 if abs(value) < 0.5 * 10 ** -decimals else value:>{width}.{decimals}f}'
                   for value in values)


def format_plan(result: dict) -> str:
    """Return the text table of :func:`describe_plan`'s result."""
    names, units, limits = result['joint_names'], result['joint_units'], result['limits']
    width = max(12, *(len(name) + 2 for name in names))
    shape = result['shape']
    count = len(result['poses'])
    what = (f'line through {count} pose{"s" if count > 1 else ""}, blend radius '
            f"{result['blend_radius']:g} m" if shape == 'line'
            else 'arc through the interim point to the goal')
    pieces = ', '.join(piece['kind'] for piece in result['pieces'])
    speeds = ', '.join(f'{value:g}' for value in dict.fromkeys(limits['max_velocity']))
    accelerations = ', '.join(f'{value:g}' for value in dict.fromkeys(limits['max_acceleration']))
    peaks = result['peaks']
    lines = [
        result['chain'],
        f"{what}: {pieces}; length {result['length']:.6f} (m, and rad at 1 m/rad)",
        f'limits: joints {speeds} rad/s, {accelerations} rad/s²; tool '
        f"{limits['max_linear_velocity']:g} m/s, {limits['max_linear_acceleration']:g} m/s², "
        f"{limits['max_angular_velocity']:.5g} rad/s",
        f"duration {result['duration']:.6f} s; speed bounded by {result['bounded_by']}",
        f"{'t (s)':>9}{'s (%)':>8}{'tool m/s':>10}{'tool rad/s':>11}"
        + ''.join(f'{name:>{width}}' for name in names),
        f"{'':>38}" + ''.join(f'{f"({unit})":>{width}}' for unit in units),
    ]
    for row in result['rows']:
        lines.append(_cells([row['t']], 9, 4) + _cells([100 * row['fraction']], 8, 2)
                     + _cells([row['tool_speed']], 10, 4)
                     + _cells([row['tool_angular_speed']], 11, 4)
                     + _cells(row['positions'], width, 6))
    lines += [f"{'peak |velocity| (unit/s)':<38}" + _cells(peaks['joint_velocity'], width, 6),
              f"{'peak |acceleration| (unit/s²)':<38}"
              + _cells(peaks['joint_acceleration'], width, 6),
              f"peak tool speed {peaks['tool_speed']:.4f} m/s, "
              f"{peaks['tool_angular_speed']:.4f} rad/s (sampled)",
              f"end: {result['tool_frame']} {result['end']['position_error_mm']:.6f} mm and "
              f"{result['end']['orientation_error_mrad']:.6f} mrad from the goal"]
    return '\n'.join(lines)


def run(args: argparse.Namespace) -> int:
    """``traj-gen solve line|arc`` (the table or JSON) or ``plot line|arc`` (the PNG)."""
    if args.command == 'solve' and args.rows < 2:
        raise UsageError(f'--rows must be at least 2 (the start and the end), not {args.rows}')
    plan = plan_tool_path(args)
    if args.command == 'plot':
        from traj_gen_ros.cli import tool_path_plot  # matplotlib: only when a plot is made
        report_plot(tool_path_plot.plot_tool_path(plan, args.output, args.size,
                                                  args.degrees), args.json)
        return EXIT_OK
    result = describe_plan(plan, args.rows, args.degrees)
    print(json.dumps(result, indent=2, ensure_ascii=False) if args.json
          else format_plan(result))
    return EXIT_OK
