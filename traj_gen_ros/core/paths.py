"""
The one entry point for paths through via points, whatever the profile.

:func:`plan_path` takes the points, the segment durations (or none, to time them from the
limits) and the start state, and hands them to the profile's own via-point planner
(Craig §7.3: cubic and quintic splines, LSPB with blends; the jerk-limited S-curve);
:func:`via_durations` times the segments from the limits. Moves from a state to one goal
go through :func:`traj_gen_ros.core.timing.min_time`.

Units: rad, rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.blends import lspb_via
from traj_gen_ros.core.jerk_limited.path import scurve_via, scurve_via_durations
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.polynomial import cubic_via, quintic_via
from traj_gen_ros.core.timing import check_profile, rest_to_rest_times, shortest_duration
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike


@validation.refuses_overflow('plan_path')
def plan_path(
    points: ArrayLike,
    durations: ArrayLike | None,
    profile: str,
    *,
    velocities: str | ArrayLike = 'heuristic',
    accelerations: ArrayLike | None = None,
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
    max_velocity: ArrayLike | None = None,
    max_acceleration: ArrayLike | None = None,
    max_jerk: ArrayLike | None = None,
    blend_acceleration: ArrayLike | None = None,
) -> Trajectory:
    """
    Plan ``profile`` through ``points`` (``(points, joints)``, rad), starting at ``points[0]``.

    :param durations: one per segment (s), kept as given; ``None`` times the path from the
        limits (:func:`via_durations`), stretched by one factor if the start state needs it.
    :param velocities: ``"heuristic"``, ``"continuous"`` or one per point and joint (rad/s).
    :param accelerations: one per point and joint (rad/s², quintic only), or ``None``.
    :param v0: start velocity (rad/s); ``a0`` start acceleration (rad/s², quintic).
    :param blend_acceleration: LSPB blend acceleration (rad/s²), default ``max_acceleration``.

    Raises ``ValueError`` saying what cannot be done; a plan with given durations is not
    checked against the limits here (:func:`traj_gen_ros.core.kinematic_limits.limit_violation`
    does).
    """
    check_profile(profile)
    path = validation.path_points(points)
    joint_count = path.shape[1]
    if blend_acceleration is None:
        blend_acceleration = max_acceleration
    if profile == 'lspb':
        if blend_acceleration is None:
            raise ValueError('lspb needs blend_acceleration or max_acceleration')
        if not isinstance(velocities, str) or accelerations is not None:
            raise ValueError('lspb takes the velocities at via points from the segment slopes '
                             '(Craig 7.3): it cannot honour given velocities/accelerations')
        blend_acceleration = validation.per_joint(
            'blend_acceleration', blend_acceleration, joint_count)
    if profile == 'cubic' and accelerations is not None:
        raise ValueError('cubic cannot honour accelerations at via points: use quintic')
    if profile == 'scurve':
        return _scurve_path(path, durations, velocities, accelerations, v0, a0,
                            (max_velocity, max_acceleration, max_jerk))
    builders: dict[str, Callable[[np.ndarray], Trajectory]] = {
        'cubic': lambda times: cubic_via(path, times, velocities, v0=v0),
        'quintic': lambda times: quintic_via(path, times, velocities, accelerations, v0=v0,
                                             a0=a0),
        'lspb': lambda times: lspb_via(path, times, blend_acceleration, v0=v0),
    }
    build = builders[profile]
    if durations is not None:
        return build(validation.segment_durations(durations, len(path) - 1))
    if max_velocity is None or max_acceleration is None:
        raise ValueError('timing a path from the limits needs max_velocity and '
                         'max_acceleration')
    max_velocity = validation.per_joint('max_velocity', max_velocity, joint_count)
    max_acceleration = validation.per_joint('max_acceleration', max_acceleration, joint_count)
    rule = velocities if isinstance(velocities, str) else 'heuristic'
    base = via_durations(path, max_velocity, max_acceleration, profile, rule,
                         blend_acceleration)
    plan = build(base)
    limit = blend_acceleration if profile == 'lspb' else max_acceleration
    if limit_violation(plan, max_velocity, limit) is None:
        return plan
    return shortest_duration(lambda scale: build(base * scale), 1.0, max_velocity, limit)


def _scurve_path(path: np.ndarray, durations: ArrayLike | None, velocities: str | ArrayLike,
                 accelerations: ArrayLike | None, v0: ArrayLike, a0: ArrayLike,
                 limits: tuple) -> Trajectory:
    """
    Plan the jerk-limited path: zero acceleration at every via point, from ``(v0, a0)``.

    Its segments are exact state-to-state S-curves, so its limits are its own; timed from
    the limits when ``durations`` is ``None`` (from rest, stretched by one factor if the
    start state needs it).
    """
    if any(limit is None for limit in limits):
        raise ValueError('scurve needs max_velocity, max_acceleration and max_jerk')
    if accelerations is not None:
        raise ValueError('scurve sets zero acceleration at every via point: leave the '
                         'accelerations empty')
    rule = velocities if not isinstance(velocities, str) else 'heuristic'

    def build(times: np.ndarray) -> Trajectory:
        return scurve_via(path, times, *limits, velocities=rule, v0=v0, a0=a0)

    if durations is not None:
        return build(validation.segment_durations(durations, len(path) - 1))
    base = scurve_via_durations(path, *limits, velocities=rule)
    try:
        return build(base)
    except ValueError:
        return shortest_duration(lambda scale: build(base * scale), 1.0, *limits[:2])


@validation.refuses_overflow('via_durations')
def via_durations(
    points: ArrayLike,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    profile: str = 'cubic',
    velocities: str = 'heuristic',
    acceleration: ArrayLike | None = None,
    max_jerk: ArrayLike | None = None,
) -> np.ndarray:
    """
    Segment durations (s) that keep a via-point path within the limits.

    ``scurve`` (with ``max_jerk``, rad/s³) is timed by
    :func:`traj_gen_ros.core.jerk_limited.path.scurve_via_durations`.

    Each segment starts from its own rest-to-rest minimum time for the slowest joint;
    the whole path is then stretched by one factor, found by bisection on the exact peaks
    of the planned ``profile`` (``cubic``/``quintic`` with ``velocities``, or ``lspb`` with
    blend ``acceleration``, default ``max_acceleration``), until no limit is exceeded.
    """
    path = validation.path_points(points)
    joint_count = path.shape[1]
    max_velocity = validation.per_joint('max_velocity', max_velocity, joint_count)
    max_acceleration = validation.per_joint(
        'max_acceleration', max_acceleration, joint_count)
    check_profile(profile)
    if profile == 'scurve':
        if max_jerk is None:
            raise ValueError('profile scurve needs max_jerk (rad/s^3, > 0)')
        return scurve_via_durations(path, max_velocity, max_acceleration, max_jerk,
                                    velocities)
    if velocities not in ('heuristic', 'continuous'):
        raise ValueError(f'velocities must be "heuristic" or "continuous", got "{velocities}"')
    blend_acceleration = max_acceleration if acceleration is None else (
        validation.per_joint('acceleration', acceleration, joint_count))
    steps = np.abs(np.diff(path, axis=0))
    base = rest_to_rest_times(steps, max_velocity, max_acceleration, profile).max(axis=1)
    if np.max(steps) <= 1e-12 * max(1.0, float(np.max(np.abs(path)))):
        raise ValueError("every via point equals the start (to 1e-12 of the path's scale): "
                         'there is nothing to move')
    base = np.maximum(base, 1e-6 * base.max())
    planners = {
        'cubic': lambda durations: cubic_via(path, durations, velocities),
        'quintic': lambda durations: quintic_via(path, durations, velocities),
        'lspb': lambda durations: lspb_via(path, durations, blend_acceleration),
    }
    plan = planners[profile]
    best = shortest_duration(lambda scale: plan(base * scale), 1.0,
                             max_velocity, max_acceleration)
    return base * (best.duration / base.sum())
