"""
The speed override over DDS (issue 23): the node as a subprocess, factors from this process.

Profile ``lspb`` with ``max_velocity`` 1 rad/s and ``max_acceleration`` 2 rad/s² for every
joint, and a goal of ``joint_1`` 0 → 2 rad: 2.5 s, cruising at 1 rad/s from 0.5 s to 2 s
(plan time). A factor asked for in the cruise ramps at ``ḟ = σ a_max / v = 1.9`` /s
(``σ = 0.95``): 1 → 0.5 takes 0.263 s, 1 → 0 0.526 s. Every joint_states sample is stamped
with the time it was sampled at, so finite differences of its velocities are the
commanded accelerations whatever the jitter of the stamps.
"""

import math
import subprocess
import sys

from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import action_types, end_process, node_env, running_node, stamp_ns, via_message
import numpy as np
import pytest
from rclpy.action import ActionClient
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from speed_probe import GOAL, speed_session, SpeedProbe, SpeedScalingFactor

FollowJointTrajectory, _ = action_types()  # skips this module without control_msgs
A_MAX = 2.0
RATE = 1.9  # σ a_max / v (1/s)
ARGS = ('-p', 'profile:=lspb', '-p', 'max_velocity:=[1.0]', '-p', 'max_acceleration:=[2.0]',
        '-p', 'rate_hz:=100.0')
#: Finite differences: stamps are the sample times; a ramp's knot may fall between two.
ACCELERATION_TOLERANCE = 0.02 * A_MAX


def assert_within_limits(times, velocities):
    """No velocity step beyond a_max × Δt: the finite-difference acceleration is in limits."""
    acceleration = np.diff(velocities) / np.diff(times)
    assert np.max(np.abs(acceleration)) <= A_MAX + ACCELERATION_TOLERANCE, \
        np.max(np.abs(acceleration))
    assert np.all(np.isfinite(velocities))


@pytest.fixture(name='probe')
def session():
    with speed_session(*ARGS) as probe:
        yield probe


def test_half_speed_mid_motion_stretches_the_remaining_time_by_two_less_the_ramp(probe):
    start_ns = probe.start_goal()
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > start_ns + 1.0e9, 5.0,
                     '1 s into the motion')
    first = probe.factor(0.5)
    probe.wait_velocity(lambda v: abs(v - 0.5) < 1e-9, 'half speed')
    probe.wait_at_rest(10.0)
    times, positions, velocities = probe.samples(first - 1)
    assert positions[-1] == pytest.approx(GOAL, abs=1e-9)
    slowing = int(np.argmax(velocities < 1.0 - 1e-9))  # the first sample of the ramp
    # Where the ramp began (between two samples): the plan time left, R = 2.5 - elapsed.
    begun = times[slowing] - (1.0 - velocities[slowing]) / RATE
    remaining = 2.5 - (begun - start_ns * 1e-9)
    ended = times[int(np.argmax(velocities == 0.0))]
    # 0.5 s of ramp at 1.9 /s: 0.263 s, 0.75 of its time advances the plan, so the rest
    # takes 2 R - 0.5 · 0.263 s.
    assert ended - begun == pytest.approx(2.0 * remaining - 0.5 * (0.5 / RATE), abs=0.015)
    assert_within_limits(times, velocities)


def test_zero_holds_still_then_one_resumes_and_reaches_the_goal(probe):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
    first = probe.factor(0.0)
    paused = probe.wait_velocity(lambda v: v == 0.0, 'the pause')
    probe.spin_until(lambda: len(probe.states) > paused + 50, 5.0, '0.5 s of pause')
    held = {tuple(s.position) for s in probe.states[paused:paused + 50]}
    assert len(held) == 1 and 0.0 < next(iter(held))[0] < GOAL
    probe.factor(1.0)
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise again')
    assert probe.wait_at_rest(10.0)[0] == pytest.approx(GOAL, abs=1e-9)
    times, _, velocities = probe.samples(first - 1)
    # From cruise at 1 rad/s to 0 at σ a_max: 1 / 1.9 s (the pause bound of docs/node.md).
    ramp = times[paused - first + 1] - times[int(np.argmax(velocities < 1.0 - 1e-9)) - 1]
    assert ramp == pytest.approx(1.0 / RATE, abs=0.025)
    assert_within_limits(times, velocities)


def test_a_burst_of_factors_never_steps_velocity_or_acceleration(probe):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
    first = probe.factor(0.0)
    probe.factor(1.0)
    probe.factor(0.3)
    probe.spin_until(lambda: len(probe.states) > first + 30, 5.0, 'the ramps')
    probe.factor(0.0)
    probe.factor(1.0)
    probe.factor(0.0)
    probe.factor(1.0)
    probe.factor(0.3)
    probe.wait_velocity(lambda v: abs(v - 0.3) < 1e-9, 'the factor 0.3')
    probe.wait_at_rest(20.0)
    times, positions, velocities = probe.samples(first - 1)
    assert positions[-1] == pytest.approx(GOAL, abs=1e-9)
    assert_within_limits(times, velocities)


def test_a_goal_while_paused_is_accepted_stays_paused_then_runs(probe):
    probe.factor(0.0)
    probe.speed_values(lambda values: values['speed scaling in force'] == '0')
    probe.start_goal()
    count = len(probe.states)
    probe.spin_until(lambda: len(probe.states) > count + 50, 5.0, '0.5 s')
    assert {s.position[0] for s in probe.states[count:]} == {0.0}
    probe.factor(1.0)
    assert probe.wait_at_rest(10.0)[0] == pytest.approx(GOAL, abs=1e-9)
    times, _, velocities = probe.samples(count)
    assert_within_limits(times, velocities)


@pytest.mark.parametrize('factor', [0.1, 1.0])
def test_stop_brakes_at_full_authority_whatever_the_factor(probe, factor):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
    probe.factor(factor)
    probe.wait_velocity(lambda v: abs(v - factor) < 1e-9, 'the factor')
    first = len(probe.states)
    response = probe.stop()
    assert response.success
    # Braking from f · 1 rad/s at a_max = 2 rad/s², as at full speed.
    assert float(response.message.split()[-2]) == pytest.approx(factor / A_MAX, abs=0.011)
    probe.wait_at_rest(5.0)
    times, _, velocities = probe.samples(first)
    braking = np.diff(velocities) / np.diff(times)
    braking = braking[(velocities[1:] > 0.0) & (velocities[:-1] < factor)]
    # (stamps of ~1.7e9 s as doubles: ~2e-7 s each, 2e-5 of a period)
    assert braking == pytest.approx(-A_MAX, abs=1e-3)


@pytest.mark.parametrize('value', [-0.1, 1.5, math.nan])
def test_invalid_factors_are_refused_as_parameters_and_ignored_on_the_topic(probe, value):
    results = probe.set_parameters(speed_scaling=value)
    assert not results[0].successful
    assert 'speed_scaling' in results[0].reason or 'range' in results[0].reason, \
        results[0].reason
    before = probe.speed_values(lambda values: True)
    ignored = int(before['speed_scaling_input ignored'])
    probe.factor(value)
    after = probe.speed_values(
        lambda values: int(values['speed_scaling_input ignored']) == ignored + 1)
    assert after['speed scaling in force'] == '1'
    assert after['speed_scaling (parameter)'] == '1'


def test_the_parameter_and_the_topic_multiply(probe):
    probe.require_parameters(speed_scaling=0.5)
    probe.factor(0.5)
    values = probe.speed_values(lambda values: values['speed scaling in force'] == '0.25')
    assert values['speed_scaling_input (topic)'] == '0.5'
    probe.factor(1.0)


#: A separate process: publishes a factor (reliable, transient local), says so, spins on.
LATCHED_PUBLISHER = """
import sys
import rclpy
from control_msgs.msg import SpeedScalingFactor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
rclpy.init()
node = rclpy.create_node('latched_factor')
publisher = node.create_publisher(
    SpeedScalingFactor, '/trajectory_generator/speed_scaling_input',
    QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
               durability=DurabilityPolicy.TRANSIENT_LOCAL))
publisher.publish(SpeedScalingFactor(factor=float(sys.argv[1])))
print('published', flush=True)
try:
    rclpy.spin(node)
except KeyboardInterrupt:
    pass
"""


def motion_time(probe, target=GOAL):
    """Send joint_1 to ``target``; return the time (s) from the plan's start to rest."""
    first = len(probe.states)
    status, plan = probe.goal({'joint_1': target})
    assert status.level == DiagnosticStatus.OK, status.message
    probe.wait_at_rest(20.0)
    times, positions, velocities = probe.samples(first)
    assert positions[-1] == pytest.approx(target, abs=1e-9)
    moving = np.flatnonzero(velocities != 0.0)
    return times[moving[-1] + 1] - stamp_ns(plan.header.stamp) * 1e-9  # its start tick


def test_a_latched_factor_published_before_the_node_starts_is_taken():
    publisher = subprocess.Popen([sys.executable, '-c', LATCHED_PUBLISHER, '0.5'],
                                 stdout=subprocess.PIPE, text=True, env=node_env())
    try:
        assert publisher.stdout.readline().strip() == 'published'
        with running_node(*ARGS):
            probe = SpeedProbe()
            try:
                probe.wait_ready()
                values = probe.speed_values(
                    lambda values: values['speed scaling in force'] == '0.5', 20.0)
                assert values['speed_scaling_input (topic)'] == '0.5'
                # LSPB 0 -> 2 rad: 2.5 s planned, 5 s at 0.5 (the ramp was at rest).
                assert motion_time(probe) == pytest.approx(5.0, abs=0.03)
                # A volatile best-effort publisher is taken too.
                volatile = probe.create_publisher(
                    SpeedScalingFactor, '/trajectory_generator/speed_scaling_input',
                    QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT,
                               durability=DurabilityPolicy.VOLATILE))

                def taken():  # best effort: sent again until /diagnostics shows it
                    probe.diagnostics.clear()
                    volatile.publish(SpeedScalingFactor(factor=1.0))
                    return probe.speed_values(lambda values: True, 10.0)[
                        'speed scaling in force'] == '1'
                probe.spin_until(taken, 60.0, 'the best-effort factor')
                assert motion_time(probe, 0.0) == pytest.approx(2.5, abs=0.03)
            finally:
                probe.destroy_node()
    finally:
        end_process(publisher, timeout=20.0)


def later_stamp(probe, seconds):
    """Return the node clock (the last sample's stamp) plus ``seconds``, as a stamp."""
    return Time(nanoseconds=stamp_ns(probe.latest().header.stamp) +
                int(seconds * 1e9)).to_msg()


def test_a_delayed_via_request_a_factor_change_would_make_jump_is_answered_dropped(probe):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
    # Starts 1.5 s from now: the goal still moves there, so slowing it moves that state.
    status, _ = probe.request(via_message(['joint_1'], [([0.5], 3.0)],
                                          later_stamp(probe, 1.5)))
    assert status.level == DiagnosticStatus.OK, status.message
    request_id = {kv.key: kv.value for kv in status.values}['request_id']
    count = len(probe.statuses)
    probe.factor(0.5)
    probe.spin_until(lambda: len(probe.statuses) > count, 10.0, 'the dropped answer')
    dropped = probe.statuses[count]
    assert dropped.level == DiagnosticStatus.ERROR
    assert {kv.key: kv.value for kv in dropped.values}['request_id'] == request_id
    assert 'via_points dropped' in dropped.message and 'resend' in dropped.message
    assert probe.wait_at_rest(20.0)[0] == pytest.approx(GOAL, abs=1e-9)  # the goal's end


def test_a_delayed_action_goal_a_factor_change_would_make_jump_is_aborted(probe):
    client = ActionClient(probe, FollowJointTrajectory,
                          '/trajectory_generator/follow_joint_trajectory')
    try:
        probe.spin_until(client.server_is_ready, 20.0, 'the action server')
        probe.start_goal()
        probe.wait_velocity(lambda v: v >= 1.0 - 1e-9, 'the cruise')
        goal = FollowJointTrajectory.Goal(trajectory=via_message(
            ['joint_1'], [([3.0], 3.0)], later_stamp(probe, 1.5)))
        count = len(probe.statuses)
        future = client.send_goal_async(goal)
        probe.spin_until(future.done, 10.0, 'the goal response')
        handle = future.result()
        assert handle.accepted
        result = handle.get_result_async()
        probe.spin_until(lambda: result.done() or len(probe.statuses) > count, 10.0,
                         'the goal accepted')
        assert not result.done(), result.result().result.error_string
        assert probe.statuses[count].level == DiagnosticStatus.OK, probe.statuses[count].message
        probe.factor(0.5)
        probe.spin_until(result.done, 20.0, 'the result')
        assert result.result().status == GoalStatus.STATUS_ABORTED
        assert 'speed scaling factor changed' in result.result().result.error_string
        probe.spin_until(lambda: any(  # ~/status says so too (it may follow the result)
            s.level == DiagnosticStatus.ERROR and 'follow_joint_trajectory dropped' in s.message
            for s in probe.statuses), 10.0, 'the dropped answer on ~/status')
    finally:
        client.destroy()
