"""node.planning.continuous_joints: continuous joints' targets the shortest way round."""

import dataclasses
import math

import numpy as np
import pytest
from traj_gen_ros.node.description.joint_limits import merge_limits, urdf_limits
from traj_gen_ros.node.messages.parsing import GoalRequest, ViaRequest
from traj_gen_ros.node.planning.continuous_joints import TURN, unwrap_targets, wrapping_joints
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.planning.pipeline import plan_request
from traj_gen_ros.node.settings.config import make_config

URDF = ('<robot name="r"><joint name="wheel" type="continuous"><limit effort="1" '
        'velocity="2"/></joint><joint name="arm" type="revolute"><limit effort="1" '
        'velocity="2" lower="-20" upper="20"/></joint><joint name="free" type="continuous"/>'
        '</robot>')
JOINTS = ['wheel', 'arm', 'free']


def test_from_ten_rad_a_goal_of_minus_a_tenth_ends_two_turns_on():
    result = unwrap_targets([10.0], [-0.1], [True])
    assert result[0] == pytest.approx(-0.1 + 2 * TURN, abs=1e-12)
    assert result[0] == pytest.approx(12.466370614359172, abs=1e-12)
    assert result[0] - 10.0 == pytest.approx(2.466370614359172)  # not -10.1 rad


def test_negative_starts_and_targets_and_joints_that_do_not_wrap():
    result = unwrap_targets([-10.0, -10.0], [0.1, 0.1], [True, False])
    assert result[0] == pytest.approx(0.1 - 2 * TURN) and result[1] == 0.1
    assert unwrap_targets([-3.0], [3.0], [True])[0] == pytest.approx(3.0 - TURN)  # -3.283
    assert unwrap_targets([0.5], [-0.5], [True])[0] == -0.5  # within half a turn: as given


def test_a_half_turn_tie_keeps_the_target_as_given():
    assert unwrap_targets([0.0], [math.pi], [True])[0] == math.pi
    assert unwrap_targets([0.0], [-math.pi], [True])[0] == -math.pi
    # Three half turns: +pi and -pi from 0 away are a tie; the nearer to the target wins.
    assert unwrap_targets([0.0], [3 * math.pi], [True])[0] == pytest.approx(math.pi)
    assert unwrap_targets([0.0], [-3 * math.pi], [True])[0] == pytest.approx(-math.pi)


def test_a_path_takes_each_point_the_shortest_way_from_the_previous_one():
    points = np.array([[3.0, 3.0], [-3.0, -3.0], [0.0, 0.0]])
    result = unwrap_targets([0.0, 0.0], points, [True, False])
    assert result[:, 0] == pytest.approx([3.0, TURN - 3.0, TURN])
    assert result[:, 1].tolist() == [3.0, -3.0, 0.0]
    assert points[1, 0] == -3.0  # the caller's array is not changed


def test_shapes_that_do_not_match_are_refused():
    with pytest.raises(ValueError, match='must be'):
        unwrap_targets([0.0, 0.0], [1.0], [True, True])


def test_only_urdf_continuous_joints_without_position_limits_wrap():
    limits = merge_limits(urdf_limits(URDF, JOINTS))
    assert wrapping_joints(limits).tolist() == [True, False, True]
    bounded = merge_limits(urdf_limits(URDF, JOINTS), max_position=[9.0, 9.0, math.inf])
    assert wrapping_joints(bounded).tolist() == [False, False, True]
    assert wrapping_joints(None).tolist() == []


def config(wraparound: bool = True):
    base = make_config(JOINTS, 100.0, 'quintic', 'heuristic', 2.0, 4.0, 0.0,
                       angle_wraparound=wraparound)
    return dataclasses.replace(base, limits=merge_limits(urdf_limits(URDF, JOINTS)))


def test_plans_take_the_short_way_and_the_parameter_turns_it_off():
    start = State(np.array([10.0, 10.0, 0.0]), np.zeros(3), np.zeros(3))
    goal = GoalRequest(np.array([0, 1]), np.array([-0.1, -0.1]))
    motion = plan_request(config(), start, start.position, goal)
    assert motion.end.tolist() == pytest.approx([-0.1 + 2 * TURN, -0.1, 0.0])
    # The revolute joint's 10.1 rad decides the duration; alone, the wheel is quick.
    wheel = plan_request(config(), start, start.position,
                         GoalRequest(np.array([0]), np.array([-0.1])))
    assert wheel.plan.duration == pytest.approx(
        plan_request(config(), start, start.position,
                     GoalRequest(np.array([0]), np.array([12.466370614359172]))).plan.duration)
    off = plan_request(config(False), start, start.position,
                       GoalRequest(np.array([0]), np.array([-0.1])))
    assert off.end[0] == -0.1 and off.plan.duration > 3 * wheel.plan.duration
    via = ViaRequest(np.array([2]), np.zeros(2), np.array([[3.0], [-3.0]]), None, None, True)
    motion = plan_request(config(), start, start.position, via)
    assert motion.end[2] == pytest.approx(TURN - 3.0)  # 0.283 rad on, not 6 back
    assert motion.plan.sample(motion.plan.duration)[0][0][2] == pytest.approx(TURN - 3.0)
