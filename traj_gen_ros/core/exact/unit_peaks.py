"""
Exact peaks of low-degree polynomials on ``[0, 1]``, vectorised over many polynomials.

The extrema of ``p`` on an interval lie at its ends or at real roots of ``p'``; for the
degrees of Craig's profiles (``p`` of degree ≤ 4, ``p'`` of degree ≤ 3) those roots have
closed forms: linear, the stable quadratic formula, and for the cubic the trigonometric
formula (three real roots) or Cardano's (one). A root off by rounding moves the value
at an extremum only to second order, so the peaks are exact to rounding. Polynomials are
ascending coefficient rows ``(count, n)``; τ is normalised time. The cubic formulas are the
classical ones (e.g. Press et al., *Numerical Recipes*, 3rd ed., §5.6).
"""

from __future__ import annotations

import numpy as np


def unit_peaks(polynomials: np.ndarray) -> np.ndarray:
    """Largest ``|p(τ)|`` on ``[0, 1]`` of ascending polynomials ``(count, n)``, ``n ≤ 5``."""
    count, size = polynomials.shape
    used = np.abs(polynomials).max(axis=0, initial=0.0).nonzero()[0]
    degree = int(used[-1]) if used.size else 0
    slope = polynomials[:, 1:degree + 1] * _POWERS[1:degree + 1]
    if degree <= 1:
        points = np.zeros((count, 0))
    elif degree == 2:
        points = _linear_roots(slope[:, 0], slope[:, 1])
    elif degree == 3:
        points = _quadratic_roots(slope[:, 0], slope[:, 1], slope[:, 2])
    else:
        # The trigonometric/Cardano roots lose the small roots when the cubic term is
        # tiny beside the others (their error grows like √eps over its relative size):
        # the roots of the quadratic part are candidates too, and two Newton steps on p'
        # polish every candidate. Extra candidates in [0, 1] can only raise the maximum
        # towards the true one; it is attained at one of them.
        points = np.concatenate([_cubic_roots(slope), _quadratic_roots(
            slope[:, 0], slope[:, 1], slope[:, 2])], axis=1)
        points = _polished(slope, np.minimum(np.maximum(points, 0.0), 1.0))
    # Every candidate, and both ends: (count, candidates + 2).
    points = np.concatenate([np.minimum(np.maximum(points, 0.0), 1.0),
                             _UNIT_ENDS.repeat(count, axis=0)], axis=1)
    powers = points[:, :, None] ** _POWERS[:degree + 1]
    values = np.einsum('cmk,ck->cm', powers, polynomials[:, :degree + 1])
    return np.maximum.reduce(np.abs(values), axis=1)


def _polished(slope: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Two Newton steps on ``p'`` (ascending ``slope`` rows) from ``points``, kept in [0, 1]."""
    size = slope.shape[1]
    pair = np.zeros((2, slope.shape[0], size))  # p' and p'' (padded), one product
    pair[0] = slope
    pair[1, :, :-1] = slope[:, 1:] * _POWERS[1:size]
    for _ in range(2):
        value, bend = np.einsum('cmk,jck->jcm', points[:, :, None] ** _POWERS[:size], pair)
        bend[bend == 0.0] = np.inf
        with np.errstate(over='ignore'):  # a step beyond ±1e308 is clipped to [0, 1] too
            points = np.minimum(np.maximum(points - value / bend, 0.0), 1.0)
    return points


def _linear_roots(c0: np.ndarray, c1: np.ndarray) -> np.ndarray:
    """Root of ``c0 + c1 τ`` per row, ``(count, 1)``; 0 where there is none."""
    with np.errstate(over='ignore'):  # a root beyond ±1e308 is clipped to [0, 1] anyway
        return (-c0 / np.where(c1 == 0.0, np.inf, c1))[:, None]


def _quadratic_roots(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray) -> np.ndarray:
    """
    Real roots of ``c0 + c1 τ + c2 τ²`` per row, ``(count, 2)``; 0 where there are fewer.

    Stable pair ``q = -(c1 + sgn(c1) √Δ)/2``, roots ``q/c2`` and ``c0/q``; ``c2 = 0``
    leaves the linear root ``-c0/c1`` as the second.
    """
    delta, c0, c1, c2 = discriminant(c0, c1, c2)
    half = -0.5 * (c1 + np.copysign(np.sqrt(np.maximum(delta, 0.0)), c1))
    real = (delta >= 0.0) & (half != 0.0)
    roots = np.zeros((c0.size, 2))
    with np.errstate(over='ignore'):  # a root beyond ±1e308 is clipped to [0, 1] anyway
        np.divide(half, c2, out=roots[:, 0], where=real & (c2 != 0.0))
        np.divide(c0, half, out=roots[:, 1], where=real)
    return roots


def discriminant(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray) -> tuple[np.ndarray, ...]:
    """
    Return ``c1² - 4 c2 c0`` with the coefficients it was computed from.

    Where it overflows (huge coefficients: a long move over a tiny duration) the rows are
    divided by their largest coefficient first; the roots do not change.
    """
    with np.errstate(over='ignore', invalid='ignore'):  # checked right below
        value = c1 * c1 - 4.0 * c2 * c0
    if np.count_nonzero(np.isfinite(value)) == value.size:  # (cheaper than .all())
        return value, c0, c1, c2
    scale = np.maximum(np.maximum(np.abs(c0), np.abs(c1)), np.abs(c2))
    scale = np.where((scale > 0.0) & np.isfinite(scale), scale, 1.0)
    c0, c1, c2 = c0 / scale, c1 / scale, c2 / scale
    return c1 * c1 - 4.0 * c2 * c0, c0, c1, c2


def _cubic_roots(cubics: np.ndarray) -> np.ndarray:
    """
    Real roots of ascending ``c0 + c1 τ + c2 τ² + c3 τ³`` (rows), ``(count, 3)``; 0 if fewer.

    The depressed cubic ``t³ + p t + q`` (``τ = t - c2/(3 c3)``): three real roots by the
    trigonometric formula when ``Δ = (q/2)² + (p/3)³ ≤ 0``, else Cardano's one. Rows whose
    cubic term is negligible (1e-9 of the largest) give 0: :func:`unit_peaks` takes the
    roots of their quadratic part anyway.
    """
    c0, c1, c2, c3 = cubics.T
    cubic = np.abs(c3) > 1e-9 * np.maximum.reduce(np.abs(cubics), axis=1)
    leading = np.where(cubic, c3, 1.0)
    a, b, c = c2 / leading, c1 / leading, c0 / leading
    p = b - a * a / 3.0
    q = (2.0 * a * a / 27.0 - b / 3.0) * a + c
    discriminant = 0.25 * q * q + p * p * p / 27.0
    root = np.sqrt(np.maximum(discriminant, 0.0))
    one = np.cbrt(-0.5 * q + root) + np.cbrt(-0.5 * q - root)
    radius = 2.0 * np.sqrt(np.maximum(-p / 3.0, 0.0))
    # Within [-1, 1] where the three real roots are taken (Δ ≤ 0); it overflows only for a
    # subnormal p·r with Δ > 0, where Cardano's root is taken: clipped, either way unused.
    with np.errstate(over='ignore'):
        cosine = 3.0 * q / np.where(radius * p == 0.0, np.inf, p * radius)
    angle = np.arccos(np.minimum(np.maximum(cosine, -1.0), 1.0)) / 3.0
    three = radius[:, None] * np.cos(angle[:, None] - _THIRDS)
    roots = np.where((discriminant > 0.0)[:, None], one[:, None], three) - a[:, None] / 3.0
    return np.where(cubic[:, None], roots, 0.0)


_THIRDS = 2.0 * np.pi * np.arange(3) / 3.0
_POWERS = np.arange(6.0)
_UNIT_ENDS = np.array([[0.0, 1.0]])
