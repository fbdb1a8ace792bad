"""traj_gen_ros.node.position_checks: requests and plans beyond the position limits."""

import dataclasses
import math

import numpy as np
import pytest
from traj_gen_ros import min_time
from traj_gen_ros.node.config import make_config
from traj_gen_ros.node.parsing import GoalRequest, RequestError, ViaRequest
from traj_gen_ros.node.planning import plan_request, plan_stop, State
from traj_gen_ros.node.position_checks import check_plan, check_request
from traj_gen_ros.node.urdf_limits import merge_limits, UrdfLimits

NAMES = ('shoulder', 'elbow', 'wrist')


def limits(lower=-1.0, upper=1.0):
    return merge_limits(UrdfLimits.unlimited(NAMES), min_position=lower, max_position=upper)


def test_a_moving_start_that_must_brake_past_the_target_is_refused():
    # From 0.6 rad at 2 rad/s, braking at 4 rad/s^2 needs at least 0.5 rad: past 1.
    start = np.array([0.6, 0.0, 0.0])
    plan = min_time(start, np.array([0.8, 0.0, 0.0]), np.full(3, 2.0), np.full(3, 4.0),
                    'quintic', v0=np.array([2.0, 0.0, 0.0]))
    assert plan.position_extrema().maximum[0] > 1.1
    with pytest.raises(RequestError, match=r"the plan would take joint 'shoulder' to 1\.[0-9]+ "
                                           r'rad, outside its range \[-1, 1\] rad \(lower from '
                                           r'parameter min_position; upper from parameter '
                                           r'max_position\)'):
        check_plan(limits(), plan, start)


def test_scurve_plans_in_the_node_keep_the_position_limits():
    config = dataclasses.replace(
        make_config(NAMES, 100.0, 'scurve', 'heuristic', 2.0, 4.0, 0.0, 10.0),
        limits=limits())
    # From 0.6 rad at 1.5 rad/s, accelerating: braking within a_max and j_max passes 1 rad.
    moving = State(np.array([0.6, 0.0, 0.0]), np.array([1.5, 0.0, 0.0]),
                   np.array([2.0, 0.0, 0.0]))
    with pytest.raises(RequestError, match="the plan would take joint 'shoulder' to 1\\."):
        plan_request(config, moving, moving.position,
                     GoalRequest(np.array([0]), np.array([0.8])))
    with pytest.raises(RequestError, match="goal position 1.25 rad for joint 'wrist'"):
        plan_request(config, moving, moving.position,
                     GoalRequest(np.array([2]), np.array([1.25])))
    slow = moving._replace(velocity=np.array([0.2, 0.0, 0.0]),
                           acceleration=np.zeros(3))
    motion = plan_request(config, slow, slow.position,
                          GoalRequest(np.array([0]), np.array([0.8])))
    assert motion.profile == 'scurve' and motion.plan.position_extrema().maximum[0] <= 1.0
    # ~/stop always runs, limits or not (it cannot be refused).
    assert plan_stop(config, moving).plan.duration > 0


def test_a_start_outside_the_range_may_come_back_but_not_go_further():
    back = min_time(np.array([1.5, 0, 0]), np.array([0.5, 0, 0]), np.full(3, 2.0),
                    np.full(3, 4.0), 'quintic')
    check_plan(limits(), back, [1.5, 0.0, 0.0])
    further = min_time(np.array([1.5, 0, 0]), np.array([1.5, 0, 0]), np.full(3, 2.0),
                       np.full(3, 4.0), 'quintic', v0=np.array([0.5, 0, 0]))
    with pytest.raises(RequestError, match="joint 'shoulder'"):
        check_plan(limits(), further, [1.5, 0.0, 0.0])


def test_commanded_positions_outside_the_range_are_refused_by_name():
    goal = GoalRequest(np.array([2]), np.array([1.25]))
    with pytest.raises(RequestError, match=r"goal position 1\.25 rad for joint 'wrist' is "
                                           r'outside its range \[-1, 1\] rad'):
        check_request(limits(), goal, np.zeros(3))
    via = ViaRequest(np.array([1, 0]), np.array([1.0, 2.0]),
                     np.array([[0.5, 0.5], [0.9, -1.5]]), None, None, False)
    with pytest.raises(RequestError, match="via point 1 position -1.5 rad for joint 'shoulder'"):
        check_request(limits(), via, np.zeros(3))
    check_request(limits(), GoalRequest(np.array([0]), np.array([1.0])), np.zeros(3))
    # A joint already outside may be told to stay where it is.
    check_request(limits(), GoalRequest(np.array([0]), np.array([3.0])), [3.0, 0.0, 0.0])
    check_request(limits(-math.inf, math.inf), goal, np.zeros(3))
