"""
A goal's *plan* step: the synchronised minimum-time move from the start state (no ROS).

:func:`plan_goal` plans with the core's :func:`traj_gen_ros.min_time` from the state
(position, velocity and, for quintic and S-curve plans, acceleration) to rest at the goal;
:func:`check_reach` refuses targets no joint could reach within ``MAX_DURATION`` before
the solver sees them. A cubic or quintic goal's duration is checked exactly by
``min_time`` itself (see :mod:`traj_gen_ros.node.planning.pipeline`).

Units: rad, rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.kinematic_limits import JointError, limit_violation
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.node.messages.parsing import GoalRequest, MAX_DURATION, RequestError
from traj_gen_ros.node.planning.motion import held, PlannedMotion, State
from traj_gen_ros.node.settings.config import Config

#: Profiles whose minimum-time goals the core checks exactly itself (see the module doc).
EXACTLY_TIMED = ('cubic', 'quintic')


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
