"""
Exact minimum-time timing of a cubic or quintic move from a moving state to rest.

A cubic (Craig eq. (9), from ``v0``) or quintic (eq. (3), from ``v0``, ``a0``) that moves
``D`` in ``T`` has, in normalised time ``τ = t/T``, position
``x(τ) = v0 T m_v(τ) + a0 T² m_a(τ) + D m_D(τ)``, where ``m_v``, ``m_a``, ``m_D`` are the
columns of the profile's boundary-condition matrix. Its velocity and acceleration times a
power of ``T`` are quadratics in ``T`` whose coefficients are polynomials in ``τ``:

``T v = a0 m_a' T² + v0 m_v' T + D m_D'``, ``T² a = a0 m_a'' T² + v0 m_v'' T + D m_D''``.

A duration where the peak ``|v|`` (or ``|a|``) just equals its limit is either one where
the limit is met at an end (``τ = 0`` or ``1``: a quadratic in ``T``) or one where an
interior extremum meets it: ``P(τ, T) = 0`` and ``∂P/∂τ = 0`` together, which the
resultant in ``T`` of the two quadratics turns into a polynomial in ``τ`` (degree ≤ 9
once the known factors ``τ`` and ``τ - 1`` are divided out). Its real roots in ``[0, 1]``
give every such duration. Between two consecutive candidate durations feasibility cannot
change, so checking each candidate and one duration inside each gap with the exact peaks
gives each joint's set of feasible durations as closed intervals: nothing is sampled.
The synchronised duration is then the smallest one in every joint's set (the shape of
Ruckig's Step 1 / synchronise / Step 2).

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from traj_gen_ros import second_order
from traj_gen_ros.limits import LIMIT_TOLERANCE
from traj_gen_ros.polynomial import CUBIC_MATRIX, QUINTIC_MATRIX
from traj_gen_ros.polynomial_peaks import derivative, evaluate, unit_peaks

#: Shortest polynomial plan (s): shorter ones' coefficients ~ D/T⁵ overflow.
SHORTEST_POLYNOMIAL = 1e-9
_IMAGINARY_SLACK = 1e-6  # roots this close to the real axis count as real (double roots)
_FIRST_BATCH = 16  # joints analysed exactly at first (the largest lower bounds)


def _columns(matrix: np.ndarray, columns: tuple[int | None, ...]) -> np.ndarray:
    """Shape polynomials ``(3, 6)``: ascending coefficients of m_v, m_a, m_D (zero if None)."""
    shapes = np.zeros((3, 6))
    for row, column in enumerate(columns):
        if column is not None:
            shapes[row, :matrix.shape[0]] = matrix[:, column]
    return shapes


_SHAPES = {
    'cubic': _columns(CUBIC_MATRIX, (1, None, 2)),
    'quintic': _columns(QUINTIC_MATRIX, (1, 2, 3)),
}


def _multiply(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Products of ascending polynomials, batched over leading axes: one outer product."""
    rows, columns = first.shape[-1], second.shape[-1]
    outer = (first[..., :, None] * second[..., None, :]).reshape(first.shape[:-1] + (-1,))
    return outer @ _product_sums(rows, columns)


@functools.cache
def _product_sums(rows: int, columns: int) -> np.ndarray:
    """0/1 matrix summing outer-product entries ``i, j`` into power ``i + j``."""
    sums = np.zeros((rows * columns, rows + columns - 1))
    powers = np.add.outer(np.arange(rows), np.arange(columns)).reshape(-1)
    sums[np.arange(rows * columns), powers] = 1.0
    return sums


def _quadratics(profile: str, order: int, displacement: np.ndarray, start_velocity: np.ndarray,
                start_acceleration: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """
    ``P(τ, T) = p2 T² + p1 T + p0`` with the limit term ``σ V`` or ``σ A``, ``σ = ±1``.

    ``order`` 1: ``T v - σ V T``; order 2: ``T² a - σ A T²``. Shaped
    ``(2 signs, joints, 3 powers of T, 6 powers of τ)``.
    """
    shapes = derivative(_SHAPES[profile], order)
    coefficients = np.empty((2, displacement.size, 3, 6))
    coefficients[:, :, 0] = start_acceleration[:, None] * shapes[1]
    coefficients[:, :, 1] = start_velocity[:, None] * shapes[0]
    coefficients[:, :, 2] = displacement[:, None] * shapes[2]
    limit_row = 0 if order == 2 else 1
    coefficients[0, :, limit_row, 0] -= limit
    coefficients[1, :, limit_row, 0] += limit
    return coefficients


def _resultants(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """
    Resultant in ``T`` of ``p = p2T² + p1T + p0`` and ``q`` (each ``(..., 3, n)``) in ``τ``.

    ``(p2q0 - q2p0)² - (p2q1 - q2p1)(p1q0 - q1p0)``: the Sylvester determinant.
    """
    first = _multiply(p[..., 0, :], q[..., 2, :]) - _multiply(q[..., 0, :], p[..., 2, :])
    second = _multiply(p[..., 0, :], q[..., 1, :]) - _multiply(q[..., 0, :], p[..., 1, :])
    third = _multiply(p[..., 1, :], q[..., 2, :]) - _multiply(q[..., 1, :], p[..., 2, :])
    return _multiply(first, first) - _multiply(second, third)


def _linear_resultants(p: np.ndarray, q: np.ndarray, rows: tuple[int, int]) -> np.ndarray:
    """Resultant of two linear polynomials in ``T`` made of rows ``rows`` of ``p`` and ``q``."""
    high, low = rows
    return _multiply(p[..., high, :], q[..., low, :]) - _multiply(q[..., high, :], p[..., low, :])


def _deflated(polynomials: np.ndarray) -> np.ndarray:
    """
    Divide out roots at ``τ = 0`` and ``τ = 1`` (up to three of each) where they are exact.

    The resultants carry ``τ`` and ``τ - 1`` factors (an extremum cannot leave through an
    end where it does not change); ends are candidates of their own, so dropping these
    roots loses nothing and lowers the degree of the eigenvalue problems.
    """
    scale = np.max(np.abs(polynomials), axis=1, keepdims=True)
    for _ in range(3):
        at_zero = np.abs(polynomials[:, :1]) <= 1e-12 * scale
        shifted = np.zeros_like(polynomials)
        shifted[:, :-1] = polynomials[:, 1:]
        polynomials = np.where(at_zero, shifted, polynomials)
        at_one = np.abs(polynomials.sum(axis=1, keepdims=True)) <= 1e-12 * scale
        # Synthetic division by (τ - 1): the quotient's coefficients are the partial sums
        # of the coefficients from the highest power down.
        quotient = np.zeros_like(polynomials)
        quotient[:, :-1] = np.cumsum(polynomials[:, :0:-1], axis=1)[:, ::-1]
        polynomials = np.where(at_one & (scale > 0.0), quotient, polynomials)
    return polynomials


@functools.cache
def _bernstein_matrix(size: int) -> np.ndarray:
    """
    Map ascending coefficients (degree ``size - 1``) to Bernstein ones on ``[0, 1]``.

    ``b_i = Σ_{k ≤ i} C(i, k) / C(n, k) c_k``.
    """
    degree = size - 1
    matrix = np.zeros((size, size))
    for power in range(size):
        for index in range(power, size):
            matrix[power, index] = math.comb(index, power) / math.comb(degree, power)
    return matrix


def _roots_in_unit_interval(polynomials: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Real roots in ``[0, 1]`` of ascending polynomials ``(count, n)`` and whose each is.

    By companion matrix: the effective degree is found per polynomial (leading
    coefficients below 1e-13 of the largest are dropped) and polynomials of one degree
    share one eigenvalue call. Roots within 1e-6 of the real axis count as real (double
    roots split by rounding): an extra candidate costs a check, a missing one a window.
    """
    polynomials = _deflated(polynomials)
    # Convex hull of the Bernstein coefficients on [0, 1]: all of one sign, no root there.
    # The margin (1e-12 of the largest) keeps rounding from hiding a touching root.
    bernstein = polynomials @ _bernstein_matrix(polynomials.shape[1])
    margin = 1e-12 * np.max(np.abs(bernstein), axis=1, keepdims=True)
    rootless = (bernstein > margin).all(axis=1) | (bernstein < -margin).all(axis=1)
    polynomials = np.where(rootless[:, None], 0.0, polynomials)
    scale = np.max(np.abs(polynomials), axis=1)
    significant = np.abs(polynomials) > 1e-13 * scale[:, None]
    degrees = np.where(significant.any(axis=1),
                       polynomials.shape[1] - 1 - np.argmax(significant[:, ::-1], axis=1), 0)
    roots, owners = [], []
    for degree in np.unique(degrees):
        if degree < 1:
            continue
        members = np.flatnonzero(degrees == degree)
        monic = polynomials[members, :degree] / polynomials[members, degree:degree + 1]
        if degree == 1:
            values = -monic.astype(complex)
        else:
            companion = np.zeros((members.size, degree, degree))
            companion[:, 1:, :-1] = np.eye(degree - 1)
            companion[:, :, -1] = -monic
            values = np.linalg.eigvals(companion)
        real = (np.abs(values.imag) <= _IMAGINARY_SLACK * (1.0 + np.abs(values.real))) & \
            (values.real >= -1e-9) & (values.real <= 1.0 + 1e-9)
        rows, columns = np.nonzero(real)
        roots.append(np.clip(values.real[rows, columns], 0.0, 1.0))
        owners.append(members[rows])
    if not roots:
        return np.zeros(0), np.zeros(0, dtype=np.intp)
    return np.concatenate(roots), np.concatenate(owners)


def _positive_roots(p2: np.ndarray, p1: np.ndarray, p0: np.ndarray) -> np.ndarray:
    """
    Positive real roots of ``p2 T² + p1 T + p0`` (flat arrays), ``(3, count)``, NaN if none.

    Row 0 and 1 are the two roots of a quadratic, row 2 the root of a linear one.
    """
    with np.errstate(divide='ignore', invalid='ignore'):
        discriminant = p1 * p1 - 4.0 * p2 * p0
        root = np.sqrt(np.maximum(discriminant, 0.0))
        # Stable pair: q = -(p1 + sgn(p1) root)/2, T = q/p2 and p0/q; linear: -p0/p1.
        half = -0.5 * (p1 + np.where(p1 >= 0.0, root, -root))
        real = discriminant >= -1e-12 * (p1 * p1 + np.abs(4.0 * p2 * p0))
        square = real & (p2 != 0.0)
        roots = np.stack([np.where(square, half / p2, np.nan),
                          np.where(square, p0 / half, np.nan),
                          np.where(p2 == 0.0, -p0 / p1, np.nan)])
    return np.where(np.isfinite(roots) & (roots > 0.0), roots, np.nan)


def _pad(polynomials: np.ndarray, size: int) -> np.ndarray:
    """Pad ascending coefficients with zeros to ``size``."""
    padded = np.zeros(polynomials.shape[:-1] + (size,))
    padded[..., :polynomials.shape[-1]] = polynomials
    return padded


def _candidates(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
                start_acceleration: np.ndarray, max_velocity: np.ndarray,
                max_acceleration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every duration at which a joint's peak can equal its limit, and that joint's index."""
    joints = displacement.size
    # (2 orders, 2 signs, joints, 3 powers of T, 6 powers of τ)
    p = np.stack([_quadratics(profile, order, displacement, start_velocity,
                              start_acceleration, limit)
                  for order, limit in ((1, max_velocity), (2, max_acceleration))])
    q = derivative(p)
    owner = np.broadcast_to(np.arange(joints)[:, None], p.shape[:3] + (3,))
    # The limit met at an end, τ = 0 or 1 (p(0) is the constant term, p(1) the sum), or
    # an extremum entering at an end (q = 0 there: where an end sits at the limit for
    # every duration, as a start at its limit does, this is where feasibility ends).
    ends = np.stack([p[..., 0], p.sum(axis=-1), q[..., 0], q.sum(axis=-1)])
    end_roots = _positive_roots(ends[..., 0].reshape(-1), ends[..., 1].reshape(-1),
                                ends[..., 2].reshape(-1))
    end_owner = np.broadcast_to(owner[..., 0], ends.shape[:-1]).reshape(-1)
    # The limit met at an interior extremum: roots in τ of the resultant of P and ∂P/∂τ.
    # Per order and joint: no T² term (velocity with a0 = 0), or no constant (D = 0).
    no_square = (~np.any(p[:, :, :, 0], axis=(1, 3)) & ~np.any(q[:, :, :, 0], axis=(1, 3)))
    no_constant = ~np.any(p[:, :, :, 2], axis=(1, 3))
    general = _resultants(p, q)
    size = general.shape[-1]
    linear = _pad(_linear_resultants(p, q, (1, 2)), size)
    without_t = _pad(_linear_resultants(p, q, (0, 1)), size)
    resultants = np.where(no_square[:, None, :, None], linear, general)
    resultants = np.where(no_constant[:, None, :, None], without_t, resultants)
    taus, rows = _roots_in_unit_interval(resultants.reshape(-1, size))
    at_taus = evaluate(p.reshape(-1, 3, 6)[rows], taus[:, None])
    interior = _positive_roots(at_taus[:, 0], at_taus[:, 1], at_taus[:, 2])
    interior_owner = rows % joints
    durations = np.concatenate([end_roots.reshape(-1), interior.reshape(-1)])
    owners = np.concatenate([np.tile(end_owner, 3), np.tile(interior_owner, 3)])
    keep = np.isfinite(durations)
    return durations[keep], owners[keep]


def _feasible(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
              start_acceleration: np.ndarray, max_velocity: np.ndarray,
              max_acceleration: np.ndarray, durations: np.ndarray,
              tolerance: float = LIMIT_TOLERANCE) -> np.ndarray:
    """Whether each move (flat arrays) stays within its limits in its duration (exact peaks)."""
    shapes = _SHAPES[profile]
    position = (start_velocity * durations)[:, None] * shapes[0] + \
        (start_acceleration * durations**2)[:, None] * shapes[1] + \
        displacement[:, None] * shapes[2]
    # In normalised time: peak |v| = max|x'(τ)|/T, peak |a| = max|x''(τ)|/T².
    derivatives = np.zeros((2, durations.size, 5))
    derivatives[0] = position[:, 1:] * np.arange(1, 6)
    derivatives[1, :, :4] = derivatives[0, :, 1:] * np.arange(1, 5)
    peaks = unit_peaks(derivatives.reshape(-1, 5)).reshape(2, -1)
    slack = 1.0 + tolerance
    return (peaks[0] <= max_velocity * durations * slack) & \
        (peaks[1] <= max_acceleration * durations**2 * slack)


class FeasibleDurations:
    """
    One joint's feasible durations: closed intervals between candidate durations.

    ``points`` are the sorted candidates (the first is ``SHORTEST_POLYNOMIAL``);
    ``feasible[k]`` says whether ``points[k]`` is feasible, ``after[k]`` whether the open
    gap after it is (the last gap runs to infinity). The end points of a feasible gap are
    feasible (the set is closed; :func:`_polish_boundaries` makes them so to rounding).
    """

    def __init__(self, points: np.ndarray, at_point: np.ndarray, after: np.ndarray) -> None:
        """Keep the candidates and their feasibility."""
        self.points = points
        self.after = after
        self.feasible = at_point

    def first_from(self, duration: float) -> float | None:
        """Return the smallest feasible duration ``>= duration`` (``>= points[0]``), or None."""
        index = int(np.searchsorted(self.points, duration, side='right')) - 1
        if (self.points[index] == duration and self.feasible[index]) or \
                (self.points[index] < duration and self.after[index]):
            return duration
        later = np.flatnonzero(self.feasible[index + 1:])
        return float(self.points[index + 1 + later[0]]) if later.size else None


def feasible_durations(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
                       start_acceleration: np.ndarray, max_velocity: np.ndarray,
                       max_acceleration: np.ndarray) -> list[FeasibleDurations]:
    """Every joint's feasible durations (Step 1), from its candidates and exact peaks."""
    durations, owners = _candidates(profile, displacement, start_velocity,
                                    start_acceleration, max_velocity, max_acceleration)
    joints = displacement.size
    keep = durations > SHORTEST_POLYNOMIAL
    durations = np.concatenate([durations[keep], np.full(joints, SHORTEST_POLYNOMIAL)])
    owners = np.concatenate([owners[keep], np.arange(joints)])
    order = np.lexsort((durations, owners))
    durations, owners = durations[order], owners[order]
    fresh = np.ones(durations.size, dtype=bool)
    fresh[1:] = (durations[1:] != durations[:-1]) | (owners[1:] != owners[:-1])
    durations, owners = durations[fresh], owners[fresh]
    last = np.ones(durations.size, dtype=bool)
    last[:-1] = owners[1:] != owners[:-1]
    # One duration inside each gap after a point: the midpoint, or twice the last point.
    gaps = np.where(last, 2.0 * durations, 0.5 * (durations + np.roll(durations, -1)))
    tests = np.concatenate([durations, gaps])
    who = np.concatenate([owners, owners])
    feasible = _feasible(profile, displacement[who], start_velocity[who],
                         start_acceleration[who], max_velocity[who], max_acceleration[who],
                         tests)
    at_point, after = feasible[:durations.size], feasible[durations.size:]
    moves = (profile, displacement, start_velocity, start_acceleration, max_velocity,
             max_acceleration)
    _polish_boundaries(moves, durations, owners, gaps, at_point, after)
    bounds = np.searchsorted(owners, np.arange(joints + 1))
    return [FeasibleDurations(durations[a:b], at_point[a:b], after[a:b])
            for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _polish_boundaries(moves: tuple, durations: np.ndarray, owners: np.ndarray,
                       gaps: np.ndarray, at_point: np.ndarray, after: np.ndarray) -> None:
    """
    Move boundary candidates that rounding left just outside their feasible gap onto it.

    A candidate next to a feasible gap is, exactly, the gap's closed end; rounding in the
    roots can leave it a hair outside (the peak over by ~1e-6). Each such candidate is
    bisected towards its gap's test duration with the exact check, 48 halvings, and
    replaced by the feasible end of the bracket (in place; the order is kept).
    """
    first = np.ones(durations.size, dtype=bool)
    first[1:] = owners[1:] != owners[:-1]
    before = np.where(first, False, np.roll(after, 1))
    rising = ~at_point & after
    falling = ~at_point & before & ~rising
    index = np.flatnonzero(rising | falling)
    if not index.size:
        return
    profile, displacement, start_velocity, start_acceleration, max_velocity, \
        max_acceleration = moves
    who = owners[index]
    bad = durations[index]
    good = np.where(rising[index], gaps[index], gaps[index - 1])
    for _ in range(48):
        middle = 0.5 * (bad + good)
        # Half the tolerance: the plan's own peaks, evaluated in real time, round apart.
        fits = _feasible(profile, displacement[who], start_velocity[who],
                         start_acceleration[who], max_velocity[who], max_acceleration[who],
                         middle, 0.5 * LIMIT_TOLERANCE)
        good = np.where(fits, middle, good)
        bad = np.where(fits, bad, middle)
    durations[index] = good
    at_point[index] = True


def synchronised_duration(joint_sets: list[FeasibleDurations]) -> float | None:
    """
    Return the smallest duration every joint can achieve, or ``None`` if there is none.

    Start at the shortest duration; while some joint cannot achieve the duration, move
    to the next duration that joint can achieve. Each step only moves forward to a
    candidate, so the loop ends, and no common duration is skipped.
    """
    duration = SHORTEST_POLYNOMIAL
    while True:
        later = [joint.first_from(duration) for joint in joint_sets]
        if any(value is None for value in later):
            return None
        latest = max(later)
        if latest == duration:
            return duration
        duration = latest


def minimum_duration(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
                     start_acceleration: np.ndarray, max_velocity: np.ndarray,
                     max_acceleration: np.ndarray) -> tuple[float | None, int | None]:
    """
    Return the smallest common duration: ``(duration, None)``, or ``(None, joint)``.

    ``joint`` is one that can achieve no duration at all (``None`` if every joint can, but
    never together). Only the joints that can bind are analysed exactly: the
    second-order time-optimal duration (:func:`second_order.minimum_times`, bang-bang with
    the same limits) is a lower bound for any profile, so joints are analysed in the order
    of that bound until the next bound is below the duration found; every other joint is
    then checked at that duration, and one that fails is analysed too.
    """
    bounds = second_order.minimum_times(displacement, start_velocity, max_velocity,
                                        max_acceleration)
    order = np.argsort(-bounds)
    analysed: dict[int, FeasibleDurations] = {}
    batch = min(order.size, _FIRST_BATCH)
    pending = order[:batch]
    duration = SHORTEST_POLYNOMIAL
    while True:
        if pending.size:
            sets = feasible_durations(profile, displacement[pending], start_velocity[pending],
                                      start_acceleration[pending], max_velocity[pending],
                                      max_acceleration[pending])
            for joint, joint_set in zip(pending.tolist(), sets, strict=True):
                if joint_set.first_from(SHORTEST_POLYNOMIAL) is None:
                    return None, joint
                analysed[joint] = joint_set
        found = synchronised_duration(list(analysed.values()))
        if found is None:
            return None, None
        duration = found
        rest = order[np.isin(order, list(analysed), invert=True)]
        if not rest.size:
            return duration, None
        # Joints whose lower bound exceeds the duration bind: analyse them first.
        binding = rest[bounds[rest] > duration]
        if binding.size:
            pending = binding[:max(batch, binding.size)]
            continue
        feasible = _feasible(profile, displacement[rest], start_velocity[rest],
                             start_acceleration[rest], max_velocity[rest],
                             max_acceleration[rest], np.full(rest.size, duration))
        pending = rest[~feasible]
        if not pending.size:
            return duration, None
