"""
The tool poses of ``traj-gen line``, ``arc`` and ``solve|plot line|arc``, from their words.

A word is parsed into 3, 6 or 7 numbers by :func:`traj_gen_ros.cli.tool_path_args.pose_word`;
here they become a position (m) and a unit quaternion (x, y, z, w): the identity for 3,
from the URDF roll, pitch, yaw (``R = Rz(yaw) Ry(pitch) Rx(roll)``, rad or deg) for 6,
checked (norm 1 within 1e-3, the node's rule, :func:`traj_gen_ros.core.kinematics.pose_matrix`)
and normalised for 7. No ROS: the offline commands use it too.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np
from traj_gen_ros.cli.common import UsageError
from traj_gen_ros.cli.kinematics import rpy_quaternion
from traj_gen_ros.core.kinematics import pose_matrix

#: How many poses each shape takes: (fewest, most).
POSE_COUNTS = {'line': (1, 1000), 'arc': (2, 2)}


def tool_pose(values: Sequence[float], degrees: bool, what: str
              ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the position (m) and unit quaternion (x, y, z, w) of one pose word's numbers.

    :raises UsageError: a quaternion off norm 1 by more than 1e-3, naming ``what``.
    """
    position = np.array(values[:3], dtype=float)
    if len(values) == 3:
        return position, np.array([0.0, 0.0, 0.0, 1.0])
    if len(values) == 6:
        scale = math.radians(1.0) if degrees else 1.0
        return position, rpy_quaternion(*(value * scale for value in values[3:]))
    quaternion = np.array(values[3:], dtype=float)
    try:
        pose_matrix(position, quaternion)
    except ValueError as error:
        raise UsageError(f'{what}: {error}') from None
    return position, quaternion / np.linalg.norm(quaternion)


def tool_poses(words: Sequence[Sequence[float]], shape: str, degrees: bool
               ) -> list[tuple[np.ndarray, np.ndarray]]:
    """
    Return the poses of a ``line`` (1 to 1000) or an ``arc`` (exactly 2: interim, goal).

    :raises UsageError: a wrong count, or a quaternion off norm 1 (naming the pose, from 1).
    """
    fewest, most = POSE_COUNTS[shape]
    if not fewest <= len(words) <= most:
        wanted = ('exactly two poses, the interim point and the goal' if shape == 'arc'
                  else f'1 to {most} poses')
        raise UsageError(f'{shape} takes {wanted}; got {len(words)}')
    return [tool_pose(values, degrees, f'pose {index}')
            for index, values in enumerate(words, start=1)]


def pose_matrices(poses: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """Return each ``(position, quaternion)`` as a ``(4, 4)`` homogeneous transform."""
    return [pose_matrix(position, quaternion) for position, quaternion in poses]
