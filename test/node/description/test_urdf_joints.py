"""The URDF reader against robot descriptions nobody here wrote (pybullet's pybullet_data)."""

import math
from pathlib import Path

from pybullet_urdfs import FILES, pybullet_urdfs
import pytest
from traj_gen_ros.node.description import joint_limits as jl
from traj_gen_ros.node.description.urdf_joints import read_joints

INF = math.inf


@pytest.fixture(scope='module')
def urdfs(request) -> dict[str, Path]:
    return pybullet_urdfs(request.config)


def movable(path: Path) -> list[str]:
    """Return the joints a trajectory could command: movable, not mimicking another."""
    return [joint.name for joint in read_joints(path.read_bytes()).values()
            if joint.type in ('revolute', 'continuous', 'prismatic') and joint.mimic is None]


@pytest.mark.parametrize('name', sorted(FILES))
def test_every_robot_loads_with_all_its_commandable_joints(urdfs, name):
    joints = movable(urdfs[name])
    limits = jl.urdf_limits(urdfs[name].read_bytes(), joints)
    assert limits.types == tuple(read_joints(urdfs[name].read_bytes())[j].type for j in joints)
    assert (limits.velocity > 0).all()
    merged = jl.merge_limits(limits)
    assert jl.describe_sources(merged).count(': ') == len(joints)


def test_joint_counts_and_types(urdfs):
    counts = {name: len(movable(urdfs[name])) for name in FILES}
    assert counts == {'panda': 8, 'iiwa': 7, 'iiwa_vr_limits': 7, 'xarm6': 6,
                      'xarm6_gripper': 7, 'husky': 4, 'r2d2': 8}


def test_limits_are_the_numbers_in_the_files(urdfs):
    panda = jl.urdf_limits(urdfs['panda'].read_text(),
                           ['panda_joint4', 'panda_joint6', 'panda_finger_joint1'])
    assert panda.lower.tolist() == [-3.1416, -0.0873, 0.0]
    assert panda.upper.tolist() == [0.0, 3.8223, 0.04]
    assert panda.velocity.tolist() == [2.175, 2.61, 0.2]
    assert panda.types == ('revolute', 'revolute', 'prismatic')

    vr = jl.urdf_limits(urdfs['iiwa_vr_limits'].read_text(),
                        ['lbr_iiwa_joint_1', 'lbr_iiwa_joint_4'])
    assert vr.lower.tolist() == [-0.96705972839, 0.19439510239]
    assert vr.upper.tolist() == [0.96705972839, 2.29439510239]
    assert vr.velocity.tolist() == [10.0, 10.0]

    husky = jl.urdf_limits(urdfs['husky'].read_text(), ['front_left_wheel'])
    assert (husky.lower[0], husky.upper[0], husky.velocity[0]) == (-INF, INF, INF)
    # r2d2's head_swivel is continuous with lower -0.38, upper 0: ignored, as KDL does.
    r2d2 = jl.urdf_limits(urdfs['r2d2'].read_text(), ['head_swivel', 'gripper_extension'])
    assert r2d2.lower.tolist() == [-INF, -0.38]
    assert r2d2.upper.tolist() == [INF, 0.0]
    assert r2d2.velocity.tolist() == [0.5, 0.5]
    assert jl.merge_limits(r2d2).units == ('rad', 'm')


@pytest.mark.parametrize('name', ['xarm6', 'xarm6_gripper'])
def test_xarm_is_read_with_its_unexpanded_transmissions(urdfs, name):
    text = urdfs[name].read_text()
    assert '<mechanicalReduction>' in text and 'reduction' in text  # what tripped before
    joints = [f'joint{index}' for index in range(1, 7)]
    limits = jl.urdf_limits(text, joints)
    assert limits.lower.tolist() == [-6.28318530718, -2.059, -3.927, -6.28318530718,
                                     -1.69297, -6.28318530718]
    assert limits.upper.tolist() == [6.28318530718, 2.0944, 0.19198, 6.28318530718,
                                     3.14159265359, 6.28318530718]
    assert limits.velocity.tolist() == [3.14] * 6


def test_xarm_gripper_mimic_joints_are_refused_by_name(urdfs):
    text = urdfs['xarm6_gripper'].read_text()
    assert jl.urdf_limits(text, ['drive_joint']).upper.tolist() == [0.85]
    with pytest.raises(ValueError, match=r"^URDF joint 'left_finger_joint' mimics joint "
                                         r"'drive_joint' \(<mimic>\)"):
        jl.urdf_limits(text, ['drive_joint', 'left_finger_joint'])
    panda = urdfs['panda'].read_text()
    with pytest.raises(ValueError, match="'panda_finger_joint2' mimics joint "
                                         "'panda_finger_joint1'"):
        jl.urdf_limits(panda, ['panda_finger_joint2'])


def test_a_broken_limit_in_a_real_urdf_is_still_refused_by_joint_and_attribute(urdfs):
    text = urdfs['xarm6'].read_text()
    broken = text.replace('velocity="3.14"', 'velocity="${max_vel}"', 2)
    with pytest.raises(ValueError, match=r"^invalid URDF: joint 'joint1': <limit> "
                                         r"velocity='\$\{max_vel\}' is not a number$"):
        jl.urdf_limits(broken, ['joint2'])
    missing = urdfs['iiwa'].read_text().replace('velocity="10"', '', 1)
    with pytest.raises(ValueError, match=r"^invalid URDF: joint 'lbr_iiwa_joint_1': <limit> "
                                         r'has no velocity attribute \(required\)$'):
        jl.urdf_limits(missing, ['lbr_iiwa_joint_1'])
