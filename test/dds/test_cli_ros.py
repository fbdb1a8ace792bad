"""traj-gen goal/via/plot --topic as a user runs them, against a real generator node."""

import json
import math
import subprocess
import sys

from cli_helpers import assert_one_line_error, legend_covers, marks_of
from diagnostic_msgs.msg import DiagnosticStatus
import matplotlib.image as mpimg
import matplotlib.pyplot as plt
from node_harness import (
    generator_session,
    JOINTS,
    node_env,
    REPO,
    seconds,
    trajectory_arrays,
)
import numpy as np
import pytest
from traj_gen_ros.cli.common import joint_names
from traj_gen_ros.cli.ros import goal_from_args, topic_figure, via_from_args, via_marks
from traj_gen_ros.node.settings.parameters import DEFAULT_JOINTS
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

TIMEOUT = 120  # s per command: generous, the machine is shared


def traj_gen(*args: str) -> subprocess.CompletedProcess:
    """Run `traj-gen ARGS` in the test's isolated ROS domain (node_harness sets it)."""
    return subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', *args], cwd=REPO,
                          env=node_env(), capture_output=True, text=True, timeout=TIMEOUT)


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        yield probe


@pytest.fixture
def rest(probe):
    return probe.wait_at_rest(timeout=30)


def now_ns(probe) -> int:
    return probe.get_clock().now().nanoseconds


def position_after(probe, stamp_ns):
    """
    Return the position of a JointState stamped after ``stamp_ns``, spinning to receive it.

    The probe does not spin while a command runs, so its queue still holds older states.
    """
    def newer():
        return next((s for s in reversed(probe.states)
                     if stamp_ns_of(s) >= stamp_ns), None)
    return np.array(probe.spin_until(newer, 30, 'a JointState after the command').position)


def stamp_ns_of(state) -> int:
    return state.header.stamp.sec * 1_000_000_000 + state.header.stamp.nanosec


def statuses_of(probe, kind):
    return [s for s in probe.statuses
            if any(v.key == 'request' and v.value == kind for v in s.values)]


def test_goal_moves_the_node_and_prints_its_ok_status(probe, rest):
    answered = len(statuses_of(probe, 'goal'))
    result = traj_gen('goal', 'joint_2=0.4', 'joint_5=-20', '--degrees', '--wait',
                      '--timeout', '30')
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith('OK: accepted: profile=quintic'), result.stdout
    assert result.stderr == ''
    # --wait returned after the motion: the stream already holds the goal.
    target = rest.copy()
    target[1], target[4] = math.radians(0.4), math.radians(-20)
    assert position_after(probe, now_ns(probe)) == pytest.approx(target, abs=1e-9)
    ours = statuses_of(probe, 'goal')[answered:]
    assert len(ours) == 1 and ours[0].level == DiagnosticStatus.OK

    # plot --topic's figure of this plan: the legend beside it covers no line (joint_5's
    # at -20° included), and start and goal are marked.
    plan = probe.spin_until(lambda: next(
        (t for t in reversed(probe.trajectories) if t.points
         and t.points[-1].positions[4] == pytest.approx(math.radians(-20))), None), 30, 'plan')
    figure = topic_figure(plan, '/trajectory_generator/trajectory', True, (900, 900))
    try:
        assert legend_covers(figure) == []
        times, positions = marks_of(figure, 'start, goal')
        assert times[4] == pytest.approx([0.0, seconds(plan.points[-1].time_from_start)])
        assert positions[4] == pytest.approx([math.degrees(rest[4]), -20.0])
    finally:
        plt.close(figure)


def refusal_line(result: subprocess.CompletedProcess) -> str:
    """Return the one line of a refusal: exit 1, once on stdout, nothing on stderr."""
    assert result.returncode == 1, (result.returncode, result.stdout, result.stderr)
    assert result.stderr == ''
    lines = result.stdout.splitlines()
    assert len(lines) == 1, result.stdout
    return lines[0]


def test_goal_refusal_exits_1_and_prints_the_reason_once(probe, rest):
    result = traj_gen('goal', 'joint_9=1.0', '--timeout', '30')
    line = refusal_line(result)
    assert line == ("ERROR: goal refused: goal names unknown joint 'joint_9'; known joints: "
                    f'{JOINTS}'), line
    assert position_after(probe, now_ns(probe)) == pytest.approx(rest)

    status = json.loads(traj_gen('goal', 'joint_9=1.0', '--timeout', '30', '--json').stdout)
    assert status['level'] == 'ERROR' and status['values']['request'] == 'goal'
    assert status['message'] == line.removeprefix('ERROR: ')


def test_via_passes_the_points_then_plot_topic_records_the_plan(probe, rest, tmp_path):
    result = traj_gen('via', '--joints', 'joint_1', 'joint_3', '--point', '0.2', '-0.1', '@1',
                      '--point', '0.5', '0.3', '@2', '--wait', '--json', '--timeout', '30')
    assert result.returncode == 0, result.stderr
    status = json.loads(result.stdout)
    assert status['level'] == 'OK' and status['name'] == '/trajectory_generator'
    assert status['values']['request'] == 'via_points'
    assert status['values']['frame_id'].startswith('traj-gen/')  # our request's token, echoed
    assert float(status['values']['duration']) == pytest.approx(2.0)
    position = position_after(probe, now_ns(probe))
    assert position[[0, 2]] == pytest.approx([0.5, 0.3], abs=1e-9)

    # The node's plan, as the probe received it: through the via point at t = 1 s.
    plan = probe.spin_until(lambda: next(
        (t for t in reversed(probe.trajectories) if t.points
         and abs(seconds(t.points[-1].time_from_start) - 2.0) < 1e-6), None), 30, 'the plan')
    times, positions, _, _ = trajectory_arrays(plan)
    assert times[-1] == pytest.approx(2.0)
    at_one = int(np.argmin(np.abs(times - 1.0)))
    assert positions[at_one, [0, 2]] == pytest.approx([0.2, -0.1], abs=1e-6)

    # A late subscriber gets the current plan (transient local) and plots it.
    output = tmp_path / 'node.png'
    result = traj_gen('plot', '--topic', '/trajectory_generator/trajectory', '-o', str(output),
                      '--size', '640x720', '--json', '--timeout', '30')
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert info['joints'] == len(JOINTS) and len(info['panels']) == 3
    assert mpimg.imread(output).shape[:2] == (720, 640)


def test_via_plot_marks_the_points_sent_on_the_nodes_plan(probe, rest, tmp_path):
    output = tmp_path / 'via.png'
    result = traj_gen('via', '--joints', 'joint_1', 'joint_3', '--point', '0.3', '-0.2', '@1',
                      '--point', '0.1', '0.2', '@2', '--plot', str(output), '--size', '700x800',
                      '--timeout', '30')
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith('OK: accepted') and lines[1].startswith(f'wrote {output} ')
    assert mpimg.imread(output).shape[:2] == (800, 700)

    # What the plot marks, from the node's plan as the probe received it.
    plan = probe.spin_until(lambda: next(
        (t for t in reversed(probe.trajectories) if t.points
         and list(t.points[-1].positions)[2] == pytest.approx(0.2)), None), 30, 'the plan')
    request = JointTrajectory(joint_names=['joint_1', 'joint_3'], points=[
        JointTrajectoryPoint(positions=[0.3, -0.2]), JointTrajectoryPoint(positions=[0.1, 0.2])])
    times, positions, _, _ = trajectory_arrays(plan)
    mark_times, mark_positions = via_marks(times, positions, list(plan.joint_names), request)
    assert mark_times == pytest.approx([0.0, 1.0, 2.0], abs=1e-9)  # 1 s is a sample at 100 Hz
    assert mark_positions[1, [0, 2]] == pytest.approx([0.3, -0.2], abs=1e-12)
    assert mark_positions[1, 1] == pytest.approx(positions[100, 1])  # unnamed: the plan's
    figure = topic_figure(plan, '/trajectory_generator/trajectory', False, (700, 800),
                          request=request)
    try:
        assert marks_of(figure, 'via points')[0] == [[1.0]] * len(JOINTS)  # one per joint
        assert legend_covers(figure) == []
    finally:
        plt.close(figure)


def test_via_refusal_exits_1_with_the_reason(probe, rest):
    result = traj_gen('via', '--joints', 'joint_1', '--point', '0.5', '@2', '--point', '0.2',
                      '@1', '--timeout', '30')
    line = refusal_line(result)
    assert line.startswith('ERROR: via_points refused: '), line
    assert position_after(probe, now_ns(probe)) == pytest.approx(rest)


def test_no_node_or_no_message_exits_3():
    line = assert_one_line_error(traj_gen('goal', 'joint_1=1', '--node', '/nobody',
                                          '--timeout', '1'), code=3)
    assert '/nobody/goal' in line
    line = assert_one_line_error(traj_gen('plot', '--topic', '/nobody/trajectory', '-o',
                                          'unused.png', '--timeout', '1'), code=3)
    assert '/nobody/trajectory' in line
    assert not (REPO / 'unused.png').exists()


def test_goal_and_via_words_become_names_positions_and_times():
    names, positions = goal_from_args(['joint_2=0.4', 'joint_5=-90'], degrees=True)
    assert names == ['joint_2', 'joint_5']
    assert positions == pytest.approx([math.radians(0.4), -math.pi / 2])
    points = via_from_args(['joint_1', 'joint_3'], [['0.2', '-0.1', '@1'], ['0.5', '0.3', '@2.5']],
                           degrees=False)
    assert points == [([0.2, -0.1], 1.0), ([0.5, 0.3], 2.5)]
    assert via_from_args(['joint_1'], [['1'], ['2']], degrees=False) == [([1.0], 0.0),
                                                                         ([2.0], 0.0)]


def test_offline_joint_names_are_the_nodes_default_joints():
    assert joint_names(len(DEFAULT_JOINTS)) == DEFAULT_JOINTS
    assert joint_names(2) == ['joint_1', 'joint_2']
