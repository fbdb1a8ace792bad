"""
A ``FollowJointTrajectory`` goal's points: parsed, checked and planned (no ROS here).

The goal is a timed trajectory (MoveIt's is already time-parameterised and collision
checked), so its shape is kept whatever the ``profile`` parameter: between consecutive
points the node interpolates from what the points give (Craig §7.3):

* positions, velocities and accelerations: a quintic per segment (:func:`quintic_via`
  with the given accelerations);
* positions and velocities: a cubic per segment (:func:`cubic_via` with the given
  velocities);
* positions only: the node's via rule, the ``via_velocities`` rule (``heuristic`` or
  ``continuous``) through the points at their times, as ``~/via_points`` does with given
  times: a cubic spline under profile ``cubic``, a quintic one (continuous acceleration,
  from the setpoint's) under every other profile.

The start is the node's own setpoint (no jump): a first point at ``time_from_start`` 0 must
be within ``allowed_start_tolerance`` of where the arm is (the measured state, else the
setpoint) and is replaced by the setpoint; a first point later than 0 gets the setpoint
prepended at 0. The interpolated trajectory is checked exactly against ``max_velocity``
and ``max_acceleration`` (:meth:`Trajectory.peaks`, closed-form extrema). Uniform time
scaling ``t → s·t`` divides velocity peaks by ``s`` and acceleration peaks by ``s²``, so
one that rides over them is slowed by exactly
``s = max(1, max_j v_peak/v_max, max_j sqrt(a_peak/a_max))`` (from rest the scaled
spline is exactly the time-scaled one; from a moving start, whose velocity is kept, the
scaled plan is checked again). Position limits are never stretched away: outside them the
goal is refused. Each refusal is a :class:`GoalError` carrying the action's error code.

Units: rad, rad/s, rad/s², s, ns.
"""

from __future__ import annotations

from collections.abc import Sequence
import dataclasses
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.kinematic_limits import limit_ratios, LIMIT_TOLERANCE, limit_violation
from traj_gen_ros.core.paths import plan_path
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.parsing import (
    JointNameError,
    MAX_DURATION,
    parse_via,
    RequestError,
    ViaPoint,
    ViaRequest,
)
from traj_gen_ros.node.planning.continuous_joints import shift_whole_turns
from traj_gen_ros.node.planning.motion import held, PlannedMotion, State
from traj_gen_ros.node.planning.pipeline import plan_request, Steps
from traj_gen_ros.node.planning.via_path import via_points
from traj_gen_ros.node.settings.config import Config

#: ``control_msgs/action/FollowJointTrajectory`` result codes (its ``Result`` constants).
SUCCESSFUL = 0
INVALID_GOAL = -1
INVALID_JOINTS = -2
OLD_HEADER_TIMESTAMP = -3
PATH_TOLERANCE_VIOLATED = -4
GOAL_TOLERANCE_VIOLATED = -5
#: What the goal is called in the reasons (its log lines say follow_joint_trajectory).
WHAT = 'the goal'
#: A last point's velocity or acceleration above this is not at rest (rad/s, rad/s²).
AT_REST = 1e-9


class GoalError(RequestError):
    """A refused goal: ``code`` is the action's error code, ``str(error)`` the reason."""

    def __init__(self, code: int, reason: str) -> None:
        """Refuse with ``code`` (e.g. :data:`INVALID_JOINTS`) and ``reason``."""
        super().__init__(reason)
        self.code = code


@dataclass
class TrajectoryGoal:
    """
    A parsed goal: its ``points``, names in the goal's order, start stamp.

    ``stamp_ns`` is the goal's ``header.stamp`` (ns, node clock; 0 = now). Planning fills
    in ``factor`` (the uniform slow-down, 1 = none) and ``slowed`` (what it says), or
    ``refusal`` (the :class:`GoalError`) when it refuses the goal.
    """

    points: ViaRequest
    names: tuple[str, ...]
    stamp_ns: int
    factor: float = 1.0
    slowed: str = ''
    refusal: GoalError | None = None

    @property
    def duration(self) -> float:
        """Return the last point's ``time_from_start`` (s), before any slow-down."""
        return float(self.points.times[-1])


def parse_trajectory_goal(joints: Sequence[str], names: Sequence[str],
                          points: Sequence[ViaPoint], stamp_ns: int,
                          multi_dof_points: int = 0) -> TrajectoryGoal:
    """
    Check a goal's ``trajectory`` against the joint set ``joints``; raise :class:`GoalError`.

    ``points`` are ``(positions, velocities, accelerations, time_from_start)``;
    ``multi_dof_points`` the size of ``multi_dof_trajectory`` (must be 0).
    """
    names = list(names)
    if multi_dof_points:
        raise GoalError(INVALID_GOAL, f'{WHAT} has {multi_dof_points} multi_dof_trajectory '
                        'points: this node executes joint trajectories only; leave it empty')
    try:
        request = parse_via(joints, names, points, WHAT)
    except JointNameError as error:
        raise GoalError(INVALID_JOINTS, str(error)) from None
    except RequestError as error:
        raise GoalError(INVALID_GOAL, str(error)) from None
    if request.auto_timed and len(request.times) > 1:
        raise GoalError(INVALID_GOAL, 'time_from_start must be strictly increasing: every '
                        'point has 0 s (this action does not time trajectories; use '
                        '~/via_points for that)')
    for field, values in (('velocity', request.velocities),
                          ('acceleration', request.accelerations)):
        if values is not None and np.any(np.abs(values[-1]) > AT_REST):
            column = int(np.argmax(np.abs(values[-1])))
            raise GoalError(INVALID_GOAL, f'the last point (point {len(request.times) - 1}) '
                            f'has {field} {values[-1, column]:.6g} for joint '
                            f'{names[column]!r}: the node ends every trajectory at rest; '
                            'give 0')
    return TrajectoryGoal(request, tuple(names), stamp_ns)


def check_stamp(goal: TrajectoryGoal, now_ns: int) -> None:
    """Refuse (OLD_HEADER_TIMESTAMP) a goal whose stamp + last time is before ``now_ns``."""
    if goal.stamp_ns == 0:
        return
    end_ns = goal.stamp_ns + int(round(goal.duration * 1e9))
    if end_ns < now_ns:
        raise GoalError(OLD_HEADER_TIMESTAMP, f'header.stamp {goal.stamp_ns * 1e-9:.6f} s + '
                        f'the last time_from_start {goal.duration:.6g} s ends '
                        f'{(now_ns - end_ns) * 1e-9:.3f} s in the past (node clock '
                        f'{now_ns * 1e-9:.6f} s): send stamp 0 to start now')


def start_from_setpoint(request: ViaRequest, state: State, reference: np.ndarray,
                        tolerance: float, joints: Sequence[str],
                        measured: bool = False) -> ViaRequest:
    """
    Return the goal's points starting at the setpoint ``state`` (see the module doc).

    A first point at time 0 farther than ``tolerance`` (rad) from ``reference`` (where the
    arm is, per joint of the joint set: ``measured``, else the setpoint) is refused
    (INVALID_GOAL); within it, its position becomes the setpoint's so that the motion
    starts without a jump.
    """
    if request.times[0] != 0.0:
        return request
    named = request.joints
    offsets = np.abs(request.positions[0] - reference[named])
    worst = int(np.argmax(offsets))
    if offsets[worst] > tolerance:
        joint = int(named[worst])
        raise GoalError(INVALID_GOAL, f'point 0 (time_from_start 0) has joint '
                        f'{joints[joint]!r} at {request.positions[0, worst]:.6g} rad, '
                        f'{offsets[worst]:.6g} rad from where the arm is '
                        f'({"measured" if measured else "setpoint"} '
                        f'{reference[joint]:.6g} rad): above allowed_start_tolerance '
                        f'{tolerance:g} rad')
    positions = request.positions.copy()
    positions[0] = state.position[named]
    return dataclasses.replace(request, positions=positions)


def interpolation(config: Config, request: ViaRequest) -> str:
    """Return the profile between points: from what they give, else the via rule."""
    if request.accelerations is not None:
        return 'quintic'
    if request.velocities is not None:
        return 'cubic'
    return 'cubic' if config.profile == 'cubic' else 'quintic'


def slow_down(plan: Trajectory, config: Config) -> tuple[float, str]:
    """
    Return the smallest uniform slow-down ``s >= 1`` that fits the limits, and why.

    ``s = max(1, v_peak/v_max, sqrt(a_peak/a_max))`` over the joints, from the exact peaks
    (the core's :func:`limit_ratios`: roots only on pieces whose Bernstein bound is above
    a limit). ``s = 1`` exactly when the core's ``limit_violation`` passes ``plan`` (the
    same ratios, the same tolerance). The text names the joint and quantity that set it,
    e.g. ``joint 'joint_1' velocity 2.06 rad/s above max_velocity 2 rad/s``.
    """
    ratios = limit_ratios(plan, config.max_velocity, config.max_acceleration)
    if np.count_nonzero(ratios <= 1.0 + LIMIT_TOLERANCE) == ratios.size:
        return 1.0, ''
    ratios[1] = np.sqrt(ratios[1])
    quantity, joint = divmod(int(np.argmax(ratios)), ratios.shape[1])
    factor = float(ratios[quantity, joint])
    name = config.joints[joint]
    if quantity == 0:
        why = (f'joint {name!r} velocity {factor * config.max_velocity[joint]:.6g} rad/s '
               f'above max_velocity {config.max_velocity[joint]:.6g} rad/s')
    else:
        why = (f'joint {name!r} acceleration '
               f'{factor ** 2 * config.max_acceleration[joint]:.6g} rad/s^2 above '
               f'max_acceleration {config.max_acceleration[joint]:.6g} rad/s^2')
    return factor, why


def plan_trajectory_goal(config: Config, state: State, hold_at: np.ndarray,
                         goal: TrajectoryGoal, reference: np.ndarray,
                         start_tolerance: float, measured: bool = False) -> PlannedMotion:
    """
    Plan ``goal`` from the setpoint ``state`` through the pipeline every request takes.

    The action's own steps (:func:`goal_steps`): its trajectory unwrapped as a whole, its
    start checked against ``reference`` (where the arm is, rad: the measured state
    (``measured``), else ``state.position``), its points interpolated and slowed to fit.
    Joints it does not name go to ``hold_at``. Sets ``goal.factor`` and ``goal.slowed``;
    raises :class:`GoalError` (also stored in ``goal.refusal``) when the goal cannot be
    executed.
    """
    try:
        return plan_request(config, state, hold_at, goal.points,
                            goal_steps(config, goal, reference, start_tolerance, measured))
    except GoalError as error:
        goal.refusal = error
        raise
    except RequestError as error:
        goal.refusal = GoalError(INVALID_GOAL, str(error))
    except ValueError as error:
        goal.refusal = GoalError(INVALID_GOAL, f'cannot interpolate the points: {error}')
    raise goal.refusal


def goal_steps(config: Config, goal: TrajectoryGoal, reference: np.ndarray,
               start_tolerance: float, measured: bool) -> Steps[ViaRequest]:
    """
    Return the action goal's own steps of the pipeline (see :func:`plan_trajectory_goal`).

    *Unwrap*: as ``joint_trajectory_controller`` does, each continuous joint's trajectory
    shifted as a whole by the ``2πk`` that puts its first point nearest the start
    (:func:`shift_whole_turns`), before the start check.
    """
    def unwrap(start: np.ndarray, points: ViaRequest, mask: np.ndarray) -> ViaRequest:
        named = points.joints
        return dataclasses.replace(
            points, positions=shift_whole_turns(start[named], points.positions, mask[named]))

    def check_start(state: State, points: ViaRequest) -> ViaRequest:
        return start_from_setpoint(points, state, reference, start_tolerance, config.joints,
                                   measured)

    def plan(config: Config, state: State, hold_at: np.ndarray, points: ViaRequest
             ) -> PlannedMotion:
        return interpolate(config, state, hold_at, goal, points)
    return Steps(plan=plan, unwrap=unwrap, check_start=check_start)


def interpolate(config: Config, state: State, hold_at: np.ndarray, goal: TrajectoryGoal,
                request: ViaRequest) -> PlannedMotion:
    """
    Interpolate the goal's points (from the setpoint) and slow them down to fit the limits.

    The pipeline's *plan* step for an action goal: sets ``goal.factor`` and
    ``goal.slowed``; :class:`GoalError` when no uniform slow-down fits.
    """
    points, times, velocities, accelerations = via_points(config.joints, state, hold_at,
                                                          request)
    if len(points) == 1:  # one point at time 0, within the tolerance: nothing to do
        if np.any(state.velocity):
            raise GoalError(INVALID_GOAL, f'{WHAT} has one point, at time_from_start 0, '
                            'while the node moves: give it a time > 0')
        return held(state.position, 'follow_joint_trajectory', 'already there')
    kind = interpolation(config, request)
    durations = np.diff(times)

    def build(scale: float) -> Trajectory:
        given_v = given_a = None
        if velocities is not None:  # the start's own row is the setpoint's: not scaled
            given_v = np.vstack([velocities[:1], velocities[1:] / scale])
        if accelerations is not None:
            given_a = np.vstack([accelerations[:1], accelerations[1:] / scale ** 2])
        return plan_path(points, durations * scale, kind,
                         velocities=config.via_velocities if given_v is None else given_v,
                         accelerations=given_a, v0=state.velocity, a0=state.acceleration)

    plan = build(1.0)
    factor, why = slow_down(plan, config)
    if factor > 1.0:
        if not math.isfinite(factor) or plan.duration * factor > MAX_DURATION:
            raise GoalError(INVALID_GOAL, f'{why}: slowed to fit, it would last '
                            f'{plan.duration * factor:.4g} s, above the limit of '
                            f'{MAX_DURATION:g} s')
        plan = build(factor)
        goal.factor = factor
        goal.slowed = f'slowed by a factor of {factor:.6g} ({why})'
        violation = limit_violation(plan, config.max_velocity, config.max_acceleration)
        if violation is not None:  # a moving start whose velocity cannot be slowed
            raise GoalError(INVALID_GOAL, 'infeasible even slowed down uniformly: '
                            f'{violation.describe(config.joints)} (from the current '
                            'motion; send it when the arm moves slower)')
    return PlannedMotion(plan, kind, points[-1], goal.slowed)
