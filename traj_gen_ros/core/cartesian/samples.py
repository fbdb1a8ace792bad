"""
The data that passes between the tool path, the joint path and the timing.

The path parameter ``s`` is the path's *combined length*: along every line and arc,
metres of tool travel and radians of tool rotation combine as ``ds² = |dp|² + (ℓ·dθ)²`` with
``ℓ = 1 m/rad`` (:data:`ROTATION_LENGTH`). A straight line of 0.3 m is 0.3 long; a pure
rotation of 1 rad is 1 long. Every rate "per unit of path" below is per that unit: per
metre for a line without rotation, per radian for a rotation in place. A blended corner
(:mod:`.corner_blend`) spans its combined length as a whole, its arc's length and the
rotation of the legs it cuts: where the tool does not turn ``|dp/ds| = 1`` along it, and
otherwise ``|dp/ds|² + ℓ²|ω_s|²`` is 1 at its ends and varies across it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory

#: Metres of path that one radian of tool rotation counts as (ℓ in ``ds² = dp² + ℓ²dθ²``).
ROTATION_LENGTH = 1.0


@dataclass(frozen=True)
class PathSamples:
    """
    The ideal tool path and its derivatives by ``s`` at ``n`` values of ``s``.

    All in ``base_frame``'s axes. At a knot (a boundary of pieces) the derivatives are one
    side's: :meth:`ToolPath.sample` says which.

    :ivar s: ``(n,)`` path parameter.
    :ivar position: ``(n, 3)`` tool point, m.
    :ivar rotation: ``(n, 3, 3)`` tool orientation.
    :ivar velocity: ``(n, 3)`` ``dp/ds`` (m per unit of path).
    :ivar acceleration: ``(n, 3)`` ``d²p/ds²``.
    :ivar angular: ``(n, 3)`` ``ω_s``, with ``dR/ds = [ω_s]× R`` (rad per unit of path).
    :ivar angular_acceleration: ``(n, 3)`` ``dω_s/ds``.
    """

    s: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    angular: np.ndarray
    angular_acceleration: np.ndarray

    def poses(self) -> np.ndarray:
        """Return the ``(n, 4, 4)`` homogeneous tool poses."""
        poses = np.zeros((len(self.s), 4, 4))
        poses[:, :3, :3] = self.rotation
        poses[:, :3, 3] = self.position
        poses[:, 3, 3] = 1.0
        return poses


@dataclass(frozen=True)
class JointPath:
    """
    The joint positions that follow a tool path, as a function of ``s``.

    :ivar joints: ``q(s)``: the core's piecewise polynomial with ``s`` in the place of
        time (breakpoints in units of path, every knot of the tool path among them);
        ``joints.sample(s)`` gives ``q``, ``dq/ds`` and ``d²q/ds²``, ``(n, joints)``.
        Between its breakpoints it is exact to the inverse kinematics' tolerance.
    :ivar knots: ``(k,)`` every boundary of the tool path's pieces, ``0`` to ``length``:
        the derivatives may jump there.
    :ivar stops: ``(m,)`` the values of ``s`` where the tool must be at rest: the start,
        the end and every corner that is not blended.
    :ivar length: the path's total ``s``.
    """

    joints: Trajectory
    knots: np.ndarray
    stops: np.ndarray
    length: float


class IdealPath(Protocol):
    """
    What the joint path and the timing need of a tool path (:class:`.tool_path.ToolPath`).

    :ivar length: the total ``s`` (units of path, > 0).
    :ivar knots: ``(k,)`` ascending boundaries of its pieces, ``knots[0] == 0``,
        ``knots[-1] == length``; the derivatives by ``s`` may jump there.
    :ivar stops: ``(m,)`` the knots where the tool must be at rest (the start, the end,
        every corner that is not blended).
    """

    length: float
    knots: np.ndarray
    stops: np.ndarray

    def sample(self, s: np.ndarray | float,
               side: Literal['left', 'right'] = 'right') -> PathSamples:
        """Sample at ``s`` (clipped to ``[0, length]``); at a knot, ``side``'s piece."""
