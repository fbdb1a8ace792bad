"""
Integration: the node's DDS transport (issue 28), UDPv4 only unless the user chose one.

Fast DDS's shared-memory transport can stall the stream for a third of a second when a
process joins the graph (eProsima/Fast-DDS#6535), so the node takes UDPv4 only where the
user configured no transport (``traj_gen_ros.node.stream.transport``). Checked in the
node process itself: with UDPv4 only it maps no Fast DDS shared-memory segment.

This test process discovers with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (the
harness); the nodes here run without it (ROS 2 Jazzy's default, ``SUBNET``), with
``SUBNET``, or with ``LOCALHOST``, where ``rmw_fastrtps`` sets the transports itself.
"""

import contextlib
from pathlib import Path

from node_harness import node_env, NodeProcess, Probe
import rclpy


@contextlib.contextmanager
def node_with(**environment):
    """Run a generator with ``environment`` (None: unset); yield (process, a ready Probe)."""
    rclpy.init()
    env = {**node_env(), **environment}
    node = NodeProcess(env={name: value for name, value in env.items() if value is not None})
    probe = None
    try:
        probe = Probe()
        probe.wait_ready()
        yield node, probe
    finally:
        if probe is not None:
            probe.destroy_node()
        rclpy.shutdown()
        code = node.stop()
        output = node.output()
        node.close()
    assert code == 0, output


def shared_memory_segments(pid: int) -> set[str]:
    """Return the Fast DDS shared-memory files the process has mapped."""
    lines = Path(f'/proc/{pid}/maps').read_text().splitlines()
    return {line.split()[-1] for line in lines if '/dev/shm/fastrtps' in line}


def test_with_no_transport_set_the_node_uses_udp_only_and_says_so():
    with node_with(ROS_AUTOMATIC_DISCOVERY_RANGE=None) as (node, probe):  # SUBNET
        assert 'DDS transport: UDPv4 only (FASTDDS_BUILTIN_TRANSPORTS=UDPv4, set by the ' \
            'node' in node.output()
        assert shared_memory_segments(node.process.pid) == set()
        status, trajectory = probe.goal({'joint_1': 0.2})  # requests, answers, the stream
        assert status.level == b'\x00' and trajectory is not None
        assert probe.wait_at_rest()[0] == 0.2


def test_a_transport_the_user_set_wins():
    with node_with(ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET',
                   FASTDDS_BUILTIN_TRANSPORTS='DEFAULT') as (node, _):
        assert 'DDS transport: FASTDDS_BUILTIN_TRANSPORTS=DEFAULT (yours)' in node.output()
        assert shared_memory_segments(node.process.pid)  # Fast DDS's default: SHM too


def test_with_localhost_discovery_rmw_fastrtps_sets_the_transports_and_the_node_says_so():
    with node_with(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST') as (node, _):
        assert 'DDS transport: shared memory and UDPv4, set by rmw_fastrtps for ' \
            'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST' in node.output()
        assert shared_memory_segments(node.process.pid)
