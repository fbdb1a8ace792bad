"""A FollowJointTrajectory goal's points: parse, start, interpolate, slow down (no ROS)."""

import numpy as np
import pytest
from traj_gen_ros import cubic_via, quintic_via
from traj_gen_ros.node.action.goal_points import (
    check_stamp,
    GOAL_TOLERANCE_VIOLATED,
    GoalError,
    INVALID_GOAL,
    INVALID_JOINTS,
    OLD_HEADER_TIMESTAMP,
    parse_trajectory_goal,
    PATH_TOLERANCE_VIOLATED,
    plan_trajectory_goal,
)
from traj_gen_ros.node.action.tolerances import (
    ABORTED,
    default_tolerances,
    goal_tolerances,
    goal_violation,
    outcome,
    path_violation,
    SUCCEEDED,
)
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.settings.config import make_config

JOINTS = ('a', 'b', 'c')
V_MAX, A_MAX = np.array([1.0, 2.0, 2.0]), np.array([2.0, 4.0, 4.0])


def config(profile='quintic'):
    return make_config(JOINTS, 100.0, profile, 'heuristic', V_MAX, A_MAX, [0.0])


def rest(position=(0.0, 0.0, 0.0)):
    position = np.array(position, dtype=float)
    return State(position, np.zeros(3), np.zeros(3))


def plan(names, points, state=None, profile='quintic', reference=None, tolerance=0.01):
    state = state or rest()
    goal = parse_trajectory_goal(JOINTS, names, points, 0)
    reference = state.position if reference is None else reference
    motion = plan_trajectory_goal(config(profile), state, state.position, goal, reference,
                                  tolerance)
    return goal, motion


def refusal(names, points, **kwargs):
    with pytest.raises(GoalError) as raised:
        plan(names, points, **kwargs)
    return raised.value.code, str(raised.value)


def test_positions_velocities_accelerations_are_the_quintic_through_them():
    q = np.array([[0.0, 0.0], [0.3, -0.2], [0.5, -0.3]])
    v = np.array([[0.0, 0.0], [0.4, -0.2], [0.0, 0.0]])
    a = np.array([[0.0, 0.0], [0.1, 0.2], [0.0, 0.0]])
    times = [0.0, 1.0, 2.0]
    points = [(q[i], v[i], a[i], times[i]) for i in range(3)]
    goal, motion = plan(['b', 'a'], points)  # any order; c holds
    assert goal.factor == 1.0 and motion.profile == 'quintic'
    expected = quintic_via(q, [1.0, 1.0], v, a)
    t = np.linspace(0.0, 2.0, 41)
    assert np.allclose(motion.plan.sample(t)[0][:, [1, 0]], expected.sample(t)[0], atol=1e-12)
    assert np.allclose(motion.plan.sample(t)[0][:, 2], 0.0)
    assert np.allclose(motion.end, [-0.3, 0.5, 0.0])


def test_positions_velocities_are_the_cubic_and_positions_only_the_via_rule():
    q = np.array([[0.0], [0.3], [0.5]])
    v = np.array([[0.0], [0.4], [0.0]])
    _, motion = plan(['a'], [(q[i], v[i], [], float(i)) for i in range(3)])
    t = np.linspace(0.0, 2.0, 41)
    assert motion.profile == 'cubic'
    assert np.allclose(motion.plan.sample(t)[0][:, 0],
                       cubic_via(q, [1.0, 1.0], v).sample(t)[0][:, 0], atol=1e-12)
    for profile, expected in (('cubic', cubic_via(q, [1.0, 1.0])),
                              ('lspb', quintic_via(q, [1.0, 1.0]))):
        _, motion = plan(['a'], [(q[i], [], [], float(i)) for i in range(3)], profile=profile)
        assert np.allclose(motion.plan.sample(t)[0][:, 0], expected.sample(t)[0][:, 0],
                           atol=1e-12)


def test_three_percent_over_the_velocity_limit_is_slowed_by_exactly_that():
    # A cubic from rest to rest peaks at 1.5 x the mean velocity: 1.03 x max_velocity
    # (its acceleration, 4 v / T, stays within max_acceleration over 3 s).
    distance = 1.03 * V_MAX[0] * 3.0 / 1.5
    goal, motion = plan(['a'], [([0.0], [0.0], [], 0.0), ([distance], [0.0], [], 3.0)])
    assert goal.factor == pytest.approx(1.03, rel=1e-12)
    assert motion.plan.duration == pytest.approx(3.09, rel=1e-12)
    assert motion.plan.peaks()[0][0] == pytest.approx(V_MAX[0], rel=1e-12)
    assert "slowed by a factor of 1.03 (joint 'a' velocity 1.03 rad/s above max_velocity" \
        in goal.slowed


def test_acceleration_sets_the_factor_as_its_square_root():
    # A cubic rest to rest: peak acceleration 6 d / T^2 = 1.21 x max -> s = 1.1.
    distance = 1.21 * A_MAX[0] / 6.0
    goal, motion = plan(['a'], [([0.0], [0.0], [], 0.0), ([distance], [0.0], [], 1.0)])
    assert goal.factor == pytest.approx(1.1, rel=1e-12)
    assert motion.plan.peaks()[1][0] == pytest.approx(A_MAX[0], rel=1e-12)


def test_start_within_tolerance_starts_at_the_setpoint_and_a_later_point_prepends_it():
    state = rest([0.1, 0.2, 0.3])
    _, motion = plan(['a'], [([0.105], [], [], 0.0), ([0.5], [], [], 1.0)], state=state)
    assert np.allclose(motion.plan.sample(0.0)[0], state.position, atol=0)
    _, motion = plan(['a'], [([0.3], [], [], 1.0)], state=state)
    assert motion.plan.duration == pytest.approx(1.0)
    assert np.allclose(motion.plan.sample(0.0)[0], state.position, atol=0)


def test_refusals_name_the_joint_point_and_value():
    good = ([0.0], [], [], 0.0)
    assert refusal(['x'], [good])[0] == INVALID_JOINTS
    assert refusal(['a', 'a'], [([0, 0], [], [], 0.0)])[0] == INVALID_JOINTS
    cases = {
        'has no points': (['a'], []),
        "point 1 position for joint 'a' is nan": (['a'], [good, ([np.nan], [], [], 1.0)]),
        'point 2 (1 s) is not after point 1 (1 s)': (
            ['a'], [good, ([0.1], [], [], 1.0), ([0.2], [], [], 1.0)]),
        'point 1 has 2 positions but joint_names has 1': (['a'], [good, ([0, 1], [], [], 1.0)]),
        "has joint 'a' at 0.1 rad, 0.1 rad from where the arm is (setpoint 0 rad): above "
        'allowed_start_tolerance 0.01 rad': (['a'], [([0.1], [], [], 0.0), ([0.2], [], [], 1)]),
        "the last point (point 1) has velocity 0.5 for joint 'a'": (
            ['a'], [([0.0], [0.0], [], 0.0), ([0.2], [0.5], [], 1.0)]),
    }
    for text, (names, points) in cases.items():
        code, reason = refusal(names, points)
        assert code == INVALID_GOAL and text in reason, reason
    with pytest.raises(GoalError) as raised:
        parse_trajectory_goal(JOINTS, ['a'], [good], 0, multi_dof_points=2)
    assert raised.value.code == INVALID_GOAL and 'multi_dof_trajectory' in str(raised.value)


def test_old_header_timestamp():
    goal = parse_trajectory_goal(JOINTS, ['a'], [([0.0], [], [], 0.0), ([1], [], [], 1.5)],
                                 10_000_000_000)
    check_stamp(goal, 11_000_000_000)  # ends at 11.5 s: still to come
    with pytest.raises(GoalError) as raised:
        check_stamp(goal, 12_000_000_000)
    assert raised.value.code == OLD_HEADER_TIMESTAMP and '0.500 s in the past' in str(
        raised.value)


def test_tolerances_follow_jtc():
    defaults = default_tolerances(3, [0.1], [0.05, 0.0, 0.02], 0.25, 0.01)
    tolerances = goal_tolerances(defaults, JOINTS, [('b', 0.3)], [('a', -1.0), ('b', 0.0)],
                                 0.0)
    assert tolerances.path.tolist() == [0.1, 0.3, 0.1]
    assert tolerances.goal.tolist() == [0.0, 0.0, 0.02]  # a: not checked, b: the default
    assert tolerances.goal_time == 0.25
    named = np.array([0, 1, 2])
    desired = np.zeros(3)
    assert path_violation(tolerances, named, desired, np.array([0.09, 0.29, 0]), JOINTS) is None
    assert "joint 'b' is at 0.31 rad, 0.31 rad from 0 rad: above path_tolerance 0.3" in \
        path_violation(tolerances, named, desired, np.array([0, 0.31, 0]), JOINTS)
    assert 'above goal_tolerance 0.02' in goal_violation(
        tolerances, named, desired, np.array([5.0, 5.0, 0.03]), None, JOINTS)
    assert "joint 'c' still moves at 0.5 rad/s" in goal_violation(
        tolerances, named, desired, desired, np.array([0, 0, 0.5]), JOINTS)
    with pytest.raises(GoalError) as raised:
        goal_tolerances(defaults, JOINTS, [('z', 0.1)], [], 0.0)
    assert raised.value.code == INVALID_JOINTS
    with pytest.raises(GoalError) as raised:
        goal_tolerances(defaults, JOINTS, [], [('a', -2.0)], 0.0)
    assert raised.value.code == INVALID_GOAL and "joint 'a' is -2.0" in str(raised.value)


def test_outcome_of_a_running_goal():
    tolerances = default_tolerances(3, [0.1], [0.02], 0.25, 0.01)
    named, desired, target = np.array([0, 1]), np.zeros(3), np.array([0.5, 0.5, 0.0])
    start, end = 0, 2_000_000_000
    still = lambda: np.zeros(3)  # noqa: E731
    # Without a measured state: success once the end is published, with the slow-down.
    assert outcome(tolerances, named, JOINTS, (start, end, end - 1, end - 1), desired, target,
                   None, still, '') is None
    slowed = 'slowed by a factor of 1.03'
    assert outcome(tolerances, named, JOINTS, (start, end, end, end), desired, target, None,
                   still, slowed) == (SUCCEEDED, 0, slowed)
    # Beyond path_tolerance during the motion.
    status, code, text = outcome(tolerances, named, JOINTS, (start, end, 1, 1), desired,
                                 target, np.array([0.0, 0.2, 0.0]), still, '')
    assert (status, code) == (ABORTED, PATH_TOLERANCE_VIOLATED) and "'b'" in text
    # At the end: within goal_tolerance and still, or not yet, or too late.
    near = target + [0.01, -0.01, 0.0]
    assert outcome(tolerances, named, JOINTS, (start, end, end, end), desired, target, near,
                   still, '')[:2] == (SUCCEEDED, 0)
    far = target + [0.05, 0.0, 0.0]
    assert outcome(tolerances, named, JOINTS, (start, end, end + 10**8, end), desired,
                   target, far, still, '') is None
    status, code, text = outcome(tolerances, named, JOINTS, (start, end, end + 3 * 10**8, end),
                                 desired, target, far, still, '')
    assert (status, code) == (ABORTED, GOAL_TOLERANCE_VIOLATED)
    assert "joint 'a' is at 0.55 rad, 0.05 rad from 0.5 rad: above goal_tolerance 0.02" in text
