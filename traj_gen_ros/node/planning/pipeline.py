"""
Step 3 of a request, *validate and plan*: the one pipeline every request goes through.

:func:`plan_request` takes a parsed request (names and values checked: *read*, *check
names and values*, in :mod:`traj_gen_ros.node.messages.parsing`) through the same named
steps for every kind: *unwrap continuous joints*, *check the start and the positions*,
*plan*, *check size and limits*; the caller *splices* the result
(:mod:`traj_gen_ros.node.requests.start_tick`). What differs between kinds is in their
:class:`Steps`: :data:`GOAL` (``~/goal``: :mod:`~traj_gen_ros.node.planning.goal_move`),
:data:`VIA` (``~/via_points``: :mod:`~traj_gen_ros.node.planning.via_path`), an action
goal's (:func:`traj_gen_ros.node.action.goal_points.goal_steps`: time-stamped points, the
slow-down, the start tolerance). ``~/stop`` (:func:`plan_stop`, the core's
:func:`traj_gen_ros.brake`, or :func:`traj_gen_ros.core.jerk_limited.brake` under
``scurve``) shares the splice but skips the checks: it always runs.

Every plan starts at a :class:`State` (the setpoint of the schedule at the stream tick where
the new motion takes over) and ends at rest. Quintic and S-curve plans start from the
state's acceleration too, so acceleration is continuous when a motion is replaced. A
refusal is a :class:`RequestError` whose message names joints by their ROS names (the
core's :class:`JointError` knows them by index). No ROS here.

Units: rad, rad/s, rad/s², rad/s³, s; arrays are ``(samples, joints)``.
"""

from __future__ import annotations

from collections.abc import Callable
import dataclasses
from dataclasses import dataclass
import math
from typing import Generic, TypeVar

import numpy as np
from traj_gen_ros.core.jerk_limited.brake import scurve_brake
from traj_gen_ros.core.kinematic_limits import JointError
from traj_gen_ros.core.stops import brake
from traj_gen_ros.node.messages.parsing import GoalRequest, MAX_DURATION, RequestError, ViaRequest
from traj_gen_ros.node.planning.continuous_joints import unwrap_targets, wrapping_joints
from traj_gen_ros.node.planning.goal_move import plan_goal
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.planning.position_checks import check_plan, check_request
from traj_gen_ros.node.planning.via_path import plan_via
from traj_gen_ros.node.settings.config import Config

#: A request the pipeline plans: ``~/goal``'s, or points (``~/via_points``, an action goal).
R = TypeVar('R')
Requested = TypeVar('Requested', GoalRequest, ViaRequest)
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


#: ``~/goal``'s steps: a synchronised minimum-time move to the goal.
GOAL: Steps[GoalRequest] = Steps(plan=plan_goal, unwrap=unwrap_each_point)
#: ``~/via_points``' steps: a path through the points with the configured profile.
VIA: Steps[ViaRequest] = Steps(plan=plan_via, unwrap=unwrap_each_point)
_OWN_STEPS = {GoalRequest: GOAL, ViaRequest: VIA}


def plan_stop(config: Config, state: State,
              running: tuple[PlannedMotion, float] | None = None) -> PlannedMotion:
    """
    Brake from ``state`` to rest within ``max_acceleration`` (rad/s²), then hold.

    A line or an arc (``running``: the motion in effect and its own time, s) brakes along
    its path, the tool kept on it (:class:`~traj_gen_ros.node.planning.motion.BrakesAlong`).
    Every other motion brakes each joint: with profile ``scurve`` the jerk stays within
    ``max_jerk`` (rad/s³) and the acceleration is continuous from the state's
    (:func:`traj_gen_ros.core.jerk_limited.brake`); the other profiles brake at
    ``max_acceleration`` at once (:func:`traj_gen_ros.brake`). ``state`` is the commanded
    state (the speed scaling factor applied): the brake is ``unscaled`` and runs on the
    node clock.
    """
    plan = None
    if running is not None and running[0].along is not None:
        plan = running[0].along.brake(running[1], state.velocity, state.acceleration)
    if plan is None and config.profile == 'scurve':
        plan = scurve_brake(state.position, state.velocity, state.acceleration,
                            config.max_acceleration, config.max_jerk)
    elif plan is None:
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
