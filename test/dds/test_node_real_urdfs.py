"""
Integration: the node with robot descriptions nobody here wrote (pybullet's pybullet_data).

Each test starts the generator as a subprocess with a URDF as its ``robot_description``
parameter (:mod:`pybullet_urdfs` fetches them) and talks to it over DDS.
"""

import contextlib
import json
import math
from pathlib import Path
import subprocess
import sys
import tempfile

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from node_harness import CONFIG, node_env, Probe, REPO, running_node, trajectory_arrays
import numpy as np
from pybullet_urdfs import pybullet_urdfs
import pytest
from traj_gen_ros import min_time

IIWA = [f'lbr_iiwa_joint_{index}' for index in range(1, 8)]
XARM = [f'joint{index}' for index in range(1, 7)]
HUSKY = ['front_left_wheel', 'front_right_wheel', 'rear_left_wheel', 'rear_right_wheel']
V_MAX, A_MAX = 2.0, 4.0


@pytest.fixture(scope='module')
def urdfs(request) -> dict[str, Path]:
    return pybullet_urdfs(request.config)


def parameters_file(folder: str, urdf: Path, joints: list[str], **extra) -> Path:
    """Write a parameters file: ``joints``, the URDF, one limit for all, ``extra``."""
    values = {'joints': joints, 'initial_positions': [0.0] * len(joints),
              'max_velocity': [V_MAX], 'max_acceleration': [A_MAX],
              'robot_description': urdf.read_text()} | extra
    path = Path(folder) / 'robot.yaml'
    path.write_text(json.dumps({'/**': {'ros__parameters': values}}))  # JSON is YAML
    return path


@contextlib.contextmanager
def session(urdf: Path, joints: list[str], **extra):
    """Run a generator with ``urdf`` and a ready probe that records /diagnostics."""
    with tempfile.TemporaryDirectory() as folder:
        path = parameters_file(folder, urdf, joints, **extra)
        with running_node('--params-file', str(path)) as node:
            probe = Probe()
            probe.diagnostics = []
            probe.create_subscription(DiagnosticArray, '/diagnostics',
                                      probe.diagnostics.append, 10)
            try:
                probe.wait_ready()
                yield node, probe
            finally:
                probe.destroy_node()


def diagnostic(probe, condition, after: int = 0) -> dict:
    """Spin until a /diagnostics status (from message ``after`` on) meets ``condition``."""
    def found():
        for array in probe.diagnostics[after:]:
            for status in array.status:
                values = {kv.key: kv.value for kv in status.values}
                values |= {'': status.message, 'level': status.level}
                if condition(values):
                    return values
        return None
    return probe.spin_until(found, 15.0, 'a matching /diagnostics message')


def test_a_start_outside_the_range_warns_and_only_goals_further_out_are_refused(urdfs):
    # KUKA iiwa model_vr_limits.urdf: lbr_iiwa_joint_4 in [0.194, 2.294]; it starts at 0.
    with session(urdfs['iiwa_vr_limits'], IIWA) as (node, probe):
        outside = ("joint 'lbr_iiwa_joint_4' is at 0 rad, outside its range [0.194395, "
                   '2.2944] rad (lower from URDF; upper from URDF)')
        assert f'{outside}: it may hold there or move toward its range' in node.output()
        values = diagnostic(probe, lambda v: 'outside range' in v)
        assert values['level'] == DiagnosticStatus.WARN
        assert values['outside range'] == outside
        # One of the summary's parts (a loaded machine may add a stream-rate warning).
        assert values[''].startswith(outside) or f'; {outside}' in values['']

        # Other joints move while it holds at 0.
        status, plan = probe.goal({'lbr_iiwa_joint_2': 0.5})
        assert status.level == DiagnosticStatus.OK, status.message
        assert np.all(trajectory_arrays(plan)[1][:, 3] == 0.0)
        # Further out is refused, naming the joint, its position and what is allowed.
        status, _ = probe.goal({'lbr_iiwa_joint_4': -0.1})
        assert status.level == DiagnosticStatus.ERROR
        assert status.message.endswith(
            "goal position -0.1 rad for joint 'lbr_iiwa_joint_4' is outside its range "
            '[0.194395, 2.2944] rad (lower from URDF; upper from URDF); it is at 0 rad, '
            'outside its range: only positions in [0, 2.2944] rad (toward or into its '
            'range) are allowed'), status.message
        # Toward the range (still outside) and then into it are accepted.
        status, plan = probe.goal({'lbr_iiwa_joint_4': 0.1})
        assert status.level == DiagnosticStatus.OK, status.message
        assert trajectory_arrays(plan)[1][-1, 3] == pytest.approx(0.1)
        probe.wait_at_rest()
        count = len(probe.diagnostics)
        status, _ = probe.goal({'lbr_iiwa_joint_4': 1.0})
        assert status.level == DiagnosticStatus.OK, status.message
        assert probe.wait_at_rest()[3] == pytest.approx(1.0)
        values = diagnostic(probe, lambda v: v['level'] == DiagnosticStatus.OK, count)
        assert 'outside range' not in values
        assert 'every joint is within its position range' in node.output()


@pytest.mark.parametrize('name', ['xarm6', 'xarm6_gripper'])
def test_the_xarm_urdfs_start_the_node_and_their_limits_apply(urdfs, name):
    with session(urdfs[name], XARM) as (node, probe):
        assert 'joint3: [-3.927, 0.19198] rad (URDF), 2 rad/s (max_velocity)' in \
            node.output()
        status, _ = probe.goal({'joint3': 0.3})
        assert status.level == DiagnosticStatus.ERROR
        assert "goal position 0.3 rad for joint 'joint3' is outside its range [-3.927, " \
               '0.19198] rad' in status.message, status.message
        status, plan = probe.goal({'joint3': -0.5})
        assert status.level == DiagnosticStatus.OK, status.message
        assert trajectory_arrays(plan)[1][-1, 2] == pytest.approx(-0.5)


def test_a_mimic_joint_in_joints_stops_the_node_with_the_reason(urdfs):
    with tempfile.TemporaryDirectory() as folder:
        joints = ['drive_joint', 'left_finger_joint']
        path = parameters_file(folder, urdfs['xarm6_gripper'], joints)
        result = subprocess.run(
            [sys.executable, '-m', 'traj_gen_ros.node.generator', '--ros-args',
             '--params-file', str(CONFIG), '--params-file', str(path)],
            capture_output=True, text=True, env=node_env(), cwd=REPO, timeout=60)
    assert result.returncode == 1, result.stderr
    assert ("invalid parameters: URDF joint 'left_finger_joint' mimics joint 'drive_joint' "
            '(<mimic>): it follows that joint and is not commanded; remove it from joints'
            ) in result.stderr


def test_a_continuous_joint_takes_the_short_way_round(urdfs):
    # Husky's wheels are continuous joints; the first starts at 10 rad.
    with session(urdfs['husky'], HUSKY, initial_positions=[10.0, 0.0, 0.0, 0.0]) \
            as (node, probe):
        del node
        status, plan = probe.goal({'front_left_wheel': -0.1})
        assert status.level == DiagnosticStatus.OK, status.message
        times, positions, _, _ = trajectory_arrays(plan)
        end = -0.1 + 2 * 2 * math.pi  # 12.466: 2.466 rad on
        expected = min_time(np.array([10.0]), np.array([end]), np.array([V_MAX]),
                            np.array([A_MAX]), 'quintic').duration
        assert times[-1] == pytest.approx(expected, abs=1e-6)
        assert times[-1] < 2.5  # unwinding 10.1 rad would take over 6 s
        assert positions[-1, 0] == pytest.approx(end, abs=1e-9)
        assert np.all(np.diff(positions[:, 0]) >= 0)  # forward all the way
        assert probe.wait_at_rest()[0] == pytest.approx(end, abs=1e-9)

        # angle_wraparound false: the target as given, the long way back.
        probe.require_parameters(angle_wraparound=False)
        status, plan = probe.goal({'front_left_wheel': 0.0})
        assert status.level == DiagnosticStatus.OK, status.message
        assert trajectory_arrays(plan)[1][-1, 0] == 0.0
        assert trajectory_arrays(plan)[0][-1] > 5.0
        assert probe.stop().success
