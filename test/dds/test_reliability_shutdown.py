"""Reliability (issue 5): SIGINT/SIGTERM mid-motion end cleanly; a restart holds still."""

from pathlib import Path
import signal

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import JOINTS, NodeProcess, Probe
import numpy as np
import pytest
import rclpy


def children(pid: int) -> list[int]:
    found = []
    for entry in Path('/proc').iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / 'stat').read_text()
            except OSError:
                continue
            if int(stat.rsplit(')', 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_shutdown_mid_motion_is_clean_and_a_restart_holds_the_initial_positions(sig):
    initial = [0.1, -0.2, 0.3, -0.4, 0.5, -0.6]
    setting = f'initial_positions:=[{", ".join(str(x) for x in initial)}]'
    rclpy.init()
    try:
        for attempt in range(2):
            node = NodeProcess('-p', setting)
            try:
                probe = Probe(name=f'restart_{attempt}')
                probe.wait_ready()
                probe.spin_until(lambda p=probe: len(p.states) > 5, 10.0, 'the stream')
                first = probe.states[0]
                assert list(first.name) == JOINTS
                assert np.allclose(first.position, initial, atol=0) and not any(first.velocity)
                status, _ = probe.goal({'joint_1': 1.5, 'joint_5': -1.0})
                assert status.level == DiagnosticStatus.OK
                probe.spin_until(lambda p=probe: any(p.latest().velocity), 5.0, 'motion')
                workers = children(node.process.pid)
                probe.destroy_node()
                code = node.stop(sig)
                output = node.output()
            finally:
                node.close()
            assert code == 0, output
            assert 'Traceback' not in output, output
            # The node plans in its own process (issue 11): nothing to orphan.
            assert workers == [], f'the node started child processes {workers}'
    finally:
        rclpy.shutdown()
