"""
The time-optimal timing of a path under joint and tool limits, as the core's Trajectory.

:func:`time_path` finds ``s(t)`` along a tool path and its joint path with TOPP-RA (Pham
& Pham, IEEE T-RO 34(3), 2018): the limits as linear constraints in ``(s̈, ṡ²)`` on a grid
(:mod:`.path_constraints`), the controllable sets backwards and the greedy pass forwards
(:mod:`.reachability`). The joints' states at the grid times become one quintic per
interval (:func:`~traj_gen_ros.core.polynomial.quintic_hermite`), checked exactly against
the joint limits: where a quintic overshoots between grid points, that interval's limits
are tightened and the path is timed again, so no plan above a limit is returned. The tool
limits are checked on the path parameter ``s(t)`` at three points inside every interval
(a sampled check: the constraints hold exactly at the grid points).

The grid (:func:`.path_constraints.path_grid`) has every knot and is cut finer where the
path bends, and around every zero of a joint's ``dq/ds`` where its acceleration limit can
bind (:mod:`.zero_inertia`: there the constraints held at both ends of an interval pinch
the speeds, and ``s̈`` dented for an interval or two); the duration is within 1 % of the
optimum.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.cartesian.bound_report import active_bounds, Bound, describe
from traj_gen_ros.core.cartesian.path_constraints import (
    assemble,
    path_grid,
    PathGrid,
    Stages,
    ToolLimits,
)
from traj_gen_ros.core.cartesian.reachability import time_optimal_squared_speed
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.exact.piece_extrema import derivative
from traj_gen_ros.core.exact.unit_peaks import unit_peaks
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.polynomial import quintic_hermite
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike

__all__ = ['Bound', 'TimedPath', 'ToolLimits', 'time_path']

#: Rounds of tightening a quintic's overshoot before the whole plan is slowed instead.
TIGHTENING_ROUNDS = 6
#: ``peak / limit`` above which a piece is tightened (inside the core's tolerance).
_SLACK = 1e-10
_MARGIN = 1.0 + 1e-9  # a tightened limit goes this much below the peak it scales away
# Ascending quartic rows to their Bernstein coefficients on [0, 1]: C(i, k) / C(4, k).
_BERNSTEIN = np.array([[math.comb(i, k) / math.comb(4, k) for i in range(5)]
                       for k in range(5)])
_TOOL_SAMPLES = np.array([0.25, 0.5, 0.75])  # where inside each interval the tool is checked


@dataclass(frozen=True)
class TimedPath:
    """
    A path's time-optimal timing: the joint trajectory and the path parameter ``s(t)``.

    :ivar trajectory: the joints in time, one quintic per grid interval.
    :ivar duration: s.
    :ivar times: ``(n,)`` the grid times, s.
    :ivar s: ``(n,)`` the grid (units of path), every knot among it.
    :ivar speed: ``(n,)`` ``ṡ`` at the grid, 0 at every stop.
    :ivar path_acceleration: ``(n - 1,)`` ``s̈``, constant on each interval.
    :ivar bounds: ``(n - 1,)`` the limit that bounds each interval (:class:`Bound`).
    :ivar joint_names: the names :meth:`describe` uses by default.
    """

    trajectory: Trajectory
    duration: float
    times: np.ndarray
    s: np.ndarray
    speed: np.ndarray
    path_acceleration: np.ndarray
    bounds: tuple[Bound, ...]
    joint_names: tuple[str, ...] | None = None

    def describe(self, joint_names: Sequence[str] | None = None) -> str:
        """Say what bounded the speed where (:func:`.bound_report.describe`)."""
        return describe(self.bounds, self.s, joint_names or self.joint_names)

    def path_parameter(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """
        Return ``s`` and ``ṡ`` at times ``t`` (s, clipped to the plan), shaped as ``t``.

        Exact: ``s̈`` is constant on each interval, so ``s`` is a parabola in time there.
        """
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        piece = np.clip(np.searchsorted(self.times, t, side='right') - 1, 0,
                        len(self.path_acceleration) - 1)
        local = t - self.times[piece]
        u = self.path_acceleration[piece]
        speed = self.speed[piece]
        return self.s[piece] + local * (speed + 0.5 * u * local), speed + u * local


def time_path(
    path: IdealPath,
    joint_path: JointPath,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    tool: ToolLimits,
    *,
    joint_names: Sequence[str] | None = None,
) -> TimedPath:
    """
    Time ``joint_path`` along ``path`` in the shortest time within every limit.

    Each joint's ``|q̇| <= max_velocity`` (rad/s) and ``|q̈| <= max_acceleration``
    (rad/s², scalars or one per joint, finite and > 0), the tool point's speed and whole
    acceleration vector, and its angular speed (:class:`ToolLimits`). The tool rests at
    every stop of the path and moves everywhere between. The result's joint trajectory is
    checked exactly against the joint limits.

    :raises ValueError: on bad limits (naming the joint), paths that disagree, or a point
        that is not a stop where the limits allow no speed (naming where).
    """
    joint_count = joint_path.joints.joint_count
    names = _joint_names(joint_names, joint_count)
    velocity = validation.per_joint('max_velocity', max_velocity, joint_count, joints=names)
    acceleration = validation.per_joint('max_acceleration', max_acceleration, joint_count,
                                        joints=names)
    if not isinstance(tool, ToolLimits):
        raise ValueError(f'tool must be ToolLimits, got {type(tool).__name__}')
    _check_lengths(path, joint_path)
    limits = tool.as_array()
    grid = path_grid(path, joint_path, tool_limited=bool(np.isfinite(limits).any()),
                     max_velocity=velocity, max_acceleration=acceleration,
                     tool_speed=limits[[0, 2]])
    return _timed(path, grid, velocity, acceleration, limits, names)


def _timed(path: IdealPath, grid: PathGrid, velocity: np.ndarray, acceleration: np.ndarray,
           tool: np.ndarray, names: tuple[str, ...] | None) -> TimedPath:
    """Time the sampled path, tightening where a quintic or the tool overshoots."""
    intervals = len(grid.s) - 1
    point_velocity = np.tile(velocity, (intervals + 1, 1))
    interval_acceleration = np.tile(acceleration, (intervals, 1))
    tool_speed = np.tile(tool[[0, 2]], (intervals + 1, 1))
    tool_acceleration = np.full(intervals, tool[1])
    for _ in range(TIGHTENING_ROUNDS):
        stages = assemble(grid, point_velocity, interval_acceleration, tool_speed,
                          tool_acceleration)
        x = _squared_speed(stages, grid)
        u, times = grid_motion(grid, x)
        trajectory = joint_trajectory(grid, x, u, times)
        tool_ratios = _tool_ratios(path, grid, x, u, tool)  # (n, 3)
        over_tool = tool_ratios > 1.0 + _SLACK
        violation = limit_violation(trajectory, velocity, acceleration)
        if violation is None and not over_tool.any():
            break
        joint_ratios = _piece_ratios(trajectory, velocity, acceleration)  # (2, n, joints)
        shrink = _shrink(joint_ratios)
        _shrink_points(point_velocity, shrink[0])
        interval_acceleration *= shrink[1]
        shrink = _shrink(tool_ratios.T)
        _shrink_points(tool_speed, shrink[[0, 2]].T)
        tool_acceleration *= shrink[1]
    else:  # still above somewhere: slow the whole plan down by the exact factor
        joint_ratios = _piece_ratios(trajectory, velocity, acceleration)
        stretch = max(float(joint_ratios[0].max()), math.sqrt(joint_ratios[1].max()),
                      float(tool_ratios[:, [0, 2]].max(initial=0.0)),
                      math.sqrt(tool_ratios[:, 1].max(initial=0.0)), 1.0) * _MARGIN
        x, u, times = x / stretch ** 2, u / stretch ** 2, times * stretch
        trajectory = joint_trajectory(grid, x, u, times)
        violation = limit_violation(trajectory, velocity, acceleration)
    if violation is not None:  # cannot happen: slowed down by the exact peak ratios
        raise RuntimeError(f'time_path: {violation.describe(names)}')
    return TimedPath(trajectory, float(times[-1]), times, grid.s, np.sqrt(x), u,
                     active_bounds(grid, x, u, velocity, acceleration, tool), names)


def _squared_speed(stages: Stages, grid: PathGrid) -> np.ndarray:
    """Return ``ṡ²`` at the grid, refusing a point between stops that cannot be moved."""
    x = time_optimal_squared_speed(stages)
    moving = ~grid.stop
    stuck = np.flatnonzero(moving & ~((x > 0.0) & np.isfinite(x)))
    if stuck.size:
        point = float(grid.s[stuck[0]])
        reason = 'allow no speed' if x[stuck[0]] <= 0.0 else 'do not bound the speed'
        raise ValueError(
            f'the limits {reason} at s = {point:.6g} ({100.0 * point / grid.s[-1]:.1f} % '
            'of the path), which is not a stop: make it a stop (a corner without blend), '
            'or check the joint path there')
    return x


def grid_motion(grid: PathGrid, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return ``s̈`` per interval and the grid times: ``Δt = 2Δ / (ṡ_i + ṡ_{i+1})``."""
    delta = grid.delta
    speed = np.sqrt(x)
    times = np.zeros(len(x))
    np.cumsum(2.0 * delta / (speed[:-1] + speed[1:]), out=times[1:])
    return (x[1:] - x[:-1]) / (2.0 * delta), times


def joint_trajectory(grid: PathGrid, x: np.ndarray, u: np.ndarray, times: np.ndarray
                     ) -> Trajectory:
    """One quintic per interval from ``q``, ``q' ṡ`` and each side's ``q' s̈ + q'' ṡ²``."""
    rate = np.empty_like(grid.q)
    rate[0], rate[-1] = grid.dq[0, 0], grid.dq[1, -1]
    rate[1:-1] = 0.5 * (grid.dq[0, 1:] + grid.dq[1, :-1])
    velocities = rate * np.sqrt(x)[:, None]
    start = grid.dq[0] * u[:, None] + grid.ddq[0] * x[:-1, None]
    end = grid.dq[1] * u[:, None] + grid.ddq[1] * x[1:, None]
    return quintic_hermite(times, grid.q, velocities, start, end)


def _piece_ratios(trajectory: Trajectory, velocity: np.ndarray, acceleration: np.ndarray
                  ) -> np.ndarray:
    """
    Each piece's peak ``|q̇|``, ``|q̈|`` over the limit, ``(2, pieces, joints)``.

    Exact (:func:`~traj_gen_ros.core.exact.unit_peaks.unit_peaks`) where above
    ``1 + _SLACK``, else a bound within it: the largest Bernstein coefficient (the convex
    hull property, as :func:`~traj_gen_ros.core.exact.piece_extrema.peak_bounds`).
    """
    lengths = np.diff(trajectory.breakpoints)[:, None, None]
    pieces, _, joints = trajectory.coefficients.shape
    rates = derivative(trajectory.coefficients)
    rows = np.zeros((2, pieces, joints, 5))
    for order, limit in ((0, velocity), (1, acceleration)):
        size = rates.shape[1]
        scaled = rates * lengths ** np.arange(size)[None, :, None]
        rows[order, :, :, :size] = scaled.transpose(0, 2, 1) / limit[None, :, None]
        rates = derivative(rates)
    rows = rows.reshape(-1, 5)
    ratios = np.abs(rows @ _BERNSTEIN).max(axis=1)
    above = ratios > 1.0 + _SLACK
    if above.any():
        ratios[above] = unit_peaks(rows[above])
    return ratios.reshape(2, pieces, joints)


def _tool_ratios(path: IdealPath, grid: PathGrid, x: np.ndarray, u: np.ndarray,
                 tool: np.ndarray) -> np.ndarray:
    """
    Sample the tool's speed, acceleration and angular speed over their limits, ``(n, 3)``.

    At :data:`_TOOL_SAMPLES` inside every interval, from ``ṡ² = x_i + 2 s̈ (s - s_i)``:
    ``|p'| ṡ``, ``|p' s̈ + p'' ṡ²|``, ``|ω_s| ṡ``. Zeros where no tool limit is finite.
    """
    ratios = np.zeros((len(u), 3))
    if not np.isfinite(tool).any():
        return ratios
    offsets = grid.delta[:, None] * _TOOL_SAMPLES
    samples = path.sample((grid.s[:-1, None] + offsets).reshape(-1))
    squared = np.maximum(x[:-1, None] + 2.0 * u[:, None] * offsets, 0.0).reshape(-1)
    accel = np.repeat(u, len(_TOOL_SAMPLES))
    rates = np.stack([
        np.linalg.norm(samples.velocity, axis=1) * np.sqrt(squared),
        np.linalg.norm(samples.velocity * accel[:, None]
                       + samples.acceleration * squared[:, None], axis=1),
        np.linalg.norm(samples.angular, axis=1) * np.sqrt(squared)], axis=1)
    return (rates / tool).reshape(len(u), len(_TOOL_SAMPLES), 3).max(axis=1)


def _shrink(ratios: np.ndarray) -> np.ndarray:
    """
    Give the factor on each interval's limits for the overshoots ``ratios`` ``(kinds, n, …)``.

    Twice the excess, and on the neighbours too: an interval's states are its
    neighbours' ends, so tightening it alone moves the overshoot next door.
    """
    excess = np.where(ratios > 1.0 + _SLACK, ratios - 1.0, 0.0)
    spread = excess.copy()
    np.maximum(spread[:, 1:], excess[:, :-1], out=spread[:, 1:])
    np.maximum(spread[:, :-1], excess[:, 1:], out=spread[:, :-1])
    return np.where(spread > 0.0, 1.0 / ((1.0 + 2.0 * spread) * _MARGIN), 1.0)


def _shrink_points(limits: np.ndarray, factors: np.ndarray) -> None:
    """Scale the limits at both ends of every interval by its factor (the smaller wins)."""
    point = np.ones_like(limits)
    point[:-1] = factors
    np.minimum(point[1:], factors, out=point[1:])
    limits *= point


def _joint_names(joint_names: Sequence[str] | None, joint_count: int
                 ) -> tuple[str, ...] | None:
    """Return the names as a tuple, one per joint, or refuse."""
    if joint_names is None:
        return None
    names = tuple(str(name) for name in joint_names)
    if len(names) != joint_count:
        raise ValueError(f'joint_names has {len(names)} names for {joint_count} joints')
    return names


def _check_lengths(path: IdealPath, joint_path: JointPath) -> None:
    """Refuse a path of no length, or a joint path of another length."""
    length = float(path.length)
    if not (math.isfinite(length) and length > 0.0):
        raise ValueError(f'the path length must be finite and > 0, got {length}')
    if abs(float(joint_path.length) - length) > 1e-9 * length:
        raise ValueError(f'the joint path is {joint_path.length} long but the tool path '
                         f'{length}: they must be the same path')
