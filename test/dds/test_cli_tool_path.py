"""
traj-gen line / arc as a user runs them: the Path they publish, the answer, --wait's end.

A stand-in in the test process (a real rclpy node in node_harness's isolated domain)
subscribes /trajectory_generator/cartesian_path and circular_goal, answers on ~/status
(with decoys that are not the answer), latches its plan on ~/trajectory and plays the
joint states: --wait ends only once they are at rest where that plan ends. Then the real
generator, with pybullet's Panda: a line and an arc end on their goals (an independent
forward kinematics, numpy_chain, of the streamed joints).
"""

import contextlib
import json
from pathlib import Path as FilePath
import subprocess
import sys
import tempfile
import time

from builtin_interfaces.msg import Time
from cli_helpers import assert_one_line_error
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from nav_msgs.msg import Path
from node_harness import in_process_node, node_env, Probe, REPO, running_node
import numpy as np
from numpy_chain import NumpyChain
from pybullet_urdfs import pybullet_urdfs
import pytest
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

NODE = '/trajectory_generator'
TIMEOUT = 120  # s per command: generous, the machine is shared
NAMES = ['joint_1', 'joint_2', 'joint_3']


class StandIn:
    """The node's side of a line or an arc: the Path in; status, plan and joint states out."""

    def __init__(self, node) -> None:
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.paths: list[tuple[str, Path]] = []
        for topic in ('cartesian_path', 'circular_goal'):
            node.create_subscription(Path, f'{NODE}/{topic}',
                                     lambda message, t=topic: self.paths.append((t, message)),
                                     reliable)
        self.status = node.create_publisher(DiagnosticStatus, f'{NODE}/status', reliable)
        self.plan = node.create_publisher(JointTrajectory, f'{NODE}/trajectory', latched)
        self.states = node.create_publisher(JointState, '/joint_states', reliable)
        self.executor = SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def spin_until(self, condition, process: subprocess.Popen, what: str):
        while not condition():
            if process.poll() is not None:
                out, err = process.communicate()
                pytest.fail(f'traj-gen ended ({process.returncode}) before {what}: {out} {err}')
            self.executor.spin_once(timeout_sec=0.05)

    def answer(self, level: bytes, message: str, name: str = NODE, **values: str) -> None:
        self.status.publish(DiagnosticStatus(
            level=level, name=name, message=message,
            values=[KeyValue(key=key, value=value) for key, value in values.items()]))

    def publish_plan(self, stamp_ns: int, end: list) -> None:
        plan = JointTrajectory(joint_names=NAMES, points=[
            JointTrajectoryPoint(positions=[0.0, 0.0, 0.0]), JointTrajectoryPoint(positions=end)])
        plan.header.stamp = Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
        self.plan.publish(plan)

    def finish(self, process: subprocess.Popen) -> subprocess.CompletedProcess:
        self.spin_until(lambda: process.poll() is not None, process, 'its end')
        out, err = process.communicate(timeout=TIMEOUT)
        return subprocess.CompletedProcess(process.args, process.returncode, out, err)


@pytest.fixture
def stand_in():
    with in_process_node('tool_path_stand_in') as node:
        yield StandIn(node)


def start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, '-m', 'traj_gen_ros.cli.main', *args],
                            cwd=REPO, env=node_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_line_publishes_the_path_and_waits_until_at_rest_where_the_plan_ends(stand_in):
    process = start('line', '0.4,0.1,0.3,180,0,0', '0.4,-0.1,0.3,180,0,90', '--degrees',
                    '--frame', 'panda_link0', '--wait', '--json', '--timeout', '60')
    stand_in.spin_until(lambda: stand_in.paths, process, 'a Path')
    (topic, message), = stand_in.paths
    assert topic == 'cartesian_path' and message.header.frame_id == 'panda_link0'
    assert [[p.pose.position.x, p.pose.position.y, p.pose.position.z]
            for p in message.poses] == [[0.4, 0.1, 0.3], [0.4, -0.1, 0.3]]
    orientation = message.poses[1].pose.orientation
    expected = Rotation.from_euler('xyz', [180, 0, 90], degrees=True).as_quat()
    assert abs(np.array([orientation.x, orientation.y, orientation.z, orientation.w])
               @ expected) == pytest.approx(1.0, abs=1e-12)

    stand_in.publish_plan(time.time_ns(), [0.25, -0.5, 1.125])
    ok, error = DiagnosticStatus.OK, DiagnosticStatus.ERROR
    stand_in.answer(error, 'a pose goal', request='pose_goal', frame_id='panda_link0')
    stand_in.answer(error, 'an arc', request='circular_goal', frame_id='panda_link0')
    stand_in.answer(error, 'another frame', request='cartesian_path', frame_id='tool')
    stand_in.answer(ok, 'accepted: profile=line, duration=0.500 s, joints=3',
                    request='cartesian_path', frame_id='panda_link0', duration='0.5',
                    start_delay='0.0', bounded_by='max_linear_velocity')
    stand_in.spin_until(lambda: stand_in.states.get_subscription_count() > 0, process,
                        'its joint_states subscription')
    # At rest at the start, moving, then at rest where the plan ends.
    stream = [([0.0, 0.0, 0.0], [0.0] * 3), ([0.1, -0.2, 0.5], [0.3, -0.6, 1.0]),
              ([0.25, -0.5, 1.125], [0.0] * 3)]
    for positions, velocities in stream[:-1]:
        stand_in.states.publish(JointState(name=NAMES, position=positions,
                                           velocity=velocities))
    deadline = time.monotonic() + TIMEOUT
    while process.poll() is None and time.monotonic() < deadline:  # the last setpoint,
        stand_in.states.publish(JointState(name=NAMES, position=stream[-1][0],  # again
                                           velocity=stream[-1][1]))
        stand_in.executor.spin_once(timeout_sec=0.05)
    result = stand_in.finish(process)
    assert result.returncode == 0, result.stderr
    assert result.stderr == '', result.stderr
    status = json.loads(result.stdout)
    assert status['level'] == 'OK' and status['values']['request'] == 'cartesian_path'
    assert status['values']['bounded_by'] == 'max_linear_velocity'


def test_wait_takes_no_older_plan_for_the_requests(stand_in):
    """A plan latched on ~/trajectory before the request is not its plan: no end to wait for."""
    stand_in.publish_plan(time.time_ns() - 10**9, [0.25, -0.5, 1.125])
    # The timeout covers the CLI's discovery of the node too: 3 s was once too short for it
    # on an idle machine (the CLI gave up before the stand-in matched it).
    process = start('line', '0.4,0.1,0.3', '--wait', '--timeout', '8')
    stand_in.spin_until(lambda: stand_in.paths, process, 'a Path')
    stand_in.answer(DiagnosticStatus.OK, 'accepted: profile=line, duration=0.100 s, joints=3',
                    request='cartesian_path', frame_id='', duration='0.1', start_delay='0.0')
    while process.poll() is None:  # at rest where the older plan ends
        stand_in.states.publish(JointState(name=NAMES, position=[0.25, -0.5, 1.125],
                                           velocity=[0.0] * 3))
        stand_in.executor.spin_once(timeout_sec=0.05)
    result = stand_in.finish(process)
    assert result.stdout == 'OK: accepted: profile=line, duration=0.100 s, joints=3\n'
    assert assert_one_line_error(result, code=3) == (
        'traj-gen line: no answer after 8 s: no /trajectory_generator/trajectory for the '
        'request')


def test_arc_prints_a_refusal_once_and_exits_1(stand_in):
    process = start('arc', '0.05,0.05,0', '0.1,0,0', '--frame', 'panda_hand_tcp',
                    '--timeout', '60')
    stand_in.spin_until(lambda: stand_in.paths, process, 'a Path')
    (topic, message), = stand_in.paths
    assert topic == 'circular_goal' and len(message.poses) == 2
    assert message.header.frame_id == 'panda_hand_tcp'
    reason = ('circular_goal refused: circular_goal: joint path: panda_joint4 would leave its '
              'limits at 62 % of the path')
    stand_in.answer(DiagnosticStatus.ERROR, reason, request='circular_goal',
                    frame_id='panda_hand_tcp')
    result = stand_in.finish(process)
    assert result.returncode == 1, result.stderr
    assert result.stderr == '' and result.stdout == f'ERROR: {reason}\n'


def test_line_without_a_node_exits_3_naming_the_topic():
    result = subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', 'line',
                             '0.3,0,0.5', '--node', '/nobody', '--timeout', '1'], cwd=REPO,
                            env=node_env(), capture_output=True, text=True, timeout=TIMEOUT)
    assert assert_one_line_error(result, code=3) == (
        'traj-gen line: no answer after 1 s: /nobody is not subscribed to '
        '/nobody/cartesian_path (is the node running, with the same ROS_DOMAIN_ID?)')


# ---------------------------------------------------------------- the real generator

PANDA = [f'panda_joint{index}' for index in range(1, 8)]
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
TOOL = 'panda_grasptarget'


@contextlib.contextmanager
def panda_node(urdf: str):
    values = {'joints': PANDA, 'initial_positions': READY, 'max_velocity': [1.5],
              'max_acceleration': [3.0], 'robot_description': urdf, 'blend_radius': 0.01}
    with tempfile.TemporaryDirectory() as folder:
        path = FilePath(folder) / 'panda.yaml'
        path.write_text(json.dumps({'/**': {'ros__parameters': values}}))
        with running_node('--params-file', str(path)):
            probe = Probe()
            try:
                probe.wait_ready(30.0)
                yield probe
            finally:
                probe.destroy_node()


def tool_at_rest(probe: Probe, chain: NumpyChain, plans: int = 0) -> np.ndarray:
    """Return the tool pose at rest after plan number ``plans`` (the probe spins only here)."""
    probe.spin_until(lambda: len(probe.trajectories) >= plans, 20.0, f'plan {plans}')
    return chain.pose(TOOL, dict(zip(PANDA, probe.wait_at_rest(20.0), strict=True)))


def traj_gen(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', *args], cwd=REPO,
                          env=node_env(), capture_output=True, text=True, timeout=TIMEOUT)


def errors(first: np.ndarray, second: np.ndarray) -> tuple[float, float]:
    angle = Rotation.from_matrix(first[:3, :3].T @ second[:3, :3]).magnitude()
    return float(np.linalg.norm(first[:3, 3] - second[:3, 3])), float(angle)


def test_line_and_arc_move_the_real_generator_onto_their_goals(request):
    urdf = pybullet_urdfs(request.config)['panda'].read_text()
    chain = NumpyChain(urdf)
    with panda_node(urdf) as probe:
        here = tool_at_rest(probe, chain)
        # Two corners in the tool's frame at the start: 3 cm along its z, then 3 cm along x.
        plans = len(probe.trajectories)
        result = traj_gen('line', '0,0,0.03', '0.03,0,0.03', '--frame', TOOL, '--wait',
                          '--timeout', '60')
        assert result.returncode == 0, result.stderr
        assert result.stdout.startswith('OK: accepted: profile=line, duration='), result.stdout
        assert '(speed bounded by ' in result.stdout
        jog = np.eye(4)
        jog[:3, 3] = [0.03, 0.0, 0.03]
        reached = tool_at_rest(probe, chain, plans + 1)
        distance, angle = errors(reached, here @ jog)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)

        # An arc in the base frame: through 5 cm along +x and +y to 10 cm along +x, the
        # tool turning 0.3 rad about the base z on the way.
        start = reached[:3, 3]
        turn = Rotation.from_euler('z', 0.3) * Rotation.from_matrix(reached[:3, :3])
        interim = ','.join(f'{value:.9f}' for value in start + [0.05, 0.05, 0.0])
        goal = ','.join(f'{value:.9f}' for value in [*(start + [0.1, 0.0, 0.0]),
                                                     *turn.as_quat()])
        plans = len(probe.trajectories)
        result = traj_gen('arc', interim, goal, '--wait', '--json', '--timeout', '60')
        assert result.returncode == 0, result.stderr
        status = json.loads(result.stdout)
        assert status['values']['request'] == 'circular_goal'
        assert status['values']['profile'] == 'arc'
        target = np.eye(4)
        target[:3, :3], target[:3, 3] = turn.as_matrix(), start + [0.1, 0.0, 0.0]
        distance, angle = errors(tool_at_rest(probe, chain, plans + 1), target)
        assert distance < 1e-4 and angle < 1e-3, (distance, angle)
