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
