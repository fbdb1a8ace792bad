"""
Synthetic tool paths and joint paths with exact derivatives, for the timing's tests.

:class:`PiecePath` is an :class:`~traj_gen_ros.core.cartesian.samples.IdealPath` made of
lines and circular arcs end to end; :class:`AnalyticJoints` is ``q(s)`` in closed form
(linear terms plus sinusoids), turned into a
:class:`~traj_gen_ros.core.cartesian.samples.JointPath` by sampling it with its exact
derivatives into :func:`~traj_gen_ros.core.polynomial.quintic_hermite` in ``s``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from traj_gen_ros.core.cartesian.samples import JointPath, PathSamples
from traj_gen_ros.core.polynomial import quintic_hermite


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


@dataclass(frozen=True)
class Line:
    """``p = start + σ v`` with ``dp/ds = v`` and a constant ``ω_s`` (rad per unit)."""

    start: np.ndarray
    velocity: np.ndarray
    length: float
    angular: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def evaluate(self, sigma: np.ndarray) -> tuple[np.ndarray, ...]:
        position = self.start + sigma[:, None] * self.velocity
        velocity = np.broadcast_to(self.velocity, position.shape).copy()
        angular = np.broadcast_to(self.angular, position.shape).copy()
        return position, velocity, np.zeros_like(position), angular

    def end(self) -> np.ndarray:
        return self.start + self.length * self.velocity


@dataclass(frozen=True)
class Arc:
    """A circle of ``radius`` about ``centre`` in the plane of ``e1``, ``e2``, by arc length."""

    centre: np.ndarray
    radius: float
    e1: np.ndarray
    e2: np.ndarray
    start_angle: float
    angle: float  # signed turn, rad

    @property
    def length(self) -> float:
        return abs(self.angle) * self.radius

    def evaluate(self, sigma: np.ndarray) -> tuple[np.ndarray, ...]:
        sign = np.sign(self.angle)
        theta = self.start_angle + sign * sigma / self.radius
        radial = np.cos(theta)[:, None] * self.e1 + np.sin(theta)[:, None] * self.e2
        tangent = sign * (-np.sin(theta)[:, None] * self.e1 + np.cos(theta)[:, None] * self.e2)
        return (self.centre + self.radius * radial, tangent, -radial / self.radius,
                np.zeros_like(radial))


class PiecePath:
    """
    Lines and arcs end to end as an ``IdealPath`` (the rotation is left at identity).

    ``stops``: the knots where the tool rests, beside the start and the end.
    """

    def __init__(self, pieces: list, stops: tuple[float, ...] = ()) -> None:
        self.pieces = pieces
        self.knots = np.concatenate([[0.0], np.cumsum([piece.length for piece in pieces])])
        self.length = float(self.knots[-1])
        self.stops = np.unique(np.concatenate([[0.0, self.length], stops]))

    def sample(self, s: np.ndarray | float, side: str = 'right') -> PathSamples:
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        inner = self.knots[1:-1]
        piece = np.searchsorted(inner, s, side='right' if side == 'right' else 'left')
        out = [np.zeros((len(s), 3)) for _ in range(4)]
        for index, shape in enumerate(self.pieces):
            mask = piece == index
            if mask.any():
                values = shape.evaluate(s[mask] - self.knots[index])
                for array, value in zip(out, values, strict=True):
                    array[mask] = value
        rotation = np.broadcast_to(np.eye(3), (len(s), 3, 3)).copy()
        return PathSamples(s, out[0], rotation, out[1], out[2], out[3], np.zeros_like(out[3]))


def line(length: float, direction=(1.0, 0.0, 0.0), turn: float = 0.0) -> PiecePath:
    """
    Make a straight line ``length`` long (units of path), turning about z on the way.

    Per unit of path the tool travels ``√(1 - turn²)`` m and turns ``turn`` rad.
    """
    unit = np.asarray(direction, float) / np.linalg.norm(direction)
    return PiecePath([Line(np.zeros(3), unit * np.sqrt(1.0 - turn ** 2), length,
                           np.array([0.0, 0.0, turn]))])


def arc(radius: float, angle: float) -> PiecePath:
    """Make a circular arc in the xy-plane from ``(radius, 0, 0)``, turning ``angle`` (rad)."""
    return PiecePath([Arc(np.zeros(3), radius, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]),
                          0.0, angle)])


def blended_corner(first: float, radius: float, angle: float, second: float,
                   stop_at_corner: bool = False) -> PiecePath:
    """Line along x, an arc tangent to it turning ``angle`` (rad), a tangent line again."""
    start = Line(np.zeros(3), np.array([1.0, 0, 0]), first)
    centre = start.end() + np.array([0.0, radius, 0.0])
    bend = Arc(centre, radius, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), -np.pi / 2, angle)
    end_point = centre + radius * np.array([np.sin(angle), -np.cos(angle), 0.0])
    direction = np.array([np.cos(angle), np.sin(angle), 0.0])
    pieces = [start, bend, Line(end_point, direction, second)]
    return PiecePath(pieces, (first,) if stop_at_corner else ())


def corner(first: float, second: float, angle: float) -> PiecePath:
    """Two lines meeting at an unblended corner of ``angle`` (rad), a stop."""
    start = Line(np.zeros(3), np.array([1.0, 0, 0]), first)
    direction = np.array([np.cos(angle), np.sin(angle), 0.0])
    return PiecePath([start, Line(start.end(), direction, second)], (first,))


@dataclass(frozen=True)
class AnalyticJoints:
    """``q_j(s) = offset_j + slope_j s + Σ amplitude_jk sin(frequency_jk s + phase_jk)``."""

    offset: np.ndarray
    slope: np.ndarray
    amplitude: np.ndarray = field(default_factory=lambda: np.zeros((1, 1)))
    frequency: np.ndarray = field(default_factory=lambda: np.zeros((1, 1)))
    phase: np.ndarray = field(default_factory=lambda: np.zeros((1, 1)))

    def states(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``q``, ``dq/ds``, ``d²q/ds²`` at ``s``, ``(len(s), joints)`` each."""
        s = np.asarray(s, float)[:, None, None]
        angle = self.frequency * s + self.phase
        q = self.offset + self.slope * s[:, :, 0] + (self.amplitude * np.sin(angle)).sum(2)
        dq = self.slope + (self.amplitude * self.frequency * np.cos(angle)).sum(2)
        ddq = -(self.amplitude * self.frequency ** 2 * np.sin(angle)).sum(2)
        return tuple(np.broadcast_to(value, q.shape).copy() for value in (q, dq, ddq))

    def joint_path(self, path: PiecePath, pieces: int = 64) -> JointPath:
        """Sample at ``pieces`` equal steps plus the knots into one quintic per step."""
        breaks = np.union1d(np.linspace(0.0, path.length, pieces + 1), path.knots)
        q, dq, ddq = self.states(breaks)
        joints = quintic_hermite(breaks, q, dq, ddq[:-1], ddq[1:])
        return JointPath(joints, path.knots.copy(), path.stops.copy(), path.length)


def seven_joints(seed: int = 7, scale: float = 1.0) -> AnalyticJoints:
    """Make a 7-joint arm's path, roughly: up to ~2 rad/m of each joint, bending over ~0.1 m."""
    rng = np.random.default_rng(seed)
    return AnalyticJoints(
        offset=rng.uniform(-1.0, 1.0, 7), slope=scale * rng.uniform(-2.0, 2.0, 7),
        amplitude=scale * rng.uniform(0.005, 0.03, (7, 2)),
        frequency=rng.uniform(5.0, 25.0, (7, 2)), phase=rng.uniform(0, 2 * np.pi, (7, 2)))


def linear_joint(slope: float = 1.0) -> AnalyticJoints:
    """One joint, ``q = slope · s``."""
    return AnalyticJoints(np.zeros(1), np.array([slope]))
