"""traj_gen_ros.node.planning.position_checks: requests and plans beyond the position limits."""

import dataclasses
import math

import numpy as np
import pytest
from traj_gen_ros import min_time
from traj_gen_ros.node.description.joint_limits import merge_limits, UrdfLimits
from traj_gen_ros.node.messages.parsing import GoalRequest, RequestError, ViaRequest
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop
from traj_gen_ros.node.planning.position_checks import check_plan, check_request, outside_ranges
from traj_gen_ros.node.settings.config import make_config

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


def test_a_joint_outside_its_range_may_move_toward_it_but_not_further_out():
    # 'shoulder' starts at 1.5, above its range [-1, 1]: any goal in [-1, 1.5] is accepted.
    start = np.array([1.5, 0.0, 0.0])
    for target in (1.5, 1.2, 1.0, 0.0, -1.0):
        check_request(limits(), GoalRequest(np.array([0]), np.array([target])), start)
    for target, allowed in ((1.6, r'\[-1, 1\.5\]'), (-1.1, r'\[-1, 1\.5\]')):
        with pytest.raises(RequestError, match=(
                rf"^goal position {target:g} rad for joint 'shoulder' is outside its range "
                r'\[-1, 1\] rad \(lower from parameter min_position; upper from '
                r'parameter max_position\); it is at 1\.5 rad, '
                rf'outside its range: only positions in {allowed} rad \(toward or into its '
                r'range\) are allowed$')):
            check_request(limits(), GoalRequest(np.array([0]), np.array([target])), start)
    # The others move while it holds; a via path may come in step by step, not go out.
    check_request(limits(), GoalRequest(np.array([2]), np.array([0.5])), start)
    path = ViaRequest(np.array([0]), np.array([1.0, 2.0]), np.array([[1.3], [0.2]]), None,
                      None, False)
    check_request(limits(), path, start)
    out = ViaRequest(np.array([0]), np.array([1.0, 2.0]), np.array([[1.3], [1.7]]), None,
                     None, False)
    with pytest.raises(RequestError, match="via point 1 position 1.7 rad for joint 'shoulder'"):
        check_request(limits(), out, start)
    # A joint inside its range gets the range alone, no widening.
    with pytest.raises(RequestError, match=r"joint 'wrist' is outside its range \[-1, 1\] "
                                           r'rad \(lower from parameter min_position; upper '
                                           r'from parameter max_position\)$'):
        check_request(limits(), GoalRequest(np.array([2]), np.array([1.1])), start)


def test_outside_ranges_names_each_joint_its_position_and_range():
    assert outside_ranges(limits(), [0.0, 1.0, -1.0]) == ''
    assert outside_ranges(None, [9.0, 9.0, 9.0]) == ''
    sources = '(lower from parameter min_position; upper from parameter max_position)'
    assert outside_ranges(limits(), [1.5, 0.0, -2.0]) == (
        f"joint 'shoulder' is at 1.5 rad, outside its range [-1, 1] rad {sources}; "
        f"joint 'wrist' is at -2 rad, outside its range [-1, 1] rad {sources}")
