"""
Why a tool path cannot be followed: :class:`PathRefusal`, with its messages.

The geometric problems of Cartesian paths in Craig §7.5 (*Introduction to Robotics*, 3rd
ed.): intermediate points unreachable (type 1), high joint rates near a singularity (type
2), start and goal reachable only in different solutions (type 3, the configuration
flip); and a joint limit on the way. Each is found on the whole path before any motion:
the joint path is given whole or not at all. Where along the path is a *fraction* of its
length ``s``; joints are named by the chain's joint names.
"""

from __future__ import annotations

from collections.abc import Sequence
import math
from typing import Literal

import numpy as np
from traj_gen_ros.core.cartesian.samples import ROTATION_LENGTH

Kind = Literal['reach', 'limit', 'singular', 'flip']


class PathRefusal(ValueError):  # noqa: N818 - the issue's name: a refusal, not an error
    """
    A tool path that the joints cannot follow, with where and why.

    :ivar kind: ``'reach'`` (a point of the path that no joint positions within the limits
        reach), ``'limit'`` (a joint would cross its position limit), ``'singular'`` (a
        joint would need more than :data:`.continuation.RATE_LIMIT` per unit of path) or
        ``'flip'`` (beyond a point the path is reachable only in another configuration).
    :ivar fraction: where, as a fraction of the path's length ``s`` (0 to 1).
    :ivar joint: the joint's index in the chain's joints (None for ``'reach'``).
    :ivar value: per kind: ``'reach'``, how far the closest attempt stays from the path
        pose, ``sqrt(d² + (ℓ·θ)²)`` in units of path (the message gives mm and mrad);
        ``'limit'``, the limit crossed (rad or m); ``'singular'``, the Jacobian's smallest
        singular value there; ``'flip'``, the jump of ``joint`` (rad or m).
    :ivar q: the joint positions at ``fraction`` on the continuation (the last it reached
        for ``'reach'`` and ``'flip'``), ``(joints,)``, or None.
    """

    def __init__(self, message: str, kind: Kind, fraction: float, joint: int | None,
                 value: float, q: np.ndarray | None = None) -> None:
        """Keep the message and the facts it states."""
        super().__init__(message)
        self.kind, self.fraction, self.joint, self.value = kind, float(fraction), joint, value
        self.q = q


def _where(s: float, length: float) -> str:
    return f'{100.0 * s / length:.4g} % of the tool path (s = {s:.6g} of {length:.6g})'


def _unit(angular: bool) -> str:
    return 'rad' if angular else 'm'


def start_refusal(names: Sequence[str], angular: Sequence[bool], joint: int, side: str,
                  bound: float, length: float, q: np.ndarray) -> PathRefusal:
    """Refuse a path whose ``q_start`` has ``joint`` beyond its ``side`` limit already."""
    unit = _unit(angular[joint])
    return PathRefusal(
        f'q_start puts joint {names[joint]!r} at {q[joint]:g} {unit}, beyond its {side} '
        f'limit {bound:g} {unit}: the joint path cannot start there', 'limit', 0.0, joint,
        float(bound), q)


def limit_refusal(names: Sequence[str], angular: Sequence[bool], joint: int, side: str,
                  bound: float, s: float, length: float, q: np.ndarray) -> PathRefusal:
    """Refuse the path where ``joint`` crosses its ``side`` ('lower'/'upper') limit."""
    unit = _unit(angular[joint])
    return PathRefusal(
        f'joint {names[joint]!r} would cross its {side} limit {bound:g} {unit} at '
        f'{_where(s, length)}: the continuation of the inverse kinematics from q_start '
        'leaves the joint limits there; start from other joint positions or change the path',
        'limit', s / length, joint, float(bound), q)


def singular_refusal(names: Sequence[str], angular: Sequence[bool], joint: int, rate: float,
                     smallest: float, limit: float, s: float, length: float,
                     q: np.ndarray) -> PathRefusal:
    """Refuse a singular path: ``joint`` needs ``rate`` (> ``limit``) per unit of path."""
    unit = _unit(angular[joint])
    need = 'an unbounded rate' if math.isinf(rate) else f'{rate:.4g} {unit} per unit of path'
    return PathRefusal(
        f'the tool path is singular at {_where(s, length)}: joint {names[joint]!r} would need '
        f'{need} there and more beyond (the limit is {limit:g} {unit}: per metre of tool '
        'travel, per radian of tool rotation); the smallest singular '
        f'value of the Jacobian there is {smallest:.3g}; keep the path away from the '
        'singularity', 'singular', s / length, joint, float(smallest), q)


def flip_refusal(names: Sequence[str], angular: Sequence[bool], jumps: np.ndarray, s: float,
                 length: float, beyond: float, q: np.ndarray) -> PathRefusal:
    """Refuse a configuration flip at ``s``: beyond it the joints would jump by ``jumps``."""
    joint = int(np.argmax(np.abs(jumps)))
    unit = _unit(angular[joint])
    return PathRefusal(
        f'configuration flip at {_where(s, length)}: the continuation of the inverse '
        f'kinematics from q_start ends there (a singularity) and {beyond * 1e3:.3g} mm of '
        'path beyond it is reachable only in another configuration, joint '
        f'{names[joint]!r} jumping by {abs(float(jumps[joint])):.4g} {unit}; start and goal '
        'need different configurations: split the path there and move between them joint '
        'by joint', 'flip', s / length, joint, abs(float(jumps[joint])), q)


def reach_refusal(position_error: float, orientation_error: float, s: float, length: float,
                  beyond: float, stopped: str, q: np.ndarray) -> PathRefusal:
    """Refuse a path that leaves the reach at ``s``; the closest attempt ``beyond`` it."""
    distance = math.hypot(position_error, ROTATION_LENGTH * orientation_error)
    return PathRefusal(
        f'the tool path leaves the reach of the arm at {_where(s, length)}: '
        f'{beyond * 1e3:.3g} mm of path beyond it, the closest the tool comes is '
        f'{position_error * 1e3:.3f} mm and {orientation_error * 1e3:.3f} mrad from the path '
        f'pose{stopped}', 'reach', s / length, None, distance, q)
