"""The test harness's isolation: every run on this machine gets its own ROS domain."""

import fcntl
import os
from pathlib import Path
import subprocess
import sys
import tempfile

import node_harness


def test_a_claimed_domain_is_not_claimed_again():
    # This process holds DOMAIN_ID; a second claim (another run) must skip it.
    other = node_harness._claim_domain()
    assert other != node_harness.DOMAIN_ID
    assert os.environ['ROS_DOMAIN_ID'] == str(node_harness.DOMAIN_ID)


def test_a_killed_run_releases_its_domain():
    child = subprocess.Popen(
        [sys.executable, '-c', 'import node_harness, time\n'
         'print(node_harness.DOMAIN_ID, flush=True)\ntime.sleep(60)'],
        env={**os.environ, 'PYTHONPATH': os.path.dirname(node_harness.__file__)},
        stdout=subprocess.PIPE, text=True)
    try:
        domain = int(child.stdout.readline())
        path = Path(tempfile.gettempdir()) / f'traj_gen_ros_domain_{domain}.lock'
        with open(path, 'w') as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                held = False
            except OSError:
                held = True
            assert held, 'the child holds its domain while it runs'
            child.kill()
            child.wait(timeout=30)
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)  # free once it is gone
    finally:
        child.kill()
        child.stdout.close()


def test_the_stream_clocks_hold_back_is_rebuilt_from_the_stamps():
    """held_back_ns (plan-clock comparisons) agrees with the node's own StreamClock."""
    import numpy as np
    from traj_gen_ros.node.stream.clock import StreamClock

    rng = np.random.default_rng(28)
    rates = [100.0] * 300 + [250.0] * 300  # rate_hz 100, then 250 from sample 300 on
    periods = np.array([int(1e9 / rate) for rate in rates])
    gaps = periods + rng.integers(-100_000, 300_000, len(rates))  # jitter (ns)
    gaps[[40, 41, 299, 300, 450]] += [300_000_000, 15_000_000, 300_000_000, 25_000_000,
                                      300_000_000]  # late ticks, one at the rate change
    stamps = (10 ** 12 + np.cumsum(gaps)).tolist()
    clock = StreamClock()
    clock.sample(stamps[0], -(2 ** 62), int(periods[0]))
    held = [0]
    for index in range(1, len(stamps)):
        clock.sample(stamps[index], stamps[index - 1], int(periods[index]))
        held.append(clock.held_ns)
    assert clock.late_ticks == 5
    rate = dict(zip(stamps, rates, strict=True))
    assert node_harness.held_back_ns(stamps, rate.__getitem__).tolist() == held
