"""
Poses as 4×4 homogeneous transforms: built from a position and a quaternion, checked, compared.

numpy only (no Pinocchio): a pose is a ``(4, 4)`` array ``[[R, p], [0, 0, 0, 1]]``, ``R``
a rotation matrix, ``p`` in metres; quaternions are ``(x, y, z, w)``, the order of
``geometry_msgs/Quaternion``. A quaternion whose norm is off 1 by more than
:data:`QUATERNION_TOLERANCE` (or zero) is refused; within it, it is normalised.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np

#: How far from 1 a quaternion's norm may be before it is refused (it is normalised).
QUATERNION_TOLERANCE = 1e-3
#: How far from orthonormal (largest entry of ``RᵀR − I``) a pose's rotation may be.
ROTATION_TOLERANCE = 1e-6


def _vector(values: Sequence[float], size: int, what: str) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'{what} must be {size} numbers, not {values!r}') from None
    if array.shape != (size,):
        raise ValueError(f'{what} must be {size} numbers, not shape {array.shape}')
    if not np.isfinite(array).all():
        raise ValueError(f'{what} {array.tolist()} is not finite')
    return array


def pose_matrix(position: Sequence[float],
                quaternion: Sequence[float] = (0.0, 0.0, 0.0, 1.0)) -> np.ndarray:
    """
    Return the pose with ``position`` (m) and orientation ``quaternion`` (x, y, z, w).

    :raises ValueError: not 3 and 4 finite numbers, or a quaternion whose norm is off 1 by
        more than :data:`QUATERNION_TOLERANCE` (zero included), saying its norm.
    """
    position = _vector(position, 3, 'position')
    x, y, z, w = quaternion = _vector(quaternion, 4, 'quaternion (x, y, z, w)')
    norm = math.sqrt(float(quaternion @ quaternion))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise ValueError(f'quaternion (x, y, z, w) {quaternion.tolist()} has norm {norm:.6g}: '
                         f'a rotation needs norm 1 (within {QUATERNION_TOLERANCE:g})')
    x, y, z, w = quaternion / norm
    pose = np.eye(4)
    pose[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    pose[:3, 3] = position
    return pose


def pose_quaternion(pose: np.ndarray, *, checked: bool = False
                    ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return ``(position, quaternion)`` of a pose: metres and ``(x, y, z, w)``, ``w >= 0``.

    The quaternion comes from the rotation matrix by its largest diagonal term (Shepperd's
    method, accurate for every rotation). ``checked``: the pose is known to be a rigid
    transform (one :meth:`Chain.forward` made), so :func:`check_pose` is skipped.
    """
    if not checked:
        pose = check_pose(pose)
    r = pose[:3, :3]
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    choice = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    if choice == 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        quaternion = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                      (r[1, 0] - r[0, 1]) / s, s / 4]
    else:
        i = choice - 1
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 0.0))
        quaternion = [0.0, 0.0, 0.0, (r[k, j] - r[j, k]) / s]
        quaternion[i] = s / 4
        quaternion[j] = (r[j, i] + r[i, j]) / s
        quaternion[k] = (r[k, i] + r[i, k]) / s
    quaternion = np.array(quaternion)
    quaternion /= np.linalg.norm(quaternion)
    return pose[:3, 3].copy(), quaternion if quaternion[3] >= 0 else -quaternion


def check_pose(pose: np.ndarray, what: str = 'pose') -> np.ndarray:
    """
    Return ``pose`` as a float ``(4, 4)`` array if it is a rigid transform; else refuse.

    :raises ValueError: not ``(4, 4)``, not finite, last row not ``[0, 0, 0, 1]``, or a
        rotation part that is not orthonormal with determinant +1 (within
        :data:`ROTATION_TOLERANCE`).
    """
    try:
        pose = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'{what} must be a 4x4 homogeneous transform') from None
    if pose.shape != (4, 4):
        raise ValueError(f'{what} must be a 4x4 homogeneous transform, not shape {pose.shape}')
    if not np.isfinite(pose).all():
        raise ValueError(f'{what} is not finite: {pose.tolist()}')
    if np.abs(pose[3] - [0.0, 0.0, 0.0, 1.0]).max() > 0.0:
        raise ValueError(f'{what}: the last row must be [0, 0, 0, 1], not {pose[3].tolist()}')
    rotation = pose[:3, :3]
    off = np.abs(rotation.T @ rotation - np.eye(3)).max()
    if off > ROTATION_TOLERANCE or np.linalg.det(rotation) < 0:
        raise ValueError(f'{what}: the upper-left 3x3 block is not a rotation (orthonormal, '
                         f'determinant +1, within {ROTATION_TOLERANCE:g}): RᵀR − I reaches '
                         f'{off:.3g}, det {np.linalg.det(rotation):.6g}')
    return pose


def pose_distance(first: np.ndarray, second: np.ndarray) -> tuple[float, float]:
    """
    Return how far apart two poses are: ``(distance of the origins in m, angle in rad)``.

    The angle is that of the rotation from one to the other, ``atan2(|vee(R − Rᵀ)|,
    trace(R) − 1)`` for ``R = R1ᵀ R2``: accurate near 0 and near π alike.
    """
    first, second = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    relative = first[:3, :3].T @ second[:3, :3]
    vee = [relative[2, 1] - relative[1, 2], relative[0, 2] - relative[2, 0],
           relative[1, 0] - relative[0, 1]]
    angle = math.atan2(math.hypot(*vee), float(np.trace(relative)) - 1.0)
    return float(np.linalg.norm(second[:3, 3] - first[:3, 3])), angle
