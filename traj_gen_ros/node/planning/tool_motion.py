"""
Lines and arcs of the tool (LIN, CIRC): ``~/cartesian_path`` and ``~/circular_goal``.

A request's poses are resolved in their frame (as a pose goal's:
:func:`~traj_gen_ros.node.planning.pose_goal.target_in_base`, at the start state, with the
chain of :func:`~traj_gen_ros.node.planning.pose_goal.request_chain`), the arm
brakes to rest if it moves (:func:`~traj_gen_ros.node.planning.pipeline.plan_stop`), and
from that rest the core plans the tool's path (:mod:`traj_gen_ros.core.cartesian`): the
ideal path (straight lines with ``blend_radius`` blends, or the circle through the
interim point), the joint path that follows it (refused where Craig §7.5's problems
arise: out of reach, a joint limit, a singularity, a configuration flip) and its
time-optimal timing under the joint limits and the tool's. Under profile ``scurve`` every
joint's jerk is bounded too (:func:`~traj_gen_ros.core.cartesian.jerk_limited_timing.
time_path_jerk_limited`): corners are not blended then (the tool stops at each), and a
brake along the path is jerk-limited. The brake and the path are one plan, through the
pipeline's checks (:data:`PATH`). No ROS here.

Units: m, rad, s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from traj_gen_ros.core.cartesian.jerk_limited_brake import brake_from_timing
from traj_gen_ros.core.cartesian.jerk_limited_timing import (
    JerkLimitedTimedPath,
    time_path_jerk_limited,
)
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_brake import brake_along
from traj_gen_ros.core.cartesian.path_refusal import PathRefusal
from traj_gen_ros.core.cartesian.path_timing import time_path, TimedPath, ToolLimits
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path
from traj_gen_ros.core.sequences import concatenate, tail
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.parsing import RequestError
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop, Steps
from traj_gen_ros.node.planning.pose_goal import PoseRequest, request_chain, target_in_base
from traj_gen_ros.node.settings.config import Config

#: The request kinds, as they appear on ``~/status``.
CARTESIAN_PATH, CIRCULAR_GOAL = 'cartesian_path', 'circular_goal'
#: Each kind's word for its plan on ``~/status`` (``profile=``).
PROFILE = {CARTESIAN_PATH: 'line', CIRCULAR_GOAL: 'arc'}


@dataclass
class ToolPathRequest:
    """
    Tool poses in ``frame_id`` (each ``(4, 4)``, m), as read; ``answer`` gets the plan's words.

    ``~/cartesian_path``: the corners of the lines, in order; ``~/circular_goal``: the
    interim point and the goal.
    """

    kind: str
    frame_id: str
    poses: tuple[np.ndarray, ...]
    answer: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class JointPathRequest:
    """
    A tool path turned into joints, as the pipeline's checks see it.

    ``joints`` are every joint (indices), ``positions`` the joint path's breakpoints
    (``(points, joints)``, rad or m), ``brake`` the plan to rest that comes first.
    """

    joints: np.ndarray
    positions: np.ndarray
    brake: Trajectory
    tool_path: IdealPath
    joint_path: JointPath
    kind: str


def joint_path_request(config: Config, request: ToolPathRequest, state: State
                       ) -> JointPathRequest:
    """
    Resolve the poses, brake to rest, and follow the tool path from there by joints.

    Under profile ``scurve`` the lines' corners are not blended (``blend_radius`` 0: a
    blend's curvature steps, so no joint's jerk would be bounded on it at speed).

    :raises RequestError: no kinematics, an unknown frame, or a path that cannot be drawn
        (coincident or collinear points) or followed (where and why).
    """
    chain = request_chain(config)
    targets = [target_in_base(chain, PoseRequest(request.frame_id, pose), state.position)
               for pose in request.poses]
    brake = plan_stop(config, state).plan
    rest = brake.sample(brake.duration)[0][0]
    start = chain.forward(rest)
    try:
        if request.kind == CIRCULAR_GOAL:
            path = circular_path(start, targets[0], targets[1])
        else:
            path = straight_path(start, targets,
                                 0.0 if config.profile == 'scurve' else config.blend_radius)
    except ValueError as error:
        raise RequestError(str(error)) from None
    limits = config.limits
    lower = None if limits is None else limits.position.lower
    upper = None if limits is None else limits.position.upper
    try:
        joint_path = follow(chain, path, rest, lower=lower, upper=upper)
    except PathRefusal as refusal:
        raise RequestError(str(refusal)) from None
    positions = joint_path.joints.sample(joint_path.joints.breakpoints)[0]
    return JointPathRequest(np.arange(len(config.joints)), positions, brake, path, joint_path,
                            request.kind)


@dataclass(frozen=True)
class AlongPath:
    """
    How a planned line or arc brakes along its path (``~/stop``, a lost measured state).

    ``offset`` (s) is when the path starts in the plan (after the brake to rest before
    it); ``timed`` its timing; the limits those it was planned with. With ``max_jerk``
    (profile ``scurve``) the brake is jerk-limited too.
    """

    tool_path: IdealPath
    joint_path: JointPath
    timed: TimedPath
    offset: float
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    tool: ToolLimits
    max_jerk: np.ndarray | None = None

    def brake(self, elapsed: float, velocity: np.ndarray,
              acceleration: np.ndarray | None = None) -> Trajectory | None:
        """
        Brake from ``elapsed`` s into the plan at joint ``velocity`` (rad/s), along the path.

        The commanded path speed is ``velocity``'s along ``q'(s)`` (the speed override
        scales ``ṡ``). Under ``scurve`` the brake starts from the commanded
        ``acceleration`` (rad/s²) too where given, else from the plan's at the override.
        None where the plan is not on its path then (before it, at its end, at rest), or
        no brake along it is found: the caller brakes each joint.
        """
        local = elapsed - self.offset
        if not 0.0 <= local < self.timed.duration:
            return None
        s, _ = self.timed.path_parameter(local)
        _, rates, curvatures = self.joint_path.joints.sample(float(s))
        rate = rates[0]
        norm = float(rate @ rate)
        speed = float(rate @ velocity) / norm if norm > 0.0 else 0.0
        if speed <= 0.0:
            return None
        if self.max_jerk is not None and isinstance(self.timed, JerkLimitedTimedPath):
            return self._jerk_limited(local, speed, rate, norm, curvatures[0], acceleration)
        try:
            plan, _ = brake_along(self.tool_path, self.joint_path, self.max_velocity,
                                  self.max_acceleration, self.tool, float(s), speed,
                                  self.timed)
        except ValueError:
            # Already braking as hard as the limits allow (near the end): the plan's own
            # rest of the path is the brake, where the arm runs at its own speed.
            _, own = self.timed.path_parameter(local)
            if abs(float(own) - speed) > 1e-6 * max(float(own), 1e-9):
                return None
            return tail(self.timed.trajectory, local)
        return plan

    def _jerk_limited(self, local: float, speed: float, rate: np.ndarray, norm: float,
                      curvature: np.ndarray, acceleration: np.ndarray | None
                      ) -> Trajectory | None:
        """
        Brake with bounded jerk from the commanded ``ṡ`` and ``s̈`` (:func:`brake_from_timing`).

        ``s̈`` is the commanded ``acceleration``'s along ``q'`` (``q̈ = q' s̈ + q'' ṡ²``)
        where given, else the plan's times the override squared, ``(ṡ / ṡ_plan)²``.
        """
        _, planned, planned_acceleration = (float(value) for value in
                                            self.timed.path_state(local))
        if acceleration is not None:
            path_acceleration = float(rate @ (acceleration - curvature * speed ** 2)) / norm
        else:
            factor = speed / planned if planned > 0.0 else 1.0
            path_acceleration = planned_acceleration * factor ** 2
        try:
            plan, _ = brake_from_timing(
                self.timed, self.tool_path, self.joint_path,
                (self.max_velocity, self.max_acceleration, self.max_jerk), self.tool, local,
                speed, path_acceleration)
        except ValueError:
            return None
        return plan


def _timed(config: Config, state: State, hold_at: np.ndarray, request: JointPathRequest
           ) -> PlannedMotion:
    """Time the joint path under the joint and tool limits; the brake first, one plan."""
    del state, hold_at  # the path starts where the brake ends; every joint moves
    tool = ToolLimits(config.max_linear_velocity, config.max_linear_acceleration,
                      config.max_angular_velocity)
    jerk = config.max_jerk if config.profile == 'scurve' else None
    if jerk is None:
        timed = time_path(request.tool_path, request.joint_path, config.max_velocity,
                          config.max_acceleration, tool, joint_names=config.joints)
    else:
        try:
            timed = time_path_jerk_limited(request.tool_path, request.joint_path,
                                           config.max_velocity, config.max_acceleration,
                                           jerk, tool, joint_names=config.joints)
        except ValueError as error:
            raise RequestError(str(error)) from None
    plan = concatenate([request.brake, timed.trajectory])
    end = plan.sample(plan.duration)[0][0]
    knots = request.joint_path.joints.breakpoints
    along = AlongPath(request.tool_path, request.joint_path, timed, request.brake.duration,
                      config.max_velocity, config.max_acceleration, tool, jerk)
    note = f'speed bounded by {timed.describe(config.joints)}'
    if jerk is not None and config.blend_radius > 0.0 and len(request.tool_path.stops) > 2:
        note += '; corners not blended under profile scurve (the tool stops at each)'
    return PlannedMotion(plan, PROFILE[request.kind], end, note,
                         tool_poses=request.tool_path.sample(knots).poses(), along=along)


def _as_planned(start: np.ndarray, request: JointPathRequest, mask: np.ndarray
                ) -> JointPathRequest:
    """Leave a joint path as it is: it is continuous from the start (no whole turns)."""
    del start, mask
    return request


#: A tool path's steps in the pipeline: its timing; no unwrap (the path is continuous).
PATH: Steps[JointPathRequest] = Steps(plan=_timed, unwrap=_as_planned)


def plan_tool_path(config: Config, state: State, hold_at: np.ndarray,
                   request: ToolPathRequest) -> PlannedMotion:
    """Plan a line or an arc from ``state``: its joint path, then the pipeline (:data:`PATH`)."""
    joint_request = joint_path_request(config, request, state)
    motion = plan_request(config, state, hold_at, joint_request, PATH)
    request.answer['bounded_by'] = motion.note.removeprefix('speed bounded by ')
    return motion
