"""
Poses from positions and quaternions, and back, against scipy's Rotation as the oracle.

Quaternions are (x, y, z, w), geometry_msgs' order; a norm off 1 by more than 1e-3 is
refused, within it normalised.
"""

import math

from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from traj_gen_ros.core.kinematics import (
    check_pose,
    pose_distance,
    pose_matrix,
    pose_quaternion,
)

quaternions = st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda values: np.linalg.norm(values) > 0.1)


@settings(deadline=None, max_examples=200, derandomize=True)
@given(direction=quaternions, position=st.lists(st.floats(-5, 5), min_size=3, max_size=3))
def test_pose_matrix_and_back_agree_with_scipy(direction, position):
    quaternion = np.array(direction) / np.linalg.norm(direction)
    pose = pose_matrix(position, quaternion)
    assert np.abs(pose[:3, :3] - Rotation.from_quat(quaternion).as_matrix()).max() < 1e-12
    assert pose[:3, 3].tolist() == position and pose[3].tolist() == [0, 0, 0, 1]
    back_position, back = pose_quaternion(pose)
    assert back_position.tolist() == position
    assert back[3] >= 0  # q and -q are the same rotation: the one with w >= 0
    assert min(np.abs(back - quaternion).max(), np.abs(back + quaternion).max()) < 1e-12


@pytest.mark.parametrize('axis', [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 1)])
def test_half_turns_convert_exactly(axis):
    """Near π the trace is -1 and the largest diagonal term carries the quaternion."""
    for angle in (math.pi, math.pi - 1e-9, 1e-12, 0.0):
        rotation = Rotation.from_rotvec(np.array(axis) / np.linalg.norm(axis) * angle)
        pose = np.eye(4)
        pose[:3, :3] = rotation.as_matrix()
        _, quaternion = pose_quaternion(pose)
        expected = rotation.as_quat()
        expected = expected if expected[3] >= 0 else -expected
        assert np.abs(quaternion - expected).max() < 1e-9 or (
            expected[3] < 1e-8 and np.abs(quaternion + expected).max() < 1e-9)


def test_quaternion_norms_off_one_are_refused_else_normalised():
    assert pose_matrix([0, 0, 0], [0, 0, 0, 1.0009])[:3, :3] == pytest.approx(np.eye(3))
    for quaternion, norm in (([0, 0, 0, 0], '0'), ([0, 0, 0, 1.002], '1.002'),
                             ([0.5, 0.5, 0.5, 0.4], '0.953939')):
        with pytest.raises(ValueError) as caught:
            pose_matrix([0, 0, 0], quaternion)
        assert str(caught.value) == (
            f'quaternion (x, y, z, w) {[float(v) for v in quaternion]} has norm {norm}: a '
            'rotation needs norm 1 (within 0.001)')
    with pytest.raises(ValueError, match='position must be 3 numbers'):
        pose_matrix([0, 0], [0, 0, 0, 1])
    with pytest.raises(ValueError, match=r'quaternion \(x, y, z, w\) \[0.0, 0.0, nan, 1.0\] '
                                         'is not finite'):
        pose_matrix([0, 0, 0], [0, 0, math.nan, 1])


def test_check_pose_refuses_what_is_no_rigid_transform():
    good = pose_matrix([0.1, 0.2, 0.3], [0, 0, math.sin(0.3), math.cos(0.3)])
    assert check_pose(good) is not None
    mirrored = good.copy()
    mirrored[:3, 0] *= -1
    bottom = good.copy()
    bottom[3, 0] = 1e-3
    for bad, expected in ((mirrored, 'det -1'), (bottom, 'the last row must be [0, 0, 0, 1]'),
                          (good[:3], 'not shape (3, 4)'), (good * np.nan, 'is not finite')):
        with pytest.raises(ValueError) as caught:
            check_pose(bad)
        assert expected in str(caught.value)


def test_pose_distance_is_the_origin_distance_and_the_rotation_angle():
    first = pose_matrix([0, 0, 0], [0, 0, 0, 1])
    for angle in (1e-7, 0.3, math.pi - 1e-6, math.pi):
        second = pose_matrix([0.3, 0.4, 0], [0, math.sin(angle / 2), 0, math.cos(angle / 2)])
        distance, turned = pose_distance(first, second)
        assert distance == pytest.approx(0.5, abs=1e-15)
        assert turned == pytest.approx(angle, rel=1e-9, abs=1e-15)
