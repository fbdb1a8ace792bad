"""
Via points' *plan* step: a path through the points from the start state (no ROS).

:func:`plan_via` keeps explicit times (a plan that would break a limit is refused with the
minimum feasible duration) or times the path from the limits; :func:`via_points` puts the
start state in front of the points (the rule is in its docstring); an action goal's
interpolation uses it too.

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from traj_gen_ros.core.kinematic_limits import JointError, limit_violation
from traj_gen_ros.core.paths import plan_path
from traj_gen_ros.core.timing import shortest_duration
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.parsing import GoalRequest, MAX_DURATION, RequestError, ViaRequest
from traj_gen_ros.node.planning.goal_move import check_reach, plan_goal
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.settings.config import Config

#: A first via point at ``time_from_start`` 0 must match the setpoint this closely (rad).
START_TOLERANCE = 1e-6


def plan_via(config: Config, state: State, hold_at: np.ndarray,
             request: ViaRequest) -> PlannedMotion:
    """
    Plan through via points from ``state`` with the configured profile.

    Explicit times are kept; a plan that would break a limit is refused with the minimum
    feasible duration (all times scaled by one factor). Auto-timed requests are timed from
    the limits by the core, stretched uniformly if the start state needs it.
    """
    _check_boundary_conditions(config.profile, request)
    points, times, velocities, accelerations = via_points(config.joints, state, hold_at,
                                                          request)
    check_reach(config, state.position, points)
    if len(points) == 1:  # only the start is left: the named joints come to rest there,
        target = np.array(hold_at, dtype=float)  # the others keep the target they had
        target[request.joints] = request.positions[-1]
        return plan_goal(config, state, target, GoalRequest(np.zeros(0, int), np.zeros(0)))

    def build(durations: np.ndarray | None) -> Trajectory:
        return plan_path(
            points, durations, config.profile,
            velocities=config.via_velocities if velocities is None else velocities,
            accelerations=accelerations, v0=state.velocity,
            a0=state.acceleration if config.keeps_acceleration else 0.0,
            max_velocity=config.max_velocity, max_acceleration=config.max_acceleration,
            max_jerk=config.max_jerk if config.profile == 'scurve' else None,
            blend_acceleration=config.lspb_acceleration)

    a_limit = config.profile_acceleration
    if times is None:
        try:
            plan = build(None)
        except ValueError as error:  # JointError too: named by the joint's ROS name
            reason = error.named(config.joints) if isinstance(error, JointError) else error
            raise RequestError(f'cannot time the via points: {reason}') from None
        note = 'timed from the limits'
    else:
        durations = np.diff(times)
        try:
            plan = build(durations)
        except JointError as error:  # e.g. an LSPB blend that does not fit in its segment
            raise RequestError(_too_short(error.named(config.joints), durations, build,
                                          config)) from None
        except ValueError as error:
            raise RequestError(_too_short(str(error), durations, build, config)) from None
        violation = limit_violation(plan, config.max_velocity, a_limit, config.jerk_limit)
        if violation is not None:
            raise RequestError(_too_short(violation.describe(config.joints), durations,
                                          build, config))
        return PlannedMotion(plan, config.profile, points[-1])
    violation = limit_violation(plan, config.max_velocity, a_limit, config.jerk_limit)
    if violation is not None:
        raise RequestError(f'the plan breaks a limit: {violation.describe(config.joints)}')
    return PlannedMotion(plan, config.profile, points[-1], note)


def _check_boundary_conditions(profile: str, request: ViaRequest) -> None:
    given = request.velocities is not None or request.accelerations is not None
    if profile == 'lspb' and given:
        raise RequestError('profile lspb takes the velocities at via points from the segment '
                           'slopes (Craig 7.3) and cannot honour given velocities/'
                           'accelerations: leave them empty or use profile cubic or quintic')
    if profile in ('cubic', 'scurve') and request.accelerations is not None:
        raise RequestError(f'profile {profile} cannot honour accelerations at via points: '
                           'leave them empty or use profile quintic')
    if request.velocities is not None and np.any(np.abs(request.velocities[-1]) > 1e-12):
        raise RequestError('the last point must have zero velocity: the generator holds '
                           'still at the end of every plan')
    if request.accelerations is not None and \
            np.any(np.abs(request.accelerations[-1]) > 1e-12):
        raise RequestError('the last point must have zero acceleration: the generator holds '
                           'still at the end of every plan')


def _too_short(problem: str, durations: np.ndarray, build, config: Config) -> str:
    """Say that the given times break a limit, and the minimum feasible duration."""
    total = float(np.sum(durations))
    ceiling = MAX_DURATION / max(total, 1e-300)
    try:
        best = shortest_duration(lambda scale: build(durations * min(scale, ceiling)), 1.0,
                                 config.max_velocity, config.profile_acceleration)
    except ValueError:
        best = None
    if best is None or best.duration > MAX_DURATION:
        return (f'{problem}; no uniform stretch of the times (at most {MAX_DURATION:g} s in '
                'all) meets the limits')
    return (f'{problem}; the requested {total:.4g} s is too short: the minimum feasible '
            f'duration is {best.duration:.4g} s (all time_from_start scaled by '
            f'{best.duration / total:.4g})')


def via_points(joints: Sequence[str], state: State, hold_at: np.ndarray, request: ViaRequest
               ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """
    Full-joint points starting at the current setpoint, and their times.

    Rule: the executed trajectory starts at the current setpoint. A first point at
    ``time_from_start`` 0 must equal the current position of the joints it names (within
    ``START_TOLERANCE``) and stands for the start; otherwise the current setpoint is
    prepended as point 0 at t=0. When all times are zero (auto-timing) a first point at the
    current position is dropped likewise. Joints not named stay at ``hold_at`` at every
    point (with zero velocity/acceleration there).
    Returns ``(points, times or None when auto-timed, velocities, accelerations)``.
    """
    count = request.positions.shape[0]
    points = np.tile(np.asarray(hold_at, dtype=float), (count, 1))
    points[:, request.joints] = request.positions
    velocities = accelerations = None
    if request.velocities is not None:
        velocities = np.zeros_like(points)
        velocities[:, request.joints] = request.velocities
    if request.accelerations is not None:
        accelerations = np.zeros_like(points)
        accelerations[:, request.joints] = request.accelerations
    times = request.times.copy()
    named = request.joints
    offset = np.zeros_like(state.position)
    offset[named] = np.abs(points[0, named] - state.position[named])
    first_is_start = request.auto_timed and not np.any(offset > START_TOLERANCE)
    if not request.auto_timed and times[0] == 0.0:
        joint = int(np.argmax(offset))
        if offset[joint] > START_TOLERANCE:
            raise RequestError(
                f'point 0 has time_from_start 0 but joint {joints[joint]!r} '
                f'is at {state.position[joint]:.6g} rad, not {points[0, joint]:.6g}: a point '
                f'at t=0 must equal the current position; give it a time > 0 or drop it')
        first_is_start = True
    if first_is_start:
        points, times = points[1:], times[1:]
        velocities = None if velocities is None else velocities[1:]
        accelerations = None if accelerations is None else accelerations[1:]
    points = np.vstack([state.position, points])
    times = np.concatenate([[0.0], times])
    if velocities is not None:
        velocities = np.vstack([state.velocity, velocities])
    if accelerations is not None:
        accelerations = np.vstack([state.acceleration, accelerations])
    return points, None if request.auto_timed else times, velocities, accelerations
