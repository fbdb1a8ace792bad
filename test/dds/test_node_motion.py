"""Integration: the generator as a subprocess, driven over DDS by a second node."""

import time

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    generator_session,
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
import rclpy
from rclpy.time import Time
from traj_gen_ros import lspb_via, min_time

RATE = 100.0


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        yield probe


@pytest.fixture
def rest(probe):
    """Start every test at rest with the default profile."""
    probe.require_parameters(profile='quintic', via_velocities='heuristic', rate_hz=RATE)
    return probe.wait_at_rest()


def status_values(status):
    return {kv.key: kv.value for kv in status.values}


def assert_continuous(probe, start_ns, end_ns=None, dt=1.0 / RATE):
    """No position/velocity jump: increments bounded by the limits over each step."""
    times, positions, velocities = probe.states_between(start_ns, end_ns)
    assert len(times) > 5
    steps = np.diff(times)[:, None]
    assert np.all(steps > 0)
    position_jump = np.abs(np.diff(positions, axis=0)) - MAX_VELOCITY * steps * 1.001 - 1e-9
    velocity_jump = np.abs(np.diff(velocities, axis=0)) - MAX_ACCELERATION * steps * 1.001 - 1e-9
    assert position_jump.max() <= 0, position_jump.max()
    assert velocity_jump.max() <= 0, velocity_jump.max()
    assert np.all(np.abs(velocities) <= MAX_VELOCITY * (1 + 1e-6))
    assert np.isfinite(positions).all() and np.isfinite(velocities).all()


def test_idle_stream_holds_still_at_rate(probe, rest):
    first = len(probe.states)
    probe.spin_until(lambda: len(probe.states) >= first + 30, 5.0, '30 JointStates')
    window = probe.states[first:first + 30]
    stamps = np.array([stamp_ns(s.header.stamp) for s in window]) * 1e-9
    assert np.median(np.diff(stamps)) == pytest.approx(1.0 / RATE, rel=0.05)
    assert all(list(s.name) == JOINTS for s in window)
    assert all(list(s.position) == list(rest) for s in window)
    assert all(not any(s.velocity) for s in window)


def test_goal_moves_named_joints_reaches_and_holds(probe, rest):
    goal = {'joint_5': rest[4] - 0.3, 'joint_2': rest[1] + 0.4}
    sent_ns = time.time_ns()
    status, trajectory = probe.goal(goal)
    assert status.level == DiagnosticStatus.OK, status.message
    assert status.name == '/trajectory_generator'
    values = status_values(status)
    assert values['profile'] == 'quintic' and values['joints'] == '6'
    assert 'accepted: profile=quintic' in status.message

    times, positions, velocities, accelerations = trajectory_arrays(trajectory)
    start_ns = stamp_ns(trajectory.header.stamp)
    # When DDS received the goal (system clock, as the stamps here): after it was sent,
    # before the motion's first setpoint.
    assert sent_ns <= int(values['received']) <= start_ns
    # How long it was planned, and how often: once, unless the stream passed the planned
    # start (a loaded machine); a plan that made its start was ready before it.
    attempts, planning_time = int(values['attempts']), float(values['planning_time'])
    assert 1 <= attempts <= 6 and planning_time > 0.0
    if attempts == 1:
        assert planning_time < (start_ns - int(values['received'])) * 1e-9
    assert list(trajectory.joint_names) == JOINTS
    assert float(values['duration']) == pytest.approx(times[-1], abs=1e-6)
    assert np.allclose(np.diff(times)[:-1], 1.0 / RATE, atol=1e-9)
    expected = rest.copy()
    expected[1], expected[4] = goal['joint_2'], goal['joint_5']
    assert np.allclose(positions[0], rest, atol=1e-12)
    assert np.allclose(positions[-1], expected, atol=1e-12)
    assert np.allclose(velocities[[0, -1]], 0, atol=1e-12)
    assert np.allclose(accelerations[[0, -1]], 0, atol=1e-9)
    # The minimum-time quintic from the limits, computed independently from the core.
    plan = min_time(rest, expected, MAX_VELOCITY, MAX_ACCELERATION, profile='quintic')
    assert times[-1] == pytest.approx(plan.duration, rel=1e-9)
    assert np.allclose(positions, plan.sample(times)[0], atol=1e-9)

    final = probe.wait_at_rest(timeout=plan.duration + 5)
    assert np.allclose(final, expected, atol=1e-12)
    stream_t, stream_q, _ = probe.states_between(start_ns, rate_hz=RATE)
    moving = stream_t <= plan.duration
    assert moving.sum() >= int(plan.duration * RATE * 0.8)
    assert np.allclose(stream_q[moving], plan.sample(stream_t[moving])[0], atol=1e-9)
    assert_continuous(probe, start_ns - int(0.1e9))


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_via_points_pass_through_at_their_times(probe, rest, profile):
    probe.require_parameters(profile=profile)
    targets = [rest + offset for offset in (0.1, 0.25, 0.15)]
    times = [0.5, 1.0, 1.5]
    names = JOINTS[::-1]  # any order
    message = via_message(names, [(q[::-1], t) for q, t in zip(targets, times, strict=True)])
    status, trajectory = probe.request(message)
    assert status.level == DiagnosticStatus.OK, status.message
    assert status_values(status)['profile'] == profile
    sample_t, positions, velocities, _ = trajectory_arrays(trajectory)
    assert sample_t[-1] == pytest.approx(1.5, abs=1e-9)
    for target, t in zip(targets, times, strict=True):
        index = int(np.argmin(np.abs(sample_t - t)))
        assert sample_t[index] == pytest.approx(t, abs=1e-9)
        assert np.allclose(positions[index], target, atol=1e-9)
    assert np.allclose(velocities[-1], 0, atol=1e-9)
    start_ns = stamp_ns(trajectory.header.stamp)
    probe.wait_at_rest(timeout=5)
    stream_t, stream_q, _ = probe.states_between(start_ns, rate_hz=RATE)
    for target, t in zip(targets, times, strict=True):  # the stream, within one period
        index = int(np.argmin(np.abs(stream_t - t)))
        assert abs(stream_t[index] - t) <= 1.0 / RATE
        assert np.allclose(stream_q[index], target, atol=MAX_VELOCITY.max() / RATE)
    assert np.allclose(probe.position(), targets[-1], atol=1e-12)


def test_lspb_via_points_match_core_lspb_via(probe, rest):
    probe.require_parameters(profile='lspb')
    targets = [rest + np.linspace(0.1, 0.3, 6), rest - 0.2]
    message = via_message(JOINTS, [(targets[0], 0.8), (targets[1], 1.6)])
    status, trajectory = probe.request(message)
    assert status.level == DiagnosticStatus.OK, status.message
    sample_t, positions, velocities, accelerations = trajectory_arrays(trajectory)
    expected = lspb_via(np.vstack([rest, targets]), [0.8, 0.8], MAX_ACCELERATION)
    exp_q, exp_v, exp_a = expected.sample(sample_t)
    assert np.allclose(positions, exp_q, atol=1e-9)
    assert np.allclose(velocities, exp_v, atol=1e-9)
    # The last point is the end at rest: LSPB's blend acceleration stops there.
    assert np.allclose(accelerations[:-1], exp_a[:-1], atol=1e-9)
    assert np.allclose(accelerations[-1], 0) and np.allclose(exp_a[-1], MAX_ACCELERATION)
    assert np.allclose(positions[-1], targets[-1], atol=1e-9)
    probe.wait_at_rest(timeout=5)


@pytest.mark.parametrize('profile', ['cubic', 'quintic', 'lspb'])
def test_profile_parameter_selects_the_minimum_time_profile(probe, rest, profile):
    probe.require_parameters(profile=profile)
    target = rest + np.array([0.5, -0.25, 0.1, 0.0, 0.3, -0.6])
    status, trajectory = probe.goal(dict(zip(JOINTS, target, strict=True)))
    assert status.level == DiagnosticStatus.OK, status.message
    assert status_values(status)['profile'] == profile
    sample_t, positions, velocities, accelerations = trajectory_arrays(trajectory)
    plan = min_time(rest, target, MAX_VELOCITY, MAX_ACCELERATION, profile=profile)
    assert sample_t[-1] == pytest.approx(plan.duration, rel=1e-9)
    exp_q, exp_v, exp_a = plan.sample(sample_t)
    assert np.allclose(positions, exp_q, atol=1e-9)
    assert np.allclose(velocities, exp_v, atol=1e-9)
    assert np.all(np.abs(accelerations) <= MAX_ACCELERATION * (1 + 1e-6))
    probe.wait_at_rest(timeout=plan.duration + 5)
    assert np.allclose(probe.position(), target, atol=1e-12)


@pytest.mark.parametrize('profile', ['cubic', 'quintic', 'lspb'])
def test_preemption_mid_motion_is_continuous(probe, rest, profile):
    probe.require_parameters(profile=profile)
    _, first = probe.goal({'joint_1': rest[0] + 1.5, 'joint_4': rest[3] - 1.0})
    first_start = stamp_ns(first.header.stamp)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > first_start + 0.4e9,
                     5.0, 'mid-motion')
    moving = np.array(probe.latest().velocity)
    assert abs(moving[0]) > 0.5
    status, second = probe.goal({'joint_1': rest[0] - 0.2})
    assert status.level == DiagnosticStatus.OK, status.message
    second_start = stamp_ns(second.header.stamp)
    _, q2, v2, a2 = trajectory_arrays(second)
    # The new plan starts exactly at the old plan's setpoint at the switch time.
    old_t, old_q, old_v, old_a = trajectory_arrays(first)
    offset = (probe.stream_ns(second_start, RATE) - probe.stream_ns(first_start, RATE)) * 1e-9
    assert np.allclose(q2[0], [np.interp(offset, old_t, old_q[:, j]) for j in range(6)],
                       atol=2e-4)
    assert np.allclose(v2[0], [np.interp(offset, old_t, old_v[:, j]) for j in range(6)],
                       atol=5e-3)
    if profile == 'quintic':
        assert np.allclose(a2[0], [np.interp(offset, old_t, old_a[:, j]) for j in range(6)],
                           atol=0.1)
    assert abs(v2[0][0]) > 0.5  # it really was moving when replaced
    probe.wait_at_rest(timeout=10)
    assert probe.position()[0] == pytest.approx(rest[0] - 0.2, abs=1e-12)
    # joint_4 was not named: it keeps the target it was moving to.
    assert probe.position()[3] == pytest.approx(rest[3] - 1.0, abs=1e-12)
    assert_continuous(probe, first_start - int(0.05e9))


def test_stop_brakes_within_max_acceleration_and_holds(probe, rest):
    _, first = probe.goal({'joint_1': rest[0] + 2.0, 'joint_6': rest[5] - 2.0})
    first_start = stamp_ns(first.header.stamp)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > first_start + 0.5e9,
                     5.0, 'mid-motion')
    count = len(probe.trajectories)
    response = probe.stop()
    assert response.success, response.message
    probe.spin_until(lambda: len(probe.trajectories) > count, 5.0, 'the stop trajectory')
    stop_plan = probe.trajectories[-1]
    stop_start = stamp_ns(stop_plan.header.stamp)
    t, q, v, a = trajectory_arrays(stop_plan)
    assert np.all(np.abs(a) <= MAX_ACCELERATION * (1 + 1e-9))
    assert abs(v[0][0]) > 0.5 and np.allclose(v[-1], 0)
    assert t[-1] <= np.max(np.abs(v[0]) / MAX_ACCELERATION) + 1e-9
    final = probe.wait_at_rest(timeout=5)
    assert final[0] < rest[0] + 2.0 - 0.1  # stopped short of the goal
    assert np.allclose(final, q[-1], atol=1e-12)
    times, _, velocities = probe.states_between(stop_start)
    decel = np.abs(np.diff(velocities, axis=0)) / np.diff(times)[:, None]
    assert np.all(decel <= MAX_ACCELERATION * 1.001)
    assert_continuous(probe, first_start)


def test_delayed_start_from_header_stamp(probe, rest):
    now = probe.get_clock().now()
    start = now + rclpy.duration.Duration(seconds=0.6)
    message = via_message(['joint_3'], [([rest[2] + 0.15], 0.5)], stamp=start.to_msg())
    status, trajectory = probe.request(message)
    assert status.level == DiagnosticStatus.OK, status.message
    assert 'starts in' in status.message
    assert stamp_ns(trajectory.header.stamp) == start.nanoseconds
    # Until the start the stream holds; then it moves and arrives at the point.
    probe.spin_until(lambda: Time.from_msg(probe.latest().header.stamp) > start, 5.0,
                     'the delayed start')
    before_t, before_q, _ = probe.states_between(now.nanoseconds, start.nanoseconds - 1)
    assert len(before_t) > 20 and np.allclose(before_q, rest, atol=0)
    final = probe.wait_at_rest(timeout=5)
    assert final[2] == pytest.approx(rest[2] + 0.15, abs=1e-12)
