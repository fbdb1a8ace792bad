"""
The ideal tool path: straight lines through poses with blended corners, or a circular arc.

``s`` is the combined length of :mod:`.samples`. A straight segment from pose ``(p0, R0)``
to ``(p1, R1)`` translates ``L = |p1 − p0|`` and turns ``θ = |log(R1 R0ᵀ)|`` (the shorter
way, ``θ <= π``); it is ``S = √(L² + (ℓθ)²)`` long (``ℓ`` =
:data:`.samples.ROTATION_LENGTH`) and along it, by the fraction ``f = (s − s0) / S``,
``p = p0 + f (p1 − p0)`` and ``R = exp(f log(R1 R0ᵀ)) R0`` (Shoemake's slerp,
:mod:`.rotations`): ``dp/ds = (p1 − p0) / S`` and ``ω_s = log(R1 R0ᵀ) / S`` are constant.
A pure rotation in place (``L = 0``) is ``ℓθ`` long. An arc (:mod:`.circle`) of radius
``ρ`` and angle ``Φ`` is ``S = √((ρΦ)² + (ℓθ)²)`` long, its angle ``φ = Φ f`` and its
orientation the same slerp by ``f``. Corners are blended by :mod:`.corner_blend`: a
blend cuts the ends of the two segments it joins and takes an ``s``-range of its own
combined length (no longer than what it cuts), so a blended path is shorter than the
unblended one; each line keeps its rates, its ``s`` offset by the blends before it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math
from typing import Literal

import numpy as np
from traj_gen_ros.core.cartesian.circle import Circle, circle_through
from traj_gen_ros.core.cartesian.corner_blend import corner_blend, CornerBlend, CornerBlends, Leg
from traj_gen_ros.core.cartesian.rotations import rotation_exp, rotation_log
from traj_gen_ros.core.cartesian.samples import PathSamples, ROTATION_LENGTH
from traj_gen_ros.core.kinematics.poses import check_pose

#: A segment translating less than this (m) is a rotation in place (never blended) ...
SAME_POSITION = 1e-6
#: ... and one that also turns less than this (rad) repeats its pose: refused.
SAME_ROTATION = 1e-6
_KINDS = ('line', 'arc', 'blend')


@dataclass(frozen=True)
class Piece:
    """
    One piece of a tool path, ``start <= s <= end``.

    :ivar kind: ``'line'`` (a straight segment or what the blends leave of it), ``'arc'``
        (the circular path) or ``'blend'`` (a rounded corner).
    :ivar start: its first ``s``.
    :ivar end: its last ``s``.
    :ivar waypoint: the index in :attr:`ToolPath.waypoints` of the pose a line or arc
        moves to, or of the corner a blend rounds.
    """

    kind: Literal['line', 'arc', 'blend']
    start: float
    end: float
    waypoint: int


class _Motions:
    """Lines and arcs, stacked: position along a line or circle, the slerp by the fraction."""

    def __init__(self, starts: np.ndarray, rotations: np.ndarray, rates: np.ndarray,
                 origins: np.ndarray, velocities: np.ndarray,
                 circle: Circle | None = None, angle_rate: float = 0.0) -> None:
        self._starts, self._rotations, self._rates = starts, rotations, rates
        self._origins, self._velocities = origins, velocities
        self._circle, self._angle_rate = circle, angle_rate

    def sample(self, rows: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, ...]:
        local = (s - self._starts[rows])[:, None]
        rates = self._rates[rows]
        rotation = rotation_exp(local * rates) @ self._rotations[rows]
        if self._circle is None:
            velocity = self._velocities[rows]
            position = self._origins[rows] + local * velocity
            acceleration = np.zeros_like(position)
        else:
            rate = self._angle_rate
            position, velocity, acceleration = self._circle.points(rate * local[:, 0])
            velocity, acceleration = rate * velocity, rate ** 2 * acceleration
        return (position, rotation, velocity, acceleration, rates,
                np.zeros_like(acceleration))


class ToolPath:
    """
    An ideal tool path, piecewise, with its derivatives by ``s`` (an :class:`.IdealPath`).

    :ivar length: the total ``s`` (units of path).
    :ivar knots: ``(k,)`` every boundary of :attr:`pieces`, ascending, 0 to ``length``.
    :ivar stops: ``(m,)`` the start, the end and every corner that is not blended.
    :ivar pieces: the :class:`Piece` s in order.
    :ivar waypoints: ``(w, 4, 4)`` the poses as given, the start first (for plots: a
        blended corner is not on the path, nor is an arc's interim orientation).
    :ivar waypoint_s: ``(w,)`` the ``s`` at which the path reaches each, or the middle of
        the blend that rounds it.
    """

    def __init__(self, pieces: Sequence[Piece], motions: _Motions, blends: CornerBlends,
                 rows: Sequence[int], stops: Sequence[float], waypoints: np.ndarray,
                 waypoint_s: np.ndarray) -> None:
        self.pieces = tuple(pieces)
        self.knots = np.array([self.pieces[0].start] + [piece.end for piece in self.pieces])
        self.length = float(self.knots[-1])
        self.stops = np.array(stops, dtype=float)
        self.waypoints, self.waypoint_s = waypoints, waypoint_s
        self._kinds = np.array([_KINDS.index(piece.kind) for piece in self.pieces])
        self._rows = np.array(rows, dtype=int)
        self._tables = (motions, motions, blends)

    def fraction(self, s: np.ndarray | float) -> np.ndarray:
        """Return ``s / length``: how much of the path lies behind ``s``."""
        return np.asarray(s, dtype=float) / self.length

    def sample(self, s: np.ndarray | float,
               side: Literal['left', 'right'] = 'right') -> PathSamples:
        """
        Return the path at ``s`` (clipped to ``[0, length]``, a scalar as one sample).

        At a knot the derivatives are those of the piece on ``side``: the one ending there
        (``'left'``) or the one starting there (``'right'``); the pose is the same.
        """
        if side not in ('left', 'right'):
            raise ValueError(f"side must be 'left' or 'right', not {side!r}")
        s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, self.length)
        if s.ndim != 1 or not np.isfinite(s).all():
            raise ValueError(f's must be finite numbers in one dimension, not shape {s.shape}')
        index = np.clip(np.searchsorted(self.knots, s, side=side) - 1, 0, len(self.pieces) - 1)
        kinds, rows = self._kinds[index], self._rows[index]
        fields = [np.empty((len(s), 3)), np.empty((len(s), 3, 3))] + [
            np.empty((len(s), 3)) for _ in range(4)]
        for code in np.unique(kinds):
            mask = kinds == code
            for field, values in zip(fields, self._tables[code].sample(rows[mask], s[mask]),
                                     strict=True):
                field[mask] = values
        return PathSamples(s, *fields)

    def poses(self, s: np.ndarray | float) -> np.ndarray:
        """Return the ``(n, 4, 4)`` tool poses at ``s``."""
        return self.sample(s).poses()


def _segments(waypoints: np.ndarray) -> tuple[np.ndarray, ...]:
    """Return each segment's ``S``, translation, rotation vector (refusing repeated poses)."""
    translations = np.diff(waypoints[:, :3, 3], axis=0)
    turns = np.array([rotation_log(second[:3, :3] @ first[:3, :3].T)
                      for first, second in zip(waypoints[:-1], waypoints[1:], strict=True)])
    lengths = np.linalg.norm(translations, axis=1)
    angles = np.linalg.norm(turns, axis=1)
    for i in np.flatnonzero((lengths < SAME_POSITION) & (angles < SAME_ROTATION)):
        before = 'start' if i == 0 else f'poses[{i - 1}]'
        raise ValueError(
            f'straight path: poses[{i}] repeats {before} (within {SAME_POSITION:g} m and '
            f'{SAME_ROTATION:g} rad), a segment of zero length; drop the repeated pose')
    return np.hypot(lengths, ROTATION_LENGTH * angles), translations, lengths, turns


def straight_path(start: np.ndarray, poses: Sequence[np.ndarray],
                  blend_radius: float = 0.0) -> ToolPath:
    """
    Return the straight lines from ``start`` through ``poses`` (``(4, 4)``, base_frame, m).

    Each segment as the module says; with ``blend_radius`` (m) positive each corner is
    rounded by :func:`.corner_blend.corner_blend` (``d = min(r, half the shorter
    segment)``), except a reversal, a sharp corner whose legs turn the tool much beside its
    short arc, and a corner of a rotation in place: there (and everywhere when
    ``blend_radius`` is 0) the tool stops.

    :raises ValueError: a pose that is not a rigid transform, no poses, a pose repeating
        the one before it (naming ``poses[i]``), a negative or non-finite radius.
    """
    if isinstance(poses, np.ndarray) and poses.shape == (4, 4):
        poses = [poses]
    if len(poses) == 0:
        raise ValueError('straight path: poses must hold at least one pose to move to')
    if not (math.isfinite(blend_radius) and blend_radius >= 0.0):
        raise ValueError(f'straight path: blend_radius must be a finite number of metres '
                         f'>= 0 (0: stop at every corner), not {blend_radius!r}')
    waypoints = np.array([check_pose(start, 'straight path: start')] + [
        check_pose(pose, f'straight path: poses[{i}]') for i, pose in enumerate(poses)])
    lengths, translations, distances, turns = _segments(waypoints)  # S, Δp, L, log(R1 R0ᵀ)
    blends: list[CornerBlend | None] = [None]
    for k in range(1, len(poses)):
        legs = [Leg(translations[i] / max(distances[i], SAME_POSITION), distances[i],
                    distances[i] / lengths[i], turns[i] / lengths[i]) for i in (k - 1, k)]
        translating = min(distances[k - 1], distances[k]) >= SAME_POSITION
        blends.append(corner_blend(waypoints[k, :3, 3], waypoints[k, :3, :3], *legs,
                                   blend_radius)
                      if blend_radius > 0.0 and translating else None)
    blends.append(None)
    pieces, rows, stops, made, blend_starts = [], [], [0.0], [], []
    line_starts, waypoint_s, s = np.zeros(len(poses)), [0.0], 0.0
    for i in range(len(poses)):
        entered = 0.0 if blends[i] is None else blends[i].cut[1]
        left = 0.0 if blends[i + 1] is None else blends[i + 1].cut[0]
        line_starts[i] = s - entered  # where the whole segment would start
        rest = float(lengths[i] - entered - left)
        if rest > 1e-12 * max(1.0, lengths[i]):
            pieces.append(Piece('line', s, s + rest, i + 1))
            rows.append(i)
            s = pieces[-1].end
        blend = blends[i + 1]
        if blend is not None:
            pieces.append(Piece('blend', s, s + float(blend.span), i + 1))
            rows.append(len(made))
            made.append(blend)
            blend_starts.append(s)
            waypoint_s.append(s + blend.span / 2.0)
            s = pieces[-1].end
        else:
            waypoint_s.append(s)
            if i + 1 < len(poses):
                stops.append(s)
    stops.append(s)
    motions = _Motions(line_starts, waypoints[:-1, :3, :3], turns / lengths[:, None],
                       waypoints[:-1, :3, 3], translations / lengths[:, None])
    return ToolPath(pieces, motions, CornerBlends(made, blend_starts), rows, stops,
                    waypoints, np.array(waypoint_s))


def circular_path(start: np.ndarray, interim: np.ndarray, goal: np.ndarray) -> ToolPath:
    """
    Return the arc from ``start`` through ``interim``'s position to ``goal`` (base_frame, m).

    Poses are ``(4, 4)`` (``interim`` may be a position, ``(3,)``: its orientation is
    ignored, Pilz's CIRC "interim"); the orientation slerps from ``start`` to ``goal`` by
    the fraction of ``s`` (the module's formulas, :mod:`.circle` for the circle).

    :raises ValueError: a pose that is not a rigid transform, or the circle's refusals
        (two points within 1 mm, three on a line within 0.1 mm).
    """
    start = check_pose(start, 'circular path: start')
    goal = check_pose(goal, 'circular path: goal')
    if np.shape(interim) == (3,):
        point = np.eye(4)
        point[:3, 3] = interim
        interim = point
    interim = check_pose(interim, 'circular path: interim')
    circle = circle_through(start[:3, 3], interim[:3, 3], goal[:3, 3])
    turn = rotation_log(goal[:3, :3] @ start[:3, :3].T)
    length = math.hypot(circle.length, ROTATION_LENGTH * float(np.linalg.norm(turn)))
    motions = _Motions(np.zeros(1), start[None, :3, :3], (turn / length)[None],
                       start[None, :3, 3], np.zeros((1, 3)), circle, circle.angle / length)
    waypoint_s = np.array([0.0, length * circle.interim_angle / circle.angle, length])
    return ToolPath([Piece('arc', 0.0, length, 2)], motions, CornerBlends([], []), [0],
                    [0.0, length], np.array([start, interim, goal]), waypoint_s)
