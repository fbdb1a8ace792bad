"""
Constant bounds of ``ṡ``, ``s̈`` and ``s⃛`` on a piece of path that keep every joint's jerk.

Along ``q(s)`` (primes: derivatives by ``s``) the chain rule gives ``q̇ = q' ṡ``,
``q̈ = q' s̈ + q'' ṡ²`` and ``q⃛ = q' s⃛ + 3 q'' ṡ s̈ + q''' ṡ³``. With ``R_k`` the largest
``|q^(k)|`` of a joint over the piece (exact: the peaks of its quintic pieces,
:meth:`~traj_gen_ros.core.trajectory.Trajectory.peaks_with_jerk`) and ``|ṡ| <= V``,
``|s̈| <= A``, ``|s⃛| <= J``, the triangle inequality bounds every joint by

    ``R1 V <= v``,  ``R1 A + R2 V² <= a``,  ``R1 J + 3 R2 V A + R3 V³ <= j``,

and the tool point the same way (``|p'| V <= v_lin``, ``|p'| A + |p''| V² <= a_lin``,
``|ω_s| V <= ω``). Any ``(V, A, J)`` that meets them keeps every limit wherever the path
parameter stays within them: a conservative bound, exact where the largest rates
coincide (a straight joint motion: ``q'' = q''' = 0``). :func:`best_bounds` chooses the
``(V, A, J)`` whose rest-to-rest S-curve over the piece is the shortest
(:func:`scurve_duration`, in closed form); :func:`brake_bounds` the ``(A, J)`` of the
shortest brake from a moving state. Both search a grid of candidates: every candidate
meets the bounds above exactly, only the choice among them is sampled.

Units: units of path (m, or rad for a rotation in place), s; the limits in rad (or m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from traj_gen_ros.core.cartesian.bound_report import Bound, TOOL_KINDS
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.jerk_limited.brake import scurve_brake
from traj_gen_ros.core.trajectory import Trajectory

#: The fractions of the largest speed, and of the largest acceleration at that speed,
#: that :func:`best_bounds` tries (1 among them), then refines about the best.
_FRACTIONS = np.unique(np.concatenate([np.geomspace(1e-4, 0.02, 12),
                                       np.linspace(0.02, 1.0, 50)]))
_COARSEST = 0.02
_REFINE = np.linspace(-1.0, 1.0, 21)
#: Where between the least and the largest J :func:`brake_bounds` tries too.
_GAPS = np.concatenate([[1e-12], np.geomspace(1e-9, 1.0, 60)])
#: The smallest share of a row's bound that :meth:`Rows.refined` takes a motion to use.
_LEAST_SHARE = 0.02
#: The fractions of the largest jerk that :func:`brake_bounds` tries.
_JERK_FRACTIONS = np.unique(np.concatenate([np.geomspace(1e-3, 1.0, 60),
                                            1.0 - np.geomspace(1e-12, 0.3, 40)]))


@dataclass(frozen=True)
class Rows:
    """
    The bounds of one piece as rows, each divided by its limit.

    :ivar velocity: ``(r,)`` ``c`` of ``c V <= 1`` (every joint, tool speed, tool turn).
    :ivar acceleration: ``(2, r)`` ``c1, c2`` of ``c1 A + c2 V² <= 1``.
    :ivar jerk: ``(3, r)`` ``c1, c2, c3`` of ``c1 J + 3 c2 V A + c3 V³ <= 1``.
    :ivar names: the :class:`Bound` of every row of each kind, in that order.
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    names: tuple[tuple[Bound, ...], tuple[Bound, ...], tuple[Bound, ...]]

    def values(self, bounds: Bounds) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return each row's left side at ``bounds``: the bound of its peak / limit."""
        v, a, j = bounds.speed, bounds.acceleration, bounds.jerk
        c1, c2, c3 = self.jerk
        return (self.velocity * v, self.acceleration[0] * a + self.acceleration[1] * v * v,
                c1 * j + 3.0 * c2 * v * a + c3 * v ** 3)

    def refined(self, bounds: Bounds, measured: dict[Bound, float], tighten: bool = False
                ) -> Rows:
        """
        Return the rows times what the motion planned with ``bounds`` really used of them.

        ``measured`` holds each limit's peak / limit of that motion (a row missing from it
        is kept as it is); the factor of a row is that over the row's own value at
        ``bounds``: at least :data:`_LEAST_SHARE` and at most 1 (a row is only loosened:
        conservative rows bound what a motion uses), or with ``tighten`` at least 1 (a
        row is only tightened: a motion above a limit is bounded by its rows again).
        """
        factors = []
        for names, values in zip(self.names, self.values(bounds), strict=True):
            share = np.array([measured.get(name, value) for name, value in
                              zip(names, values.tolist(), strict=True)])
            with np.errstate(divide='ignore', invalid='ignore'):
                factor = np.where(values > 0.0, share / values, 1.0)
            factors.append(np.maximum(factor, 1.0) if tighten
                           else np.clip(factor, _LEAST_SHARE, 1.0))
        return Rows(self.velocity * factors[0], self.acceleration * factors[1],
                    self.jerk * factors[2], self.names)


@dataclass(frozen=True)
class Bounds:
    """The chosen ``(V, A, J)`` of a piece and the limit each came from (:class:`Bound`)."""

    speed: float
    acceleration: float
    jerk: float
    speed_bound: Bound
    acceleration_bound: Bound
    jerk_bound: Bound


def piece_rows(path: IdealPath, joint_path: JointPath, start: float, end: float,
               velocity: np.ndarray, acceleration: np.ndarray, jerk: np.ndarray,
               tool: np.ndarray) -> Rows:
    """
    Build the rows of the piece ``[start, end]`` from the largest rates on it.

    The joints' ``R1..R3`` are the exact peaks of every quintic of ``q(s)`` that overlaps
    the piece; the tool's ``|p'|``, ``|p''|``, ``|ω_s|`` the largest at the joint path's
    breakpoints on it and the middles between them (constant along lines and arcs). A
    joint whose ``R1`` is 0 does not move on the piece and has no row.
    """
    joints = joint_path.joints
    breaks = joints.breakpoints
    first = max(int(np.searchsorted(breaks, start, side='right')) - 1, 0)
    last = min(int(np.searchsorted(breaks, end, side='left')), len(breaks) - 1)
    last = max(last, first + 1)
    piece = Trajectory(breaks[first:last + 1] - breaks[first],
                       joints.coefficients[first:last])
    rates = np.array(piece.peaks_with_jerk())  # (3, joints): max |q'|, |q''|, |q'''|
    inside = np.clip(breaks[first:last + 1], start, end)
    probe = np.union1d(inside, 0.5 * (inside[1:] + inside[:-1]))
    samples = path.sample(probe[:-1], 'right')
    ends = path.sample(probe[-1:], 'left')
    tangent = max(np.linalg.norm(samples.velocity, axis=1).max(),
                  np.linalg.norm(ends.velocity, axis=1).max())
    bend = max(np.linalg.norm(samples.acceleration, axis=1).max(),
               np.linalg.norm(ends.acceleration, axis=1).max())
    turn = max(np.linalg.norm(samples.angular, axis=1).max(),
               np.linalg.norm(ends.angular, axis=1).max())
    moving = np.flatnonzero(rates[0] > 0.0)
    joint_rows = rates[:, moving]
    velocity_rows = np.concatenate([joint_rows[0] / velocity[moving],
                                    [tangent / tool[0], turn / tool[2]]])
    acceleration_rows = np.concatenate(
        [joint_rows[:2] / acceleration[moving], [[tangent / tool[1]], [bend / tool[1]]]],
        axis=1)
    names = ([Bound('velocity', int(j)) for j in moving]
             + [Bound(TOOL_KINDS[0]), Bound(TOOL_KINDS[2])],
             [Bound('acceleration', int(j)) for j in moving] + [Bound(TOOL_KINDS[1])])
    speed_keep, accel_keep = velocity_rows > 0.0, acceleration_rows[0] > 0.0
    return Rows(velocity_rows[speed_keep], acceleration_rows[:, accel_keep],
                joint_rows / jerk[moving],
                (tuple(name for name, kept in zip(names[0], speed_keep, strict=True) if kept),
                 tuple(name for name, kept in zip(names[1], accel_keep, strict=True) if kept),
                 tuple(Bound('jerk', int(j)) for j in moving)))


def _acceleration_room(rows: Rows, speed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the largest ``A`` at each speed ``V`` and the row that sets it."""
    c1, c2 = rows.acceleration[:, None, :]
    room = (1.0 - c2 * speed[:, None] ** 2) / c1
    return room.min(axis=1), room.argmin(axis=1)


def _jerk_room(rows: Rows, speed: np.ndarray, acceleration: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Return the largest ``J`` at each ``(V, A)`` and the row that sets it."""
    c1, c2, c3 = rows.jerk[:, None, :]
    v, a = speed[:, None], acceleration[:, None]
    room = (1.0 - 3.0 * c2 * v * a - c3 * v ** 3) / c1
    return room.min(axis=1), room.argmin(axis=1)


def scurve_duration(length: float, speed: np.ndarray, acceleration: np.ndarray,
                    jerk: np.ndarray) -> np.ndarray:
    """
    Time the rest-to-rest seven-phase S-curve over ``length`` (Biagiotti & Melchiorri §3.4).

    Accelerating takes ``T_a = A/J + V/A`` where ``V J >= A²``, else ``2 √(V/J)``; with a
    cruise (``length >= V T_a``) the motion lasts ``length / V + T_a``; without,
    ``T_a = (A/J + √((A/J)² + 4 length / A)) / 2`` and it lasts ``2 T_a`` where the
    acceleration still reaches ``A`` (``length >= 2 A³ / J²``), else ``4 ∛(length / 2J)``.
    """
    v, a, j = (np.asarray(value, dtype=float) for value in (speed, acceleration, jerk))
    with np.errstate(divide='ignore', invalid='ignore'):
        ramp = a / j
        accelerating = np.where(v * j >= a * a, ramp + v / a, 2.0 * np.sqrt(v / j))
        cruise = length / v + accelerating
        short = np.where(length >= 2.0 * a ** 3 / (j * j),
                         ramp + np.sqrt(ramp * ramp + 4.0 * length / a),
                         4.0 * np.cbrt(0.5 * length / j))
        duration = np.where(length >= v * accelerating, cruise, short)
    return np.where((v > 0.0) & (a > 0.0) & (j > 0.0), duration, np.inf)


def best_bounds(rows: Rows, length: float) -> Bounds:
    """
    Choose the ``(V, A, J)`` of the shortest rest-to-rest S-curve over ``length``.

    ``V`` a fraction of the largest speed, ``A`` a fraction of the largest acceleration at
    ``V``, ``J`` the largest at both: a grid of fractions, then a finer one about the best.

    :raises ValueError: no speed is possible (no bound at all, or none leaves room).
    """
    top = 1.0 / rows.velocity.max(initial=0.0)
    if not (np.isfinite(top) and rows.jerk.shape[1]):
        raise ValueError('the piece moves no joint: nothing bounds its speed')
    best = _search(rows, length, top, *np.meshgrid(_FRACTIONS, _FRACTIONS))
    width = _COARSEST
    for _ in range(2):  # _REFINE holds 0: the best so far is among the candidates
        best = _search(rows, length, top, *np.meshgrid(
            np.clip(best[0] + width * _REFINE, 1e-6, 1.0),
            np.clip(best[1] + width * _REFINE, 1e-6, 1.0)))
        width *= 0.1
    speed_fraction, acceleration_fraction, duration = best
    if not np.isfinite(duration):
        raise ValueError('the limits leave no room to move along this piece of the path '
                         "(the joints' curvature uses up their acceleration or jerk at "
                         'every speed)')
    speed = np.array([top * speed_fraction])
    room, row = _acceleration_room(rows, speed)
    acceleration = room * acceleration_fraction
    jerk, jerk_row = _jerk_room(rows, speed, acceleration)
    jerk_name = rows.names[2][int(jerk_row[0])]
    return Bounds(
        float(speed[0]), float(acceleration[0]), float(jerk[0]),
        rows.names[0][int(rows.velocity.argmax())] if speed_fraction == 1.0 else jerk_name,
        rows.names[1][int(row[0])] if acceleration_fraction == 1.0 else jerk_name, jerk_name)


def _search(rows: Rows, length: float, top: float, speed_fraction: np.ndarray,
            acceleration_fraction: np.ndarray) -> tuple[float, float, float]:
    """Return the fractions with the shortest duration and that duration (inf: none)."""
    speed_fraction, acceleration_fraction = speed_fraction.ravel(), acceleration_fraction.ravel()
    speed = top * speed_fraction
    room, _ = _acceleration_room(rows, speed)
    acceleration = np.maximum(room, 0.0) * acceleration_fraction
    jerk, _ = _jerk_room(rows, speed, acceleration)
    duration = scurve_duration(length, speed, acceleration, jerk)
    best = int(np.argmin(duration))
    return float(speed_fraction[best]), float(acceleration_fraction[best]), \
        float(duration[best])


def brake_bounds(rows: Rows, speed: float, path_acceleration: float, room: float,
                 margin: float = 1.0) -> tuple[float, float] | None:
    """
    Choose the ``(A, J)`` of the shortest jerk-limited brake from ``(ṡ, s̈)``; None: none.

    A brake that starts with ``s̈ > 0`` first speeds up to ``V = ṡ + s̈² / 2J``; ``A``
    must hold ``|s̈|`` (:func:`~traj_gen_ros.core.jerk_limited.brake.scurve_brake` keeps a
    start beyond its limit), and it must come to rest within ``room`` (units of path).
    Candidates are fractions of the largest ``J`` at ``(ṡ, |s̈|)``, many of them near 1:
    from a state of a timing, its own ``J`` is the one that rests at the next stop. The
    chosen ``A`` and ``J`` are then times ``margin`` (``A`` no lower than ``|s̈|``).
    """
    start, rising = abs(path_acceleration), max(path_acceleration, 0.0)
    ceiling, _ = _jerk_room(rows, np.array([speed]), np.array([start]))
    if not ceiling[0] > 0.0:
        return None
    # The least J: the peak speed ṡ + s̈²/2J within the speed rows and where the
    # acceleration rows still hold |s̈| (c1 |s̈| + c2 V² <= 1).
    c1, c2 = rows.acceleration
    with np.errstate(divide='ignore', invalid='ignore'):
        top = min(1.0 / rows.velocity.max(initial=0.0),
                  float(np.sqrt(np.where(c2 > 0.0, (1.0 - c1 * start) / c2, np.inf)).min(
                      initial=np.inf)))
    if rising > 0.0 and not top > speed:
        return None
    # ... and no reversal: from s̈ < 0 the speed falls by s̈² / 2J before s̈ is back at 0.
    falling = max(-path_acceleration, 0.0)
    least = max(rising * rising / (2.0 * (top - speed)) if rising > 0.0 else 0.0,
                falling * falling / (2.0 * speed) if falling > 0.0 else 0.0)
    jerk = ceiling[0] * _JERK_FRACTIONS
    if 0.0 < least < ceiling[0]:
        jerk = np.union1d(jerk, least + (ceiling[0] - least) * _GAPS)
    jerk = jerk[jerk >= least]
    peak = speed + rising ** 2 / (2.0 * jerk)
    by_acceleration, _ = _acceleration_room(rows, peak)
    c1, c2, c3 = rows.jerk[:, None, :]
    with np.errstate(divide='ignore', invalid='ignore'):
        by_jerk = np.where(c2 > 0.0, (1.0 - c1 * jerk[:, None] - c3 * peak[:, None] ** 3)
                           / (3.0 * c2 * peak[:, None]), np.inf).min(axis=1)
    acceleration = np.minimum(by_acceleration, by_jerk)
    feasible = (acceleration >= start * (1.0 - 1e-9)) & (acceleration > 0.0) & \
        (peak * rows.velocity.max(initial=0.0) <= 1.0 + 1e-9)
    if not feasible.any():
        return None
    jerk = jerk[feasible] * margin
    acceleration = np.maximum(acceleration[feasible] * margin, start)
    plans = scurve_brake(np.zeros(jerk.size), speed, path_acceleration, acceleration, jerk)
    duration = np.where(plans.coefficients[3, 0] <= room, plans.breakpoints[3], np.inf)
    best = int(np.argmin(duration))
    if not np.isfinite(duration[best]):
        return None
    return float(acceleration[best]), float(jerk[best])
