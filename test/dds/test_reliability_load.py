"""
Issue 11: the stream holds on a loaded machine.

One busy process per core runs beside the node (the test starts them and always stops
them) while goals preempt each other and ``~/stop`` brakes, at 100 Hz. The stream must
have no ``joint_states`` gap longer than 3 periods, no position or velocity step beyond
the limits, nothing non-finite, and every request must be answered.

The 3-period bound relies on the stream thread's raised priority (``SCHED_FIFO`` or a
lower nice value, which the node reports at start-up); where the node is not permitted to
raise it, a plain time-shared thread is only held to 10 periods.
"""

import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    busy_processes,
    generator_session,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    stamp_ns,
)
import numpy as np

RATE = 100.0


def may_raise_priority() -> bool:
    """Whether a process here may lower its nice value (as the node's threads do)."""
    probe = 'import os; os.setpriority(os.PRIO_PROCESS, 0, -10)'
    return subprocess.run([sys.executable, '-c', probe], capture_output=True).returncode == 0


def test_stream_holds_beside_a_busy_process_per_core():
    with generator_session('-p', f'rate_hz:={RATE}') as probe:
        rest = probe.wait_at_rest()
        begin = stamp_ns(probe.latest().header.stamp)
        with busy_processes():
            for index in range(8):  # each goal preempts the one before, mid-motion
                sign = 1.0 if index % 2 == 0 else -1.0
                status, _ = probe.goal({'joint_1': rest[0] + sign, 'joint_4': rest[3] - sign})
                assert status.level == DiagnosticStatus.OK, status.message
                pause = time.monotonic() + 0.25
                probe.spin_until(lambda pause=pause: time.monotonic() > pause, 5.0, 'a pause')
            assert probe.stop().success
            probe.wait_at_rest(timeout=20.0)
            end = stamp_ns(probe.latest().header.stamp)
        times, positions, velocities = probe.states_between(begin, end)
    gaps = np.diff(times)
    assert len(times) >= 0.8 * (end - begin) * 1e-9 * RATE, len(times)
    assert np.isfinite(positions).all() and np.isfinite(velocities).all()
    steps = gaps[:, None]
    assert (np.abs(np.diff(positions, axis=0)) - MAX_VELOCITY * steps * 1.001 - 1e-9).max() <= 0
    assert (np.abs(np.diff(velocities, axis=0)) - MAX_ACCELERATION * steps * 1.001
            - 1e-9).max() <= 0
    print(f'\nbeside {len(gaps)} periods of load: gap p50 {np.median(gaps) * 1e3:.2f} ms, '
          f'p99 {np.percentile(gaps, 99) * 1e3:.2f} ms, max {gaps.max() * 1e3:.2f} ms')
    assert gaps.max() <= (3.0 if may_raise_priority() else 10.0) / RATE, gaps.max()
