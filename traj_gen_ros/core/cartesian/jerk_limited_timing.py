"""
The timing of a path with every joint's jerk bounded too: the S-curve profile of a path.

:func:`time_path_jerk_limited` rests at every knot of the path (a blend's curvature steps
at its ends, so ``q''`` jumps there and ``q̈ = q' s̈ + q'' ṡ²`` would jump at any speed:
under a jerk limit every corner is a stop). Between two knots the path parameter runs
one rest-to-rest seven-phase S-curve (Biagiotti & Melchiorri §3.4, the core's
:func:`~traj_gen_ros.core.timing.min_time` with profile ``scurve`` for one axis ``s``)
within constant ``(V, A, J)``: first the conservative ones of :mod:`.jerk_bounds` (the
chain rule's bound of every joint's rates from its largest ``|q'|``, ``|q''|``,
``|q'''|`` on the piece, which keeps every limit), then, up to :data:`REFINEMENTS`
times, ones chosen in the same rows scaled by what the motion before really used of
each (the bound is loose where the largest rates do not meet). The joints ``q(s(t))``
are sampled into quintics (:func:`.jerk_limited_sampling.sample_motion`: ``q``,
``q' ṡ`` and ``q' s̈ + q'' ṡ²``, the same on both sides of every sample, ``q''`` being
continuous between knots) and every motion is checked: the joints exactly against their
limits, jerk included (:func:`~traj_gen_ros.core.kinematic_limits.limit_ratios`), the
tool at the samples (as :func:`.path_timing.time_path`'s). Where above a limit it is
slowed by the exact factor ``k`` (``v/k``, ``a/k²``, ``j/k³``: a polynomial's time
scales exactly), so no plan above a joint limit is returned; the shortest is kept.

Units: units of path, s; rad (or m), rad/s, rad/s², rad/s³.
"""

from __future__ import annotations

from collections.abc import Sequence
import dataclasses
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.cartesian.bound_report import Bound, TOOL_KINDS
from traj_gen_ros.core.cartesian.jerk_bounds import (
    best_bounds,
    Bounds,
    piece_rows,
    Rows,
)
from traj_gen_ros.core.cartesian.jerk_limited_sampling import (
    sample_motion,
    scaled,
    used_limits,
)
from traj_gen_ros.core.cartesian.path_constraints import merge_values, ToolLimits
from traj_gen_ros.core.cartesian.path_timing import TimedPath
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike

__all__ = ['JerkLimitedTimedPath', 'time_path_jerk_limited']

#: Motions planned after the first, each within the bounds refined by the one before.
REFINEMENTS = 3
#: The refinements end where one shortens the piece by less than this fraction.
_GAIN = 1e-3
_MARGIN = 1.0 + 1e-12  # a stretch goes this much beyond the exact peak ratio
#: How each limit's peak scales with a stretch ``k`` of time: as ``k`` to the minus this.
_ORDER = {'velocity': 1, 'acceleration': 2, 'jerk': 3, TOOL_KINDS[0]: 1, TOOL_KINDS[1]: 2,
          TOOL_KINDS[2]: 1}


@dataclass(frozen=True)
class JerkLimitedTimedPath(TimedPath):
    """
    A :class:`~.path_timing.TimedPath` whose path parameter is a jerk-limited S-curve.

    The grid (``times``, ``s``, ``speed``) is the joints' sampling; ``path_acceleration``
    is each interval's mean ``s̈`` (it is linear in time inside the S-curve's phases),
    ``bounds`` the limit of each interval's phase: the jerk's while ``s⃛ ≠ 0``, the
    acceleration's while ``s̈`` holds, the speed's while cruising.

    :ivar profile: ``s(t)``, one axis, the S-curves end to end (cubic pieces).
    :ivar pieces: the :class:`~.jerk_bounds.Bounds` of each rest-to-rest piece, in order.
    :ivar stretch: each piece's slow-down after the exact check (1: none).
    :ivar rest_times: ``(pieces + 1,)`` when the tool rests at each knot, s.
    :ivar models: each piece's :class:`~.jerk_bounds.Rows` its bounds were chosen in
        (the conservative ones, or refined: :meth:`~.jerk_bounds.Rows.refined`).
    """

    profile: Trajectory | None = None
    pieces: tuple[Bounds, ...] = ()
    stretch: tuple[float, ...] = ()
    rest_times: np.ndarray | None = None
    models: tuple[Rows, ...] = ()

    def path_parameter(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Return ``s`` and ``ṡ`` at times ``t`` (s, clipped to the plan): exact."""
        s, speed, _ = self.path_state(t)
        return s, speed

    def path_state(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``s``, ``ṡ`` and ``s̈`` at times ``t``, shaped as ``t``: exact."""
        shape = np.shape(t)
        states = self.profile.sample(np.asarray(t, dtype=float).reshape(-1))
        return tuple(state[:, 0].reshape(shape) for state in states)


def time_path_jerk_limited(
    path: IdealPath,
    joint_path: JointPath,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
    tool: ToolLimits,
    *,
    joint_names: Sequence[str] | None = None,
) -> JerkLimitedTimedPath:
    """
    Time ``joint_path`` along ``path`` with every joint's jerk within ``max_jerk`` too.

    Each joint's ``|q̇|``, ``|q̈|``, ``|q⃛|`` within ``max_velocity`` (rad/s),
    ``max_acceleration`` (rad/s²), ``max_jerk`` (rad/s³), scalars or one per joint, and
    the tool's :class:`~.path_constraints.ToolLimits`. The tool rests at every knot of
    the path (every corner, blended or not: build lines with ``blend_radius`` 0). The
    joint trajectory is checked exactly against the joint limits, jerk included.

    :raises ValueError: bad limits (naming the joint), paths that disagree, or a piece
        of the path where the limits leave no room to move (saying where).
    """
    count = joint_path.joints.joint_count
    names = None if joint_names is None else tuple(str(name) for name in joint_names)
    if names is not None and len(names) != count:
        raise ValueError(f'joint_names has {len(names)} names for {count} joints')
    limits = [validation.per_joint(name, value, count, joints=names) for name, value in
              (('max_velocity', max_velocity), ('max_acceleration', max_acceleration),
               ('max_jerk', max_jerk))]
    if not isinstance(tool, ToolLimits):
        raise ValueError(f'tool must be ToolLimits, got {type(tool).__name__}')
    length = float(path.length)
    if not (math.isfinite(length) and length > 0.0):
        raise ValueError(f'the path length must be finite and > 0, got {length}')
    if abs(float(joint_path.length) - length) > 1e-9 * length:
        raise ValueError(f'the joint path is {joint_path.length} long but the tool path '
                         f'{length}: they must be the same path')
    rests = merge_values(length, path.knots, path.stops, joint_path.knots, joint_path.stops)
    parts = [_piece(path, joint_path, float(start), float(end), limits, tool.as_array())
             for start, end in zip(rests[:-1], rests[1:], strict=True)]
    return _joined(parts, names)


@dataclass(frozen=True)
class _Part:
    """One rest-to-rest piece, timed from 0: its joints, grid, S-curve and bounds."""

    trajectory: Trajectory
    times: np.ndarray
    s: np.ndarray
    speed: np.ndarray
    profile: Trajectory
    bounds: Bounds
    phases: tuple[Bound, ...]
    stretch: float
    used: dict[Bound, float]
    model: Rows | None = None

    @property
    def duration(self) -> float:
        """Return how long the piece takes, s."""
        return float(self.times[-1])


def _piece(path: IdealPath, joint_path: JointPath, start: float, end: float,
           limits: list[np.ndarray], tool: np.ndarray) -> _Part:
    """
    Time the piece ``[start, end]``, rest to rest, within the limits exactly.

    First within the conservative bounds, then :data:`REFINEMENTS` times within the rows
    scaled by what the last motion used of them (:meth:`~.jerk_bounds.Rows.refined`);
    every motion is checked and, where above a limit, slowed: the shortest is kept, and
    the refinement ends where it gains less than :data:`_GAIN` of the duration.
    """
    rows = piece_rows(path, joint_path, start, end, *limits, tool)
    model, best = rows, None
    for _ in range(REFINEMENTS + 1):
        try:
            bounds = best_bounds(model, end - start)
        except ValueError as error:
            raise ValueError(f'{error}: from s = {start:.6g} to {end:.6g} ('
                             f'{100.0 * start / path.length:.1f} % to '
                             f'{100.0 * end / path.length:.1f} % of the path)') from None
        part = _timed(path, joint_path, start, end, bounds, limits, tool)
        if best is not None and part.duration >= best.duration * (1.0 - _GAIN):
            break
        best = dataclasses.replace(part, model=model)
        model = rows.refined(bounds, part.used)
    return best


def _timed(path: IdealPath, joint_path: JointPath, start: float, end: float, bounds: Bounds,
           limits: list[np.ndarray], tool: np.ndarray) -> _Part:
    """Plan the S-curve of ``bounds`` over the piece, sample it, check it, slow it."""
    plan = min_time(0.0, end - start, bounds.speed, bounds.acceleration, 'scurve',
                    max_jerk=bounds.jerk)
    breaks, coefficients = plan.shared_pieces
    coefficients = coefficients.copy()
    coefficients[:, 0] += start
    profile = Trajectory(breaks - breaks[0], coefficients)
    times, s, speed, trajectory = sample_motion(joint_path, profile, start, end)
    used = used_limits(path, profile, times, s, trajectory, limits, tool)
    stretch = max([1.0] + [value ** (1.0 / _ORDER[bound.kind]) for bound, value in
                           used.items()])
    if stretch > 1.0:
        stretch *= _MARGIN
        trajectory, profile = scaled(trajectory, stretch), scaled(profile, stretch)
        times, speed = times * stretch, speed / stretch
    violation = limit_violation(trajectory, *limits)
    if violation is not None:  # cannot happen: slowed down by the exact peak ratios
        raise RuntimeError(f'time_path_jerk_limited: {violation.describe()}')
    return _Part(trajectory, times, s, speed, profile, bounds,
                 _phases(profile, times, bounds), stretch, used)


def _phases(profile: Trajectory, times: np.ndarray, bounds: Bounds) -> tuple[Bound, ...]:
    """Name the bound of every sample interval: its S-curve phase's limit."""
    middle = 0.5 * (times[1:] + times[:-1])
    piece = np.clip(np.searchsorted(profile.breakpoints, middle, side='right') - 1, 0,
                    profile.piece_count - 1)
    jerk = np.abs(profile.coefficients[piece, 3, 0])
    acceleration = np.abs(profile.sample(middle)[2][:, 0])
    scale = np.abs(profile.coefficients[:, 3, 0]).max(initial=0.0)
    top = np.abs(profile.sample(profile.breakpoints)[2][:, 0]).max(initial=0.0)
    return tuple(bounds.jerk_bound if j > 1e-6 * scale else
                 bounds.acceleration_bound if a > 1e-6 * top else bounds.speed_bound
                 for j, a in zip(jerk.tolist(), acceleration.tolist(), strict=True))


def _joined(parts: list[_Part], names: tuple[str, ...] | None) -> JerkLimitedTimedPath:
    """Put the rest-to-rest pieces end to end."""
    offsets = np.concatenate([[0.0], np.cumsum([part.times[-1] for part in parts])])
    times = np.concatenate([parts[0].times[:1]] + [part.times[1:] + offset for part, offset
                                                   in zip(parts, offsets, strict=False)])
    s = np.concatenate([parts[0].s[:1]] + [part.s[1:] for part in parts])
    speed = np.concatenate([parts[0].speed[:1]] + [part.speed[1:] for part in parts])
    trajectory = Trajectory(times, np.concatenate([part.trajectory.coefficients
                                                   for part in parts]))
    profile = Trajectory(
        np.concatenate([[0.0]] + [part.profile.breakpoints[1:] + offset
                                  for part, offset in zip(parts, offsets, strict=False)]),
        np.concatenate([part.profile.coefficients for part in parts]))
    return JerkLimitedTimedPath(
        trajectory=trajectory, duration=float(times[-1]), times=times, s=s, speed=speed,
        path_acceleration=np.diff(speed) / np.diff(times),
        bounds=tuple(bound for part in parts for bound in part.phases), joint_names=names,
        profile=profile, pieces=tuple(part.bounds for part in parts),
        stretch=tuple(part.stretch for part in parts), rest_times=offsets,
        models=tuple(part.model for part in parts))
