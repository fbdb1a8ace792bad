"""
traj-gen pose as a user runs it: the PoseStamped it publishes and how it takes the answer.

The node's ~/pose_goal is written elsewhere; here a stand-in in the test process (a real
rclpy node, in node_harness's isolated domain) subscribes /trajectory_generator/pose_goal,
checks what arrives, answers on ~/status (with decoys that are not the answer) and plays
the joint states --wait waits for.
"""

import json
import math
import subprocess
import sys
import time

from cli_helpers import assert_one_line_error
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped
from node_harness import in_process_node, node_env, REPO
import numpy as np
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import JointState
from traj_gen_ros.cli.pose_goal import answered_joints

NODE = '/trajectory_generator'
TIMEOUT = 120  # s per command: generous, the machine is shared


class StandIn:
    """The node's side of a pose goal: ~/pose_goal in, ~/status and joint_states out."""

    def __init__(self, node) -> None:
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self.node = node
        self.poses: list[PoseStamped] = []
        node.create_subscription(PoseStamped, f'{NODE}/pose_goal', self.poses.append,
                                 reliable)
        self.status = node.create_publisher(DiagnosticStatus, f'{NODE}/status', reliable)
        self.states = node.create_publisher(JointState, '/joint_states', reliable)
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def spin_until(self, condition, process: subprocess.Popen, what: str):
        """Spin until ``condition()``; fail (with the command's output) if it ended first."""
        while not condition():
            if process.poll() is not None:
                out, err = process.communicate()
                pytest.fail(f'traj-gen ended ({process.returncode}) before {what}: {out} {err}')
            self.executor.spin_once(timeout_sec=0.05)

    def answer(self, level: bytes, message: str, name: str = NODE, **values: str) -> None:
        self.status.publish(DiagnosticStatus(
            level=level, name=name, message=message,
            values=[KeyValue(key=key, value=value) for key, value in values.items()]))

    def finish(self, process: subprocess.Popen) -> subprocess.CompletedProcess:
        """Spin until the command has ended (it may still wait on joint states); return it."""
        self.spin_until(lambda: False if process.poll() is None else True, process, 'its end')
        out, err = process.communicate(timeout=TIMEOUT)
        return subprocess.CompletedProcess(process.args, process.returncode, out, err)


@pytest.fixture
def stand_in():
    with in_process_node('pose_goal_stand_in') as node:
        yield StandIn(node)


def start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, '-m', 'traj_gen_ros.cli.main', 'pose', *args],
                            cwd=REPO, env=node_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_pose_publishes_the_pose_stamped_and_waits_for_the_answered_joint_goal(stand_in):
    process = start('0.4', '-0.1', '0.3', '--rpy', '180', '0', '45', '--degrees', '--frame',
                    'panda_link0', '--wait', '--json', '--timeout', '60')
    stand_in.spin_until(lambda: stand_in.poses, process, 'a PoseStamped')
    message, = stand_in.poses
    assert message.header.frame_id == 'panda_link0'
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (0, 0)
    position = message.pose.position
    assert [position.x, position.y, position.z] == [0.4, -0.1, 0.3]
    orientation = message.pose.orientation
    quaternion = np.array([orientation.x, orientation.y, orientation.z, orientation.w])
    expected = Rotation.from_euler('xyz', [180, 0, 45], degrees=True).as_quat()
    assert np.linalg.norm(quaternion) == pytest.approx(1.0, abs=1e-15)
    assert abs(quaternion @ expected) == pytest.approx(1.0, abs=1e-12)

    # Not the answer: another kind, another frame, another node. Then the answer, with the
    # joint goal the inverse kinematics chose.
    ok, error = DiagnosticStatus.OK, DiagnosticStatus.ERROR
    stand_in.answer(error, 'a goal', request='goal', frame_id='panda_link0')
    stand_in.answer(error, 'another frame', request='pose_goal', frame_id='panda_hand')
    stand_in.answer(error, 'another node', name='/arm/trajectory_generator',
                    request='pose_goal', frame_id='panda_link0')
    stand_in.answer(ok, 'accepted: profile=quintic, duration=0.500 s, joints=3',
                    request='pose_goal', request_id='4', frame_id='panda_link0',
                    duration='0.5', joint_1='0.25', joint_2='-0.5', joint_3='1.125',
                    ik_position_error_mm='0.000100')
    # The stream: moving, then at rest off the goal, then at rest on it (--wait's end).
    names = ['joint_1', 'joint_2', 'joint_3', 'joint_4']
    stand_in.spin_until(lambda: stand_in.states.get_subscription_count() > 0, process,
                        'its joint_states subscription')
    stream = [([0.25, -0.5, 1.125, 0.0], [0.1, 0.0, 0.0, 0.0]),
              ([0.25, -0.4, 1.125, 0.0], [0.0] * 4), ([0.25, -0.5, 1.125, 0.0], [0.0] * 4)]
    for positions, velocities in stream:
        stand_in.states.publish(JointState(name=names, position=positions,
                                           velocity=velocities))

    deadline = time.monotonic() + TIMEOUT
    while process.poll() is None and time.monotonic() < deadline:  # as a node streams:
        stand_in.states.publish(JointState(name=names, position=stream[-1][0],  # the last
                                           velocity=stream[-1][1]))  # setpoint, again
        stand_in.executor.spin_once(timeout_sec=0.05)
    result = stand_in.finish(process)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ''
    status = json.loads(result.stdout)
    assert status['level'] == 'OK' and status['name'] == NODE
    assert status['values']['request'] == 'pose_goal'
    assert status['values']['joint_2'] == '-0.5'


def test_pose_prints_a_refusal_once_and_sends_the_identity_by_default(stand_in):
    process = start('0', '0', '0.05', '--frame', 'panda_hand_tcp', '--timeout', '60')
    stand_in.spin_until(lambda: stand_in.poses, process, 'a PoseStamped')
    message, = stand_in.poses
    orientation = message.pose.orientation
    assert message.header.frame_id == 'panda_hand_tcp'
    assert [orientation.x, orientation.y, orientation.z, orientation.w] == [0, 0, 0, 1]
    assert message.pose.position.z == 0.05
    reason = "pose goal (frame 'panda_hand_tcp'): no joint positions within the limits"
    stand_in.answer(DiagnosticStatus.ERROR, reason, request='pose_goal',
                    frame_id='panda_hand_tcp')
    result = stand_in.finish(process)
    assert result.returncode == 1, result.stderr
    assert result.stderr == '' and result.stdout == f'ERROR: {reason}\n'


def test_a_quaternion_off_norm_is_refused_before_anything_is_sent(stand_in):
    for quaternion, norm in ((['0', '0', '0', '0.5'], '0.5'), (['0', '0', '0', '0'], '0'),
                             (['0.6', '0', '0', '0.8015'], '1.0012')):
        process = start('0.3', '0', '0.5', '--quat', *quaternion, '--timeout', '60')
        result = stand_in.finish(process)
        line = assert_one_line_error(result)
        assert line == (f'traj-gen pose: error: --quat: quaternion (x, y, z, w) '
                        f'{[float(value) for value in quaternion]} has norm {norm}: a '
                        'rotation needs norm 1 (within 0.001)'), line
    # Within 1e-3 of norm 1 it is sent, normalised (the sign as given).
    process = start('0.3', '0', '0.5', '--quat', '-0.6', '0', '0', '-0.8008', '--timeout',
                    '60')
    stand_in.spin_until(lambda: stand_in.poses, process, 'a PoseStamped')
    message, = stand_in.poses  # the refused ones never came
    orientation = message.pose.orientation
    norm = math.hypot(0.6, 0.8008)
    assert [orientation.x, orientation.y, orientation.z, orientation.w] == pytest.approx(
        [-0.6 / norm, 0.0, 0.0, -0.8008 / norm], abs=1e-15)
    stand_in.answer(DiagnosticStatus.OK, 'accepted', request='pose_goal', frame_id='')
    result = stand_in.finish(process)
    assert (result.returncode, result.stdout) == (0, 'OK: accepted\n'), result.stderr


def test_pose_without_a_node_exits_3_naming_the_topic():
    result = subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', 'pose', '0.3',
                             '0', '0.5', '--node', '/nobody', '--timeout', '1'], cwd=REPO,
                            env=node_env(), capture_output=True, text=True, timeout=TIMEOUT)
    line = assert_one_line_error(result, code=3)
    assert line == ('traj-gen pose: no answer after 1 s: /nobody is not subscribed to '
                    '/nobody/pose_goal (is the node running, with the same ROS_DOMAIN_ID?)')


def test_the_answered_joint_goal_is_read_by_name():
    values = {'request': 'pose_goal', 'frame_id': '', 'duration': '1.5', 'joint_1': '0.25',
              'joint_3': '-1e-3', 'joint_4': 'nan?'}
    assert answered_joints(values, ['joint_1', 'joint_2', 'joint_3', 'joint_4']) == {
        'joint_1': 0.25, 'joint_3': -0.001}
    assert answered_joints(values, ['duration_joint']) == {}
    assert math.isclose(answered_joints({'j': '3.14159265'}, ['j'])['j'], 3.14159265)
