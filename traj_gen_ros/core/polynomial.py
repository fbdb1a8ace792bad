"""
Cubic and quintic polynomial profiles, single segment and through via points.

Equation numbers are those of the lecture (Craig, *Introduction to Robotics*, 3rd ed.,
§7.3): cubic eq. (6) rest-to-rest and eq. (9) with boundary velocities, the two-segment
spline eq. (13), the quintic eq. (3) of "higher-order polynomials".

Every segment is solved in normalised time ``s = t / t_f``, where the coefficients are one
constant matrix ``M`` (Craig's closed form with ``t_f = 1``) times the conditions scaled by
``t_f**order``; undoing the scaling, ``a_k = Σ_i M[k, i] t_f**(order_i - k) b_i``: one small
matrix product per segment for all joints at once.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike

# Eq. (9) with t_f = 1; columns are (θ0, θ̇0, θf, θ̇f), rows a0…a3.
CUBIC_MATRIX = np.array([
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [-3.0, -2.0, 3.0, -1.0],
    [2.0, 1.0, -2.0, 1.0],
])
_CUBIC_ORDERS = np.array([0, 1, 0, 1])
_CUBIC_EXPONENTS = _CUBIC_ORDERS[None, :] - np.arange(4)[:, None]

# Quintic eq. (3) with t_f = 1; columns are (θ0, θ̇0, θ̈0, θf, θ̇f, θ̈f), rows a0…a5.
QUINTIC_MATRIX = np.array([
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
    [-10.0, -6.0, -1.5, 10.0, -4.0, 0.5],
    [15.0, 8.0, 1.5, -15.0, 7.0, -1.0],
    [-6.0, -3.0, -0.5, 6.0, -3.0, 0.5],
])
_QUINTIC_ORDERS = np.array([0, 1, 2, 0, 1, 2])
_QUINTIC_EXPONENTS = _QUINTIC_ORDERS[None, :] - np.arange(6)[:, None]

# Shorter segments would overflow t_f**-5 (float64 reaches 1.8e308), longer ones underflow
# it (a quintic's a5 = 6 Δθ / t_f**5 would vanish: a plan that silently stands still).
_SHORTEST_SEGMENT = 1e-60
_LONGEST_SEGMENT = 1e60
# Above this many unknown via velocities the dense solve gives way to the O(n) sweep.
_DENSE_SOLVE_LIMIT = 128


@validation.refuses_overflow('cubic')
def cubic(
    q0: ArrayLike, qf: ArrayLike, duration: float, v0: ArrayLike = 0.0, vf: ArrayLike = 0.0
) -> Trajectory:
    """
    Cubic from ``q0`` to ``qf`` (rad) in ``duration`` (s): Craig eq. (6), or (9) with velocities.

    ``v0``, ``vf`` (rad/s) default to rest. Scalars are one joint; 1-D arrays one per joint.
    """
    conditions = validation.per_joint_rows(q0=q0, v0=v0, qf=qf, vf=vf)
    duration = validation.duration_of(duration)
    start = conditions[0].copy()
    conditions[0], conditions[2] = 0.0, conditions[2] - start
    return _segments(CUBIC_MATRIX, _CUBIC_EXPONENTS, start[None], conditions[None],
                     np.array([duration]))


@validation.refuses_overflow('quintic')
def quintic(
    q0: ArrayLike,
    qf: ArrayLike,
    duration: float,
    v0: ArrayLike = 0.0,
    vf: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
    af: ArrayLike = 0.0,
) -> Trajectory:
    """
    Quintic meeting position, velocity and acceleration at both ends: Craig's eq. (3).

    Units: rad, rad/s, rad/s², s. Scalars are one joint; 1-D arrays one per joint.
    """
    conditions = validation.per_joint_rows(q0=q0, v0=v0, a0=a0, qf=qf, vf=vf, af=af)
    duration = validation.duration_of(duration)
    start = conditions[0].copy()
    conditions[0], conditions[3] = 0.0, conditions[3] - start
    return _segments(QUINTIC_MATRIX, _QUINTIC_EXPONENTS, start[None], conditions[None],
                     np.array([duration]))


def to_rest(profile: str, start: np.ndarray, goal: np.ndarray, duration: float,
            start_velocity: np.ndarray, start_acceleration: np.ndarray) -> Trajectory:
    """
    :func:`cubic` (from ``v0``) or :func:`quintic` (from ``v0``, ``a0``) to rest at ``goal``.

    For inputs already validated (flat per-joint arrays, a valid duration), as the timing
    of a move from a moving state has them: the same plan without checking them again.
    """
    cubic_profile = profile == 'cubic'
    matrix, exponents = (CUBIC_MATRIX, _CUBIC_EXPONENTS) if cubic_profile else \
        (QUINTIC_MATRIX, _QUINTIC_EXPONENTS)
    conditions = np.zeros((1, matrix.shape[1], start.size))
    conditions[0, 1] = start_velocity
    if cubic_profile:
        np.subtract(goal, start, out=conditions[0, 2])
    else:
        conditions[0, 2] = start_acceleration
        np.subtract(goal, start, out=conditions[0, 3])
    if not _SHORTEST_SEGMENT <= duration <= _LONGEST_SEGMENT:  # _segments says what is wrong
        return _segments(matrix, exponents, start[None], conditions, np.array([duration]))
    # _segments' product for one segment, without its array bookkeeping.
    with np.errstate(over='ignore', invalid='ignore'):  # checked right below
        coefficients = (matrix * duration ** exponents) @ conditions
        coefficients[:, 0] += start
    if not validation.every(np.isfinite(coefficients)):
        return _segments(matrix, exponents, start[None], conditions, np.array([duration]))
    return Trajectory(np.array([0.0, duration]), coefficients)


@validation.refuses_overflow('cubic_via')
def cubic_via(
    points: ArrayLike,
    durations: ArrayLike,
    velocities: str | ArrayLike = 'heuristic',
    v0: ArrayLike = 0.0,
) -> Trajectory:
    """
    Cubic spline through every point, one eq. (9) cubic per segment.

    :param points: positions (rad), ``(points,)`` or ``(points, joints)``.
    :param durations: one duration (s) per segment.
    :param velocities: the velocity at every point: ``"heuristic"`` (Craig: average of the
        neighbouring slopes, zero where the slope changes sign), ``"continuous"`` (the
        spline with continuous acceleration at every via point; for two equal segments
        it is eq. (13)), or an array ``(points,)`` / ``(points, joints)`` in rad/s.
    :param v0: start velocity (rad/s) for the two rules; they end at rest. Ignored with an
        array, which gives every point's velocity itself.

    """
    path, durations, point_velocities = _via_inputs(points, durations, velocities, v0)
    steps = np.diff(path, axis=0)
    boundary = np.stack([np.zeros_like(steps), point_velocities[:-1], steps,
                         point_velocities[1:]], axis=1)
    return _segments(CUBIC_MATRIX, _CUBIC_EXPONENTS, path[:-1], boundary, durations)


@validation.refuses_overflow('quintic_via')
def quintic_via(
    points: ArrayLike,
    durations: ArrayLike,
    velocities: str | ArrayLike = 'heuristic',
    accelerations: ArrayLike | None = None,
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
) -> Trajectory:
    """
    Quintic spline through every point: one eq. (3) quintic per segment.

    Velocities follow :func:`cubic_via`. ``accelerations`` (rad/s², ``(points, joints)``)
    default to ``a0`` at the start, rest at the goal and, at each via point, the mean of
    the two cubic segments' accelerations there (for ``"continuous"`` velocities: the
    spline's own), so position, velocity and acceleration are continuous everywhere.
    """
    path, durations, point_velocities = _via_inputs(points, durations, velocities, v0)
    if accelerations is None:
        point_accelerations = _mean_cubic_accelerations(path, durations, point_velocities)
        point_accelerations[0] = validation.per_joint_rows(a0=a0, like=path[0])[0]
    else:
        point_accelerations = validation.per_point('accelerations', accelerations, path.shape)
    steps = np.diff(path, axis=0)
    boundary = np.stack([
        np.zeros_like(steps), point_velocities[:-1], point_accelerations[:-1],
        steps, point_velocities[1:], point_accelerations[1:],
    ], axis=1)
    return _segments(QUINTIC_MATRIX, _QUINTIC_EXPONENTS, path[:-1], boundary, durations)


def quintic_hermite(
    breakpoints: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    start_accelerations: np.ndarray,
    end_accelerations: np.ndarray,
) -> Trajectory:
    """
    One eq. (3) quintic per interval from the states at its two ends.

    The building block of sampled paths (:mod:`traj_gen_ros.core.cartesian`): position
    and velocity are shared by the intervals that meet at a breakpoint; the acceleration is
    each interval's own at either end, so it may step there.

    :param breakpoints: ``(n,)`` ascending, in the trajectory's time unit (s, or units of
        path where the polynomial is in ``s``).
    :param positions: ``(n, joints)`` at the breakpoints.
    :param velocities: ``(n, joints)`` at the breakpoints.
    :param start_accelerations: ``(n - 1, joints)``, each interval's at its start.
    :param end_accelerations: ``(n - 1, joints)``, each interval's at its end.
    """
    breakpoints = np.asarray(breakpoints, dtype=float)
    positions, velocities = np.asarray(positions, float), np.asarray(velocities, float)
    boundary = np.stack([
        np.zeros_like(positions[1:]), velocities[:-1], np.asarray(start_accelerations, float),
        positions[1:] - positions[:-1], velocities[1:], np.asarray(end_accelerations, float),
    ], axis=1)
    trajectory = _segments(QUINTIC_MATRIX, _QUINTIC_EXPONENTS, positions[:-1], boundary,
                           np.diff(breakpoints))
    if breakpoints[0] != 0.0:
        trajectory = Trajectory(breakpoints.copy(), trajectory.coefficients)
    return trajectory


def heuristic_velocities(
    path: np.ndarray, durations: np.ndarray, v0: np.ndarray | float = 0.0,
    resolution: float = 0.0,
) -> np.ndarray:
    """
    Craig's via-point velocity rule (§7.3): mean of the neighbouring slopes, or zero.

    Zero where the slope changes sign or either neighbouring slope is zero; ``v0`` at
    the start, rest at the goal. ``path`` is ``(points, joints)``; result in rad/s. A
    step no larger than ``resolution`` (rad) counts as none: its slope is zero (the
    S-curve path passes Ruckig's precision, below which a step is no motion).
    """
    steps = np.diff(path, axis=0)
    if resolution > 0.0:
        steps = np.where(np.abs(steps) <= resolution, 0.0, steps)
    slopes = steps / durations[:, None]
    left, right = slopes[:-1], slopes[1:]
    interior = np.where(left * right > 0.0, 0.5 * (left + right), 0.0)
    start = np.broadcast_to(v0, path[0].shape)[None]
    return np.concatenate([start, interior, np.zeros_like(path[:1])])


def continuous_velocities(
    path: np.ndarray, durations: np.ndarray, v0: np.ndarray | float = 0.0
) -> np.ndarray:
    """
    Via velocities that make the cubic spline's acceleration continuous (clamped ends).

    Equating eq. (9)'s end acceleration of segment k-1 with the start acceleration of
    segment k at every via point gives, with ``h`` the durations and ``Δ`` the steps,
    ``v[k-1]/h[k-1] + 2 v[k] (1/h[k-1] + 1/h[k]) + v[k+1]/h[k]
    = 3 (Δ[k-1]/h[k-1]² + Δ[k]/h[k]²)``: a tridiagonal system, one right side per joint.
    """
    start = np.broadcast_to(np.asarray(v0, dtype=float), path[0].shape)
    velocities = np.zeros_like(path)
    velocities[0] = start
    unknowns = len(path) - 2
    if unknowns == 0:
        return velocities
    inverse = 1.0 / durations
    steps = np.diff(path, axis=0) * (inverse**2)[:, None]
    rhs = 3.0 * (steps[:-1] + steps[1:])
    rhs[0] -= start * inverse[0]
    diagonal = 2.0 * (inverse[:-1] + inverse[1:])
    off_diagonal = inverse[1:-1]
    if unknowns <= _DENSE_SOLVE_LIMIT:
        matrix = np.diag(diagonal) + np.diag(off_diagonal, 1) + np.diag(off_diagonal, -1)
        velocities[1:-1] = np.linalg.solve(matrix, rhs)
    else:
        velocities[1:-1] = _tridiagonal_sweep(off_diagonal, diagonal, rhs)
    return velocities


def _tridiagonal_sweep(
    off_diagonal: np.ndarray, diagonal: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """Thomas algorithm for a symmetric tridiagonal system; memory O(n) for long paths."""
    count = len(diagonal)
    pivots = diagonal.astype(float).copy()
    rhs = rhs.copy()
    for row in range(1, count):
        factor = off_diagonal[row - 1] / pivots[row - 1]
        pivots[row] -= factor * off_diagonal[row - 1]
        rhs[row] -= factor * rhs[row - 1]
    solution = np.empty_like(rhs)
    solution[-1] = rhs[-1] / pivots[-1]
    for row in range(count - 2, -1, -1):
        solution[row] = (rhs[row] - off_diagonal[row] * solution[row + 1]) / pivots[row]
    return solution


def _via_inputs(
    points: ArrayLike, durations: ArrayLike, velocities: str | ArrayLike, v0: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate and return path ``(points, joints)``, durations and point velocities."""
    path = validation.path_points(points)
    durations = validation.segment_durations(durations, len(path) - 1)
    if isinstance(velocities, str):
        start = validation.per_joint_rows(v0=v0, like=path[0])[0]
        rules = {'heuristic': heuristic_velocities, 'continuous': continuous_velocities}
        if velocities not in rules:
            raise ValueError(f'velocities must be "heuristic", "continuous" or an array of '
                             f'one velocity per point, got "{velocities}"')
        return path, durations, rules[velocities](path, durations, start)
    return path, durations, validation.per_point('velocities', velocities, path.shape)


def _mean_cubic_accelerations(
    path: np.ndarray, durations: np.ndarray, velocities: np.ndarray
) -> np.ndarray:
    """At each via point, the mean of the two eq. (9) cubics' accelerations; 0 at the goal."""
    steps = np.diff(path, axis=0)
    h = durations[:, None]
    start = 6.0 * steps / h**2 - (4.0 * velocities[:-1] + 2.0 * velocities[1:]) / h
    end = -6.0 * steps / h**2 + (2.0 * velocities[:-1] + 4.0 * velocities[1:]) / h
    accelerations = np.zeros_like(path)
    accelerations[1:-1] = 0.5 * (end[:-1] + start[1:])
    return accelerations


def _segments(
    matrix: np.ndarray,
    exponents: np.ndarray,
    start: np.ndarray,
    boundary: np.ndarray,
    durations: np.ndarray,
) -> Trajectory:
    """
    Solve one polynomial per segment from its boundary conditions.

    ``start`` is each segment's start position ``(segments, joints)``; ``boundary`` holds
    the conditions ``(segments, conditions, joints)`` in the matrix's column order with
    positions relative to ``start`` (0 at the start, the step at the end), so a joint that
    does not move keeps exactly zero higher coefficients however short the segment.
    ``exponents[k, i] = order_i - k`` undoes the normalised-time scaling.
    """
    if np.count_nonzero(durations < _SHORTEST_SEGMENT):  # (cheaper than .min() on a few)
        raise ValueError(f'segment {int(np.argmin(durations))} lasts {durations.min():g} s: '
                         f'polynomial segments must last at least {_SHORTEST_SEGMENT:g} s')
    if np.count_nonzero(durations > _LONGEST_SEGMENT):
        raise ValueError(f'segment {int(np.argmax(durations))} lasts {durations.max():g} s: '
                         f'polynomial segments must last at most {_LONGEST_SEGMENT:g} s (their '
                         'coefficients would underflow)')
    with np.errstate(over='ignore', invalid='ignore'):  # checked right below
        coefficients = (matrix * durations[:, None, None] ** exponents) @ boundary
        coefficients[:, 0] += start
    if not validation.every(np.isfinite(coefficients)):
        segment = int(np.argmin(np.isfinite(coefficients).all(axis=(1, 2))))
        raise ValueError(f'segment {segment} lasts {durations[segment]:g} s, too short for its '
                         'boundary conditions (or its positions and velocities too large): its '
                         'coefficients overflow; give a longer duration or smaller values')
    breakpoints = np.zeros(len(durations) + 1)
    np.cumsum(durations, out=breakpoints[1:])
    return Trajectory(breakpoints, coefficients)
