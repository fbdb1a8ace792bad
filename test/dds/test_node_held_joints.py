"""
A URDF joint outside ``joints`` held at its measured value, over DDS (issue 29).

pybullet's Franka Panda; the node commands panda_joint1..6 only (tool frame
``panda_grasptarget``, so panda_joint7 is on the chain). A stand-in robot follows the
node's position commands and reports panda_joint7 at 0.5 rad in its measured state
(``standin_robot.py --extra``). ``~/tool_pose``, ``/diagnostics``, a pose goal and a line
of the tool must all see panda_joint7 at 0.5 rad: each is judged by ``numpy_chain`` (the
URDF's origins and axes in numpy) with that value, and would be 0.5 rad off with 0.
"""

import contextlib
import json
from pathlib import Path as FilePath
import subprocess
import sys
import tempfile

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from node_harness import end_process, node_env, running_node, stamp_ns
import numpy as np
from numpy_chain import NumpyChain
from pybullet_urdfs import pybullet_urdfs
import pytest
from scipy.spatial.transform import Rotation
from test_node_pose_goal import errors, PoseProbe, quaternion
from test_node_tool_path import line_errors

JOINTS = [f'panda_joint{index}' for index in range(1, 7)]
START = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571]
MEASURED = {'panda_joint7': 0.5}  # what standin_robot.py reports for an --extra joint
BASE, TOOL = 'panda_link0', 'panda_grasptarget'
ROBOT = FilePath(__file__).resolve().parents[1] / 'support' / 'standin_robot.py'


@pytest.fixture(scope='module')
def urdf(request) -> str:
    return pybullet_urdfs(request.config)['panda'].read_text()


class HeldProbe(PoseProbe):
    """A PoseProbe that also sends lines and records ``/diagnostics``."""

    def __init__(self):
        super().__init__()
        self.line_pub = self.create_publisher(Path, '/trajectory_generator/cartesian_path', 10)
        self.diagnostics = []
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)
        self.spin_until(lambda: self.line_pub.get_subscription_count() > 0, 20.0,
                        'the cartesian_path subscription')

    def line(self, goal, frame=''):
        """Send one straight line to ``goal`` (``(4, 4)``) in ``frame``; return the answer."""
        message = Path()
        message.header.frame_id = frame
        stamped = PoseStamped()
        point, orientation = stamped.pose.position, stamped.pose.orientation
        point.x, point.y, point.z = (float(v) for v in goal[:3, 3])
        orientation.x, orientation.y, orientation.z, orientation.w = \
            Rotation.from_matrix(goal[:3, :3]).as_quat()
        message.poses.append(stamped)
        return self._next_status(lambda: self.line_pub.publish(message), 20.0)


@contextlib.contextmanager
def session(urdf_text):
    """Run the node for panda_joint1..6 beside a stand-in robot; yield a ready HeldProbe."""
    values = {'joints': JOINTS, 'robot_description': urdf_text, 'tool_frame': TOOL,
              'joint_topic': '/robot/joint_states', 'command_out_topic': '/robot/commands',
              'state_tolerance': [0.0], 'max_velocity': [1.5], 'max_acceleration': [3.0]}
    with tempfile.TemporaryDirectory() as folder:
        path = FilePath(folder) / 'panda.yaml'
        path.write_text(json.dumps({'/**': {'ros__parameters': values}}))
        with running_node('--params-file', str(path)) as node:
            robot = subprocess.Popen(
                [sys.executable, str(ROBOT), '--joints', ','.join(JOINTS),
                 '--start', ','.join(map(str, START)), '--extra', 'panda_joint7'],
                env=node_env(), stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
            try:
                probe = HeldProbe()
                try:
                    probe.wait_ready(30.0)
                    yield node, probe
                finally:
                    probe.destroy_node()
            finally:
                end_process(robot)


def pose(chain, position, link=TOOL, **others):
    """Return the link's pose at the node's joints ``position``, panda_joint7 as measured."""
    return chain.pose(link, dict(zip(JOINTS, position, strict=True)) | (MEASURED | others))


def test_tool_pose_and_diagnostics_stand_the_joint_where_it_is_measured(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (node, probe):
        probe.spin_until(lambda: len(probe.tool_poses) > 20, 10.0, '~/tool_pose')
        states = {stamp_ns(s.header.stamp): s for s in probe.states}
        for message in probe.tool_poses[-5:]:
            assert message.header.frame_id == BASE
            nearest = min(states, key=lambda stamp: abs(stamp - stamp_ns(message.header.stamp)))
            expected = pose(chain, states[nearest].position)
            p, q = message.pose.position, message.pose.orientation
            assert np.allclose([p.x, p.y, p.z], expected[:3, 3], atol=1e-9)
            assert np.allclose(np.abs(np.dot([q.x, q.y, q.z, q.w], quaternion(expected))),
                               1.0, atol=1e-9)
            at_zero = pose(chain, states[nearest].position, panda_joint7=0.0)
            assert errors(at_zero, expected)[1] == pytest.approx(0.5, abs=1e-9)
        # Built before the first measured state: 0 at start-up; /diagnostics says 0.5 now.
        assert 'held on the way: panda_joint7=0' in node.output()

        def held_line():
            for array in probe.diagnostics:
                for status in array.status:
                    values = {kv.key: kv.value for kv in status.values}
                    if 'held on the way: panda_joint7=0.5' in values.get('kinematics', ''):
                        return True
            return False
        probe.spin_until(held_line, 15.0, '/diagnostics naming panda_joint7=0.5')


def test_a_pose_goal_and_a_line_are_planned_with_the_measured_joint(urdf):
    chain = NumpyChain(urdf)
    with session(urdf) as (_, probe):
        start = probe.wait_at_rest(20.0)
        assert np.allclose(start, START)
        # A pose in the base frame: where these joints put the tool with panda_joint7 at 0.5.
        goal = np.array(START) + [0.2, 0.15, -0.1, 0.2, 0.1, -0.15]
        target = pose(chain, goal)
        plans = len(probe.trajectories)
        status = probe.pose_goal(target)
        assert status.level == DiagnosticStatus.OK, status.message
        # The answer may come before the plan's ~/trajectory, by which wait_at_rest knows
        # the motion's end: until then the stream's rest before the motion looks like it.
        probe.spin_until(lambda: len(probe.trajectories) > plans, 20.0, 'the ~/trajectory')
        reached = pose(chain, probe.wait_at_rest(20.0))
        distance, angle = errors(reached, target)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)
        # A 5 cm line along the tool's own x (which panda_joint7 turns), every setpoint on it.
        here = reached
        step = np.eye(4)
        step[0, 3] = 0.05
        sent_ns = stamp_ns(probe.latest().header.stamp)
        plans = len(probe.trajectories)
        status = probe.line(step, TOOL)
        assert status.level == DiagnosticStatus.OK, status.message
        probe.spin_until(lambda: len(probe.trajectories) > plans, 20.0, 'the ~/trajectory')
        probe.wait_at_rest(30.0)
        states = [s for s in probe.states if stamp_ns(s.header.stamp) >= sent_ns]
        poses = np.array([pose(chain, s.position) for s in states])
        distance, angle = line_errors(poses, here, here @ step)
        assert distance.max() < 1e-4 and angle.max() < 1e-3, (distance.max(), angle.max())
        assert np.linalg.norm(poses[-1, :3, 3] - (here @ step)[:3, 3]) < 1e-4
