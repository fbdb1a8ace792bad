"""
Reliability (issue 5): parameter changes mid-motion; subscribers that come and go.

Each test drives the node subprocess (isolated domain) from a probe over DDS.
"""


from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    generator_session,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    stamp_ns,
    trajectory_arrays,
)
import numpy as np
import pytest
import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        yield probe


def assert_no_jump(probe, start_ns, v_max=MAX_VELOCITY, a_max=MAX_ACCELERATION, gap=0.1):
    """Finite, no position/velocity step beyond the limits, no gap longer than ``gap``."""
    times, q, v = probe.states_between(start_ns)
    assert len(times) > 10
    steps = np.diff(times)
    assert np.all(steps > 0) and steps.max() <= gap, steps.max()
    assert np.isfinite(q).all() and np.isfinite(v).all()
    assert (np.abs(np.diff(q, axis=0)) - v_max * steps[:, None] * 1.001 - 1e-9).max() <= 0
    assert (np.abs(np.diff(v, axis=0)) - a_max * steps[:, None] * 1.001 - 1e-9).max() <= 0
    return times, q, v


def follows(probe, trajectory, until_ns, rate_hz=100.0):
    """
    Assert the stream between the plan's start and ``until_ns`` is that plan.

    On the node's stream clock (late ticks hold it back), the node at ``rate_hz``.
    """
    start = stamp_ns(trajectory.header.stamp)
    t, q, _, _ = trajectory_arrays(trajectory)
    times, positions, _ = probe.states_between(start, until_ns, rate_hz=rate_hz)
    inside = times <= t[-1]
    expected = np.column_stack([np.interp(times[inside], t, q[:, j]) for j in range(6)])
    # Linear interpolation of the 100 Hz samples: within a_max * dt^2 / 8 of the curve.
    assert np.allclose(positions[inside], expected, atol=6.0 * 0.01 ** 2 / 8 + 1e-9)


def test_parameter_changes_mid_motion_apply_from_the_next_request(probe):
    probe.require_parameters(profile='quintic', rate_hz=100.0, max_velocity=[2.0, 2.0, 2.0,
                             3.0, 3.0, 3.0], lspb_acceleration=0.0)
    rest = probe.wait_at_rest()
    status, first = probe.goal({'joint_1': rest[0] + 2.0, 'joint_4': rest[3] - 2.0})
    assert status.level == DiagnosticStatus.OK
    start = stamp_ns(first.header.stamp)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > start + 0.3e9, 5.0,
                     'mid-motion')
    # Rate, profile and limits change while the motion runs; a bad value is refused.
    probe.require_parameters(rate_hz=250.0)
    changed = probe.get_clock().now().nanoseconds  # the node streams at 250 Hz from here
    probe.require_parameters(profile='lspb')
    probe.require_parameters(max_velocity=0.5)
    refused = probe.set_parameters(lspb_acceleration=50.0)
    assert not refused[0].successful and 'above max_acceleration' in refused[0].reason
    end = start + int(trajectory_arrays(first)[0][-1] * 1e9)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > end + 0.1e9, 10.0,
                     'the end of the first motion')
    follows(probe, first, end, lambda stamp: 100.0 if stamp < changed else 250.0)
    # The executing plan went on unchanged.
    times, _, _ = assert_no_jump(probe, start - int(0.05e9))
    late = times > (end - start) * 1e-9 + 0.05
    assert np.median(np.diff(times[late])) == pytest.approx(1 / 250.0, rel=0.1)
    # The next request uses the new profile and limit.
    status, second = probe.goal({'joint_1': rest[0]})
    assert status.level == DiagnosticStatus.OK, status.message
    assert 'profile=lspb' in status.message
    _, _, v, _ = trajectory_arrays(second)
    assert np.abs(v).max() <= 0.5 * (1 + 1e-6)
    assert np.diff(trajectory_arrays(second)[0])[0] == pytest.approx(1 / 250.0, abs=1e-9)
    probe.wait_at_rest(timeout=20)
    assert_no_jump(probe, start - int(0.05e9))
    probe.require_parameters(profile='quintic', rate_hz=100.0,
                             max_velocity=[2.0, 2.0, 2.0, 3.0, 3.0, 3.0])


def test_subscribers_coming_and_going_do_not_disturb_the_stream(probe):
    rest = probe.wait_at_rest()
    status, plan = probe.goal({'joint_2': rest[1] + 1.0, 'joint_6': rest[5] - 1.5})
    assert status.level == DiagnosticStatus.OK
    start = stamp_ns(plan.header.stamp)
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    for round_ in range(15):
        visitor = Node(f'visitor_{round_}')
        visitor.create_subscription(JointState, '/joint_states', lambda m: None, reliable)
        visitor.create_subscription(DiagnosticStatus, '/trajectory_generator/status',
                                    lambda m: None, reliable)
        received = []
        visitor.create_subscription(JointTrajectory, '/trajectory_generator/trajectory',
                                    received.append, LATCHED)
        # A late subscriber to ~/trajectory gets the plan being executed.
        deadline = probe.get_clock().now().nanoseconds + int(10e9)
        while not received and probe.get_clock().now().nanoseconds < deadline:
            rclpy.spin_once(visitor, timeout_sec=0.01)
            rclpy.spin_once(probe, timeout_sec=0.0)
        assert received, 'a late subscriber did not get the current plan'
        assert stamp_ns(received[0].header.stamp) == start
        assert len(received[0].points) == len(plan.points)
        visitor.destroy_node()
    probe.wait_at_rest(timeout=10)
    follows(probe, plan, start + int(trajectory_arrays(plan)[0][-1] * 1e9))
    assert_no_jump(probe, start - int(0.05e9))
