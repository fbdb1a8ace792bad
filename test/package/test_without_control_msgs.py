"""
A clone with nothing beside it: without control_msgs the suite collects, its tests skip.

A user who clones the repository has no ``../shared/control_msgs`` to build from, so
control_msgs is not importable there. The suite is collected here in a fresh interpreter
with control_msgs made unimportable (``sys.modules['control_msgs'] = None``): no error,
and exactly the modules that need it skip, each saying why.
"""

import re
import subprocess
import sys

from node_harness import REPO

HIDDEN = """
import sys
sys.modules['control_msgs'] = None  # import control_msgs: ModuleNotFoundError
import pytest
sys.exit(pytest.main(['--collect-only', '-q', '-rs', '-p', 'no:cacheprovider', 'test']))
"""
#: The test modules that need control_msgs (the action, the speed-override topic).
NEEDING = {'test_node_follow_joint_trajectory.py', 'test_node_action_on_robot.py',
           'test_node_action_log.py', 'test_node_continuous_joints.py',
           'test_node_speed_scaling.py', 'test_node_speed_scaling_scurve.py',
           'test_node_speed_scaling_input.py'}


def test_without_control_msgs_the_suite_collects_and_its_tests_skip_saying_why():
    result = subprocess.run([sys.executable, '-c', HIDDEN], cwd=REPO, capture_output=True,
                            text=True, timeout=300)
    out = result.stdout + result.stderr
    assert result.returncode == 0, out  # collected without an error
    assert 'error' not in out.lower().split('short test summary info')[-1], out
    reasons = re.findall(r'^SKIPPED \[(\d+)\] (\S+): (.*)$', out, re.MULTILINE)
    assert sum(int(count) for count, _, _ in reasons) == len(NEEDING), out
    for _, _, reason in reasons:
        assert reason.startswith('control_msgs is not importable'), reason
        assert 'the node runs without ~/' in reason, reason
    collected = set(re.findall(r'^test/\S+/(test_\w+\.py)::', out, re.MULTILINE))
    assert collected.isdisjoint(NEEDING) and len(collected) > 50, collected
