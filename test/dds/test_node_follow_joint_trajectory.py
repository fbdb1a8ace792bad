"""
``~/follow_joint_trajectory`` over DDS: the calls MoveIt's controller handle makes.

The generator runs as a subprocess; this process is the action client (send, status and
result, cancel, a continuation goal while one runs) and reads ``joint_states``.
"""

import subprocess
import sys
import time

from action_msgs.msg import GoalStatus
from node_harness import (
    action_session,
    action_types,
    end_process,
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    node_env,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
from traj_gen_ros import cubic_via, quintic_via
from trajectory_msgs.msg import MultiDOFJointTrajectoryPoint

FollowJointTrajectory, JointTolerance = action_types()

RATE = 100.0
ACTION = '/trajectory_generator/follow_joint_trajectory'
Result = FollowJointTrajectory.Result


@pytest.fixture(scope='module')
def session():
    with action_session() as session:
        yield session


@pytest.fixture
def rest(session):
    probe, _ = session
    probe.require_parameters(profile='quintic', via_velocities='heuristic')
    return probe.wait_at_rest(timeout=20)


def send(session, points, names=JOINTS, **goal_fields):
    """Send a goal of ``[(positions, time, velocities?, accelerations?)]``; its handle."""
    probe, client = session
    goal = FollowJointTrajectory.Goal(trajectory=via_message(names, points), **goal_fields)
    future = client.send_goal_async(goal)
    probe.spin_until(future.done, 10.0, 'the goal response')
    handle = future.result()
    assert handle.accepted  # every goal is accepted; a refused one is aborted at once
    return handle


def result(session, handle, timeout=20.0):
    """Wait for the result: ``(status, error_code, error_string)``."""
    probe, _ = session
    future = handle.get_result_async()
    probe.spin_until(future.done, timeout, 'the result')
    response = future.result()
    return response.status, response.result.error_code, response.result.error_string


def started(probe, count, timeout=10.0):
    """Wait for the ``count``-th ``~/trajectory`` (the plan spliced in) and return it."""
    probe.spin_until(lambda: len(probe.trajectories) > count, timeout, 'the plan')
    return probe.trajectories[-1]


def assert_continuous(probe, start_ns, end_ns=None):
    """No position or velocity jump between consecutive setpoints (within the limits)."""
    times, positions, velocities = probe.states_between(start_ns, end_ns)
    assert len(times) > 5
    steps = np.diff(times)[:, None]
    assert np.all(steps > 0) and steps.max() < 0.2  # the stream never stopped
    assert (np.abs(np.diff(positions, axis=0)) - MAX_VELOCITY * steps * 1.001).max() <= 1e-9
    assert (np.abs(np.diff(velocities, axis=0)) - MAX_ACCELERATION * steps * 1.001
            ).max() <= 1e-9
    assert np.isfinite(positions).all() and np.isfinite(velocities).all()


def test_goal_with_all_three_is_the_quintic_through_its_points(session, rest):
    probe, _ = session
    q = np.array([rest, rest + [0.3, -0.2, 0.1, 0, 0, 0.2], rest + [0.5, -0.3, 0.2, 0, 0, 0]])
    v = np.array([np.zeros(6), [0.3, -0.15, 0.1, 0, 0, 0], np.zeros(6)])
    a = np.array([np.zeros(6), [0.05, 0.1, 0, 0, 0, -0.2], np.zeros(6)])
    count = len(probe.trajectories)
    sent = time.monotonic()
    handle = send(session, [(q[i], float(i), v[i], a[i]) for i in range(3)])
    status, code, text = result(session, handle)
    assert time.monotonic() - sent < 1.1 * 2.0 + 0.5  # before MoveIt's timeout
    assert (status, code, text) == (GoalStatus.STATUS_SUCCEEDED, Result.SUCCESSFUL, '')
    plan = probe.trajectories[-1]
    assert len(probe.trajectories) == count + 1
    start = stamp_ns(plan.header.stamp)
    expected = quintic_via(q, [1.0, 1.0], v, a)
    times, positions, _, _ = trajectory_arrays(plan)
    assert times[-1] == pytest.approx(2.0, abs=1e-9)
    assert np.allclose(positions, expected.sample(times)[0], atol=1e-9)
    final = probe.wait_at_rest()
    assert np.allclose(final, q[-1], atol=1e-12)
    stream_t, stream_q, _ = probe.states_between(start, start + int(2e9), rate_hz=RATE)
    assert len(stream_t) > 150
    assert np.allclose(stream_q, expected.sample(stream_t)[0], atol=1e-9)
    assert_continuous(probe, start - int(0.1e9))


def test_subset_in_another_order_cubic_and_positions_only(session, rest):
    probe, _ = session
    names = ['joint_5', 'joint_2']
    q = np.array([[rest[4], rest[1]], [rest[4] - 0.2, rest[1] + 0.3],
                  [rest[4] - 0.3, rest[1] + 0.4]])
    v = np.array([[0, 0], [-0.1, 0.2], [0, 0]])
    for given in (True, False):
        expected = cubic_via(q, [0.8, 0.8], v) if given else quintic_via(q, [0.8, 0.8])
        count = len(probe.trajectories)
        points = [(q[i], 0.8 * i, v[i]) if given else (q[i], 0.8 * i) for i in range(3)]
        handle = send(session, points, names)
        assert result(session, handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, Result.SUCCESSFUL)
        plan = started(probe, count)
        times, positions, _, _ = trajectory_arrays(plan)
        assert np.allclose(positions[:, [4, 1]], expected.sample(times)[0], atol=1e-9)
        others = [0, 2, 3, 5]
        assert np.allclose(positions[:, others], rest[others], atol=0)  # the others hold
        assert np.allclose(probe.wait_at_rest()[[4, 1]], q[-1], atol=1e-12)
        q, v = q[::-1].copy(), -v[::-1]  # back again


def test_three_percent_over_the_velocity_limit_is_slowed_by_exactly_that(session, rest):
    probe, _ = session
    # A cubic rest to rest peaks at 1.5 distance / T: 1.03 x max_velocity for joint_1.
    distance = 1.03 * MAX_VELOCITY[0] * 3.0 / 1.5
    target = rest.copy()
    target[0] += distance
    count = len(probe.trajectories)
    handle = send(session, [(rest, 0.0, np.zeros(6)), (target, 3.0, np.zeros(6))])
    status, code, text = result(session, handle)
    assert (status, code) == (GoalStatus.STATUS_SUCCEEDED, Result.SUCCESSFUL)
    assert "slowed by a factor of 1.03 (joint 'joint_1' velocity 2.06 rad/s above " \
        'max_velocity 2 rad/s)' in text
    times, positions, velocities, _ = trajectory_arrays(started(probe, count))
    assert times[-1] == pytest.approx(3.0 * 1.03, abs=1e-9)
    assert np.abs(velocities[:, 0]).max() <= MAX_VELOCITY[0] * (1 + 1e-9)
    assert np.allclose(probe.wait_at_rest(), target, atol=1e-12)


def refusal_cases(rest):
    far = rest + 1.0
    return {
        'unknown': (Result.INVALID_JOINTS, "names unknown joint 'elbow'",
                    {'names': ['elbow'], 'points': [([0.1], 1.0)]}),
        'duplicate': (Result.INVALID_JOINTS, "names joint 'joint_1' more than once",
                      {'names': ['joint_1', 'joint_1'], 'points': [([0.1, 0.1], 1.0)]}),
        'no points': (Result.INVALID_GOAL, 'has no points', {'points': []}),
        'nan': (Result.INVALID_GOAL, "point 1 position for joint 'joint_3' is nan",
                {'points': [(rest, 0.0), (np.where(np.arange(6) == 2, np.nan, rest), 1.0)]}),
        'times': (Result.INVALID_GOAL, 'point 2 (1 s) is not after point 1 (1 s)',
                  {'points': [(rest, 0.0), (far, 1.0), (rest, 1.0)]}),
        'lengths': (Result.INVALID_GOAL, 'point 1 has 5 positions but joint_names has 6',
                    {'points': [(rest, 0.0), (far[:5], 1.0)]}),
        'start': (Result.INVALID_GOAL, "point 0 (time_from_start 0) has joint 'joint_1' at "
                  f'{far[0]:.6g} rad, 1 rad from where the arm is',
                  {'points': [(far, 0.0), (rest, 1.0)]}),
        'infeasible': (Result.INVALID_GOAL, 'above the limit of 3600 s',
                       {'points': [(rest, 0.0), (rest + 1e6, 1.0)]}),
        'tolerance': (Result.INVALID_JOINTS, "goal_tolerance names unknown joint 'z'",
                      {'points': [(far, 1.0)], 'goal_tolerance': [JointTolerance(name='z')]}),
    }


def test_every_refusal_aborts_at_once_with_its_code_and_changes_nothing(session, rest):
    probe, _ = session
    for case, (code, text, fields) in refusal_cases(rest).items():
        count = len(probe.trajectories)
        points = [(np.asarray(q, dtype=float), t) for q, t in fields.pop('points')]
        handle = send(session, points, fields.pop('names', JOINTS), **fields)
        status, error_code, error_string = result(session, handle, 5.0)
        assert (status, error_code) == (GoalStatus.STATUS_ABORTED, code), (case, error_string)
        assert text in error_string, (case, error_string)
        assert len(probe.trajectories) == count, case  # nothing spliced in
    assert np.allclose(probe.wait_at_rest(), rest, atol=0)


def test_old_header_timestamp_and_multi_dof(session, rest):
    probe, client = session
    message = via_message(JOINTS, [(rest + 0.1, 0.5)])
    message.header.stamp.sec = 1000  # 1970: long past
    future = client.send_goal_async(FollowJointTrajectory.Goal(trajectory=message))
    probe.spin_until(future.done, 10.0, 'the goal response')
    status, code, text = result(session, future.result())
    assert (status, code) == (GoalStatus.STATUS_ABORTED, Result.OLD_HEADER_TIMESTAMP), text
    assert 'in the past' in text
    goal = FollowJointTrajectory.Goal(trajectory=via_message(JOINTS, [(rest + 0.1, 0.5)]))
    goal.multi_dof_trajectory.points.append(MultiDOFJointTrajectoryPoint())
    future = client.send_goal_async(goal)
    probe.spin_until(future.done, 10.0, 'the goal response')
    status, code, text = result(session, future.result())
    assert (status, code) == (GoalStatus.STATUS_ABORTED, Result.INVALID_GOAL)
    assert 'multi_dof_trajectory' in text


def running(session, rest, after):
    """Send a 3 s goal and wait until ``after`` s into it; its handle, points and start."""
    probe, _ = session
    points = [(rest, 0.0), (rest + np.array([1.0, -1.0, 0.8, 1.2, -1.2, 1.0]), 3.0)]
    count = len(probe.trajectories)
    handle = send(session, points)
    start = stamp_ns(started(probe, count).header.stamp)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > start + int(after * 1e9),
                     10.0, 'the motion under way')
    return handle, points, start


def test_cancel_brakes_to_rest_then_canceled(session, rest):
    probe, _ = session
    handle, points, start = running(session, rest, 1.2)
    assert np.abs(probe.latest().velocity).max() > 0.3
    future = handle.cancel_goal_async()
    probe.spin_until(future.done, 10.0, 'the cancel response')
    assert len(future.result().goals_canceling) == 1
    status, code, text = result(session, handle)
    arrived_ns = time.time_ns()  # the node's clock is the wall clock here
    assert status == GoalStatus.STATUS_CANCELED, text
    assert 'braked to rest' in text
    at_rest = probe.wait_at_rest()
    # CANCELED is sent only after the first setpoint at rest is: that setpoint was stamped
    # before the answer arrived (the two travel on different topics, so they may arrive in
    # either order), and nothing stamped after the answer moves.
    first_rest = next(s for s in probe.states
                      if stamp_ns(s.header.stamp) > start and not any(s.velocity))
    assert stamp_ns(first_rest.header.stamp) < arrived_ns
    assert not any(any(s.velocity) for s in probe.states
                   if stamp_ns(s.header.stamp) >= arrived_ns)
    assert not np.allclose(at_rest, points[-1][0])  # it did not go on to the end
    assert_continuous(probe, start)


def test_continuation_goal_replaces_the_running_one_without_a_jump(session, rest):
    probe, _ = session
    first, _, start = running(session, rest, 1.0)
    target = rest + 0.3
    second = send(session, [(target, 1.5)])  # first point later than 0: the setpoint first
    status, code, text = result(session, first)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, Result.INVALID_GOAL)
    assert 'replaced by a newer follow_joint_trajectory goal' in text
    assert result(session, second)[:2] == (GoalStatus.STATUS_SUCCEEDED, Result.SUCCESSFUL)
    assert np.allclose(probe.wait_at_rest(), target, atol=1e-12)
    assert_continuous(probe, start)


@pytest.mark.parametrize('other', ['goal', 'stop'])
def test_goal_or_stop_preempts_an_action_goal(session, rest, other):
    probe, _ = session
    handle, _, start = running(session, rest, 0.8)
    if other == 'goal':
        assert probe.goal({'joint_1': float(rest[0])})[0].level == b'\x00'
    else:
        assert probe.stop().success
    status, code, text = result(session, handle)
    assert status == GoalStatus.STATUS_ABORTED
    assert f'replaced by a ~/{other}' in text, text
    then = 'the arm brakes to rest' if other == 'stop' else 'its motion continues'
    assert then in text, text
    probe.wait_at_rest()
    assert_continuous(probe, start)


def test_points_with_effort_are_refused_the_node_commands_positions(session, rest):
    """As JTC without an effort command interface: INVALID_GOAL, and ~/via_points alike."""
    probe, client = session
    count = len(probe.trajectories)
    message = via_message(JOINTS, [(rest, 0.0), (rest + 0.2, 1.0)])
    message.points[1].effort = [1.0] * len(JOINTS)
    future = client.send_goal_async(FollowJointTrajectory.Goal(trajectory=message))
    probe.spin_until(future.done, 10.0, 'the goal response')
    status, code, text = result(session, future.result())
    assert (status, code) == (GoalStatus.STATUS_ABORTED, Result.INVALID_GOAL), text
    assert text == ('the goal point 1 has 6 effort values: this node commands positions '
                    'only (no effort command interface); leave effort empty')
    answer, _ = probe.request(message)
    assert answer.level == b'\x02'
    assert answer.message == ('via_points refused: via_points point 1 has 6 effort values: '
                              'this node commands positions only (no effort command '
                              'interface); leave effort empty')
    assert len(probe.trajectories) == count  # nothing spliced in
    assert np.array_equal(probe.wait_at_rest(), rest)


def test_feedback_at_a_steady_rate(session, rest):
    probe, _ = session
    feedback = []
    goal = FollowJointTrajectory.Goal(trajectory=via_message(['joint_3'], [([rest[2] + 0.4],
                                                                            1.0)]))
    future = session[1].send_goal_async(goal, feedback_callback=feedback.append)
    probe.spin_until(future.done, 10.0, 'the goal response')
    assert result(session, future.result())[0] == GoalStatus.STATUS_SUCCEEDED
    assert len(feedback) >= 30  # 50 Hz over 1 s, on a busy machine
    last = feedback[-1].feedback
    assert list(last.joint_names) == ['joint_3']
    assert list(last.error.positions) == [0.0]  # no measured state: actual = desired
    stamps = np.array([stamp_ns(f.feedback.header.stamp) for f in feedback]) * 1e-9
    assert np.median(np.diff(stamps)) == pytest.approx(0.02, abs=0.005)


CLIENT = """
import os, sys, rclpy
from rclpy.action import ActionClient
from control_msgs.action import FollowJointTrajectory
from trajectory_msgs.msg import JointTrajectoryPoint
rclpy.init()
node = rclpy.create_node('dying_client')
client = ActionClient(node, FollowJointTrajectory, sys.argv[1])
client.wait_for_server(timeout_sec=20)
goal = FollowJointTrajectory.Goal()
goal.trajectory.joint_names = ['joint_1']
goal.trajectory.points = [JointTrajectoryPoint(positions=[float(sys.argv[2])])]
goal.trajectory.points[0].time_from_start.sec = 1
future = client.send_goal_async(goal)
rclpy.spin_until_future_complete(node, future, timeout_sec=20)
print('accepted', future.result().accepted, flush=True)
os._exit(0)  # dies mid-goal, without a word
"""


def test_a_client_that_dies_mid_goal(session, rest):
    probe, _ = session
    count = len(probe.trajectories)
    target = float(rest[0] + 0.5)
    process = subprocess.Popen([sys.executable, '-c', CLIENT, ACTION, str(target)],
                               env=node_env(), stdout=subprocess.PIPE, text=True)
    try:
        assert process.wait(30) == 0
        assert 'accepted True' in process.stdout.read()
    finally:
        end_process(process)
    start = stamp_ns(started(probe, count).header.stamp)
    final = probe.wait_at_rest(timeout=10)
    assert final[0] == pytest.approx(target, abs=1e-12)
    assert_continuous(probe, start)


def test_a_burst_of_goals_and_cancels(session, rest):
    probe, client = session
    begin = stamp_ns(probe.latest().header.stamp)
    handles = []
    rng = np.random.default_rng(22)
    for index in range(20):
        target = rest + rng.uniform(-0.3, 0.3, 6)
        goal = FollowJointTrajectory.Goal(trajectory=via_message(JOINTS, [(target, 1.0)]))
        future = client.send_goal_async(goal)
        probe.spin_until(future.done, 10.0, 'the goal response')
        handles.append(future.result())
        if index % 3 == 1 and index < 19:
            handles[-1].cancel_goal_async()
        until = time.monotonic() + 0.01  # goals 10 ms apart, the client spinning between
        probe.spin_until(lambda until=until: time.monotonic() > until, 1.0)
    statuses = [result(session, handle)[0] for handle in handles]
    assert all(s in (GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED,
                     GoalStatus.STATUS_CANCELED) for s in statuses)
    assert statuses[-1] == GoalStatus.STATUS_SUCCEEDED
    probe.wait_at_rest()
    assert_continuous(probe, begin)


def test_a_goal_slowed_by_speed_scaling_runs_twice_as_long_and_succeeds(session, rest):
    probe, _ = session
    q = np.array([rest, rest + [0.2, 0, 0, 0, 0, -0.1]])
    probe.require_parameters(speed_scaling=0.5)
    try:
        count = len(probe.trajectories)
        handle = send(session, [(q[0], 0.0), (q[1], 1.0)])
        status, code, text = result(session, handle, timeout=30.0)
        assert (status, code, text) == (GoalStatus.STATUS_SUCCEEDED, Result.SUCCESSFUL, '')
        plan = started(probe, count)
        start = stamp_ns(plan.header.stamp)
        assert seconds_of_plan(plan) == pytest.approx(1.0, abs=1e-9)  # ~/trajectory: unscaled
        final = probe.wait_at_rest(timeout=10)
        assert np.allclose(final, q[1], atol=1e-12)
        times, positions, _ = probe.states_between(start, start + int(4e9), rate_hz=RATE)
        arrived = times[np.flatnonzero(np.abs(positions[:, 0] - q[1, 0]) <= 1e-9)[0]]
        assert arrived == pytest.approx(2.0, abs=0.05)  # the plan at f = 0.5
        assert_continuous(probe, start)
    finally:
        probe.require_parameters(speed_scaling=1.0)


def seconds_of_plan(plan) -> float:
    last = plan.points[-1].time_from_start
    return last.sec + last.nanosec * 1e-9
