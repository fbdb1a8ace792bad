"""
Step 3 of a request, *validate and plan*: a checked plan from a start state.

Every plan starts at a :class:`State` (the setpoint of the schedule at the stream tick where
the new motion takes over) and ends at rest. The core's single entry points do the work:

* a goal: :func:`traj_gen_ros.min_time` (synchronised, minimum time, from the state);
* via points: :func:`traj_gen_ros.plan_path` (given times kept, or timed from the limits);
* ``~/stop``: :func:`traj_gen_ros.brake` (profile ``scurve``: the jerk-limited
  :func:`traj_gen_ros.core.jerk_limited.brake`); at rest already: :func:`traj_gen_ros.hold`.

Quintic and S-curve plans start from the state's acceleration too, so acceleration is
continuous when a motion is replaced; the other profiles start from zero acceleration.
Each plan is checked with the core's :func:`traj_gen_ros.limit_violation` (one tolerance,
exact peaks; jerk too for ``scurve``) and bounded in duration and size, except a cubic or
quintic goal: :func:`traj_gen_ros.min_time` returns only a duration whose exact peaks it
has checked against the same limits (or, from rest, Craig's closed-form peaks), so a
second check would only delay the start (0.1-0.3 ms). A refusal is a
:class:`RequestError` whose message names joints by their ROS names (the core's
:class:`JointError` knows them by index). No ROS here.

Units: rad, rad/s, rad/s², rad/s³, s; arrays are ``(samples, joints)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import dataclasses
from dataclasses import dataclass
import math
from typing import Generic, TypeVar

import numpy as np
from traj_gen_ros.core.jerk_limited.brake import scurve_brake
from traj_gen_ros.core.kinematic_limits import JointError, limit_violation
from traj_gen_ros.core.paths import plan_path
from traj_gen_ros.core.stops import brake
from traj_gen_ros.core.timing import min_time, shortest_duration
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.parsing import GoalRequest, MAX_DURATION, RequestError, ViaRequest
from traj_gen_ros.node.planning.continuous_joints import unwrap_targets, wrapping_joints
from traj_gen_ros.node.planning.motion import held, PlannedMotion, State
from traj_gen_ros.node.planning.position_checks import check_plan, check_request
from traj_gen_ros.node.settings.config import Config

#: A request the pipeline plans: ``~/goal``'s, or points (``~/via_points``, an action goal).
R = TypeVar('R', GoalRequest, ViaRequest)
Requested = TypeVar('Requested', GoalRequest, ViaRequest)
#: Profiles whose minimum-time goals the core checks exactly itself (see the module doc).
EXACTLY_TIMED = ('cubic', 'quintic')
#: A first via point at ``time_from_start`` 0 must match the setpoint this closely (rad).
START_TOLERANCE = 1e-6
#: Most samples one plan may have on ``~/trajectory`` (duration x rate_hz + 2).
MAX_TRAJECTORY_POINTS = 200_000


@dataclass(frozen=True)
class Steps(Generic[R]):
    """
    What one kind of request brings to the pipeline (:func:`plan_request`): its own steps.

    ``plan(config, state, hold_at, request)`` is the kind's planning (a goal's
    minimum-time move, a path through via points, an action goal's interpolation and
    slow-down), its own limit checks included. ``unwrap(start, request, mask)`` takes the
    wrapping joints (``mask``) the short way from ``start`` (:func:`unwrap_each_point`, or
    the action's :func:`shift_whole_turns` of the whole trajectory); ``check_start(state,
    request)`` checks where the request starts and may replace its first point (the
    action's start tolerance), before the position checks.
    """

    plan: Callable[[Config, State, np.ndarray, R], PlannedMotion]
    unwrap: Callable[[np.ndarray, R, np.ndarray], R]
    check_start: Callable[[State, R], R] = lambda state, request: request


def plan_request(config: Config, state: State, hold_at: np.ndarray, request: R,
                 steps: Steps[R] | None = None) -> PlannedMotion:
    """
    Plan ``request`` from ``state`` through the one pipeline that every request goes through.

    The steps after *read* and *check names and values* (the parsing of each kind):

    1. *unwrap continuous joints* (``config.angle_wraparound``): ``steps.unwrap``;
    2. *check the start* (``steps.check_start``) and *the positions*: every commanded
       position within the position limits in force (``config.limits``,
       :mod:`traj_gen_ros.node.planning.position_checks`);
    3. *plan*: ``steps.plan`` from ``state``; joints the request does not name go to
       ``hold_at``, where the motion being replaced would have come to rest (rad);
    4. *check size and limits*: finite, bounded in duration and samples (:func:`check_size`),
       and the plan's exact position extrema within the limits.

    The last step, *splice*, is the caller's (:mod:`traj_gen_ros.node.requests.start_tick`).
    ``steps`` default to the request's own: :data:`GOAL` or :data:`VIA`. Raises
    :class:`RequestError` with the reason when the request cannot be executed.
    """
    steps = steps or _OWN_STEPS[type(request)]
    if config.angle_wraparound:
        mask = wrapping_joints(config.limits)
        if mask.any():
            request = steps.unwrap(state.position, request, mask)
    request = steps.check_start(state, request)
    if config.limits is not None:
        check_request(config.limits, request, state.position)
    try:
        motion = steps.plan(config, state, hold_at, request)
    except JointError as error:
        raise RequestError(error.named(config.joints)) from None
    motion = check_size(motion, config)
    if config.limits is not None:
        check_plan(config.limits, motion.plan, state.position)
    return motion


def unwrap_each_point(start: np.ndarray, request: Requested, mask: np.ndarray) -> Requested:
    """
    Return ``request`` with each wrapping joint's targets the shortest way round (rad).

    A goal is taken from ``start``; via points each from the previous one, the first from
    ``start`` (:func:`traj_gen_ros.node.planning.continuous_joints.unwrap_targets`); ``mask``
    marks the wrapping joints of the joint set.
    """
    named = request.joints
    positions = unwrap_targets(start[named], request.positions, mask[named])
    return dataclasses.replace(request, positions=positions)


def plan_goal(config: Config, state: State, hold_at: np.ndarray,
              request: GoalRequest) -> PlannedMotion:
    """Plan the synchronised minimum-time move from ``state`` to the goal, at rest."""
    target = np.array(hold_at, dtype=float)
    target[request.joints] = request.positions
    check_reach(config, state.position, target[None, :])
    keeps = config.keeps_acceleration
    velocity = state.velocity
    acceleration = state.acceleration if keeps else np.zeros_like(velocity)
    if _at_rest_at(state, target, keeps):
        return held(target, config.profile, 'already there')
    try:
        plan = min_time(state.position, target, config.max_velocity,
                        config.profile_acceleration, config.profile, v0=velocity,
                        a0=acceleration, max_jerk=config.max_jerk)
    except ValueError as error:  # JointError too: named by the joint's ROS name
        reason = error.named(config.joints) if isinstance(error, JointError) else str(error)
        moving = '' if not (np.any(velocity) or np.any(acceleration)) else (
            f' from the current motion (velocity {np.round(velocity, 4).tolist()} rad/s, '
            f'acceleration {np.round(acceleration, 4).tolist()} rad/s^2); resend it when '
            'the motion has slowed, or call ~/stop first')
        raise RequestError(f'cannot plan the goal with profile {config.profile}{moving}: '
                           f'{reason}') from None
    if config.profile in EXACTLY_TIMED:
        return PlannedMotion(plan, config.profile, target)
    # As in the core: a start already at (or, after limits were lowered, beyond) a limit
    # may stay at that level while it slows down. With bounded jerk the velocity goes on
    # by a0 |a0| / (2 max_jerk) while the acceleration returns to zero: unavoidable too.
    a_limit = config.profile_acceleration
    v_limit = np.maximum(config.max_velocity, np.abs(velocity))
    if config.jerk_limit is not None:
        v_limit = np.maximum(v_limit, np.abs(
            velocity + acceleration * np.abs(acceleration) / (2.0 * config.jerk_limit)))
    violation = limit_violation(
        plan, v_limit, np.maximum(a_limit, np.abs(acceleration)) if keeps else a_limit,
        config.jerk_limit)
    if violation is not None:
        raise RequestError('the minimum-time plan breaks a limit: '
                           f'{violation.describe(config.joints)}')
    return PlannedMotion(plan, config.profile, target)


def check_reach(config: Config, start: np.ndarray, points: np.ndarray) -> None:
    """
    Refuse points (rad, ``(points, joints)``) a joint cannot reach within ``MAX_DURATION``.

    Even at ``max_velocity`` all the way a joint needs ``|point - start| / max_velocity``
    s. Checked before planning, so that finite but huge positions (1e308) are refused by
    the duration limit instead of overflowing inside the solver.
    """
    seconds = np.abs(np.asarray(points, dtype=float) - start) / config.max_velocity
    worst = divmod(int(seconds.argmax()), seconds.shape[-1])  # (point, joint)
    if seconds[worst] > MAX_DURATION:
        joint = config.joints[worst[-1]]
        raise RequestError(f'joint {joint!r} would need at least {seconds[worst]:.4g} s at '
                           f'max_velocity to reach {np.asarray(points)[worst]:.6g} rad: the '
                           f'plan would last above the limit of {MAX_DURATION:g} s')


def _at_rest_at(state: State, target: np.ndarray, keeps_acceleration: bool) -> bool:
    offsets = [state.velocity, state.position - target]
    if keeps_acceleration:
        offsets.append(state.acceleration)
    return float(np.abs(np.concatenate(offsets)).max()) <= 1e-12


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


#: ``~/goal``'s steps: a synchronised minimum-time move to the goal.
GOAL: Steps[GoalRequest] = Steps(plan=plan_goal, unwrap=unwrap_each_point)
#: ``~/via_points``' steps: a path through the points with the configured profile.
VIA: Steps[ViaRequest] = Steps(plan=plan_via, unwrap=unwrap_each_point)
_OWN_STEPS = {GoalRequest: GOAL, ViaRequest: VIA}


def plan_stop(config: Config, state: State) -> PlannedMotion:
    """
    Brake from ``state`` to rest within ``max_acceleration`` (rad/s²), then hold.

    With profile ``scurve`` the jerk stays within ``max_jerk`` (rad/s³) and the
    acceleration is continuous from the state's (:func:`traj_gen_ros.core.jerk_limited.brake`);
    the other profiles brake at ``max_acceleration`` at once (:func:`traj_gen_ros.brake`).
    ``state`` is the commanded state (the speed scaling factor applied): the brake is
    ``unscaled`` and runs on the node clock.
    """
    if config.profile == 'scurve':
        plan = scurve_brake(state.position, state.velocity, state.acceleration,
                            config.max_acceleration, config.max_jerk)
    else:
        plan = brake(state.position, state.velocity, config.max_acceleration)
    # Never slowed by the speed scaling factor: it brakes at full authority.
    return PlannedMotion(plan, 'stop', plan.sample(plan.duration)[0][0], unscaled=True)


def check_size(motion: PlannedMotion, config: Config) -> PlannedMotion:
    """
    Refuse a plan that is not finite, longer than ``MAX_DURATION`` or too many samples long.

    The bounds keep the published message and the time to build it finite; the reason
    names the limit. Returns ``motion`` unchanged when it fits.
    """
    plan = motion.plan
    if np.count_nonzero(np.isfinite(plan.coefficients)) != plan.coefficients.size or \
            np.count_nonzero(np.isfinite(plan.breakpoints)) != plan.breakpoints.size:
        raise RequestError('the plan is not finite: not executed')
    duration = plan.duration
    if not math.isfinite(duration) or duration > MAX_DURATION:
        raise RequestError(f'the plan would last {duration:.4g} s, above the limit of '
                           f'{MAX_DURATION:g} s: move a shorter distance or raise the limits')
    samples = int(duration * config.rate_hz) + 2
    if samples > MAX_TRAJECTORY_POINTS:
        raise RequestError(f'the plan would have {samples} samples on ~/trajectory '
                           f'({duration:.4g} s at {config.rate_hz:g} Hz), above the limit of '
                           f'{MAX_TRAJECTORY_POINTS}: lower rate_hz or split the motion')
    return motion


def sample_grid(plan: Trajectory, rate_hz: float) -> np.ndarray:
    """Return ``0, 1/rate, 2/rate, ...`` (s) up to the plan's end, ending at its duration."""
    count = int(math.floor(plan.duration * rate_hz + 1e-9))
    times = np.arange(count + 1) / rate_hz
    if plan.duration - times[-1] > 1e-9:
        times = np.append(times, plan.duration)
    return times


def sample_motion(motion: PlannedMotion, rate_hz: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Step 6, *sample*: the plan every ``1/rate_hz`` s from its start, for ``~/trajectory``.

    The last sample is exactly the end, at rest. Raises :class:`RequestError` if any
    sample is not finite (then nothing of the plan is published or executed).
    """
    times = sample_grid(motion.plan, rate_hz)
    positions, velocities, accelerations = motion.plan.sample(times)
    positions[-1] = motion.end
    velocities[-1] = 0.0
    accelerations[-1] = 0.0
    finite = np.isfinite
    if not (finite(positions).all() and finite(velocities).all()
            and finite(accelerations).all()):
        raise RequestError('the plan has a non-finite sample: not executed')
    return times, positions, velocities, accelerations
