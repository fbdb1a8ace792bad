"""The node beside a robot (issue 22): measured state in, commands out, priorities."""

import contextlib
import os
from pathlib import Path
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from jtc_interpolation import hermite
from node_harness import (
    end_process,
    JOINTS,
    MAX_ACCELERATION,
    node_env,
    NodeProcess,
    Probe,
    REPO,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

ROBOT = Path(__file__).resolve().parents[1] / 'support' / 'standin_robot.py'
TOPIC = '/robot/joint_states'
START = [0.3, -0.2, 0.1, 0.05, -0.4, 0.6]
WAITING = f'waiting for the measured state on {TOPIC}'


def start_robot(*args):
    return subprocess.Popen([sys.executable, str(ROBOT), *args], env=node_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)


class RobotProbe(Probe):
    """A Probe that also records the robot's state, the commands and /diagnostics."""

    def __init__(self):
        super().__init__()
        self.measured, self.commands, self.diagnostics, self.plans = [], [], [], []
        self.create_subscription(JointState, TOPIC, self.measured.append,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))
        self.create_subscription(Float64MultiArray, '/robot/commands', self.commands.append,
                                 1000)
        self.create_subscription(JointTrajectory, '/robot/jtc', self.plans.append, 100)
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)
        self.nudge = self.create_publisher(Float64MultiArray, '/robot/nudge', 10)

    def diagnostic(self, condition, what, timeout=15.0):
        """Wait for a /diagnostics status for which ``condition(status, values)`` holds."""
        def found():
            for array in self.diagnostics:
                for status in array.status:
                    values = {kv.key: kv.value for kv in status.values}
                    if condition(status, values):
                        return status, values
            return None
        return self.spin_until(found, timeout, what)


@contextlib.contextmanager
def session(*ros_args, robot=None):
    """Run the node (and a stand-in robot with ``robot`` args); yield a RobotProbe."""
    rclpy.init()
    node = NodeProcess('-p', f'joint_topic:={TOPIC}', *ros_args)
    robot_process = start_robot(*robot) if robot is not None else None
    probe = RobotProbe()
    try:
        yield probe, node
    finally:
        probe.destroy_node()
        rclpy.shutdown()
        if robot_process is not None:
            end_process(robot_process)
        code = node.stop()
        output = node.output()
        node.close()
    assert code == 0, output
    assert 'Traceback' not in output, output


def test_waits_for_the_measured_state_then_starts_there():
    with session('-p', 'command_out_topic:=/robot/commands') as (probe, node):
        probe.spin_until(lambda: probe.goal_pub.get_subscription_count()
                         and probe.stop_client.service_is_ready(), 20.0, 'the node')
        status, _ = probe.goal({'joint_1': 0.5})
        assert status.level == DiagnosticStatus.ERROR
        assert status.message == f'goal refused: {WAITING}'
        assert WAITING in probe.stop().message or not probe.stop().success
        status, _ = probe.request(via_message(['joint_1'], [([0.5], 1.0)]))
        assert status.message == f'via_points refused: {WAITING}'
        warn, _ = probe.diagnostic(lambda s, v: WAITING in s.message, '/diagnostics waiting')
        assert warn.level == DiagnosticStatus.WARN
        assert not probe.states and not probe.commands  # streams nothing meanwhile
        # Extra joints, reversed order, best effort, joint_3 missing until the first nudge.
        robot = start_robot('--start', ','.join(map(str, START)), '--extra', 'gripper,base',
                            '--reliability', 'best_effort', '--omit', 'joint_3',
                            '--nudge-hold', '0')
        try:
            probe.spin_until(lambda: len(probe.measured) >= 20, 20.0, 'the robot')
            assert all('joint_3' not in m.name for m in probe.measured)
            status, _ = probe.goal({'joint_1': 0.5})  # lacking joint_3: still waiting
            assert status.message == f'goal refused: {WAITING}'
            assert not probe.states
            probe.nudge.publish(Float64MultiArray(data=[0.0, 0.0]))  # now all joints
            probe.wait_ready()
            first = probe.states[0]
            assert list(first.name) == JOINTS
            assert list(first.position) == START and not any(first.velocity)
            # A motion: the robot follows the commands; no re-seed while it does.
            status, _ = probe.goal({'joint_1': 1.0, 'joint_4': -0.5})
            assert status.level == DiagnosticStatus.OK, status.message
            probe.wait_at_rest()
            probe.spin_until(lambda: abs(probe.measured[-1].position[-1] - 1.0) < 1e-3,
                             10.0, 'the robot to follow')
            # Float64MultiArray data is the joint_states position of the same tick.
            positions = {tuple(s.position) for s in probe.states}
            assert len(probe.commands) > 50
            assert all(tuple(c.data) in positions for c in probe.commands[-50:])
            assert 'holding where the arm is' not in node.output()
        finally:
            end_process(robot)


def test_stop_while_the_measured_state_is_awaited_answers_why():
    """``~/stop``'s response gives the reason, as ``~/status`` does (issue 28)."""
    with session() as (probe, _):
        probe.spin_until(lambda: probe.stop_client.service_is_ready()
                         and probe.count_publishers('/trajectory_generator/status'),
                         20.0, 'the node')
        count = len(probe.statuses)
        response = probe.stop()
        assert not response.success
        assert response.message == f'stop refused: {WAITING}'
        probe.spin_until(lambda: len(probe.statuses) > count, 10.0, 'the stop answer')
        status = probe.statuses[count]
        assert status.level == DiagnosticStatus.ERROR
        assert status.message == response.message
        assert {kv.key: kv.value for kv in status.values}['request'] == 'stop'
        assert not probe.states  # streams nothing meanwhile


def test_arm_moved_by_hand_reseeds_the_setpoint():
    with session('-p', 'command_out_topic:=/robot/commands', '-p', 'state_tolerance:=0.05',
                 robot=['--start', ','.join(map(str, START)), '--nudge-hold', '3.0']
                 ) as (probe, node):
        probe.wait_ready()
        probe.spin_until(lambda: probe.nudge.get_subscription_count(), 10.0, 'the robot')
        before = probe.position()
        probe.nudge.publish(Float64MultiArray(data=[1.0, 0.2]))  # joint_2 by +0.2 rad
        target = before.copy()
        target[1] += 0.2
        probe.spin_until(lambda: abs(probe.position()[1] - target[1]) < 1e-12, 10.0,
                         'the setpoint to follow the arm')
        assert np.array_equal(probe.position(), target)  # exactly where the arm is
        steps = {tuple(s.position) for s in probe.states}
        assert steps == {tuple(before), tuple(target)}  # one step, toward the arm
        probe.spin_until(lambda: 'joint_2 measured +0.2000 rad' in node.output(), 10.0, 'log')
        probe.diagnostic(lambda s, v: v.get('re-seeds') == '1', 're-seeds on /diagnostics')


def test_feedback_timeout_brakes_and_refuses():
    with session('-p', 'command_out_topic:=/robot/commands', '-p', 'joint_topic_timeout:=0.5',
                 robot=['--stop-after', '6']) as (probe, node):
        probe.wait_ready()
        status, _ = probe.goal({'joint_1': 10.0})  # ~6 s: still moving when it stops
        assert status.level == DiagnosticStatus.OK, status.message
        reason = f'no measured state on {TOPIC} for 0.5 s'
        probe.spin_until(lambda: reason in node.output(), 20.0, 'the timeout')
        rest = probe.wait_at_rest()
        assert rest[0] < 10.0 - 1e-3  # braked short of the goal
        times, positions, velocities = probe.states_between(0)
        assert np.isfinite(positions).all()
        assert np.all(np.abs(np.diff(velocities[:, 0])) <= MAX_ACCELERATION[0]
                      * np.diff(times) * 1.001 + 1e-9)
        status, _ = probe.goal({'joint_1': 0.0})
        assert status.message == f'goal refused: {reason}'
        error, _ = probe.diagnostic(lambda s, v: reason in s.message, '/diagnostics ERROR')
        assert error.level == DiagnosticStatus.ERROR


def test_reliable_publisher_works_too():
    with session(robot=['--start', ','.join(map(str, START)), '--reliability', 'reliable']
                 ) as (probe, _):
        probe.wait_ready()
        assert list(probe.states[0].position) == START


@pytest.mark.parametrize('args,reason', [
    (['-p', 'joint_topic:=/joint_states'], 'where this node publishes its own setpoint'),
    (['-p', 'joint_topic:=/robot/joint_states', '-r', 'joint_states:=/robot/joint_states'],
     'where this node publishes its own setpoint'),
    (['-p', 'command_out_type:=std_msgs/Float64'],
     'command_out_type must be one of std_msgs/Float64MultiArray, '
     'trajectory_msgs/JointTrajectory'),
])
def test_refuses_to_start(args, reason):
    node = NodeProcess(*args)
    try:
        assert node.process.wait(60) == 1
        assert reason in node.output(), node.output()
    finally:
        node.close()


def test_joint_trajectory_out_is_the_plan_for_a_jtc():
    rclpy.init()
    node = NodeProcess('-p', 'publish_joint_states:=false', '-p', 'command_out_topic:=/robot/jtc',
                       '-p', 'command_out_type:=trajectory_msgs/JointTrajectory',
                       '-p', 'rate_hz:=500.0')
    probe = RobotProbe()
    try:
        probe.spin_until(lambda: probe.goal_pub.get_subscription_count()
                         and probe.count_publishers('/robot/jtc'), 20.0, 'the node')
        for profile in ('quintic', 'lspb', 'scurve', 'cubic'):
            probe.require_parameters(profile=profile)
            for request in (via_message(['joint_1', 'joint_3'], [([0.4, -0.3], 0.0),
                                                                 ([-0.2, 0.5], 0.0)]),
                            JointState(name=['joint_2'], position=[0.7])):
                count = len(probe.plans)
                status, sampled = probe.request(request)
                assert status.level == DiagnosticStatus.OK, status.message
                probe.spin_until(lambda n=count: len(probe.plans) > n, 10.0, 'the JTC plan')
                plan = probe.plans[-1]
                assert list(plan.joint_names) == JOINTS
                assert stamp_ns(plan.header.stamp) == stamp_ns(sampled.header.stamp)
                times, positions, velocities, accelerations = trajectory_arrays(plan)
                assert np.all(np.diff(times) > 0) and times[0] == 0.0
                assert not velocities[-1].any()
                assert len(times) < 50  # the pieces' ends, not one point per tick
                if accelerations.size == 0:
                    accelerations = None
                dense_t, dense_p, _, _ = trajectory_arrays(sampled)
                assert np.array_equal(positions[0], dense_p[0])  # the state at its start
                error = np.abs(hermite(times, positions, velocities, accelerations, dense_t)
                               - dense_p)
                assert error.max() < 1e-8, (profile, error.max())
                assert profile not in ('quintic', 'scurve') or accelerations is not None
                # The next request from rest (an auto-timed LSPB path from a moving state
                # can be infeasible): the node clock is the system clock.
                end_ns = stamp_ns(plan.header.stamp) + int(times[-1] * 1e9)
                probe.spin_until(lambda end=end_ns: time.time_ns() > end, 30.0, 'the end')
        assert probe.count_publishers('/joint_states') == 0 and not probe.states
    finally:
        probe.destroy_node()
        rclpy.shutdown()
        code = node.stop()
        output = node.output()
        node.close()
    assert code == 0 and 'Traceback' not in output, output


def thread_policies(pid):
    """(policy, nice) of every thread of ``pid``, from /proc/<pid>/task/*/stat."""
    found = []
    for stat in Path(f'/proc/{pid}/task').glob('*/stat'):
        fields = stat.read_text().rsplit(')', 1)[1].split()
        found.append((int(fields[38]), int(fields[16])))  # policy (field 41), nice (19)
    return found


def test_normal_priority_on_request():
    rclpy.init()
    env = node_env()
    env['TRAJ_GEN_ROS_PRIORITY'] = 'normal'
    node = NodeProcess(env=env)
    probe = Probe()
    try:
        probe.wait_ready()
        probe.spin_until(lambda: 'streaming' in node.output(), 10.0, 'the start-up log')
        assert 'normal priority (TRAJ_GEN_ROS_PRIORITY=normal)' in node.output()
        policies = thread_policies(node.process.pid)
        assert len(policies) > 3 and set(policies) == {(os.SCHED_OTHER, 0)}, policies
    finally:
        probe.destroy_node()
        rclpy.shutdown()
        node.stop()
        node.close()
    bad = dict(env, TRAJ_GEN_ROS_PRIORITY='high')
    process = subprocess.run([sys.executable, '-m', 'traj_gen_ros.node.generator'], env=bad,
                             cwd=REPO, capture_output=True, text=True, timeout=60)
    assert process.returncode == 1
    assert 'TRAJ_GEN_ROS_PRIORITY must be one of realtime, normal' in process.stderr
