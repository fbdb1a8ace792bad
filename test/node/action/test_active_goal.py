"""ActiveGoal: when a running goal ends, and the feedback it gives (no DDS)."""

from types import SimpleNamespace

import numpy as np
from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.action.goal_points import parse_trajectory_goal
from traj_gen_ros.node.action.tolerances import default_tolerances
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.requests.request import Request

JOINTS = ('a', 'b', 'c')
SECOND = 1_000_000_000


def active(names=('c', 'a'), start_ns=5 * SECOND, seconds=2.0):
    """Return a goal of ``names`` started at ``start_ns``, planned to last ``seconds``."""
    goal = parse_trajectory_goal(JOINTS, names, [([0.5] * len(names), (), (), seconds)], 0)
    return ActiveGoal(None, goal, Request('follow_joint_trajectory', {}, 0, goal),
                      default_tolerances(3, 0.0, 0.0, 0.0, 0.0), start_ns=start_ns,
                      end_ns=start_ns + int(seconds * SECOND), target=np.full(3, 0.5))


def empty_feedback():
    """Return what the monitor fills: a ``FollowJointTrajectory.Feedback``'s fields."""
    return SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0)))


def test_the_end_is_the_planned_one_at_a_factor_of_one():
    goal = active()
    # Before the start, or still moving: not ended (at least the planned end).
    assert goal.end(6 * SECOND, 4 * SECOND, False) == goal.end_ns
    assert goal.end(6 * SECOND, 6 * SECOND, True) == goal.end_ns
    assert goal.at_rest_ns is None
    # At rest at the planned end: that is the end.
    assert goal.end(7 * SECOND, goal.end_ns, False) == goal.end_ns


def test_a_slowed_goal_ends_at_its_first_setpoint_at_rest_after_the_start():
    goal = active()
    late = goal.end_ns + SECOND  # speed scaling stretched it by 1 s
    assert goal.end(late - 1, late - 10, True) == late  # moving: a nanosecond ahead of now
    assert goal.end(late + 5, late, False) == late
    assert goal.at_rest_ns == late
    assert goal.end(late + 10 * SECOND, late + 9 * SECOND, False) == late  # kept


def test_feedback_is_in_the_goals_order_with_the_time_since_its_start():
    goal = active(names=('c', 'a'))
    desired = State(np.array([0.1, 0.2, 0.3]), np.array([1.0, 2.0, 3.0]),
                    np.array([-1.0, -2.0, -3.0]))
    measured = np.array([0.11, 0.25, 0.28])
    velocities = np.array([0.9, 2.0, 3.5])
    now = goal.start_ns + 1_250_000_000
    feedback = goal.feedback(empty_feedback(), now, desired, measured, velocities)
    assert feedback.joint_names == ['c', 'a']
    assert (feedback.header.stamp.sec, feedback.header.stamp.nanosec) == (6, 250_000_000)
    assert list(feedback.desired.positions) == [0.3, 0.1]
    assert list(feedback.desired.velocities) == [3.0, 1.0]
    assert list(feedback.desired.accelerations) == [-3.0, -1.0]
    assert list(feedback.actual.positions) == [0.28, 0.11]
    assert list(feedback.actual.velocities) == [3.5, 0.9]
    assert np.allclose(feedback.error.positions, [0.02, -0.01], atol=1e-15)
    assert np.allclose(feedback.error.velocities, [-0.5, 0.1], atol=1e-15)
    for point in (feedback.desired, feedback.actual):
        assert (point.time_from_start.sec, point.time_from_start.nanosec) == (1, 250_000_000)


def test_without_a_measured_state_actual_is_the_setpoint():
    goal = active(names=('b',))
    desired = State(np.array([0.1, 0.2, 0.3]), np.array([0.0, 0.7, 0.0]), np.zeros(3))
    feedback = goal.feedback(empty_feedback(), goal.start_ns, desired, None)
    assert list(feedback.actual.positions) == [0.2]
    assert list(feedback.actual.velocities) == [0.7]
    assert list(feedback.error.positions) == [0.0]
