"""
A test-only ideal tool path: one straight line from a start pose to a goal pose.

The position moves linearly and the orientation by slerp, both in ``u = s / S`` with ``S =
sqrt(L² + (ℓθ)²)`` (``L`` the distance, ``θ`` the rotation's angle, ``ℓ`` the contract's
ROTATION_LENGTH): ``p(s) = p₀ + u Δp``, ``R(s) = exp(u θ [a]×) R₀`` with ``a`` the axis of
``R₁ R₀ᵀ`` in base axes. Its derivatives are analytic: ``p' = Δp / S``, ``p'' = 0``,
``ω_s = a θ / S``, ``dω_s/ds = 0``. Knots and stops are ``[0, S]``. It satisfies
:class:`traj_gen_ros.core.cartesian.samples.IdealPath`; the real path is
:mod:`traj_gen_ros.core.cartesian.tool_path`.
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.cartesian.samples import PathSamples, ROTATION_LENGTH


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Return ``θ a`` of a rotation matrix (the angle below π; numpy, for the tests)."""
    vee = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                    rotation[1, 0] - rotation[0, 1]])
    sine, cosine = 0.5 * np.linalg.norm(vee), 0.5 * (np.trace(rotation) - 1.0)
    angle = math.atan2(sine, cosine)
    return vee * (0.5 if sine < 1e-12 else 0.5 * angle / sine)


def rotations(vectors: np.ndarray) -> np.ndarray:
    """Return ``exp([v]×)`` for ``(n, 3)`` rotation vectors (Rodrigues), ``(n, 3, 3)``."""
    angle = np.linalg.norm(vectors, axis=1)
    axis = vectors / np.where(angle > 0.0, angle, 1.0)[:, None]
    cross = np.zeros((len(vectors), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    cross -= cross.transpose(0, 2, 1)
    sine, versine = np.sin(angle)[:, None, None], (1.0 - np.cos(angle))[:, None, None]
    return np.eye(3) + sine * cross + versine * (cross @ cross)


class LineStub:
    """
    The straight line from ``start`` to ``goal`` (``(4, 4)`` poses), parameterised by ``s``.

    :ivar length: ``S``, units of path; :ivar knots: ``[0, S]``; :ivar stops: ``[0, S]``.
    """

    def __init__(self, start: np.ndarray, goal: np.ndarray) -> None:
        """Build the line; refuse a line of no length."""
        self.start, self.goal = np.asarray(start, float), np.asarray(goal, float)
        self.step = self.goal[:3, 3] - self.start[:3, 3]
        self.turn = rotation_vector(self.goal[:3, :3] @ self.start[:3, :3].T)
        self.length = math.hypot(float(np.linalg.norm(self.step)),
                                 ROTATION_LENGTH * float(np.linalg.norm(self.turn)))
        if self.length == 0.0:
            raise ValueError('the line has no length: start and goal are the same pose')
        self.knots = np.array([0.0, self.length])
        self.stops = self.knots.copy()

    def sample(self, s: np.ndarray | float, side: str = 'right') -> PathSamples:
        """Sample at ``s`` (clipped to ``[0, S]``); one piece, so ``side`` changes nothing."""
        s = np.clip(np.asarray(s, dtype=float).reshape(-1), 0.0, self.length)
        u = s / self.length
        rotation = rotations(u[:, None] * self.turn) @ self.start[:3, :3]
        count = len(s)
        return PathSamples(
            s=s, position=self.start[:3, 3] + u[:, None] * self.step, rotation=rotation,
            velocity=np.tile(self.step / self.length, (count, 1)),
            acceleration=np.zeros((count, 3)),
            angular=np.tile(self.turn / self.length, (count, 1)),
            angular_acceleration=np.zeros((count, 3)))

    def pose(self, s: float) -> np.ndarray:
        """Return the ``(4, 4)`` pose at one ``s``."""
        return self.sample(s).poses()[0]


class PolylineStub:
    """
    Straight lines through ``poses`` one after another, a corner (a knot and a stop) at each.

    Each line is a :class:`LineStub`; at a knot ``sample(s, 'left')`` gives the derivatives of
    the line that ends there, ``'right'`` those of the line that starts there.
    """

    def __init__(self, poses: list[np.ndarray]) -> None:
        """Build the lines between consecutive poses."""
        self.lines = [LineStub(first, second)
                      for first, second in zip(poses[:-1], poses[1:], strict=True)]
        self.knots = np.concatenate([[0.0], np.cumsum([line.length for line in self.lines])])
        self.stops = self.knots.copy()
        self.length = float(self.knots[-1])

    def sample(self, s: np.ndarray | float, side: str = 'right') -> PathSamples:
        """Sample at ``s`` (clipped to ``[0, length]``), each on its line (``side`` at a knot)."""
        s = np.clip(np.asarray(s, dtype=float).reshape(-1), 0.0, self.length)
        found = np.searchsorted(self.knots, s, side='left' if side == 'left' else 'right') - 1
        found = np.clip(found, 0, len(self.lines) - 1)
        parts = [self.lines[k].sample(value - self.knots[k])
                 for k, value in zip(found, s, strict=True)]
        fields = ('position', 'rotation', 'velocity', 'acceleration', 'angular',
                  'angular_acceleration')
        return PathSamples(s=s, **{name: np.concatenate([getattr(part, name) for part in parts])
                                   for name in fields})

    def pose(self, s: float) -> np.ndarray:
        """Return the ``(4, 4)`` pose at one ``s``."""
        return self.sample(s).poses()[0]


def tool_errors(chain, joints, path, count: int = 10_000) -> tuple[float, float]:
    """
    Return how far the tool strays from ``path`` at ``count`` values of ``s``: (m, rad).

    The tool's pose is the chain's forward kinematics of ``joints.sample(s)``; the angle
    of ``R_idealᵀ R`` by ``atan2(|vee|, tr − 1)`` (accurate near 0), all in numpy.
    """
    s = np.linspace(0.0, path.length, count)
    poses = chain.forward(joints.sample(s)[0])
    ideal = path.sample(s)
    distance = np.linalg.norm(poses[:, :3, 3] - ideal.position, axis=1)
    relative = ideal.rotation.transpose(0, 2, 1) @ poses[:, :3, :3]
    vee = np.stack([relative[:, 2, 1] - relative[:, 1, 2], relative[:, 0, 2] - relative[:, 2, 0],
                    relative[:, 1, 0] - relative[:, 0, 1]], axis=1)
    angle = np.arctan2(np.linalg.norm(vee, axis=1), np.trace(relative, axis1=1, axis2=2) - 1)
    return float(distance.max()), float(angle.max())
