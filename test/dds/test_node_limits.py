"""
Integration: joint limits from the robot's URDF and the parameters (issue 13).

The URDF reaches the generator as robot_state_publisher sends it: ``std_msgs/String`` on
``robot_description``, reliable and transient local, published by a second process that
starts *before* the generator (so only durability can deliver it). A second test gives the
URDF as the ``robot_description`` parameter instead.
"""

import contextlib
from pathlib import Path
import re
import subprocess
import sys
import tempfile
import textwrap

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from node_harness import (
    CONFIG,
    end_process,
    node_env,
    Probe,
    running_node,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

DESCRIPTION_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)


def arm(joint_1: str = 'lower="-3.5" upper="3.5"') -> str:
    """Return a URDF for joint_1…joint_5 (joint_6 absent) with a fixed tool joint."""
    joints = [('joint_1', 'revolute', f'<limit {joint_1} effort="9" velocity="1.5"/>'),
              ('joint_2', 'revolute', '<limit lower="-0.5" upper="2.0" effort="9" '
                                      'velocity="10"/>'),
              ('joint_3', 'revolute', '<limit lower="-1" upper="1" effort="9" velocity="10"/>'),
              ('joint_4', 'continuous', '<limit effort="9" velocity="2.5"/>'),
              ('joint_5', 'prismatic', '<limit lower="0" upper="0.4" effort="9" '
                                       'velocity="0.5"/>'),
              ('tool_joint', 'fixed', '')]
    links = ''.join(f'<link name="link_{index}"/>' for index in range(len(joints) + 1))
    body = ''.join(
        f'<joint name="{name}" type="{kind}"><parent link="link_{index}"/>'
        f'<child link="link_{index + 1}"/><axis xyz="0 0 1"/>{limit}</joint>'
        for index, (name, kind, limit) in enumerate(joints))
    return f'<?xml version="1.0"?><robot name="arm">{links}{body}</robot>'


PUBLISHER = textwrap.dedent("""
    import sys
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node('robot_state_publisher_stand_in')
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_publisher(String, 'robot_description', qos).publish(
        String(data=sys.stdin.read()))
    print('published', flush=True)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, Exception):
        pass
""")


def goal_status(probe, positions):
    status, _ = probe.goal(positions)
    return status


def wait_for_log(node, text: str, probe) -> str:
    """Spin the probe until the generator's log contains ``text``; return the log."""
    return probe.spin_until(lambda: text in node.output() and node.output(), 20.0,
                            f'the log line {text!r}')


@contextlib.contextmanager
def session(*ros_args: str):
    """Run a generator and a ready probe; yield both (the node's log is ``node.output()``)."""
    with running_node(*ros_args) as node:
        probe = Probe()
        try:
            probe.wait_ready()
            yield node, probe
        finally:
            probe.destroy_node()


@pytest.fixture(scope='module')
def published_first():
    """Publish the URDF from a second process, before the generator exists."""
    process = subprocess.Popen([sys.executable, '-c', PUBLISHER], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, env=node_env(), text=True)
    try:
        process.stdin.write(arm())
        process.stdin.close()
        assert process.stdout.readline().strip() == 'published'
        yield process
    finally:
        end_process(process)
        process.stdout.close()


def test_urdf_from_the_topic_limits_goals_via_points_and_plans(published_first):
    del published_first
    with session() as (node, probe):
        log = wait_for_log(node, 'joint limits (URDF: topic /robot_description)', probe)
        assert 'joint_1: [-3.5, 3.5] rad (URDF), 1.5 rad/s (URDF)' in log
        assert 'joint_4: position unlimited, 2.5 rad/s (URDF)' in log
        assert 'joint_6: position unlimited, 3 rad/s (max_velocity)' in log
        assert "has no joint ['joint_6']" in log

        # A goal and a via point outside the URDF range are refused, naming joint and range.
        status = goal_status(probe, {'joint_2': 2.5})
        assert status.level == DiagnosticStatus.ERROR
        assert ("goal position 2.5 rad for joint 'joint_2' is outside its range [-0.5, 2] "
                'rad (lower from URDF; upper from URDF)') in status.message, status.message
        status, _ = probe.request(via_message(['joint_3'], [([0.5], 1.0), ([1.2], 2.0)]))
        assert status.level == DiagnosticStatus.ERROR
        assert "via point 1 position 1.2 rad for joint 'joint_3' is outside its range " \
               '[-1, 1] rad' in status.message, status.message

        # The URDF velocity limit (1.5) lowers max_velocity (2) for joint_1.
        status, plan = probe.goal({'joint_1': 1.0})
        assert status.level == DiagnosticStatus.OK, status.message
        peak = np.abs(trajectory_arrays(plan)[2][:, 0]).max()
        assert 1.45 < peak <= 1.5 * (1 + 1e-9)
        probe.wait_at_rest()

        # A new URDF on the topic narrows joint_1 to [-1, 2] while joint_1 moves to 3.4 at
        # a gentle acceleration (1 rad/s^2): a goal just ahead must brake past 2.
        probe.require_parameters(max_acceleration=[1.0, 4.0, 4.0, 6.0, 6.0, 6.0])
        status, _ = probe.goal({'joint_1': 3.4})
        assert status.level == DiagnosticStatus.OK, status.message
        update = probe.create_publisher(String, '/robot_description', DESCRIPTION_QOS)
        update.publish(String(data=arm('lower="-1" upper="2"')))
        wait_for_log(node, 'joint_1: [-1, 2] rad (URDF)', probe)

        def fast_enough():  # braking at 1 rad/s^2 from >= 0.95 rad/s takes >= 0.45 rad
            q, v = probe.position()[0], probe.latest().velocity[0]
            return q >= 1.6 and v >= 0.95 and q
        position = probe.spin_until(fast_enough, 10.0, 'joint_1 beyond 1.6 rad, fast')
        status = goal_status(probe, {'joint_1': min(position + 0.05, 1.95)})
        assert status.level == DiagnosticStatus.ERROR
        assert re.search(r"the plan would take joint 'joint_1' to [0-9.]+ rad, outside its "
                         r'range \[-1, 2\] rad', status.message), status.message
        # ~/stop always runs, even beyond the range; from there a goal may come back in.
        assert probe.stop().success
        rest = probe.wait_at_rest()
        status, _ = probe.goal({'joint_1': 1.5})
        assert status.level == DiagnosticStatus.OK, (rest, status.message)
        probe.wait_at_rest()
        probe.require_parameters(max_acceleration=[4.0, 4.0, 4.0, 6.0, 6.0, 6.0])

        # /diagnostics says where the limits came from; an invalid URDF on the topic is
        # refused there and in the log, and the limits in force stay.
        seen = []
        probe.create_subscription(DiagnosticArray, '/diagnostics', seen.append, 10)

        def diagnostics(condition):
            def found():
                values = [{kv.key: kv.value for kv in status.values} | {
                    '': status.message, 'level': status.level}
                    for array in seen for status in array.status]
                return next((v for v in values if condition(v)), None)
            return probe.spin_until(found, 15.0, 'a matching /diagnostics message')
        values = diagnostics(lambda v: v['robot_description'] == 'topic /robot_description')
        assert 'joint_1: [-1, 2] rad (URDF), 1.5 rad/s (URDF)' in values['limits']
        update.publish(String(data='<robot name="broken"><joint name="x"/></robot>'))
        values = diagnostics(lambda v: 'robot_description refused' in v)
        assert values['level'] == DiagnosticStatus.WARN
        assert 'robot_description on /robot_description refused: invalid URDF' in values['']
        assert values['robot_description refused'].startswith(
            'robot_description on /robot_description refused: invalid URDF'), values
        wait_for_log(node, 'robot_description on /robot_description refused', probe)
        status = goal_status(probe, {'joint_2': 2.5})
        assert status.level == DiagnosticStatus.ERROR and 'upper from URDF' in status.message
        probe.destroy_publisher(update)


def test_urdf_and_limits_as_parameters():
    with tempfile.TemporaryDirectory() as folder:
        params = Path(folder) / 'robot.yaml'
        urdf = textwrap.indent(arm(), ' ' * 8)
        params.write_text(f'/**:\n  ros__parameters:\n    robot_description: |\n{urdf}\n')
        with session('--params-file', str(params)) as (node, probe):
            wait_for_log(node, 'joint limits (URDF: parameter robot_description)', probe)
            status = goal_status(probe, {'joint_2': -0.7})
            assert status.level == DiagnosticStatus.ERROR
            assert "joint 'joint_2' is outside its range [-0.5, 2] rad" in status.message
            # A tighter parameter wins, and is named as the source.
            probe.require_parameters(max_position=[9.0, 9.0, 0.96, 9.0, 9.0, 9.0])
            # Quintic through 0.9 (1 s) and 0.95 (3 s) overshoots to 0.965 between them.
            status, _ = probe.request(via_message(['joint_3'], [([0.9], 1.0), ([0.95], 3.0)]))
            assert status.level == DiagnosticStatus.ERROR
            assert ("the plan would take joint 'joint_3' to 0.964978 rad, outside its range "
                    '[-1, 0.96] rad (lower from URDF; upper from parameter max_position)'
                    ) in status.message, status.message
            status, _ = probe.request(via_message(['joint_3'], [([0.9], 1.0), ([0.95], 3.5)]))
            assert status.level == DiagnosticStatus.ERROR  # still overshoots
            points = [([0.5], 1.0), ([0.95], 3.0)]
            status, plan = probe.request(via_message(['joint_3'], points))
            assert status.level == DiagnosticStatus.OK, status.message
            assert trajectory_arrays(plan)[1][:, 2].max() <= 0.96
            probe.wait_at_rest()
            # Limits that leave no valid position, and an invalid URDF, are refused.
            refused = probe.set_parameters(min_position=[0.5, -9.0, 0.97, -9.0, -9.0, -9.0])
            assert not refused[0].successful
            assert "joint 'joint_3' has no valid position" in refused[0].reason
            refused = probe.set_parameters(robot_description='<robot name="x"><joint/>')
            assert not refused[0].successful and 'invalid URDF' in refused[0].reason
            # Clearing the URDF leaves only the parameters.
            probe.require_parameters(robot_description='', max_position=[float('inf')])
            status = goal_status(probe, {'joint_2': -0.7})
            assert status.level == DiagnosticStatus.OK, status.message
            probe.wait_at_rest()


def test_the_config_file_declares_no_position_limits():
    text = CONFIG.read_text()
    assert 'min_position: [-.inf]' in text and 'max_position: [.inf]' in text
