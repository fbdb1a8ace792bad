"""
Velocity commands (issue 28): ``command_out_interface`` velocity, over DDS.

Three processes: the generator (``joint_topic`` and ``command_out_topic`` set, velocity
commands), the stand-in robot integrating the velocities it receives (``--integrate``;
``--velocity-scale`` below 1 is a drive that falls short of them) and this probe, which
records the commands, the setpoints (``joint_states``) and the robot's state.
"""

import contextlib
from pathlib import Path
import signal
import subprocess
import sys

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    end_process,
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    node_env,
    NodeProcess,
    Probe,
)
import numpy as np
import pytest
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

ROBOT = Path(__file__).resolve().parents[1] / 'support' / 'standin_robot.py'
TOPIC = '/robot/joint_states'
START = np.array([0.3, -0.2, 0.1, 0.05, -0.4, 0.6])
VELOCITY = ('-p', f'joint_topic:={TOPIC}', '-p', 'command_out_topic:=/robot/commands',
            '-p', 'command_out_interface:=velocity')
PERIOD = 0.01  # rate_hz 100 in config/generator.yaml


class VelocityProbe(Probe):
    """A Probe that also records the velocity commands and the robot's measured state."""

    def __init__(self):
        super().__init__()
        self.commands, self.measured = [], []
        self.create_subscription(Float64MultiArray, '/robot/commands', self.commands.append,
                                 QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE))
        self.create_subscription(JointState, TOPIC, self.measured.append,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))
        self.nudge = self.create_publisher(Float64MultiArray, '/robot/nudge', 10)

    def command_array(self) -> np.ndarray:
        """Return every command received, ``(commands, joints)``, rad/s."""
        return np.array([c.data for c in self.commands])

    def robot_position(self) -> np.ndarray:
        """Return the robot's latest measured positions in ``JOINTS`` order."""
        message = self.measured[-1]
        found = dict(zip(message.name, message.position, strict=True))
        return np.array([found[name] for name in JOINTS])


@contextlib.contextmanager
def session(*ros_args, robot=()):
    """Run the node with velocity commands and the integrating robot; yield both and a probe."""
    rclpy.init()
    node = NodeProcess(*VELOCITY, *ros_args)
    robot_process = subprocess.Popen(
        [sys.executable, str(ROBOT), '--integrate', '--start', ','.join(map(str, START)),
         *robot], env=node_env(), stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    probe = VelocityProbe()
    try:
        probe.wait_ready()
        # The node streams once it has the robot's state; this probe's own best-effort
        # subscription to it may match later (seen under load: none by the goal's end).
        probe.spin_until(lambda: probe.measured, 20.0, "the robot's measured state")
        yield probe, node
    finally:
        probe.destroy_node()
        rclpy.shutdown()
        end_process(robot_process)
        code = node.stop()
        output = node.output()
        node.close()
    assert code == 0, output
    assert 'Traceback' not in output, output


def goal(probe, positions):
    """Send a goal ``{joint: rad}``; return the setpoint it ends at."""
    status, _ = probe.goal(positions)
    assert status.level == DiagnosticStatus.OK, status.message
    target = START.copy()
    for name, value in positions.items():
        target[JOINTS.index(name)] = value
    return target


def test_the_robot_follows_a_goal_with_a_position_gain():
    # The drive reaches 0.9 of what it is told: the feed-forward alone would end short.
    with session('-p', 'position_gain:=8.0', robot=['--velocity-scale', '0.9']) as (probe, _):
        target = goal(probe, {'joint_1': 1.0, 'joint_4': -0.5})
        assert np.array_equal(probe.wait_at_rest(), target)
        probe.spin_until(lambda: np.abs(probe.robot_position() - target).max() < 1e-3, 15.0,
                         'the robot at the goal')
        commands = probe.command_array()
        assert np.all(np.abs(commands) <= MAX_VELOCITY)
        assert np.abs(commands[:, 0]).max() > 1.0  # it did move at speed
        probe.spin_until(lambda: np.abs(probe.command_array()[-1]).max() < 1e-3, 15.0,
                         'the command to settle at zero')


def test_without_a_gain_the_command_is_the_setpoint_velocity():
    with session(robot=['--velocity-scale', '1.0']) as (probe, node):
        target = goal(probe, {'joint_1': 1.0, 'joint_4': -0.5})
        probe.wait_at_rest()
        probe.spin_until(lambda: not probe.command_array()[-1].any(), 10.0, 'a zero command')
        # Feed-forward only: every command is a setpoint's velocity, exactly.
        velocities = {tuple(s.velocity) for s in probe.states}
        assert all(tuple(c.data) in velocities for c in probe.commands)
        assert np.abs(probe.command_array()).max() > 1.0
        # The robot drifts from the goal by its integration error only, and stays there.
        count = len(probe.measured)
        probe.spin_until(lambda: len(probe.measured) > count + 30, 10.0, 'the robot')
        drift = probe.robot_position() - target
        assert np.abs(drift).max() < 0.02, drift
        later = {tuple(m.position) for m in probe.measured[-20:]}
        assert len(later) == 1  # not moving: no correction
        assert 'holding where the arm is' not in node.output()


def test_the_command_never_exceeds_max_velocity():
    # A drive at half the command lags more and more: the correction asks for more than
    # max_velocity, which the command never exceeds.
    with session('-p', 'position_gain:=4.0', robot=['--velocity-scale', '0.5']) as (probe, _):
        goal(probe, {'joint_1': 3.3, 'joint_2': -1.0})
        probe.wait_at_rest()
        commands = probe.command_array()
        assert np.all(np.abs(commands) <= MAX_VELOCITY)
        assert np.abs(commands[:, 0]).max() == MAX_VELOCITY[0]  # clipped there


def test_a_reseed_does_not_make_the_command_jump():
    # Joint 2 moved by hand by 0.2 rad and held there: until the node re-seeds where the arm
    # is, the error is 0.2 rad, and k_p * 0.2 = 0.8 rad/s would be a jump; the correction
    # grows by at most max_acceleration * period per tick, then is 0 where the arm is.
    with session('-p', 'position_gain:=4.0', '-p', 'state_tolerance:=0.05',
                 robot=['--nudge-hold', '1.0']) as (probe, node):
        probe.spin_until(lambda: probe.nudge.get_subscription_count(), 10.0, 'the robot')
        count = len(probe.commands)
        probe.nudge.publish(Float64MultiArray(data=[1.0, 0.2]))
        nudged = START[1] + 0.2
        probe.spin_until(lambda: abs(probe.position()[1] - nudged) < 1e-12, 10.0,
                         'the setpoint to follow the arm')
        probe.spin_until(lambda: 'joint_2 measured +0.2000 rad' in node.output(), 10.0, 'log')
        probe.spin_until(lambda: len(probe.commands) > count + 20, 10.0, 'commands')
        joint_2 = probe.command_array()[count:, 1]
        step = MAX_ACCELERATION[1] * PERIOD
        assert np.all(np.abs(joint_2[1:]) <= np.abs(joint_2[:-1]) + step * (1 + 1e-9)), joint_2
        assert np.abs(joint_2).max() < 0.8 - step
        assert joint_2[-1] == 0.0  # the setpoint is where the arm is
        count = len(probe.measured)
        probe.spin_until(lambda: len(probe.measured) > count + 20, 10.0, 'the robot')
        assert abs(probe.robot_position()[1] - nudged) < 1e-3  # not pulled back


def test_a_brake_ends_with_a_zero_command():
    with session('-p', 'position_gain:=4.0') as (probe, _):
        goal(probe, {'joint_1': 3.0})
        probe.spin_until(lambda: np.abs(probe.command_array()[-1]).max() > 1.0, 10.0,
                         'the motion at speed')
        assert probe.stop().success
        rest = probe.wait_at_rest()
        assert rest[0] < 3.0 - 0.1  # braked short of the goal
        probe.spin_until(lambda: np.abs(probe.command_array()[-1]).max() < 1e-4, 10.0,
                         'a zero command')
        probe.spin_until(lambda: np.abs(probe.robot_position() - rest).max() < 1e-4, 10.0,
                         'the robot where the setpoint rests')
        assert np.all(np.abs(probe.command_array()) <= MAX_VELOCITY)


def test_lost_feedback_brakes_to_an_exact_zero_without_correction():
    # The robot stops publishing (and moving) while the node commands 2 rad/s: the node
    # brakes, the stale measured state corrects nothing, the brake ends at exactly 0.
    with session('-p', 'position_gain:=4.0', '-p', 'joint_topic_timeout:=0.5',
                 robot=['--stop-after', '6']) as (probe, node):
        goal(probe, {'joint_1': 10.0})
        reason = f'no measured state on {TOPIC} for 0.5 s'
        probe.spin_until(lambda: reason in node.output(), 20.0, 'the timeout')
        probe.wait_at_rest()
        count = len(probe.commands)
        probe.spin_until(lambda: len(probe.commands) > count + 10, 10.0, 'commands at rest')
        assert not probe.command_array()[count:].any()
        velocities = {tuple(s.velocity) for s in probe.states}
        commands = probe.command_array()
        assert np.all(np.abs(commands) <= MAX_VELOCITY)
        assert all(tuple(c) in velocities for c in commands[-60:])  # the brake's own


@pytest.mark.parametrize('sig', [signal.SIGTERM, signal.SIGINT])
def test_the_last_command_before_exit_is_zero(sig):
    with session('-p', 'position_gain:=4.0') as (probe, node):
        goal(probe, {'joint_1': 3.0})
        probe.spin_until(lambda: np.abs(probe.command_array()[-1]).max() > 1.0, 10.0,
                         'the motion at speed')
        assert node.stop(sig) == 0
        probe.spin_until(lambda: not probe.command_array()[-1].any(), 10.0,
                         'the last command, zero')
        commands = probe.command_array()
        # Moving until then (the correction k_p·(q_ref − q) may take a little off the
        # 1 rad/s seen above: 0.9985 under load).
        assert commands[-2, 0] > 0.5
        assert 'could not be sent' not in node.output()


@pytest.mark.parametrize('args,reason', [
    (['-p', 'command_out_interface:=effort'],
     "command_out_interface must be one of position, velocity; got 'effort'"),
    (['-p', 'command_out_interface:=velocity',
      '-p', 'command_out_type:=trajectory_msgs/JointTrajectory'],
     'command_out_interface velocity needs command_out_type std_msgs/Float64MultiArray'),
    (['-p', 'position_gain:=[1.0, -2.0, 1.0, 1.0, 1.0, 1.0]'],
     "position_gain must be finite and >= 0; joint 'joint_2' has -2.0"),
    (['-p', 'position_gain:=[1.0, 2.0]'],
     'position_gain has 2 values but there are 6 joints'),
    (['-p', 'position_gain:=.nan'], "position_gain must be finite and >= 0; joint 'joint_1'"),
])
def test_refuses_to_start(args, reason):
    node = NodeProcess(*args)
    try:
        assert node.process.wait(60) == 1
        assert reason in node.output(), node.output()
    finally:
        node.close()
