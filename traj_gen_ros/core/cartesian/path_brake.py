"""
A brake *along* a tool path: from a point and speed on it to rest, the tool kept on it.

``~/stop``, a lost measured state and a cancel brake a line or an arc without leaving it:
the path parameter is slowed, not each joint. From ``(s_0, ṡ_0)`` the greedy pass takes
the *smallest* ``s̈`` the constraints of :mod:`.path_constraints` allow at every grid point
(``U_lo(x)``, the largest deceleration: the mirror of :mod:`.reachability`'s forward
pass), until ``ṡ`` reaches 0 inside an interval; that end is where it rests. Each
interval's joint states become one quintic (as :func:`.path_timing.time_path`'s), checked
exactly against the joint limits; where one overshoots, every limit is lowered by
:data:`BACK_OFF` and the brake is planned again.

Units: units of path (m, or rad for a rotation in place), s; rad (or m).
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.cartesian.path_constraints import (
    assemble,
    merge_values,
    nearest_points,
    path_grid,
    PathGrid,
    sample_grid,
    Stages,
    ToolLimits,
)
from traj_gen_ros.core.cartesian.path_timing import grid_motion, joint_trajectory, TimedPath
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.trajectory import Trajectory

#: The factors of the acceleration limits, one per attempt: the first attempts shave off
#: the quintics' overshoot between grid points (parts per million), the later ones more.
BACK_OFF = (1.0, 1.0 - 1e-6, 1.0 - 1e-5, 1.0 - 1e-4, 1.0 - 1e-3, 0.99, 0.97, 0.9, 0.8)


def brake_along(path: IdealPath, joint_path: JointPath, max_velocity: np.ndarray,
                max_acceleration: np.ndarray, tool: ToolLimits, s0: float, speed: float,
                timed: TimedPath | None = None) -> tuple[Trajectory, float]:
    """
    Return the brake from ``s0`` at ``ṡ = speed`` to rest along the path, and where it rests.

    The trajectory is in local time from 0 (joints, as ``joint_path``); it starts at
    ``q(s0)`` with velocity ``q'(s0)·speed`` and ends at rest at ``q(s_end)``.

    ``timed``: the path's own timing, where the brake starts on it. The brake then runs on
    its grid and never faster than it: where the plan itself slows down as hard as the
    limits allow (before a tighter stretch), the brake is the plan there, exactly.

    :raises ValueError: ``speed`` < 0, or no brake within the limits was found (the caller
        brakes each joint instead).
    """
    if not speed >= 0.0:
        raise ValueError(f'brake_along: speed {speed!r} must be >= 0')
    length = float(path.length)
    s0 = min(max(float(s0), 0.0), length)
    velocity = np.asarray(max_velocity, dtype=float)
    acceleration = np.asarray(max_acceleration, dtype=float)
    limits = tool.as_array()
    if timed is None:
        full = path_grid(path, joint_path, tool_limited=bool(np.isfinite(limits).any()),
                         max_velocity=velocity, max_acceleration=acceleration,
                         tool_speed=limits[[0, 2]]).s
    else:
        full = timed.s
    ahead = full[full > s0 + 1e-12 * length]
    if ahead.size >= 2 and ahead[0] - s0 < 0.5 * (ahead[1] - ahead[0]):
        ahead = ahead[1:]  # no sliver of an interval first: its quintic would be stiff
    if speed == 0.0 or ahead.size == 0:
        raise ValueError('brake_along: nothing to brake (at rest, or at the end)')
    cap = None
    if timed is not None:  # never faster than the plan: ṡ² at the grid ahead
        cap = np.concatenate([[speed * speed], np.interp(ahead, timed.s, timed.speed ** 2)])
    for scale in BACK_OFF:  # the accelerations only: the speed may be at its bound already
        plan = _attempt(path, joint_path, np.concatenate([[s0], ahead]), speed,
                        velocity, acceleration * scale, limits * [1.0, scale, 1.0], cap)
        if plan is not None and limit_violation(plan[0], velocity, acceleration) is None:
            return plan
    raise ValueError('brake_along: no brake along the path within the limits stops before '
                     "its end (the timing's own deceleration is the brake there)")


def _attempt(path: IdealPath, joint_path: JointPath, s: np.ndarray, speed: float,
             velocity: np.ndarray, acceleration: np.ndarray, tool: np.ndarray,
             cap: np.ndarray | None = None) -> tuple[Trajectory, float] | None:
    """
    Decelerate as hard as the (scaled) limits allow from ``s[0]``; None: not at rest.

    ``cap``: the largest ``ṡ²`` at each point of ``s`` (the plan's own), or None.
    """
    grid = _grid(path, joint_path, s)
    stages = _stages(grid, velocity, acceleration, tool)
    a, b, c, twice = stages.a, stages.b, stages.c, 2.0 * stages.delta
    x = [speed * speed]
    for index in range(len(twice)):
        rows = a[index] < 0.0
        lowest = float(np.max((c[index, rows] - b[index, rows] * x[-1]) / a[index, rows]))
        following = x[-1] + twice[index] * lowest
        if following <= 0.0:  # at rest inside this interval: end the grid there
            end = float(s[index] + x[-1] / (-2.0 * lowest))
            cut = np.concatenate([s[:index + 1], [end]])
            if index > 0 and end - s[index] < 0.5 * (s[index] - s[index - 1]):
                # No sliver last: the rest is reached over the interval before it too.
                cut, x = np.concatenate([s[:index], [end]]), x[:-1]
            grid = _grid(path, joint_path, cut)
            squared = np.array(x + [0.0] if len(x) < len(cut) else x)
            u, times = grid_motion(grid, squared)
            return joint_trajectory(grid, squared, u, times), float(cut[-1])
        bound = float(stages.x_max[index + 1]) if cap is None else \
            min(float(stages.x_max[index + 1]), float(cap[index + 1]))
        x.append(min(following, bound))
    return None  # the path ended first: the timing's own end brakes there


def _grid(path: IdealPath, joint_path: JointPath, s: np.ndarray) -> PathGrid:
    """Sample both paths at ``s`` (its knots those of the path), no stop but the end."""
    knots = merge_values(float(path.length), path.knots, joint_path.knots)
    inside = knots[(knots > s[0]) & (knots < s[-1])]
    at_knots = nearest_points(s, inside) if inside.size else np.zeros(0, dtype=int)
    return sample_grid(path, joint_path, s, at_knots, np.zeros(0, dtype=int))


def _stages(grid: PathGrid, velocity: np.ndarray, acceleration: np.ndarray,
            tool: np.ndarray) -> Stages:
    """Build the constraints of every interval, with the (scaled) limits everywhere."""
    intervals = len(grid.s) - 1
    return assemble(grid, np.tile(velocity, (intervals + 1, 1)),
                    np.tile(acceleration, (intervals, 1)),
                    np.tile(tool[[0, 2]], (intervals + 1, 1)), np.full(intervals, tool[1]))
