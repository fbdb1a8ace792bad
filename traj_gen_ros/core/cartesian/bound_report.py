"""
What bounded the speed where along a timed path: the active limit of every interval.

A time-optimal timing touches a limit at every instant (Pham & Pham 2018, §IV): on each
interval the limit closest to tight (largest ``rate / limit`` at either end) is the one
that bounds it. :func:`describe` says it in words, by runs of the path's length.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from traj_gen_ros.core.cartesian.path_constraints import PathGrid

#: The tool's limits, in :class:`~.path_constraints.ToolLimits`' order.
TOOL_KINDS = ('max_linear_velocity', 'max_linear_acceleration', 'max_angular_velocity')
#: From this ``rate / limit`` on, a limit is tight. An interval with none (where ``s̈``
#: turns from its largest to its smallest) takes the bound of the one before.
TIGHT = 0.99
#: Runs shorter than this fraction of the path are folded into their neighbours.
SHORTEST_RUN = 0.02


@dataclass(frozen=True)
class Bound:
    """
    The limit that bounds the speed on an interval.

    :ivar kind: ``'velocity'`` or ``'acceleration'`` of joint ``joint``, one of
        :data:`TOOL_KINDS`, or ``'stop'`` (no limit is tight anywhere: only the rests at
        the stops bound the speed).
    :ivar joint: the joint's index for a joint limit, else ``None``.
    """

    kind: str
    joint: int | None = None

    def name(self, joint_names: Sequence[str] | None = None) -> str:
        """Say which limit it is: ``joint 'j4' velocity``, ``max_linear_velocity``."""
        if self.joint is None:
            return self.kind
        joint = f'joint {self.joint}' if joint_names is None else \
            f'joint {joint_names[self.joint]!r}'
        return f'{joint} {self.kind}'


def active_bounds(grid: PathGrid, squared_speed: np.ndarray, path_acceleration: np.ndarray,
                  max_velocity: np.ndarray, max_acceleration: np.ndarray,
                  tool: np.ndarray) -> tuple[Bound, ...]:
    """
    Find every interval's active limit from its ``rate / limit`` at both ends.

    :param squared_speed: ``(n + 1,)`` ``ṡ²`` at the grid.
    :param path_acceleration: ``(n,)`` ``s̈`` on each interval.
    :param max_velocity: ``(joints,)`` rad/s; ``max_acceleration`` rad/s².
    :param tool: ``(3,)`` the :class:`~.path_constraints.ToolLimits` as an array.
    """
    ends = np.stack([squared_speed[:-1], squared_speed[1:]])  # (2, n)
    speed = np.sqrt(ends)
    u = path_acceleration[None]
    joint_velocity = np.abs(grid.dq) * speed[..., None]
    joint_acceleration = np.abs(grid.dq * u[..., None] + grid.ddq * ends[..., None])
    tool_acceleration = np.hypot(grid.tangent * u + grid.along * ends, grid.across * ends)
    rates = np.concatenate([
        joint_velocity, joint_acceleration,
        np.stack([grid.tangent * speed, tool_acceleration, grid.turn * speed], axis=2),
    ], axis=2).max(axis=0)  # (n, 2 joints + 3)
    limits = np.concatenate([max_velocity, max_acceleration, tool])
    ratios = rates / limits
    codes = ratios.argmax(axis=1)
    tight = ratios.max(axis=1) >= TIGHT
    if not tight.any():
        codes[:] = len(limits)
    elif not tight.all():  # where s̈ turns from the largest to the smallest: the one before
        last = np.maximum.accumulate(np.where(tight, np.arange(len(codes)), -1))
        codes = np.where(last >= 0, codes[np.maximum(last, 0)], codes[np.argmax(tight)])
    joints = len(max_velocity)
    kinds = [Bound('velocity', j) for j in range(joints)] + \
        [Bound('acceleration', j) for j in range(joints)] + \
        [Bound(kind) for kind in TOOL_KINDS] + [Bound('stop')]
    return tuple(kinds[code] for code in codes.tolist())


def describe(bounds: Sequence[Bound], s: np.ndarray,
             joint_names: Sequence[str] | None = None) -> str:
    """
    Say what bounded the speed where, e.g. ``joint 'j4' velocity from 38 % to 61 % …``.

    Runs of one bound are merged, runs under :data:`SHORTEST_RUN` of the path are folded
    into the longer neighbour, and the bound that covers most of the path is named last
    as ``elsewhere``. ``s`` is the grid, ``(len(bounds) + 1,)``.
    """
    length = float(s[-1] - s[0])
    runs: list[list] = []
    for bound, start, end in zip(bounds, s[:-1].tolist(), s[1:].tolist(), strict=True):
        if runs and runs[-1][0] == bound:
            runs[-1][2] = end
        else:
            runs.append([bound, start, end])
    while len(runs) > 1:
        shortest = min(range(len(runs)), key=lambda k: runs[k][2] - runs[k][1])
        if runs[shortest][2] - runs[shortest][1] >= SHORTEST_RUN * length:
            break
        neighbours = [k for k in (shortest - 1, shortest + 1) if 0 <= k < len(runs)]
        into = max(neighbours, key=lambda k: runs[k][2] - runs[k][1])
        runs[shortest][0] = runs[into][0]
        merged = [runs[0]]
        for run in runs[1:]:
            if run[0] == merged[-1][0]:
                merged[-1][2] = run[2]
            else:
                merged.append(run)
        runs = merged
    if len(runs) == 1:
        return f'{runs[0][0].name(joint_names)} on the whole path'
    covered: dict[Bound, float] = {}
    for bound, start, end in runs:
        covered[bound] = covered.get(bound, 0.0) + end - start
    elsewhere = max(covered, key=covered.__getitem__)
    parts = []
    for bound in covered:
        if bound != elsewhere:
            spans = ' and '.join(
                f'from {_percent(start, s[0], length)} to {_percent(end, s[0], length)}'
                for kind, start, end in runs if kind == bound)
            parts.append(f'{bound.name(joint_names)} {spans} of the path')
    return '; '.join(parts + [f'{elsewhere.name(joint_names)} elsewhere'])


def _percent(value: float, start: float, length: float) -> str:
    """Print where ``value`` lies on the path, in whole per cent."""
    return f'{100.0 * (value - start) / length:.0f} %'
