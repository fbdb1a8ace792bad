"""Integration: /diagnostics over DDS, as rqt_robot_monitor reads it (issue 13)."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from node_harness import generator_session
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

NAME = 'trajectory_generator: Trajectory generator'
KEYS = ['stream rate (Hz)', 'rate_hz', 'joints', 'profile', 'motion', 'limits',
        'robot_description', 'accepted', 'refused', 'superseded', 'late ticks', 'held back (s)',
        'speed_scaling (parameter)', 'speed_scaling_input (topic)', 'speed scaling in force',
        'speed_scaling_input ignored']


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        probe.diagnostics = []
        probe.create_subscription(DiagnosticArray, '/diagnostics', probe.diagnostics.append,
                                  QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        yield probe


def next_status(probe, condition=lambda values: True, timeout=15.0):
    """Wait for a new /diagnostics message whose values satisfy ``condition``."""
    seen = len(probe.diagnostics)

    def found():
        for array in probe.diagnostics[seen:]:
            for status in array.status:
                values = {item.key: item.value for item in status.values}
                if status.name == NAME and condition(values):
                    return status, values
        return None
    return probe.spin_until(found, timeout, 'a matching /diagnostics message')


def test_diagnostics_report_the_node(probe):
    status, values = next_status(probe, lambda v: v['stream rate (Hz)'] != 'not measured yet')
    assert list(values) == KEYS
    assert status.hardware_id == ''
    assert values['rate_hz'] == '100' and values['joints'] == '6'
    assert values['profile'] == 'quintic' and values['motion'] == 'holding'
    assert values['robot_description'] == 'none'
    assert values['limits'].startswith('joint_1: position unlimited, 2 rad/s (max_velocity);')
    rate = float(values['stream rate (Hz)'])
    assert 0.0 < rate < 150.0
    if status.level == DiagnosticStatus.OK:
        assert status.message.startswith('streaming 6 joints at ') and 'holding' in status.message
    else:  # a busy machine may slow the stream below 90 %: then it says so
        assert status.level == DiagnosticStatus.WARN
        assert 'is below 90% of rate_hz 100' in status.message, status.message


def test_counts_and_motion_follow_the_requests(probe):
    _, before = next_status(probe)
    refused = int(before['refused'])
    status, _ = probe.request(JointState(name=['elbow'], position=[0.1]))
    assert status.level == DiagnosticStatus.ERROR
    _, after = next_status(probe, lambda v: int(v['refused']) == refused + 1)
    assert after['accepted'] == before['accepted']
    accepted = int(after['accepted'])
    start = probe.wait_at_rest()
    status, _ = probe.goal({'joint_4': start[3] + 8.0})  # about 5 s at 3 rad/s
    assert status.level == DiagnosticStatus.OK
    _, moving = next_status(probe, lambda v: v['motion'].startswith('quintic, '))
    assert moving['motion'].endswith(' s left') and int(moving['accepted']) == accepted + 1
    probe.wait_at_rest(timeout=20)
    next_status(probe, lambda v: v['motion'] == 'holding')
