"""
A ``~/follow_joint_trajectory`` goal: read from its message; its end and feedback as it runs.

Times are ns of the node clock; positions rad (or m), velocities rad/s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from builtin_interfaces.msg import Duration
import numpy as np
from rclpy.action.server import ServerGoalHandle
from traj_gen_ros.node.action.goal_points import (
    check_stamp,
    GoalError,
    INVALID_GOAL,
    parse_trajectory_goal,
    TrajectoryGoal,
    WHAT,
)
from traj_gen_ros.node.action.tolerances import goal_tolerances, Tolerances
from traj_gen_ros.node.messages.parsing import check_no_effort, RequestError, seconds
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.requests.request import Request
from trajectory_msgs.msg import JointTrajectoryPoint


@dataclass
class ActiveGoal:
    """A goal being executed: its handle, request, tolerances and times (ns, node clock)."""

    handle: ServerGoalHandle | None  # None until rclpy has made it (after the plan)
    goal: TrajectoryGoal
    request: Request
    tolerances: Tolerances
    start_ns: int = 0
    end_ns: int = 0
    target: np.ndarray | None = None
    cancel: Request | None = None
    brake_start_ns: int | None = None
    replaced: str = ''
    feedback_ns: int = -(2 ** 62)
    at_rest_ns: int | None = None  # the first setpoint published at the end, at rest
    #: An end decided before the handle existed: ``(status, error_code, error_string)``.
    early_end: tuple[str, int, str] | None = None
    ended: bool = False  # its end is decided: the first one counts

    def end(self, now_ns: int, published_ns: int, moving: bool) -> int:
        """
        Return when the goal's motion ends (ns): its planned end, later if it was slowed.

        With speed scaling (``speed_scaling``) the plan runs on its own clock: the end is
        the first setpoint the stream publishes at rest (``moving`` false at
        ``published_ns``) after the goal started, and the goal-time check counts from
        there (a slowed goal is not failed for being slow). At a factor of 1 that is the
        planned end's tick.
        """
        if self.at_rest_ns is None:
            if published_ns < self.start_ns or moving:
                return max(self.end_ns, now_ns + 1)
            self.at_rest_ns = published_ns
        return max(self.end_ns, self.at_rest_ns)

    def feedback(self, feedback: object, now_ns: int, desired: State,
                 measured: np.ndarray | None, velocities: np.ndarray | None = None) -> object:
        """
        Fill a ``FollowJointTrajectory.Feedback``: the goal's joints, in its order.

        ``desired`` is the commanded setpoint, ``actual`` the measured positions and
        ``velocities`` (rad, rad/s; without a measured state the setpoint's) and ``error``
        their difference. ``time_from_start`` of ``desired`` and ``actual`` is the time
        since the goal's start (as ``joint_trajectory_controller`` fills it), ``error``'s 0.
        """
        named = self.goal.points.joints
        actual = desired.position if measured is None else measured
        if measured is None:
            velocities = desired.velocity
        feedback.joint_names = list(self.goal.names)
        feedback.header.stamp.sec, feedback.header.stamp.nanosec = divmod(now_ns, 1_000_000_000)
        since = Duration()
        since.sec, since.nanosec = divmod(max(now_ns - self.start_ns, 0), 1_000_000_000)
        feedback.desired = JointTrajectoryPoint(
            positions=desired.position[named].tolist(),
            velocities=desired.velocity[named].tolist(),
            accelerations=desired.acceleration[named].tolist(), time_from_start=since)
        feedback.actual = JointTrajectoryPoint(
            positions=actual[named].tolist(), time_from_start=since,
            velocities=[] if velocities is None else velocities[named].tolist())
        error = JointTrajectoryPoint(positions=(desired.position[named] - actual[named]).tolist())
        if velocities is not None:
            error.velocities = (desired.velocity[named] - velocities[named]).tolist()
        feedback.error = error
        return feedback


def read_goal_message(message: object, request: Request, joints: Sequence[str],
                      defaults: Tolerances, now_ns: int) -> ActiveGoal:
    """
    Read a goal's message (``FollowJointTrajectory.Goal``): points, stamp, tolerances.

    ``GoalError`` if it cannot be executed. ``request`` (the goal's answer on
    ``~/status``) gets the parsed goal and its stamp (ns); ``defaults`` are the tolerance
    parameters; ``now_ns`` the node clock (ns), for ``OLD_HEADER_TIMESTAMP``. The
    :class:`ActiveGoal` has no handle yet.
    """
    trajectory = message.trajectory
    stamp = trajectory.header.stamp
    points = [(p.positions, p.velocities, p.accelerations, seconds(p.time_from_start))
              for p in trajectory.points]
    try:
        check_no_effort([p.effort for p in trajectory.points], WHAT)
    except RequestError as error:
        raise GoalError(INVALID_GOAL, str(error)) from None
    goal = parse_trajectory_goal(joints, trajectory.joint_names, points,
                                 stamp.sec * 1_000_000_000 + stamp.nanosec,
                                 len(message.multi_dof_trajectory.points))
    tolerances = goal_tolerances(
        defaults, joints, [(t.name, t.position) for t in message.path_tolerance],
        [(t.name, t.position) for t in message.goal_tolerance],
        seconds(message.goal_time_tolerance))
    check_stamp(goal, now_ns)
    request.parsed, request.stamp_ns = goal, goal.stamp_ns
    return ActiveGoal(None, goal, request, tolerances)
