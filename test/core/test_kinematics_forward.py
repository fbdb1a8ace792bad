"""
Forward kinematics and the Jacobian of traj_gen_ros.core.kinematics against an oracle.

The oracle (test/support/numpy_chain.py) composes the URDF's joint origins and axes in
numpy; the real URDFs are pybullet_data's Panda, KUKA iiwa and xArm 6 and
example-robot-data's Panda and UR10, at random positions within their limits.
"""

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from kinematics_robots import FLOATING_ARM, PANDA, robot_urdf, ROBOTS, UR
import numpy as np
from numpy_chain import NumpyChain
import pytest
from traj_gen_ros.core.kinematics import Chain

TOLERANCE = 1e-9


def sample(chain: Chain, count: int, seed: int = 0) -> np.ndarray:
    """Return ``(count, joints)`` positions within the limits (±π where there are none)."""
    rng = np.random.default_rng(seed)
    low = np.where(np.isfinite(chain.lower), chain.lower, -math.pi)
    high = np.where(np.isfinite(chain.upper), chain.upper, math.pi)
    return rng.uniform(low, high, size=(count, len(chain.joints)))


def finite_difference_jacobian(oracle: NumpyChain, chain: Chain, q: np.ndarray,
                               step: float = 1e-6) -> np.ndarray:
    """Return the oracle's Jacobian by central differences: velocity, then angular."""
    columns = []
    for k in range(q.size):
        poses = []
        for sign in (1, -1):
            moved = q.copy()
            moved[k] += sign * step
            poses.append(oracle.pose(chain.tool_frame, dict(zip(chain.joints, moved,
                                                                strict=True)),
                                     chain.base_frame))
        plus, minus = poses
        spin = plus[:3, :3] @ minus[:3, :3].T  # ≈ I + [ω]× 2h, in base axes
        angular = np.array([spin[2, 1] - spin[1, 2], spin[0, 2] - spin[2, 0],
                            spin[1, 0] - spin[0, 1]]) / 2
        columns.append(np.concatenate([plus[:3, 3] - minus[:3, 3], angular]) / (2 * step))
    return np.array(columns).T


@pytest.fixture(params=sorted(ROBOTS))
def robot(request):
    spec = ROBOTS[request.param]
    urdf = robot_urdf(request.config, spec.source, spec.name)
    return spec, urdf, Chain.from_urdf(urdf, spec.joints), NumpyChain(urdf)


def test_forward_matches_the_numpy_chain_on_real_arms(robot):
    spec, _, chain, oracle = robot
    assert chain.tool_frame == spec.default_tool
    positions = sample(chain, 25)
    poses = chain.forward(positions)
    assert poses.shape == (25, 4, 4)
    for q, pose in zip(positions, poses, strict=True):
        expected = oracle.pose(chain.tool_frame, dict(zip(spec.joints, q, strict=True)))
        assert np.abs(pose - expected).max() < TOLERANCE
        assert np.abs(chain.forward(q) - expected).max() < TOLERANCE  # one sample alike


def test_every_link_pose_matches_the_numpy_chain(robot):
    spec, _, chain, oracle = robot
    for q in sample(chain, 3, seed=1):
        values = dict(zip(spec.joints, q, strict=True))
        for link in chain.links:
            assert np.abs(chain.frame_pose(link, q) - oracle.pose(link, values)).max() \
                < TOLERANCE, link


def test_jacobian_matches_finite_differences_of_the_numpy_chain(robot):
    _, _, chain, oracle = robot
    for q in sample(chain, 5, seed=2):
        jacobian = chain.jacobian(q)
        assert jacobian.shape == (6, len(chain.joints))
        assert np.abs(jacobian - finite_difference_jacobian(oracle, chain, q)).max() < 1e-7


def test_panda_defaults_and_the_start_up_line(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'erd', 'panda')
    chain = Chain.from_urdf(urdf, PANDA)
    assert (chain.base_frame, chain.tool_frame) == ('panda_link0', 'panda_hand_tcp')
    assert chain.describe() == ('kinematic chain panda_link0 -> panda_hand_tcp: 7 joints '
                                + ', '.join(PANDA))
    assert chain.lower[3] == -3.0718 and chain.upper[5] == 3.7525  # the URDF's limits
    # At the zero pose the TCP sits 0.088 m forward and 0.8226 m up, pointing down.
    pose = chain.forward(np.zeros(7))
    assert pose[:3, 3] == pytest.approx([0.088, 0.0, 0.8226], abs=1e-12)
    assert pose[:3, 2] == pytest.approx([0.0, 0.0, -1.0], abs=1e-12)


def test_another_base_frame_and_a_chain_read_backwards(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'erd', 'ur10')
    oracle = NumpyChain(urdf)
    chain = Chain.from_urdf(urdf, UR, base_frame='base', tool_frame='tool0')
    # The base runs up the tree, every joint between it and the tool: the base moves.
    backwards = Chain.from_urdf(urdf, UR, base_frame='tool0', tool_frame='base_link')
    for q in sample(chain, 5, seed=3):
        values = dict(zip(UR, q, strict=True))
        assert np.abs(chain.forward(q) - oracle.pose('tool0', values, 'base')).max() \
            < TOLERANCE
        assert np.abs(backwards.forward(q) - oracle.pose('base_link', values, 'tool0')).max() \
            < TOLERANCE
        assert np.abs(backwards.jacobian(q)
                      - finite_difference_jacobian(oracle, backwards, q)).max() < 1e-7


def test_held_joints_and_a_mimic_finger(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'erd', 'panda')
    oracle = NumpyChain(urdf)
    chain = Chain.from_urdf(urdf, PANDA, held={'panda_finger_joint1': 0.03, 'other': 1.0})
    assert chain.held == {'panda_finger_joint1': 0.03, 'panda_finger_joint2': 0.03}
    q = sample(chain, 1, seed=4)[0]
    values = dict(zip(PANDA, q, strict=True)) | {'panda_finger_joint1': 0.03}
    for link in ('panda_leftfinger', 'panda_rightfinger'):
        assert np.abs(chain.frame_pose(link, q) - oracle.pose(link, values)).max() < TOLERANCE
    chain.hold({'panda_finger_joint1': 0.01, 'panda_joint1': 2.0})  # a chain joint: ignored
    assert chain.held['panda_finger_joint2'] == 0.01
    apart = chain.frame_pose('panda_rightfinger', q)[:3, 3] - chain.frame_pose(
        'panda_leftfinger', q)[:3, 3]
    assert np.linalg.norm(apart) == pytest.approx(0.02, abs=1e-12)
    # One finger seen from the other: the base moves with the joint, the mimic doubles it.
    fingers = Chain.from_urdf(urdf, ['panda_finger_joint1'], base_frame='panda_leftfinger',
                              tool_frame='panda_rightfinger')
    assert fingers.forward([0.04])[1, 3] - fingers.forward([0.0])[1, 3] == pytest.approx(
        -0.08, abs=1e-12)
    assert fingers.jacobian([0.02])[:, 0] == pytest.approx([0, -2, 0, 0, 0, 0], abs=1e-12)
    copy = chain.copy()
    copy.hold({'panda_finger_joint1': 0.04})
    assert chain.held['panda_finger_joint1'] == 0.01  # a copy has its own state


def test_mimic_joints_on_the_chain_of_the_xarm_gripper(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'pybullet', 'xarm6_gripper')
    oracle = NumpyChain(urdf)
    joints = [*ROBOTS['pybullet-xarm6'].joints, 'drive_joint']
    chain = Chain.from_urdf(urdf, joints, tool_frame='left_finger')  # via left_finger_joint
    for q in sample(chain, 5, seed=5):
        values = dict(zip(joints, q, strict=True))
        assert np.abs(chain.forward(q) - oracle.pose('left_finger', values)).max() < TOLERANCE
        assert np.abs(chain.jacobian(q) - finite_difference_jacobian(oracle, chain, q)).max() \
            < 1e-7


def test_a_floating_base_continuous_prismatic_and_offset_mimic_chain():
    oracle = NumpyChain(FLOATING_ARM)
    chain = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'j3'], held={'side': 0.7})
    assert (chain.base_frame, chain.tool_frame) == ('world', 'l3')  # l3's child moves (j4)
    assert chain.lower.tolist() == [-2.5, -math.inf, -0.2]
    assert chain.periodic.tolist() == [False, True, False]  # j1 is led: j4 mimics it
    tool = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'j3'], tool_frame='tool')
    for q in [*sample(chain, 5, seed=6), np.array([1.0, 5.5, 0.1]),
              np.array([-2.0, -9.0, -0.2])]:
        values = dict(zip(chain.joints, q, strict=True))
        assert np.abs(chain.forward(q) - oracle.pose('l3', values)).max() < TOLERANCE
        assert np.abs(tool.forward(q) - oracle.pose('tool', values)).max() < TOLERANCE
        assert np.abs(tool.jacobian(q) - finite_difference_jacobian(oracle, tool, q)).max() \
            < 1e-7
        side = oracle.pose('arm_side', values | {'side': 0.7})
        assert np.abs(chain.frame_pose('arm_side', q) - side).max() < TOLERANCE
    # A continuous joint is periodic: a whole turn is the same pose.
    q = np.array([0.3, 0.4, 0.05])
    assert np.abs(tool.forward(q) - tool.forward(q + [0, 2 * math.pi, 0])).max() < 1e-12


def test_the_r2d2_gripper_prismatic_and_a_continuous_head(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'pybullet', 'r2d2')
    oracle = NumpyChain(urdf)
    gripper = Chain.from_urdf(urdf, ['gripper_extension', 'left_gripper_joint'])
    head = Chain.from_urdf(urdf, ['head_swivel'])
    assert (gripper.tool_frame, head.tool_frame) == ('left_tip', 'box')
    assert gripper.lower.tolist() == [-0.38, 0.0]  # m, then rad
    assert head.lower.tolist() == [-math.inf]  # continuous: its <limit> lower is ignored
    for q in sample(gripper, 5, seed=7):
        values = dict(zip(gripper.joints, q, strict=True))
        assert np.abs(gripper.forward(q) - oracle.pose('left_tip', values)).max() < TOLERANCE
    for angle in (-4.0, 0.5, 3.5, 7.0):
        assert np.abs(head.forward([angle]) - oracle.pose('box', {'head_swivel': angle})
                      ).max() < TOLERANCE


@pytest.fixture(scope='module')
def iiwa(pytestconfig):
    spec = ROBOTS['pybullet-iiwa']
    urdf = robot_urdf(pytestconfig, spec.source, spec.name)
    return Chain.from_urdf(urdf, spec.joints), NumpyChain(urdf)


@settings(deadline=None, max_examples=40, derandomize=True)
@given(fractions=st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7))
def test_forward_is_a_rigid_transform_matching_the_oracle_property(iiwa, fractions):
    """Any position within the limits: a rigid transform equal to the oracle's."""
    chain, oracle = iiwa
    q = np.array(fractions) * chain.upper  # the iiwa's limits are symmetric
    pose = chain.forward(q)
    assert np.abs(pose[:3, :3].T @ pose[:3, :3] - np.eye(3)).max() < 1e-12
    expected = oracle.pose(chain.tool_frame, dict(zip(chain.joints, q, strict=True)))
    assert np.abs(pose - expected).max() < TOLERANCE
