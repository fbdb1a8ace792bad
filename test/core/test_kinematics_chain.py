"""
Choosing and checking a chain: defaults, held joints on the way, every refusal, the imports.

A refusal is a ValueError that says what is wrong and what would be valid; Pinocchio is
imported only when a chain is built.
"""

from pathlib import Path
import subprocess
import sys

from kinematics_robots import FLOATING_ARM, PANDA, robot_urdf, UR
import numpy as np
import pytest
from traj_gen_ros.core.kinematics import Chain
from traj_gen_ros.core.kinematics.pinocchio_model import PINNED

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope='module')
def panda_urdf(pytestconfig):
    return robot_urdf(pytestconfig, 'erd', 'panda')


@pytest.mark.parametrize('arguments, expected', [
    ({'tool_frame': 'gripper'},
     "unknown tool_frame 'gripper': the URDF has no such link; its links are "
     "'panda_link0', 'panda_link1', "),
    ({'base_frame': 'world'}, "unknown base_frame 'world': the URDF has no such link"),
    ({'base_frame': 'panda_link3'},
     "the chain from 'panda_link3' to 'panda_hand_tcp' does not contain joint(s) "
     "'panda_joint1', 'panda_joint2', 'panda_joint3' of joints (its joints are "
     "'panda_joint4', 'panda_joint5', 'panda_joint6', 'panda_joint7'): choose a base_frame "
     'above and a tool_frame below every joint'),
    ({'tool_frame': 'panda_link5'},
     "does not contain joint(s) 'panda_joint6', 'panda_joint7' of joints"),
    ({'base_frame': 'panda_hand', 'tool_frame': 'panda_hand_tcp'},
     "the chain from 'panda_hand' to 'panda_hand_tcp' does not contain joint(s) "
     "'panda_joint1', "),
    ({'joints': [*PANDA[:6], 'panda_joint9']},
     "unknown joint 'panda_joint9': the URDF has no such joint; its movable joints are "
     "'panda_joint1', "),
    ({'joints': [*PANDA, 'panda_finger_joint2']},
     "joint 'panda_finger_joint2' mimics 'panda_finger_joint1': it follows its leader and "
     'cannot be one of the joints'),
    ({'joints': [*PANDA, 'panda_joint8']},
     "joint 'panda_joint8' is a fixed joint: a chain moves only revolute, continuous and "
     'prismatic joints'),
    ({'joints': [*PANDA, 'panda_joint1']}, "joints names 'panda_joint1' more than once"),
    ({'joints': []}, "joints is empty; the URDF's movable joints are 'panda_joint1'"),
    ({'joints': 'panda_joint1'}, 'joints must be a sequence of joint names'),
])
def test_a_chain_that_cannot_be_is_refused_saying_what_would_be_valid(panda_urdf, arguments,
                                                                      expected):
    arguments = {'joints': PANDA} | arguments
    with pytest.raises(ValueError) as caught:
        Chain.from_urdf(panda_urdf, arguments.pop('joints'), **arguments)
    assert expected in str(caught.value), str(caught.value)
    assert '\n' not in str(caught.value)


def test_a_urdf_pinocchio_cannot_read_is_refused_with_urdfdoms_reasons(pytestconfig, capfd):
    husky = robot_urdf(pytestconfig, 'pybullet', 'husky')  # an unexpanded $(optenv ...)
    with pytest.raises(ValueError) as caught:
        Chain.from_urdf(husky, ['front_left_wheel'])
    assert str(caught.value) == (
        'invalid URDF: Pinocchio cannot read it: Unable to parse component [$(optenv] to a '
        'double (while parsing a vector value); Malformed parent origin element for joint '
        '[imu_joint]; joint xml is not initialized correctly')
    assert capfd.readouterr().err == ''  # said once, in the error, not on stderr too
    no_limit = ('<robot name="r"><link name="a"/><link name="b"/><joint name="j" '
                'type="revolute"><parent link="a"/><child link="b"/></joint></robot>')
    with pytest.raises(ValueError, match=r'Joint \[j\] is of type REVOLUTE but it does not '
                                         'specify limits'):
        Chain.from_urdf(no_limit, ['j'])


@pytest.mark.parametrize('urdf, expected', [
    ('<robot name="r"><link name="a"', 'invalid URDF: not well-formed XML'),
    ('<model/>', 'invalid URDF: the root element is <model>, not <robot>'),
    ('', 'invalid URDF: the robot description is empty'),
    ('<robot name="r"><link name="a"/><link name="b"/></robot>',
     "invalid URDF: 2 root links ('a', 'b'); a robot description is one tree of links"),
    ('<robot name="r"><link name="a"/><joint name="j" type="fixed"><parent link="a"/>'
     '<child link="c"/></joint></robot>',
     "invalid URDF: joint 'j' names link 'c', which the URDF does not have"),
    ('<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="hinge">'
     '<parent link="a"/><child link="b"/></joint></robot>',
     "invalid URDF: joint 'j' has type 'hinge'; the types are revolute, continuous"),
    ('<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
     '<parent link="a"/><child link="b"/><limit lower="x" upper="1"/></joint></robot>',
     "invalid URDF: joint 'j': <limit> lower='x' is not a number"),
    ('<robot name="r"><link name="a"/><link name="b"/><link name="c"/>'
     '<joint name="j" type="continuous"><parent link="a"/><child link="b"/>'
     '<mimic joint="k"/></joint><joint name="k" type="continuous"><parent link="b"/>'
     '<child link="c"/><mimic joint="j"/></joint></robot>',
     'invalid URDF: the mimic joints j, k follow each other in a circle'),
])
def test_an_invalid_urdf_is_refused_in_one_line(urdf, expected):
    with pytest.raises(ValueError) as caught:
        Chain.from_urdf(urdf, ['j'])
    assert str(caught.value).startswith(expected), str(caught.value)


def test_joints_off_the_joint_set_on_the_way_are_held_and_named(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'erd', 'ur10')
    chain = Chain.from_urdf(urdf, UR[1:], held={'shoulder_pan_joint': 0.3})
    assert chain.describe() == (
        'kinematic chain world -> wrist_3_link: 5 joints shoulder_lift_joint, elbow_joint, '
        'wrist_1_joint, wrist_2_joint, wrist_3_joint; held on the way: '
        'shoulder_pan_joint=0.3')
    full = Chain.from_urdf(urdf, UR, base_frame='', tool_frame='')  # '': the defaults
    assert (full.base_frame, full.tool_frame) == ('world', 'wrist_3_link')
    q = np.array([-1.2, 1.5, -1.0, -1.3, 0.5])
    assert np.abs(chain.forward(q) - full.forward([0.3, *q])).max() < 1e-12
    floating = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'j3'], tool_frame='tool')
    assert floating.describe().endswith('j1, j2, j3; j4 mimics j1; held on the way: float '
                                        '(neutral)')
    with pytest.raises(ValueError, match="held position 'x' of joint 'shoulder_pan_joint' "
                                         r'is not a finite number \(rad or m\)'):
        chain.hold({'shoulder_pan_joint': 'x'})


def test_joint_positions_and_links_are_checked(panda_urdf):
    chain = Chain.from_urdf(panda_urdf, PANDA)
    with pytest.raises(ValueError, match=r'q has shape \(6,\): expected \(7,\) or '
                                         r'\(samples, 7\), one value per joint of panda_joint1'):
        chain.forward(np.zeros(6))
    with pytest.raises(ValueError, match="q of joint 'panda_joint2' is inf: every position "
                                         'must be finite'):
        chain.forward([[0, 0, 0, 0, 0, 0, 0], [0, np.inf, 0, 0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r'the Jacobian takes \(7,\)'):
        chain.jacobian(np.zeros((2, 7)))
    with pytest.raises(ValueError, match="unknown link 'camera': the URDF has no such link"):
        chain.frame_pose('camera', np.zeros(7))


def test_pinocchio_is_imported_only_when_a_chain_is_built(panda_urdf):
    script = ('import sys, traj_gen_ros, traj_gen_ros.core.kinematics as k\n'
              'before = "pinocchio" in sys.modules\n'
              'k.Chain.from_urdf(sys.stdin.read(), ["panda_joint1"])\n'
              'print(before, "lxml" in sys.modules, "pinocchio" in sys.modules)\n')
    result = subprocess.run([sys.executable, '-c', script], input=panda_urdf,
                            capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.split() == ['False', 'True', 'True']
    plain = subprocess.run([sys.executable, '-c', 'import sys, traj_gen_ros\n'
                            'print("pinocchio" in sys.modules, "lxml" in sys.modules)'],
                           capture_output=True, text=True, timeout=120, check=True)
    assert plain.stdout.split() == ['False', 'False']  # import traj_gen_ros stays cheap


def test_the_pinocchio_named_in_the_import_error_is_the_pinned_one():
    assert f'pin=={PINNED}' in (REPO / 'requirements.txt').read_text().split()
    assert '<exec_depend>pinocchio</exec_depend>' in (REPO / 'package.xml').read_text()
