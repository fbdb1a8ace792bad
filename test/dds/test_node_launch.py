"""Integration: namespaced/remapped launches, sim time, signals and bad configuration."""

import signal

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import generator_session, JOINTS, NodeProcess, Probe, running_node, stamp_ns
import numpy as np
import pytest
import rclpy
from rosgraph_msgs.msg import Clock


def test_namespaced_and_remapped_launch():
    with generator_session('-r', '__ns:=/arm', '-r', '__node:=gen',
                           '-r', 'joint_states:=setpoints', '-r', '~/goal:=command',
                           generator='/arm/gen', joint_states='/arm/setpoints',
                           goal='/arm/command') as probe:
        assert probe.count_publishers('/joint_states') == 0
        status, trajectory = probe.goal({'joint_3': 0.2})
        assert status.level == DiagnosticStatus.OK, status.message
        assert status.name == '/arm/gen'
        final = probe.wait_at_rest()
        assert final[2] == pytest.approx(0.2, abs=1e-12)
        assert list(trajectory.joint_names) == JOINTS


def test_sim_time_stamps_follow_the_clock_topic():
    with running_node('-p', 'use_sim_time:=true'):
        probe = Probe()
        clock = probe.create_publisher(Clock, '/clock', 10)
        sim_ns = [1000 * 10**9]

        def tick():
            sim_ns[0] += 10**7  # 10 ms of sim time per wall tick
            clock.publish(Clock(clock=rclpy.time.Time(nanoseconds=sim_ns[0]).to_msg()))

        probe.create_timer(0.01, tick)
        probe.spin_until(lambda: len(probe.states) >= 20, 20.0, 'sim-time JointStates')
        stamps = np.array([stamp_ns(s.header.stamp) for s in probe.states])
        assert np.all(stamps >= 1000 * 10**9) and np.all(stamps <= sim_ns[0])
        assert np.all(np.diff(stamps) > 0)
        probe.destroy_node()


def test_sigterm_ends_cleanly():
    with running_node(sig=signal.SIGTERM):
        probe = Probe()
        probe.wait_ready()
        probe.destroy_node()


@pytest.mark.parametrize('override, reason', [
    ('profile:=septic', "profile must be one of lspb, cubic, quintic, scurve; got 'septic'"),
    ('max_velocity:=[1.0, 2.0]', 'max_velocity has 2 values but there are 6 joints'),
    ('initial_positions:=[0.0]', 'initial_positions has 1 values but joints has 6'),
])
def test_invalid_configuration_exits_with_the_reason(override, reason):
    node = NodeProcess('-p', override)
    try:
        code = node.process.wait(30)
        output = node.output()
    finally:
        node.close()
    assert code == 1, output
    assert f'invalid parameters: {reason}' in output
    assert 'Traceback' not in output
