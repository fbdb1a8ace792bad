"""
Exact extrema of piecewise polynomials: peaks of ``|p|`` and the positions' extrema.

A plan (:class:`traj_gen_ros.core.trajectory.Trajectory`) is one polynomial per piece and
joint, in local time. Every extremum of a piece lies at one of its ends or at a real root
of its derivative; each piece is rescaled to unit time (``c_k L^k``, ``s = t / L``), and
the roots come in closed form (:mod:`traj_gen_ros.core.exact.unit_peaks`, derivative of
degree ≤ 3) or from the one root finder (:mod:`traj_gen_ros.core.exact.unit_roots`). Exact
to rounding, never a sampled estimate that could miss an overshoot.

Coefficients are ascending, ``(pieces, n + 1, joints)``; durations ``(pieces, joints)``, s.
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.exact.unit_peaks import unit_peaks
from traj_gen_ros.core.exact.unit_roots import roots_in_unit_interval


def derivative(coefficients: np.ndarray) -> np.ndarray:
    """Ascending coefficients of the time derivative, same layout ``(pieces, n, joints)``."""
    powers = np.arange(1, coefficients.shape[1], dtype=float)[None, :, None]
    return coefficients[:, 1:] * powers


def _without_end_roots(velocity: np.ndarray) -> np.ndarray:
    """
    Divide roots at ``s = 0`` and ``s = 1`` (up to double ones) out of ascending rows.

    A piece that starts or ends at rest has its velocity's roots there; the ends are
    extremum candidates anyway, and such roots would send the root finder to its slow,
    eigenvalue path. ``p(s) = s q(s)`` shifts the coefficients; ``p(s) = (s - 1) q(s)``
    has ``q``'s descending coefficients as the running sums of ``p``'s (synthetic division).
    """
    velocity = velocity.copy()
    for _ in range(2):
        scale = np.abs(velocity).max(axis=1)
        start = (np.abs(velocity[:, 0]) <= 1e-12 * scale) & (scale > 0.0)
        velocity[start, :-1], velocity[start, -1] = velocity[start, 1:], 0.0
        end = (np.abs(velocity.sum(axis=1)) <= 1e-12 * scale) & (scale > 0.0)
        quotient = np.cumsum(velocity[end, ::-1], axis=1)[:, :-1]
        velocity[end, :-1], velocity[end, -1] = quotient[:, ::-1], 0.0
    return velocity


def polyval(coefficients: np.ndarray, points: np.ndarray) -> np.ndarray:
    """
    Evaluate each row's ascending ``coefficients`` ``(rows, n + 1)`` at its ``points``.

    ``points`` is ``(rows, k)``; returns ``(rows, k)`` values, by Horner's rule.
    """
    value = np.zeros_like(points)
    for power in range(coefficients.shape[1] - 1, -1, -1):
        value = value * points + coefficients[:, power][:, None]
    return value


def peak_abs(durations: np.ndarray, *series: np.ndarray) -> list[np.ndarray]:
    """
    Find the exact largest ``|p(t)|`` over every piece, per joint, for each of ``series``.

    Each series is ``(pieces, n + 1, joints)`` coefficients in local time (``n ≤ 4``);
    returns one ``(joints,)`` array per series. Every extremum lies at a piece end or
    where ``p'`` vanishes: each piece is rescaled to unit time (``c_k L^k``) and
    :func:`traj_gen_ros.core.exact.unit_peaks.unit_peaks` finds the roots of ``p'`` (degree
    ≤ 3) in closed form, every series, piece and joint in one call.
    """
    rows = _unit_rows(durations, series)
    pieces, joints = durations.shape
    peaks = unit_peaks(rows.reshape(-1, 5)).reshape(len(series), pieces, joints)
    return list(peaks.max(axis=1, initial=0.0))


def peak_bounds(durations: np.ndarray, *series: np.ndarray) -> list[np.ndarray]:
    """
    Bound ``|p(t)|`` from above over every piece, per joint: ``>=`` :func:`peak_abs`'s peaks.

    The convex hull property of the Bernstein form (e.g. Farouki, "The Bernstein polynomial
    basis: a centennial retrospective", CAGD 29, 2012, §2): on ``[0, 1]`` a polynomial of
    degree ``n`` with power coefficients ``c_k`` is a convex combination of its Bernstein
    coefficients ``b_i = Σ_{k≤i} C(i, k) / C(n, k) · c_k``, so ``|p| <= max_i |b_i|``.
    Each piece is split into ``HULL_PARTS`` equal parts first (the bound closes on the
    peak quadratically in the part's length: within about 1 % of it for Craig's profiles'
    pieces), all in one matrix product, no roots: a plan whose bound is within its limits
    is within them (:func:`peaks_above` finds the exact peaks only of the pieces whose
    bound is not).
    """
    rows = _unit_rows(durations, series)
    pieces, joints = durations.shape
    bounds = np.abs(rows @ _HULL).max(axis=2).reshape(len(series), pieces, joints)
    return list(bounds.max(axis=1, initial=0.0))


def peaks_above(durations: np.ndarray, limits: list[np.ndarray], *series: np.ndarray
                ) -> list[np.ndarray]:
    """
    Per joint, the exact peak of ``|p(t)|`` where it is above ``limits``, else a bound within.

    As :func:`peak_bounds` then :func:`peak_abs`, but the roots are found only for the
    pieces whose Bernstein bound is above the joint's limit (``limits``: one ``(joints,)``
    per series). Each result is ``max(exact peaks of those pieces, bounds of the others)``:
    the others' bounds are within the limit, so a result above the limit is the exact
    peak, and one within it bounds the peak from above.
    """
    rows = _unit_rows(durations, series)
    pieces, joints = durations.shape
    bounds = np.abs(rows @ _HULL).max(axis=2)  # (series, pieces · joints)
    limit = np.stack([np.broadcast_to(np.asarray(lim, dtype=float), (joints,))
                      for lim in limits])  # (series, joints)
    above = bounds > np.tile(limit, (1, pieces))  # piece-major, as the rows
    if above.any():
        bounds[above] = unit_peaks(rows[above])
    return list(bounds.reshape(len(series), pieces, joints).max(axis=1, initial=0.0))


def _unit_rows(durations: np.ndarray, series: tuple[np.ndarray, ...]) -> np.ndarray:
    """Each series' pieces rescaled to unit time (``c_k L^k``), ``(series, pieces·joints, 5)``."""
    pieces, joints = durations.shape
    rows = np.zeros((len(series), pieces * joints, 5))
    for index, coefficients in enumerate(series):
        size = coefficients.shape[1]
        if size:  # else a derivative of a constant: zero
            scaled = coefficients * durations[:, None, :] ** np.arange(size)[None, :, None]
            rows[index, :, :size] = scaled.transpose(0, 2, 1).reshape(-1, size)
    return rows


def _hull_matrix(parts: int, degree: int = 4) -> np.ndarray:
    """
    Map ascending rows to the Bernstein coefficients of ``parts`` equal parts of ``[0, 1]``.

    ``(degree + 1, parts · (degree + 1))``, the parts side by side. Part ``[a, a + w]``:
    ``p(a + w s)`` has coefficients ``c'_j = Σ_k c_k C(k, j) a^(k-j) w^j`` (binomial
    expansion), whose Bernstein coefficients are ``c' @ M`` with ``M[k, i] = C(i, k) /
    C(n, k)`` for ``k <= i``. Degree 4 serves the lower degrees too (rows padded with
    zeros are the same polynomial, degree-elevated).
    """
    bernstein = np.zeros((degree + 1, degree + 1))
    for i in range(degree + 1):
        for k in range(i + 1):
            bernstein[k, i] = math.comb(i, k) / math.comb(degree, k)
    blocks = []
    for part in range(parts):
        start, width = part / parts, 1.0 / parts
        shift = np.zeros((degree + 1, degree + 1))
        for k in range(degree + 1):
            for j in range(k + 1):
                shift[k, j] = math.comb(k, j) * start ** (k - j) * width ** j
        blocks.append(shift @ bernstein)
    return np.hstack(blocks)


#: Parts each piece is split into for :func:`peak_bounds`.
HULL_PARTS = 4
_HULL = _hull_matrix(HULL_PARTS)


def position_extrema(starts: np.ndarray, durations: np.ndarray, coefficients: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return each joint's lowest and highest position and their times, ``(joints,)`` each.

    Candidates are every piece's ends and the real roots in ``[0, 1]`` of every piece's
    velocity, all joints at once (:func:`roots_in_unit_interval`); every candidate is a
    position the plan takes and every extremum is a candidate. On a tie the earliest.

    :param starts: each piece's start time per joint, s, ``(pieces, joints)``.
    :param durations: each piece's length per joint, s, ``(pieces, joints)``.
    :param coefficients: ascending, ``(pieces, n + 1, joints)``, rad (or m).
    :return: ``(minimum, maximum, time_of_minimum, time_of_maximum)``.
    """
    pieces, size, joints = coefficients.shape
    lengths = durations.reshape(-1)  # piece-major: piece·joints + j
    starts = starts.reshape(-1)
    rows = np.moveaxis(coefficients, 1, 2).reshape(-1, size).copy()
    for power in range(1, size):  # c_k L^k as c_k L … L: no L^k to overflow
        rows[:, power:] *= lengths[:, None]
    owners = [np.arange(rows.shape[0])] * 2
    values, times = [rows[:, 0], rows.sum(axis=1)], [starts, starts + lengths]
    if size > 2:
        roots, of = roots_in_unit_interval(_without_end_roots(rows[:, 1:] *
                                                              np.arange(1.0, size)))
        owners.append(of)
        values.append(polyval(rows[of], roots[:, None])[:, 0])
        times.append(starts[of] + roots * lengths[of])
    joint = np.concatenate(owners) % joints
    values, times = np.concatenate(values), np.concatenate(times)
    # Sorted by joint, then value (rising for the minimum, falling for the maximum),
    # then time: each joint's first entry is its extremum.
    lowest = np.lexsort((times, values, joint))
    highest = np.lexsort((times, -values, joint))
    first = np.searchsorted(joint[lowest], np.arange(joints))
    return (values[lowest[first]], values[highest[first]], times[lowest[first]],
            times[highest[first]])
