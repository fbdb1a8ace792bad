"""
Continuous joints are angles: a target is reached the shortest way round.

No ROS here. A joint is *wrapping* when its URDF type is ``continuous`` and no position
limit is in force for it (``min_position``/``max_position`` on it make it an ordinary,
bounded joint): :func:`wrapping_joints`. For such a joint a target ``q`` stands for every
``q + 2πk``; :func:`unwrap_targets` picks the one nearest the previous position, so the
published value stays continuous (from 10 rad, a goal of −0.1 rad ends at
−0.1 + 2·2π = 12.466 rad, 2.466 rad on, instead of unwinding 10.1 rad). A target already
within half a turn of the previous position is kept exactly as given; on a tie (exactly
half a turn) too, so a half turn goes the way the request says. The node applies it to
goals, via points and (the same function) FollowJointTrajectory goals while the
parameter ``angle_wraparound`` is true (the default).

Units: rad.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np
from traj_gen_ros.node.description.joint_limits import JointLimits

TURN = 2.0 * math.pi


def wrapping_joints(limits: JointLimits | None) -> np.ndarray:
    """
    Return the mask of joints whose targets wrap: URDF ``continuous``, position unlimited.

    :param limits: the limits in force (None: no URDF, so no joint wraps).
    :return: ``(joints,)`` bool.
    """
    if limits is None:
        return np.zeros(0, dtype=bool)
    continuous = np.array([kind == 'continuous' for kind in limits.types], dtype=bool)
    unlimited = ~np.isfinite(limits.position.lower) & ~np.isfinite(limits.position.upper)
    return continuous & unlimited


def unwrap_targets(start_positions: Sequence[float] | np.ndarray,
                   targets: Sequence[float] | np.ndarray,
                   continuous_mask: Sequence[bool] | np.ndarray) -> np.ndarray:
    """
    Move each continuous joint's target by whole turns to the nearest one.

    :param start_positions: where the joints are, rad, ``(joints,)``.
    :param targets: a goal ``(joints,)``, or a path ``(points, joints)`` whose every
        point is taken the shortest way from the previous one (the first from the start).
    :param continuous_mask: ``(joints,)`` bool; other joints' targets are returned as given.
    :return: the targets, same shape, each continuous one ``target + 2πk`` with the
        integer ``k`` that minimises ``|target + 2πk − previous|`` (on a tie the ``k``
        nearest 0: a target within half a turn is returned unchanged).
    :raises ValueError: shapes that do not match.
    """
    start = np.asarray(start_positions, dtype=float)
    path = np.array(targets, dtype=float)
    mask = np.asarray(continuous_mask, dtype=bool)
    single = path.ndim == 1
    rows = np.atleast_2d(path)
    if start.ndim != 1 or mask.shape != start.shape or rows.ndim != 2 or \
            rows.shape[1] != start.shape[0]:
        raise ValueError(f'unwrap_targets: start {start.shape}, targets {path.shape} and '
                         f'mask {mask.shape} must be (joints,), (joints,) or (points, joints) '
                         'and (joints,)')
    if not mask.any():
        return path
    previous = start[mask]
    for row in rows:
        turns = (previous - row[mask]) / TURN
        whole = np.sign(turns) * np.ceil(np.abs(turns) - 0.5)  # nearest, ties toward 0
        row[mask] = row[mask] + TURN * whole
        previous = row[mask]
    return rows[0] if single else rows


def shift_whole_turns(start_positions: Sequence[float] | np.ndarray,
                      path: Sequence[float] | np.ndarray,
                      continuous_mask: Sequence[bool] | np.ndarray) -> np.ndarray:
    """
    Shift each continuous joint's path by the whole turns that put its first point nearest.

    What ``joint_trajectory_controller`` does with a timed trajectory (its
    ``wraparound_joint``): the points keep their shape, each continuous joint's column
    moved by the same ``2πk``, ``k`` the integer that minimises ``|path[0] + 2πk − start|``
    (on a tie the ``k`` nearest 0).

    :param start_positions: where the joints are, rad, ``(joints,)``.
    :param path: ``(points, joints)``, rad.
    :param continuous_mask: ``(joints,)`` bool; other joints' columns are returned as given.
    :return: the shifted path, ``(points, joints)``.
    """
    start = np.asarray(start_positions, dtype=float)
    rows = np.array(path, dtype=float)
    mask = np.asarray(continuous_mask, dtype=bool)
    if rows.ndim != 2 or rows.shape[1] != start.shape[0] or mask.shape != start.shape:
        raise ValueError(f'shift_whole_turns: start {start.shape}, path {rows.shape} and '
                         f'mask {mask.shape} must be (joints,), (points, joints), (joints,)')
    if mask.any() and rows.shape[0]:
        first = unwrap_targets(start[mask], rows[0, mask], np.ones(int(mask.sum()), bool))
        rows[:, mask] += first - rows[0, mask]
    return rows
