"""
``~/follow_joint_trajectory`` beside a robot: the action against the measured state.

Three processes over DDS: the generator (``joint_topic`` and ``command_out_topic`` set), the
stand-in robot (test/support/standin_robot.py: follows the ``Float64MultiArray`` commands with a
lag,
publishes its measured ``joint_states``; here also offset, frozen mid-motion or silent),
and this one, the action client as MoveIt's controller handle uses it (send, result by
status and error code, feedback), which also reads the setpoint and the robot's state.
"""

import contextlib
from pathlib import Path
import re
import subprocess
import sys
import time

from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from node_harness import (
    action_types,
    end_process,
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    node_env,
    Probe,
    running_node,
    seconds,
    stamp_gaps,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

FollowJointTrajectory, JointTolerance = action_types()

ROBOT = Path(__file__).resolve().parents[1] / 'support' / 'standin_robot.py'
TOPIC = '/robot/joint_states'
ACTION = '/trajectory_generator/follow_joint_trajectory'
Result = FollowJointTrajectory.Result
ABORTED, SUCCEEDED = GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_SUCCEEDED


class ArmProbe(Probe):
    """A Probe that is also the action client and records the robot's state and commands."""

    def __init__(self):
        super().__init__()
        self.measured, self.measured_times, self.commands = [], [], []
        self.create_subscription(JointState, TOPIC, self._on_measured,
                                 QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT))
        self.create_subscription(Float64MultiArray, '/robot/commands', self.commands.append,
                                 1000)
        self.freeze = self.create_publisher(Float64MultiArray, '/robot/freeze', 10)
        self.pause = self.create_publisher(Float64MultiArray, '/robot/pause', 10)
        self.client = ActionClient(self, FollowJointTrajectory, ACTION)

    def _on_measured(self, message):
        by_name = dict(zip(message.name, message.position, strict=True))
        self.measured.append(np.array([by_name[name] for name in JOINTS]))
        self.measured_times.append(time.monotonic())

    def arm(self):
        """Where the robot says it is (the latest measured positions, in JOINTS order)."""
        return self.measured[-1].copy()

    def settled(self, timeout=15.0):
        """Wait until the node holds still and the arm with it (ten equal measurements)."""
        self.wait_at_rest(timeout)
        self.spin_until(lambda: len(self.measured) > 10 and np.ptp(
            np.array(self.measured[-10:]), axis=0).max() < 1e-12, timeout, 'the arm at rest')
        return self.position(), self.arm()

    def when_setpoint(self, joint, beyond, timeout=15.0):
        """Wait until the setpoint of joint index ``joint`` is past ``beyond`` (rad)."""
        self.spin_until(lambda: self.states and self.states[-1].position[joint] > beyond,
                        timeout, f'the setpoint of {JOINTS[joint]} past {beyond}')

    def send(self, points, names=JOINTS, feedback=None, **fields):
        """Send a goal of ``[(positions, time), ...]``; return its accepted handle."""
        goal = FollowJointTrajectory.Goal(trajectory=via_message(names, points), **fields)
        future = self.client.send_goal_async(goal, feedback_callback=feedback)
        self.spin_until(future.done, 10.0, 'the goal response')
        handle = future.result()
        assert handle.accepted  # every goal is accepted; a refused one is aborted at once
        return handle

    def result(self, handle, timeout=20.0):
        """Wait for the result: ``(status, error_code, error_string, arrival (time.time_ns))``."""
        future = handle.get_result_async()
        self.spin_until(future.done, timeout, 'the result')
        arrival = time.time_ns()
        response = future.result()
        return response.status, response.result.error_code, response.result.error_string, \
            arrival


@contextlib.contextmanager
def session(*ros_args, robot=()):
    """Run the node on the stand-in robot (started with ``robot`` args); yield an ArmProbe."""
    with running_node('-p', f'joint_topic:={TOPIC}', '-p', 'command_out_topic:=/robot/commands',
                      *ros_args) as node:
        robot_process = subprocess.Popen([sys.executable, str(ROBOT), *robot], env=node_env(),
                                         stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        probe = ArmProbe()
        try:
            probe.wait_ready(30.0)
            probe.spin_until(lambda: probe.client.server_is_ready() and probe.measured
                             and probe.freeze.get_subscription_count()
                             and probe.pause.get_subscription_count(), 30.0,
                             'the action and the robot')
            yield probe, node
        finally:
            probe.client.destroy()
            probe.destroy_node()
            end_process(robot_process)


def plan_end_ns(probe):
    """End of the last plan spliced in (``~/trajectory``), node clock (ns)."""
    plan = probe.trajectories[-1]
    return stamp_ns(plan.header.stamp) + int(round(trajectory_arrays(plan)[0][-1] * 1e9))


def moveit_timeout_ns(duration):
    """Return MoveIt's execution timeout for a goal of ``duration`` s (its default scaling)."""
    return int((1.1 * duration + 0.5) * 1e9)


def assert_within_limits(probe, start_ns=0):
    """Check the setpoint never jumps (position, velocity steps within the limits), streams."""
    times, positions, velocities = probe.states_between(start_ns)
    steps = np.diff(times)[:, None]
    assert len(times) > 10 and np.all(steps > 0) and steps.max() < 0.2
    assert (np.abs(np.diff(positions, axis=0)) - MAX_VELOCITY * steps * 1.001).max() <= 1e-9
    assert (np.abs(np.diff(velocities, axis=0)) - MAX_ACCELERATION * steps * 1.001
            ).max() <= 1e-9


OFFSET = np.array([0.0, 0.03, -0.02, 0.0, 0.0, 0.0])  # within state_tolerance (0.05)


def test_start_is_checked_against_the_measured_position_and_feedback_is_measured():
    with session(robot=['--offset', ','.join(map(str, OFFSET))]) as (probe, node):
        setpoint, arm = probe.settled()
        assert np.allclose(arm - setpoint, OFFSET, atol=1e-9)  # the robot's bias stays
        # A client that trusts the node's joint_states: 0.03 rad from the measured joint_2.
        count = len(probe.trajectories)
        target = setpoint + [0.4, 0.2, -0.3, 0, 0, 0]
        handle = probe.send([(setpoint, 0.0), (target, 1.5)])
        status, code, text, _ = probe.result(handle, 10.0)
        assert (status, code) == (ABORTED, Result.INVALID_GOAL), text
        assert text == (f"point 0 (time_from_start 0) has joint 'joint_2' at "
                        f'{setpoint[1]:.6g} rad, {abs(OFFSET[1]):.6g} rad from where the arm is '
                        f'(measured {arm[1]:.6g} rad): above allowed_start_tolerance 0.01 rad')
        assert len(probe.trajectories) == count  # nothing spliced in
        assert np.array_equal(probe.position(), setpoint)
        # MoveIt's start is the measured state: within the tolerance. The motion starts from
        # the node's own setpoint (no jump), and the feedback's actual is the measured state.
        names = ['joint_3', 'joint_2']
        order = [JOINTS.index(name) for name in names]
        feedback = []
        start_ns = time.time_ns()
        handle = probe.send([(arm[order] + [0.004, -0.004], 0.0), (target[order], 1.5)], names,
                            feedback=feedback.append)
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
        _, positions, _, _ = trajectory_arrays(probe.trajectories[-1])
        assert np.array_equal(positions[0], setpoint)
        assert_within_limits(probe, start_ns - int(0.2e9))
        final, arm = probe.settled()
        assert np.allclose(final[order], target[order], atol=1e-12)
        assert np.allclose(arm - final, OFFSET, atol=1e-9)
        assert len(feedback) >= 20, len(feedback)  # 50 Hz over 1.5 s, on a busy machine
        measured = {tuple(m[order]) for m in probe.measured}
        exact = 0
        for message in feedback:
            fb = message.feedback
            assert list(fb.joint_names) == names
            exact += tuple(fb.actual.positions) in measured  # exactly a measured state
            assert np.allclose(np.subtract(fb.desired.positions, fb.actual.positions),
                               fb.error.positions, atol=1e-15)
        assert exact >= 0.9 * len(feedback)  # this process may miss a best-effort message
        # As JTC fills them: the time since the goal's start in desired and actual, and the
        # measured velocities (the stand-in robot reports them).
        since = [seconds(m.feedback.desired.time_from_start) for m in feedback]
        assert since == [seconds(m.feedback.actual.time_from_start) for m in feedback]
        assert np.all(np.diff(since) > 0) and since[0] >= 0 and since[-1] > 1.0, since
        assert all(len(m.feedback.actual.velocities) == len(names) for m in feedback)
        assert max(abs(v) for m in feedback for v in m.feedback.actual.velocities) > 0.1
        at_rest = feedback[-1].feedback  # the setpoint at the end, the arm off by its bias
        assert np.allclose(at_rest.desired.positions, target[order], atol=1e-9)
        assert np.allclose(np.array(at_rest.actual.positions) - at_rest.desired.positions,
                           OFFSET[order], atol=2e-3)


@pytest.mark.parametrize('velocities', [[], ['--no-velocity']],
                         ids=['velocities reported', 'no velocities'])
def test_goal_tolerance_met_by_a_robot_that_follows(velocities):
    """A robot that follows settles within goal_tolerance and stopped_velocity_tolerance."""
    with session('-p', 'goal_tolerance:=[0.01]', robot=velocities) as (probe, _):
        setpoint, arm = probe.settled()
        for own in ([], [JointTolerance(name='joint_1', position=0.002)]):
            target = setpoint + [0.6, -0.3, 0, 0, 0, 0]
            sent = time.time_ns()
            handle = probe.send([(arm, 0.0), (target, 1.5)], goal_tolerance=own)
            status, code, text, arrival = probe.result(handle)
            assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
            assert arrival - sent < moveit_timeout_ns(1.5)
            assert arrival >= plan_end_ns(probe)  # not before the trajectory's end
            setpoint, arm = probe.settled()
            assert np.allclose(arm, target, atol=1e-9)


def goal_violation(text):
    """``(at, error, target, tolerance, after)`` from a GOAL_TOLERANCE_VIOLATED string."""
    found = re.fullmatch(r"joint 'joint_1' is at (\S+) rad, (\S+) rad from (\S+) rad: above "
                         r'goal_tolerance (\S+) rad (\S+) s after the end', text)
    assert found, text
    return [float(x) for x in found.groups()]


def test_goal_tolerance_violated_by_a_joint_that_freezes_near_the_end():
    with session('-p', 'goal_tolerance:=[0.01]') as (probe, node):
        setpoint, arm = probe.settled()
        target = setpoint + [0.6, -0.3, 0, 0, 0, 0]
        sent = time.time_ns()
        handle = probe.send([(arm, 0.0), (target, 3.0)])
        probe.when_setpoint(0, setpoint[0] + 0.5)  # about 70 % of the way
        probe.freeze.publish(Float64MultiArray(data=[0.0]))
        status, code, text, arrival = probe.result(handle)
        assert (status, code) == (ABORTED, Result.GOAL_TOLERANCE_VIOLATED), text
        at, error, wanted, tolerance, after = goal_violation(text)
        frozen = probe.arm()[0]
        assert (at, wanted, tolerance, after) == (float(f'{frozen:.6g}'),
                                                  float(f'{target[0]:.6g}'), 0.01, 0.25)
        assert error == pytest.approx(target[0] - frozen, rel=1e-5) and error > 0.05
        end_ns = plan_end_ns(probe)
        assert end_ns + 0.25e9 <= arrival < sent + moveit_timeout_ns(3.0)


def test_a_joint_that_does_not_settle_violates_stopped_velocity_tolerance():
    """Within goal_tolerance but measured moving: JTC's "still" check, by name."""
    with session('-p', 'goal_tolerance:=[0.01]', '-p', 'stopped_velocity_tolerance:=0.02',
                 robot=['--velocity-offset', '0,0,0.05,0,0,0']) as (probe, _):
        setpoint, arm = probe.settled()
        target = setpoint + [0.3, 0, 0, 0, 0, 0]
        handle = probe.send([(arm, 0.0), (target, 1.0)])
        status, code, text, _ = probe.result(handle)
        assert (status, code) == (ABORTED, Result.GOAL_TOLERANCE_VIOLATED), text
        found = re.fullmatch(r"joint 'joint_3' still moves at (\S+) rad/s, above "
                             r'stopped_velocity_tolerance 0.02 rad/s 0.25 s after the end',
                             text)
        assert found and float(found.group(1)) == pytest.approx(0.05, abs=1e-9), text


def test_goal_tolerance_of_the_goal_itself_violated_by_a_robot_that_lags():
    with session(robot=['--tau', '3.0']) as (probe, _):
        setpoint, arm = probe.settled()
        target = setpoint + [0.6, 0, 0, 0, 0, 0]
        sent = time.time_ns()
        handle = probe.send([(arm, 0.0), (target, 3.0)],
                            goal_tolerance=[JointTolerance(name='joint_1', position=0.02)],
                            goal_time_tolerance=Duration(nanosec=300_000_000))
        status, code, text, arrival = probe.result(handle)
        assert (status, code) == (ABORTED, Result.GOAL_TOLERANCE_VIOLATED), text
        at, error, wanted, tolerance, after = goal_violation(text)
        assert (wanted, tolerance, after) == (float(f'{target[0]:.6g}'), 0.02, 0.3)
        assert error == pytest.approx(target[0] - at, rel=1e-5, abs=1e-6) and error > 0.1
        assert min(abs(m[0] - at) for m in probe.measured[-100:]) < 2e-3  # measured, then
        end_ns = plan_end_ns(probe)
        assert end_ns + 0.3e9 <= arrival < sent + moveit_timeout_ns(3.0)


@pytest.mark.parametrize('goal_time', [1.0, 0.0], ids=['goal_time_tolerance 1 s', 'no limit'])
def test_a_lagging_joint_released_within_the_goal_time_reaches_the_goal(goal_time):
    """
    While the goal waits for its tolerance the node keeps commanding its end (as JTC).

    joint_1 is held back near the end and released 0.25 s after the trajectory's end: the
    setpoint is not re-seeded where the arm is (0.2 rad off, beyond ``state_tolerance``),
    so the released arm arrives and the goal succeeds; then the arm is the reference again.
    """
    with session('-p', f'goal_time_tolerance:={goal_time}') as (probe, node):
        setpoint, arm = probe.settled()
        target = setpoint + [0.6, -0.3, 0, 0, 0, 0]
        handle = probe.send([(arm, 0.0), (target, 2.0)],
                            goal_tolerance=[JointTolerance(name='joint_1', position=0.02)],
                            goal_time_tolerance=Duration(sec=int(goal_time)))
        probe.when_setpoint(0, target[0] - 0.2)
        probe.freeze.publish(Float64MultiArray(data=[0.0]))
        probe.wait_at_rest(10.0)
        end_ns = plan_end_ns(probe)
        probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > end_ns + 0.25e9,
                         10.0, '0.25 s after the end')
        assert np.array_equal(probe.position(), target)  # the goal's end, not the arm
        assert target[0] - probe.arm()[0] > 0.1
        probe.freeze.publish(Float64MultiArray(data=[]))
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
        final, arm = probe.settled()
        assert np.array_equal(final, target) and np.allclose(arm, target, atol=1e-9)
        assert 'holding where the arm is' not in node.output()


def test_path_tolerance_violated_holds_where_the_arm_is_then_a_new_goal_runs():
    with session('-p', 'path_tolerance:=[0.2]') as (probe, node):
        setpoint, arm = probe.settled()
        target = setpoint + [1.0, -0.5, 0, 0, 0, 0]
        handle = probe.send([(arm, 0.0), (target, 2.5)])
        probe.when_setpoint(0, setpoint[0] + 0.3)
        probe.freeze.publish(Float64MultiArray(data=[0.0]))
        status, code, text, _ = probe.result(handle)
        assert (status, code) == (ABORTED, Result.PATH_TOLERANCE_VIOLATED), text
        frozen = probe.arm()[0]
        found = re.fullmatch(r"joint 'joint_1' is at (\S+) rad, (\S+) rad from (\S+) rad: "
                             r'above path_tolerance 0.2 rad', text)
        assert found, text
        assert float(found[1]) == float(f'{frozen:.6g}') and 0.2 < float(found[2]) < 0.5
        held, arm = probe.settled()
        assert held[0] == frozen  # exactly where the arm is
        assert np.allclose(arm, held, atol=1e-9)  # the others followed the hold
        assert not np.allclose(held[:2], target[:2], atol=0.1)  # not the goal's end
        # One step, toward the arm, then no further motion.
        positions = np.array([s.position for s in probe.states])
        first = int(np.flatnonzero(np.all(positions == held, axis=1))[0])
        before = positions[first - 1]
        # The setpoint was ahead of the frozen joint_1, by about the tolerance (checked
        # against the setpoint at the monitor's time, up to a tick past the last published).
        assert 0.15 < before[0] - held[0] < float(found[2]) + 0.05
        assert -0.2 < before[1] - held[1] < 0  # joint_2 (moving down) lagged a little
        assert np.all(positions[first:] == held)
        assert not np.any([s.velocity for s in probe.states[first:]])
        commands = np.array([c.data for c in probe.commands])
        hold_commands = int(np.flatnonzero(np.all(commands == held, axis=1))[0])
        assert np.all(commands[hold_commands:] == held)
        assert np.all(np.abs(np.diff(positions[:first], axis=0)) <= 0.05)  # smooth before
        hold_ns = stamp_ns(probe.states[first].header.stamp)
        probe.spin_until(lambda: len(probe.states) > first + 100, 10.0, 'more setpoints')
        assert stamp_gaps(probe, hold_ns).max() < 0.2  # it keeps streaming
        assert 'path tolerance violated: holding where the arm is' in node.output()
        # A new goal from there (MoveIt starts from the measured state), the joint free again.
        probe.freeze.publish(Float64MultiArray(data=[]))
        start_ns = time.time_ns()
        handle = probe.send([(arm, 0.0), (setpoint, 2.5)])
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
        _, positions, _, _ = trajectory_arrays(probe.trajectories[-1])
        assert np.array_equal(positions[0], held)
        final, arm = probe.settled()
        assert np.array_equal(final, setpoint) and np.allclose(arm, setpoint, atol=1e-9)
        assert_within_limits(probe, start_ns - int(0.2e9))


def test_joint_tolerance_minus_one_turns_the_check_off_for_that_joint():
    with session('-p', 'path_tolerance:=[0.2]', '-p', 'goal_tolerance:=[0.01]',
                 robot=['--frozen', 'joint_1']) as (probe, node):
        setpoint, arm = probe.settled()
        target = setpoint + [0.8, -0.4, 0, 0, 0, 0]
        off = [JointTolerance(name='joint_1', position=-1.0)]
        handle = probe.send([(arm, 0.0), (target, 2.0)], path_tolerance=off,
                            goal_tolerance=off)
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
        assert abs(probe.arm()[1] - target[1]) <= 0.01  # joint_2 was checked: it followed
        # Idle, the setpoint 0.8 rad from the frozen joint_1: it holds where the arm is.
        probe.spin_until(lambda: probe.position()[0] == probe.arm()[0], 10.0, 'the re-seed')
        _, arm = probe.settled()
        # The same goal with the parameters' tolerances: joint_1 is checked, and aborts.
        handle = probe.send([(arm, 0.0), (arm + [0.8, 0.2, 0, 0, 0, 0], 2.0)])
        status, code, text, _ = probe.result(handle)
        assert (status, code) == (ABORTED, Result.PATH_TOLERANCE_VIOLATED), text
        assert text.startswith(f"joint 'joint_1' is at {arm[0]:.6g} rad, ")


@pytest.mark.parametrize('path_tolerance', [0.0, 0.2])
def test_measured_state_lost_mid_goal_aborts_brakes_and_refuses_until_it_returns(
        path_tolerance):
    # With a path tolerance, the last measured state grows stale before the timeout says
    # so: it must not pass for a deviation (nor the node hold where the arm was).
    reason = f'no measured state on {TOPIC} for 0.5 s'
    with session('-p', 'joint_topic_timeout:=0.5', '-p', f'path_tolerance:=[{path_tolerance}]'
                 ) as (probe, node):
        setpoint, arm = probe.settled()
        start_ns = time.time_ns()
        handle = probe.send([(arm, 0.0), (setpoint + [1.5, 0, 0, 0, 0, 0], 3.0)])
        probe.when_setpoint(0, setpoint[0] + 0.5)
        probe.pause.publish(Float64MultiArray(data=[4.0]))
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (ABORTED, Result.PATH_TOLERANCE_VIOLATED, reason)
        # A goal while the measured state is lost: refused with that reason.
        count = len(probe.trajectories)
        handle = probe.send([(probe.position() + [0.1, 0, 0, 0, 0, 0], 1.0)])
        status, code, text, _ = probe.result(handle, 10.0)
        assert (status, code, text) == (ABORTED, Result.INVALID_GOAL, reason)
        assert len(probe.trajectories) == count
        braked, _ = probe.settled(20.0)  # the robot is back (4 s) and at rest
        assert setpoint[0] + 0.5 < braked[0] < setpoint[0] + 1.5 - 1e-3  # braked short
        assert_within_limits(probe, start_ns - int(0.2e9))
        probe.spin_until(lambda: f'measured state on {TOPIC} again' in node.output(), 10.0,
                         'the measured state again')
        handle = probe.send([(probe.arm(), 0.0), (setpoint, 2.0)])
        status, code, text, _ = probe.result(handle)
        assert (status, code, text) == (SUCCEEDED, Result.SUCCESSFUL, '')
        assert np.array_equal(probe.settled()[0], setpoint)
