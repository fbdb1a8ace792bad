"""
Trajectories run one after the other: one :class:`Trajectory` with shared breakpoints.

A brake to rest followed by a path along the tool (:mod:`traj_gen_ros.core.cartesian`) is
one plan: the second trajectory starts where the first ends, in time and state. Pieces of
lower degree are padded with zero coefficients; per-joint breakpoints (LSPB, the brake)
are merged first (a Taylor shift of each joint's pieces onto the union of breakpoints).

Units: s; rad (or m).
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory


def concatenate(trajectories: Sequence[Trajectory]) -> Trajectory:
    """
    Join ``trajectories`` end to end: each starts at the previous one's duration.

    Zero-duration ones (a hold) add nothing. The joint counts must agree; that each starts
    at the previous one's end state is the caller's to ensure (it is not checked).

    :raises ValueError: no trajectory, or joint counts that differ.
    """
    if not trajectories:
        raise ValueError('concatenate needs at least one trajectory')
    joints = {plan.joint_count for plan in trajectories}
    if len(joints) != 1:
        raise ValueError(f'concatenate: joint counts differ ({sorted(joints)})')
    moving = [plan for plan in trajectories if plan.duration > 0.0] or [trajectories[-1]]
    degree = max(plan.degree for plan in moving)
    breakpoints, coefficients, start = [np.zeros(1)], [], 0.0
    for plan in moving:
        shared, pieces = plan.shared_pieces
        padded = np.zeros((pieces.shape[0], degree + 1, pieces.shape[2]))
        padded[:, :pieces.shape[1]] = pieces
        breakpoints.append(shared[1:] - shared[0] + start)
        coefficients.append(padded)
        start = breakpoints[-1][-1]
    return Trajectory(np.concatenate(breakpoints), np.concatenate(coefficients))


def tail(trajectory: Trajectory, start: float) -> Trajectory:
    """
    Return ``trajectory`` from ``start`` (s) on, in local time from 0.

    The piece that holds ``start`` is re-expanded about it (a Taylor shift:
    ``c'_k = Σ_m C(m, k) c_m d^(m-k)``); the later pieces are kept as they are.

    :raises ValueError: ``start`` outside ``[0, duration]``.
    """
    if not 0.0 <= start <= trajectory.duration:
        raise ValueError(f'tail: start {start!r} s is outside [0, {trajectory.duration:g}] s')
    breakpoints, coefficients = trajectory.shared_pieces
    piece = int(np.clip(np.searchsorted(breakpoints, start, side='right') - 1, 0,
                        len(coefficients) - 1))
    offset = start - breakpoints[piece]
    degree = coefficients.shape[1] - 1
    shift = np.array([[math.comb(m, k) * offset ** (m - k) if m >= k else 0.0
                       for m in range(degree + 1)] for k in range(degree + 1)])
    first = np.einsum('km,mj->kj', shift, coefficients[piece])
    kept = np.concatenate([first[None], coefficients[piece + 1:]])
    return Trajectory(np.concatenate([[0.0], breakpoints[piece + 1:] - start]), kept)
