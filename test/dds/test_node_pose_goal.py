"""
Pose goals over DDS (issue 29): the tool pose reached by inverse kinematics, on a real arm.

The generator runs with pybullet's Franka Panda URDF (seven joints; the default tool frame
is ``panda_grasptarget``). Every pose is judged on the streamed joint states through an
independent forward kinematics (``numpy_chain``: the URDF's joint origins and axes in
numpy): the arm at rest after a pose goal is within 0.1 mm and 1 mrad of the pose asked.
"""

import contextlib
import json
import math
from pathlib import Path
import subprocess
import sys
import tempfile

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from node_harness import node_env, Probe, REPO, running_node, stamp_ns
import numpy as np
from numpy_chain import NumpyChain, rpy_matrix, transform
from pybullet_urdfs import pybullet_urdfs
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from tool_at_rest import tool_at_rest

JOINTS = [f'panda_joint{index}' for index in range(1, 8)]
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
BASE, TOOL = 'panda_link0', 'panda_grasptarget'


@pytest.fixture(scope='module')
def urdf(request) -> str:
    return pybullet_urdfs(request.config)['panda'].read_text()


class PoseProbe(Probe):
    """A Probe that sends pose goals and records ``~/tool_pose``."""

    def __init__(self):
        super().__init__()
        self.pose_pub = self.create_publisher(PoseStamped, '/trajectory_generator/pose_goal',
                                              10)
        self.tool_poses = []
        self.create_subscription(PoseStamped, '/trajectory_generator/tool_pose',
                                 self.tool_poses.append,
                                 QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        self.spin_until(lambda: self.pose_pub.get_subscription_count() > 0, 20.0,
                        'the pose_goal subscription')

    def pose_goal(self, pose, frame=''):
        """Send the pose ``(4, 4)`` in ``frame``; return the answer on ~/status."""
        message = PoseStamped()
        message.header.frame_id = frame
        message.pose.position.x, message.pose.position.y, message.pose.position.z = pose[:3, 3]
        x, y, z, w = quaternion(pose)
        orientation = message.pose.orientation
        orientation.x, orientation.y, orientation.z, orientation.w = x, y, z, w
        return self._next_status(lambda: self.pose_pub.publish(message), 10.0)


@contextlib.contextmanager
def session(urdf_text=None, **extra):
    """Run a generator for the Panda's joints (its URDF unless ``urdf_text`` is '')."""
    values = {'joints': JOINTS, 'initial_positions': READY, 'max_velocity': [1.5],
              'max_acceleration': [3.0]} | extra
    if urdf_text:
        values['robot_description'] = urdf_text
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / 'panda.yaml'
        path.write_text(json.dumps({'/**': {'ros__parameters': values}}))
        with running_node('--params-file', str(path)) as node:
            probe = PoseProbe()
            try:
                probe.wait_ready(30.0)
                yield node, probe
            finally:
                probe.destroy_node()


def quaternion(pose):
    """Return ``(x, y, z, w)`` of a rotation matrix (independent of the node's)."""
    r = pose[:3, :3]
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    if w > 1e-3:
        return ((r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w),
                (r[1, 0] - r[0, 1]) / (4 * w), w)
    x = math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0
    return (x, (r[0, 1] + r[1, 0]) / (4 * x), (r[0, 2] + r[2, 0]) / (4 * x),
            (r[2, 1] - r[1, 2]) / (4 * x))


def errors(first, second):
    """Return ``(position error m, rotation angle rad)`` between two poses."""
    rotation = first[:3, :3].T @ second[:3, :3]
    angle = math.acos(max(-1.0, min(1.0, (np.trace(rotation) - 1.0) / 2.0)))
    return float(np.linalg.norm(first[:3, 3] - second[:3, 3])), angle


def test_a_pose_goal_ends_within_a_tenth_of_a_millimetre_and_a_milliradian(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (node, probe):
        assert f'kinematic chain {BASE} -> {TOOL}: 7 joints' in node.output()
        probe.diagnostics = []
        probe.create_subscription(DiagnosticArray, '/diagnostics', probe.diagnostics.append, 10)
        probe.spin_until(lambda: probe.diagnostics, 10.0, '/diagnostics')
        values = {kv.key: kv.value for kv in probe.diagnostics[-1].status[0].values}
        assert values['kinematics'].startswith(f'kinematic chain {BASE} -> {TOOL}')
        start, here = tool_at_rest(probe, chain, JOINTS, TOOL)
        target = here @ transform(rpy_matrix(0.1, -0.15, 0.2), np.zeros(3))
        target[:3, 3] += [0.06, -0.08, -0.1]
        status = probe.pose_goal(target)
        assert status.level == DiagnosticStatus.OK, status.message
        values = {kv.key: kv.value for kv in status.values}
        assert values['request'] == 'pose_goal'
        goal = np.array([float(values[name]) for name in JOINTS])
        final, reached = tool_at_rest(probe, chain, JOINTS, TOOL)
        assert np.allclose(final, goal, atol=1e-9)  # the joint goal the answer said
        distance, angle = errors(reached, target)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)
        assert np.max(np.abs(final - start)) < 1.0  # the nearest solution: a small move


def test_a_jog_in_the_tool_frame_and_a_pose_in_another_links_frame(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (_, probe):
        _, here = tool_at_rest(probe, chain, JOINTS, TOOL)
        jog = np.eye(4)
        jog[2, 3] = 0.05  # 5 cm along the tool's own z
        assert probe.pose_goal(jog, TOOL).level == DiagnosticStatus.OK
        _, reached = tool_at_rest(probe, chain, JOINTS, TOOL)
        distance, angle = errors(reached, here @ jog)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)
        assert np.linalg.norm(reached[:3, 3] - here[:3, 3]) == pytest.approx(0.05, abs=1e-4)
        # The tool pose given in panda_link5's frame at the start of the motion.
        position, _ = tool_at_rest(probe, chain, JOINTS, TOOL)
        values = dict(zip(JOINTS, position, strict=True))
        relative = np.linalg.inv(chain.pose('panda_link5', values)) @ reached
        relative[:3, 3] += [0.0, 0.02, 0.0]
        expected = chain.pose('panda_link5', values) @ relative
        assert probe.pose_goal(relative, 'panda_link5').level == DiagnosticStatus.OK
        _, reached = tool_at_rest(probe, chain, JOINTS, TOOL)
        distance, angle = errors(reached, expected)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)


def test_tool_pose_is_the_setpoints_tool_pose_in_the_base_frame(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (_, probe):
        probe.spin_until(lambda: len(probe.tool_poses) > 20, 10.0, '~/tool_pose')
        states = {stamp_ns(s.header.stamp): s for s in probe.states}
        message = probe.tool_poses[-1]
        assert message.header.frame_id == BASE
        nearest = min(states, key=lambda stamp: abs(stamp - stamp_ns(message.header.stamp)))
        values = dict(zip(JOINTS, states[nearest].position, strict=True))
        expected = chain.pose(TOOL, values)
        p, q = message.pose.position, message.pose.orientation
        assert np.allclose([p.x, p.y, p.z], expected[:3, 3], atol=1e-9)
        assert np.allclose(np.abs(np.dot([q.x, q.y, q.z, q.w], quaternion(expected))), 1.0,
                           atol=1e-9)


def test_refusals_say_why_and_change_nothing(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (_, probe):
        start, here = tool_at_rest(probe, chain, JOINTS, TOOL)
        far = here.copy()
        far[:3, 3] = [2.0, 0.0, 0.5]
        cases = [
            (far, '', 'mm'),
            (here, 'gripper_cam', "pose frame_id 'gripper_cam' is not a link"),
        ]
        for pose, frame, text in cases:
            status = probe.pose_goal(pose, frame)
            assert status.level == DiagnosticStatus.ERROR
            assert status.message.startswith('pose_goal refused: '), status.message
            assert text in status.message, status.message
        message = PoseStamped()
        message.pose.orientation.w = 0.0  # a zero quaternion
        status = probe._next_status(lambda: probe.pose_pub.publish(message), 10.0)
        assert status.level == DiagnosticStatus.ERROR and 'has norm 0' in status.message
        assert np.array_equal(probe.wait_at_rest(), start)


def test_without_a_urdf_a_pose_goal_is_refused_saying_so():
    with session('') as (_, probe):
        status = probe.pose_goal(np.eye(4))
        assert status.level == DiagnosticStatus.ERROR
        assert 'no robot description' in status.message, status.message


def test_traj_gen_pose_moves_the_node_and_prints_its_answer(urdf):
    """The CLI's ``pose`` against the real node: a 3 cm jog along the tool's z, --wait."""
    chain = NumpyChain(urdf)
    with session(urdf) as (_, probe):
        start, here = tool_at_rest(probe, chain, JOINTS, TOOL)
        result = subprocess.run(
            [sys.executable, '-m', 'traj_gen_ros.cli.main', 'pose', '0', '0', '0.03',
             '--frame', TOOL, '--wait', '--timeout', '60'], cwd=REPO, env=node_env(),
            capture_output=True, text=True, timeout=120)
        assert result.returncode == 0, result.stderr
        assert result.stdout.startswith('OK: accepted: profile=quintic'), result.stdout
        jog = np.eye(4)
        jog[2, 3] = 0.03
        probe.spin_until(lambda: not np.array_equal(probe.position(), start), 10.0,
                         'the motion in this process')
        _, reached = tool_at_rest(probe, chain, JOINTS, TOOL)
        distance, angle = errors(reached, here @ jog)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)
