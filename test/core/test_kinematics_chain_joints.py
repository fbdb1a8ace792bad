"""
chain_joints: the joints of a chain nobody named, from the URDF's tree (real and written).

The default tool is the end of the unbranched arm (above a gripper's fingers); every
chain it gives builds, with the tool a Chain of those joints takes by default.
"""

from kinematics_robots import FLOATING_ARM, PANDA, robot_urdf, ROBOTS, UR
import pytest
from traj_gen_ros.core.kinematics import Chain, chain_joints
from traj_gen_ros.core.kinematics.urdf_tree import UrdfTree

IIWA = ROBOTS['pybullet-iiwa'].joints
XARM = ROBOTS['pybullet-xarm6'].joints


@pytest.mark.parametrize('source, name, joints, tool', [
    ('pybullet', 'panda', PANDA, 'panda_grasptarget'),  # fingers branch off at panda_hand
    ('erd', 'panda', PANDA, 'panda_hand_tcp'),
    ('pybullet', 'iiwa', IIWA, 'lbr_iiwa_link_7'),
    ('pybullet', 'xarm6', XARM, 'link6'),
    ('pybullet', 'xarm6_gripper', XARM, 'xarm_gripper_base_link'),  # 1 drive, 5 mimics
    ('erd', 'ur10', UR, 'wrist_3_link'),
])
def test_the_arm_of_a_real_urdf_gives_its_joints_and_the_default_tool(pytestconfig, source,
                                                                      name, joints, tool):
    urdf = robot_urdf(pytestconfig, source, name)
    assert chain_joints(urdf) == joints
    chain = Chain.from_urdf(urdf, chain_joints(urdf))
    assert chain.tool_frame == tool and chain.joints == joints


def test_a_named_tool_gives_the_joints_on_its_path_base_first(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'pybullet', 'panda')
    assert chain_joints(urdf, tool_frame='panda_link4') == PANDA[:4]
    assert chain_joints(urdf, 'panda_link2', 'panda_hand') == PANDA[2:]
    # A finger: the arm and the finger's prismatic joint; the mimic finger stands for its
    # leader, named once.
    assert chain_joints(urdf, tool_frame='panda_leftfinger') == (*PANDA, 'panda_finger_joint1')
    assert chain_joints(urdf, tool_frame='panda_rightfinger') == (*PANDA, 'panda_finger_joint1')
    # Read backwards (base below the tool): from the base up.
    assert chain_joints(urdf, 'panda_link3', 'panda_link1') == ('panda_joint3', 'panda_joint2')


def test_mimic_floating_continuous_and_prismatic_joints_of_the_written_arm():
    # float (floating) is left out; j4 mimics j1, which is already there.
    assert chain_joints(FLOATING_ARM, tool_frame='tool') == ('j1', 'j2', 'j3')
    # Only the mimic joint on the path: its leader, off the path, moves the tool.
    assert chain_joints(FLOATING_ARM, 'l3', 'tool') == ('j1',)
    chain = Chain.from_urdf(FLOATING_ARM, chain_joints(FLOATING_ARM, 'l3', 'tool'), 'l3',
                            'tool')
    assert chain.joints == ('j1',)
    assert chain_joints(FLOATING_ARM, 'base', 'arm_side') == ('side',)
    assert chain_joints(FLOATING_ARM, 'l1', 'l2') == ('j2',)


@pytest.mark.parametrize('arguments, expected', [
    ({}, "no arm below 'world' to take the joints from: it branches at 'base' into 'l1', "
         "'arm_side'; name the tool_frame (or the joints)"),
    ({'base_frame': 'l4'}, "no arm below 'l4' to take the joints from: no joint below 'l4' "
                           'moves; name the tool_frame (or the joints)'),
    ({'base_frame': 'l4', 'tool_frame': 'tool'},
     "the chain from 'l4' to 'tool' has no revolute, continuous or prismatic joint: choose a "
     'tool_frame below a moving joint'),
    ({'tool_frame': 'gripper'}, "unknown tool_frame 'gripper': the URDF has no such link; its "
                                "links are 'world', 'base', "),
    ({'base_frame': 'nowhere'}, "unknown base_frame 'nowhere': the URDF has no such link"),
])
def test_no_joints_to_take_is_refused_saying_why(arguments, expected):
    with pytest.raises(ValueError) as caught:
        chain_joints(FLOATING_ARM, **arguments)
    assert str(caught.value).startswith(expected), str(caught.value)


def test_the_tree_methods_behind_it():
    tree = UrdfTree.parse(FLOATING_ARM)
    assert tree.moving_branches('world') == ['base']  # through the floating joint
    assert tree.moving_branches('base') == ['l1', 'arm_side']
    assert tree.moving_branches('l4') == []
    assert tree.arm_end('world') == 'base' and tree.arm_end('l1') == 'l4'
    assert tree.chain_joints('l1', 'tool') == ['j2', 'j3', 'j1']
