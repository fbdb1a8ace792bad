"""
Integration: a stalled node resumes its motion from the last setpoint, no jump (issue 28).

The node process is stopped (SIGSTOP) for 0.3 s in the middle of a motion, as a stalled
machine or a blocked DDS call would stop its stream, then continued. Every setpoint it
publishes must differ from the one before it by no more than the plan moves in
``LATE_PERIODS`` periods, the motion must still end exactly at the goal (that much later),
and ``/diagnostics`` must count the late tick.
"""

import os
import re
import signal
import time

from diagnostic_msgs.msg import DiagnosticArray
from node_harness import MAX_ACCELERATION, MAX_VELOCITY, Probe, running_node, stamp_ns
import numpy as np
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.node.diagnostics.publisher import LATE_LOG_PERIOD
from traj_gen_ros.node.stream.clock import LATE_PERIODS

RATE = 100.0
PERIOD = 1.0 / RATE
STALL = 0.3  # s
GOAL = {'joint_1': 3.0, 'joint_2': -2.0, 'joint_3': 1.0, 'joint_4': 2.5, 'joint_5': -1.0,
        'joint_6': 0.5}
NAME = 'trajectory_generator: Trajectory generator'
HELD_AT_LEAST = STALL - LATE_PERIODS * PERIOD - 0.05  # s


def test_a_stalled_stream_resumes_from_its_last_setpoint_and_counts_the_late_tick():
    with running_node('-p', f'rate_hz:={RATE}') as node:
        probe = Probe()
        try:
            raw, sequence = [], []  # joint_states as published, with DDS sequence numbers
            probe.create_subscription(
                JointState, '/joint_states',
                lambda data, info: (raw.append(data),
                                    sequence.append(info['publication_sequence_number'])),
                QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE), raw=True)
            diagnostics = []
            probe.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append,
                                      QoSProfile(depth=100,
                                                 reliability=ReliabilityPolicy.RELIABLE))
            probe.wait_ready()
            probe.wait_at_rest()
            first = len(raw)
            status, trajectory = probe.goal(GOAL)
            assert status.level == b'\x00', status.message
            start_ns = stamp_ns(trajectory.header.stamp)
            span = trajectory.points[-1].time_from_start
            end_ns = start_ns + span.sec * 1_000_000_000 + span.nanosec
            assert end_ns - start_ns > 2e9  # long enough to stall in the middle of it
            probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > start_ns + 0.6e9,
                             10.0, 'the motion under way')
            os.kill(node.process.pid, signal.SIGSTOP)
            try:
                stopped_until = time.monotonic() + STALL
                while time.monotonic() < stopped_until:
                    rclpy.spin_once(probe, timeout_sec=0.01)
            finally:
                os.kill(node.process.pid, signal.SIGCONT)
            final = probe.wait_at_rest(timeout=15.0)
            at_rest = len(diagnostics)

            def stall_counted():  # in a report from after the motion's end
                for message in diagnostics[at_rest:]:
                    for status in message.status:
                        values = {kv.key: kv.value for kv in status.values}
                        if status.name == NAME and int(values.get('late ticks', '0')) >= 1 \
                                and float(values['held back (s)']) >= HELD_AT_LEAST:
                            return values
                return None
            values = probe.spin_until(stall_counted, 5.0, '/diagnostics counting the late tick')

            def stall_logged():  # at once, or within LATE_LOG_PERIOD of an earlier warning
                gaps = re.findall(r'stream: \d+ late ticks? \(the longest ([0-9.]+) ms',
                                  node.output())
                return any(float(gap) >= STALL * 1e3 * 0.8 for gap in gaps)
            probe.spin_until(stall_logged, LATE_LOG_PERIOD + 5.0, 'the late tick logged')
        finally:
            probe.destroy_node()
    assert np.allclose(final, [GOAL[joint] for joint in sorted(GOAL)], atol=1e-12)
    messages = [deserialize_message(data, JointState) for data in raw[first:]]
    stamps = np.array([stamp_ns(m.header.stamp) for m in messages]) * 1e-9
    positions = np.array([m.position for m in messages])
    velocities = np.array([m.velocity for m in messages])
    consecutive = np.diff(np.array(sequence[first:])) == 1  # a lost sample is not a step
    assert consecutive.any()
    assert np.diff(stamps).max() >= STALL * 0.8  # the stream did stall
    # Each setpoint is at most LATE_PERIODS periods of the plan after the one before it.
    allowed = LATE_PERIODS * PERIOD * 1.001
    position_steps = np.abs(np.diff(positions, axis=0))[consecutive]
    velocity_steps = np.abs(np.diff(velocities, axis=0))[consecutive]
    assert (position_steps - MAX_VELOCITY * allowed).max() <= 1e-9, position_steps.max(axis=0)
    assert (velocity_steps - MAX_ACCELERATION * allowed).max() <= 1e-9, velocity_steps.max(axis=0)
    # It came to rest later than planned, by about what the late ticks held it back.
    moving = np.flatnonzero(np.any(velocities != 0.0, axis=1))
    rest_s = stamps[moving[-1] + 1]
    assert rest_s - end_ns * 1e-9 >= HELD_AT_LEAST
    assert rest_s - end_ns * 1e-9 <= float(values['held back (s)']) + 3 * PERIOD
