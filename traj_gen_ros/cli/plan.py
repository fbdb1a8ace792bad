"""
``traj-gen solve`` and ``plot``: turn the command line into a plan with the core.

Every plan comes from the core's entry points (:func:`traj_gen_ros.min_time`,
:func:`traj_gen_ros.plan_path`) or, for the textbook profiles with given durations, from
Craig's own functions; a refusal becomes a :class:`UsageError` (exit 2). Units are the
user's (rad, or deg with ``--degrees``: the core is linear in the position unit) and s.
"""

from __future__ import annotations

import argparse

import numpy as np
from traj_gen_ros import core
from traj_gen_ros.cli.common import joint_names, UsageError
from traj_gen_ros.core.validation import per_joint


class Plan:
    """A planned trajectory with what the user gave, in the user's units."""

    def __init__(self, trajectory: object, profile: str, points: np.ndarray,
                 point_times: np.ndarray, unit: str) -> None:
        self.trajectory = trajectory
        self.profile = profile
        self.points = points  # (points, joints) in user units
        self.point_times = point_times  # (points,) s
        self.unit = unit


def _per_joint(values: list[float] | None, name: str, joints: int,
               default: float | None = 0.0) -> np.ndarray | None:
    if values is None:
        return None if default is None else np.full(joints, default)
    try:
        return per_joint(f'--{name}', values, joints, 'any')
    except ValueError as error:
        raise UsageError(str(error)) from None


def _segment_durations(durations: list[float], points: int) -> np.ndarray:
    """Return ``--durations`` as an array; UsageError unless there is one per segment."""
    segments = points - 1
    if len(durations) != segments:
        raise UsageError(f'{points} points need {segments} duration'
                         f'{"s" if segments > 1 else ""}, got {len(durations)}')
    return np.array(durations, dtype=float)


def make_plan(args: argparse.Namespace) -> Plan:
    """Plan ``args.profile`` with the core solver; raise UsageError on refusal."""
    if not args.points:
        raise UsageError('--points is required (see traj-gen solve --help)')
    counts = {len(point) for point in args.points}
    if len(counts) > 1:
        raise UsageError(f'every point needs the same number of joints, got '
                         f'{" ".join(str(len(p)) for p in args.points)} (joints are '
                         'separated by commas: --points 0,0 1,2)')
    if len(args.points) < 2:
        raise UsageError('--points needs at least two points (start and goal)')
    # The core is linear in the position unit, so degrees are solved as they are: results
    # and the solver's messages then come out in degrees too.
    unit = 'deg' if args.degrees else 'rad'
    points = np.array(args.points, dtype=float)
    joints = points.shape[1]
    path = points
    profile = args.profile

    def joint_values(name: str, default: float | None = 0.0) -> np.ndarray | None:
        return _per_joint(getattr(args, name.replace('-', '_')), name, joints, default)

    def durations(single: bool) -> np.ndarray:
        if args.durations is None:
            raise UsageError(f'{profile} needs --duration{"" if single else "s"}')
        return _segment_durations(args.durations, len(points))

    try:
        if profile in ('cubic', 'quintic'):
            if len(points) != 2:
                raise UsageError(f'{profile} takes 2 points (start and goal), got '
                                 f'{len(points)}; use {profile}-via for via points')
            duration = float(durations(True)[0])
            extra = {'v0': joint_values('v0'), 'vf': joint_values('vf')}
            if profile == 'quintic':
                extra.update(a0=joint_values('a0'), af=joint_values('af'))
            solver = core.cubic if profile == 'cubic' else core.quintic
            trajectory = solver(path[0], path[1], duration, **extra)
            times = np.array([0.0, duration])
        elif profile in ('cubic-via', 'quintic-via'):
            segment_durations = durations(False)
            solver = core.cubic_via if profile == 'cubic-via' else core.quintic_via
            trajectory = solver(path, segment_durations, args.velocities,
                                v0=joint_values('v0'))
            times = np.concatenate([[0.0], np.cumsum(segment_durations)])
        elif profile == 'lspb':
            acceleration = joint_values('acceleration', None)
            if acceleration is None:
                raise UsageError('lspb needs --acceleration (the blend acceleration |θ̈|)')
            segment_durations = durations(len(points) == 2)
            if len(points) == 2:
                trajectory = core.lspb(path[0], path[1], float(segment_durations[0]),
                                       acceleration, v0=joint_values('v0'))
            else:
                trajectory = core.lspb_via(path, segment_durations, acceleration,
                                           v0=joint_values('v0'))
            times = np.concatenate([[0.0], np.cumsum(segment_durations)])
        elif profile == 'scurve':
            trajectory, times = _scurve(args, path, joint_values)
        else:
            trajectory, times = _min_time(args, path, joint_values)
    except core.JointError as error:  # the core knows joints by index: name them as the node does
        raise UsageError(f'{profile}: {error.named(joint_names(joints))}') from None
    except ValueError as error:
        raise UsageError(f'{profile}: {error}') from None
    if profile == 'min-time':
        profile = f'min-time {args.shape}'
    return Plan(trajectory, profile, points, times, unit)


def _scurve(args: argparse.Namespace, path: np.ndarray,
            joint_values: object) -> tuple[object, np.ndarray]:
    """
    Plan the jerk-limited S-curve: minimum time, or the given ``--durations``.

    Two points: from ``--v0``/``--a0`` to rest (``min_time(..., 'scurve')`` or ``scurve``);
    more: through the via points with heuristic velocities (``plan_path``, timed from the
    limits when no durations are given).
    """
    limits = [joint_values(name, None) for name in ('max-velocity', 'max-acceleration',
                                                    'max-jerk')]
    if any(limit is None for limit in limits):
        raise UsageError('scurve needs --max-velocity, --max-acceleration and --max-jerk')
    if args.velocities != 'heuristic':
        raise UsageError('scurve takes --velocities heuristic only (zero acceleration at '
                         'every via point)')
    if args.durations is not None:
        _segment_durations(args.durations, len(path))
    start = {'v0': joint_values('v0'), 'a0': joint_values('a0')}
    if len(path) == 2 and args.durations is None:
        trajectory = core.min_time(path[0], path[1], limits[0], limits[1], 'scurve',
                                   max_jerk=limits[2], **start)
    elif len(path) == 2:
        trajectory = core.scurve(path[0], path[1], float(args.durations[0]), *limits,
                                 **start)
    else:
        trajectory = core.plan_path(path, args.durations, 'scurve', max_velocity=limits[0],
                                    max_acceleration=limits[1], max_jerk=limits[2],
                                    **start)
    if len(path) == 2:
        return trajectory, np.array([0.0, trajectory.duration])
    durations = np.array(args.durations, dtype=float) if args.durations is not None else \
        core.via_durations(path, limits[0], limits[1], 'scurve', max_jerk=limits[2])
    return trajectory, np.concatenate([[0.0], np.cumsum(durations)])


def _min_time(args: argparse.Namespace, path: np.ndarray,
              joint_values: object) -> tuple[object, np.ndarray]:
    if args.durations is not None:
        raise UsageError('min-time finds the durations itself: drop --durations')
    max_velocity = joint_values('max-velocity', None)
    max_acceleration = joint_values('max-acceleration', None)
    if max_velocity is None or max_acceleration is None:
        raise UsageError('min-time needs --max-velocity and --max-acceleration')
    if len(path) == 2:
        trajectory = core.min_time(path[0], path[1], max_velocity, max_acceleration,
                                   profile=args.shape)
        return trajectory, np.array([0.0, trajectory.duration])
    acceleration = joint_values('acceleration', None)
    durations = core.via_durations(path, max_velocity, max_acceleration, args.shape,
                                   args.velocities, acceleration)
    trajectory = core.plan_path(path, durations, args.shape, velocities=args.velocities,
                                max_velocity=max_velocity,
                                max_acceleration=max_acceleration,
                                blend_acceleration=acceleration)
    return trajectory, np.concatenate([[0.0], np.cumsum(durations)])
