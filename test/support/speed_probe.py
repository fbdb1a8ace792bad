"""
A node under the speed override, and a probe that sends factors and reads /diagnostics.

Skips the importing test module where control_msgs is not importable (the factor's type is
control_msgs/SpeedScalingFactor).
"""

import contextlib

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from node_harness import (
    held_back_ns,
    Probe,
    running_node,
    speed_scaling_factor_type,
    stamp_ns,
)
import numpy as np
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

SpeedScalingFactor = speed_scaling_factor_type()  # skips the test module without it


#: The goal of joint_1 (rad) from 0.
GOAL = 2.0
#: The rate the speed tests run the node at (Hz).
RATE_HZ = 100.0


class SpeedProbe(Probe):
    """A Probe with a factor publisher (reliable, transient local) and /diagnostics."""

    def __init__(self):
        super().__init__()
        self.factor_pub = self.create_publisher(
            SpeedScalingFactor, '/trajectory_generator/speed_scaling_input',
            QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self.diagnostics = []
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)
        self.spin_until(lambda: self.factor_pub.get_subscription_count() >= 3, 10.0,
                        'the speed_scaling_input subscriptions')  # node/speed/input.py

    def factor(self, value: float) -> int:
        """Publish a factor; return how many samples the stream had published by then."""
        count = len(self.states)
        self.factor_pub.publish(SpeedScalingFactor(factor=float(value)))
        return count

    def wait_velocity(self, condition, what, timeout=10.0):
        """Wait for a sample whose joint_1 velocity meets ``condition``; return its index."""
        start = len(self.states)

        def found():
            for index in range(start, len(self.states)):
                if condition(self.states[index].velocity[0]):
                    return index + 1  # truthy
            return None
        return self.spin_until(found, timeout, what) - 1

    def speed_values(self, condition, timeout=10.0):
        """Wait for a /diagnostics status whose values meet ``condition``; return them."""
        def found():
            for array in self.diagnostics:
                for status in array.status:
                    values = {kv.key: kv.value for kv in status.values}
                    if 'speed scaling in force' in values and condition(values):
                        return values
            return None
        return self.spin_until(found, timeout, '/diagnostics speed values')

    def start_goal(self):
        """Send the goal; return its start (ns, the ~/trajectory stamp)."""
        status, trajectory = self.goal({'joint_1': GOAL})
        assert status.level == DiagnosticStatus.OK, status.message
        return stamp_ns(trajectory.header.stamp)

    def samples(self, first=0, rate_hz=RATE_HZ):
        """
        Return times (s), positions and velocities of joint_1 from sample ``first`` on.

        The times are the stamps (s) less what late ticks held the node's stream clock
        back since sample ``first`` (``held_back_ns``, the node at ``rate_hz``): the
        schedule's time after it.
        """
        stamps = np.array([stamp_ns(s.header.stamp) for s in self.states], dtype=np.int64)
        held = held_back_ns(stamps, rate_hz)
        times = (stamps[first:] - (held[first:] - held[max(first - 1, 0)])) * 1e-9
        return (times, np.array([s.position[0] for s in self.states[first:]]),
                np.array([s.velocity[0] for s in self.states[first:]]))


@contextlib.contextmanager
def speed_session(*ros_args):
    """Run the node with ``ros_args``; yield a ready :class:`SpeedProbe`."""
    with running_node(*ros_args):
        probe = SpeedProbe()
        try:
            probe.wait_ready()
            yield probe
        finally:
            probe.destroy_node()
