"""
Exact peaks of low-degree polynomials on ``[0, 1]``, vectorised over many polynomials.

The extrema of ``p`` on an interval lie at its ends or at real roots of ``p'``; for the
degrees of Craig's cubic and quintic (``p'`` of degree ≤ 3) those roots have closed forms
(Cardano and the trigonometric formula for the cubic, the stable quadratic formula).
Polynomials are ascending coefficient rows ``(count, n)``; τ is normalised time.
"""

from __future__ import annotations

import numpy as np


def derivative(coefficients: np.ndarray, order: int = 1) -> np.ndarray:
    """d/dτ of ascending coefficients along the last axis, keeping the length."""
    for _ in range(order):
        powers = np.arange(1, coefficients.shape[-1])
        shifted = np.zeros_like(coefficients)
        shifted[..., :-1] = coefficients[..., 1:] * powers
        coefficients = shifted
    return coefficients


def evaluate(polynomials: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Ascending polynomials ``(..., n)`` at ``points`` broadcast against ``(...)``."""
    value = np.zeros(np.broadcast_shapes(polynomials.shape[:-1], points.shape))
    for power in range(polynomials.shape[-1] - 1, -1, -1):
        value = value * points + polynomials[..., power]
    return value


def unit_peaks(polynomials: np.ndarray) -> np.ndarray:
    """
    Largest ``|p(τ)|`` on ``[0, 1]`` of ascending polynomials ``(count, n)``, ``n ≤ 5``.

    Extrema lie at the ends or at the real roots of ``p'`` (degree ≤ 3), found in closed
    form (:func:`real_roots`) and polished by two Newton steps.
    """
    slope = derivative(polynomials)[:, :4]
    points = np.clip(np.nan_to_num(real_roots(slope), nan=0.0), 0.0, 1.0)
    curvature = derivative(slope)
    for _ in range(2):
        bend = evaluate(curvature[:, None, :], points)
        step = evaluate(slope[:, None, :], points) / np.where(bend == 0.0, 1.0, bend)
        points = np.clip(points - np.where(bend == 0.0, 0.0, step), 0.0, 1.0)
    points = np.concatenate([points, np.zeros((len(points), 1)), np.ones((len(points), 1))],
                            axis=1)
    return np.abs(evaluate(polynomials[:, None, :], points)).max(axis=1)


def real_roots(cubics: np.ndarray) -> np.ndarray:
    """
    Real roots of ascending ``c0 + c1 τ + c2 τ² + c3 τ³`` (rows), ``(count, 3)``, NaN if fewer.

    Cardano's formula (one real root) or the trigonometric one (three), for the depressed
    cubic ``t³ + p t + q`` with ``τ = t - c2/(3 c3)``; rows whose cubic term is negligible
    (1e-9 of the largest) take the stable quadratic formula instead.
    """
    c0, c1, c2, c3 = cubics.T
    scale = np.max(np.abs(cubics), axis=1)
    cubic = np.abs(c3) > 1e-9 * scale
    roots = np.full((len(cubics), 3), np.nan)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        a, b, c = c2 / c3, c1 / c3, c0 / c3
        p = b - a * a / 3.0
        q = 2.0 * a**3 / 27.0 - a * b / 3.0 + c
        discriminant = (0.5 * q) ** 2 + (p / 3.0) ** 3
        root = np.sqrt(np.maximum(discriminant, 0.0))
        one = np.cbrt(-0.5 * q + root) + np.cbrt(-0.5 * q - root) - a / 3.0
        radius = 2.0 * np.sqrt(np.maximum(-p / 3.0, 0.0))
        angle = np.arccos(np.clip(3.0 * q / (p * radius), -1.0, 1.0)) / 3.0
        three = radius[:, None] * np.cos(angle[:, None] - 2.0 * np.pi * np.arange(3) / 3.0) \
            - a[:, None] / 3.0
        single = cubic & (discriminant > 0.0)
        roots[single, 0] = one[single]
        triple = cubic & (discriminant <= 0.0) & (p < 0.0)
        roots[triple] = three[triple]
        flat = cubic & (discriminant <= 0.0) & (p >= 0.0)  # p = q = 0: a triple root
        roots[flat, 0] = -a[flat] / 3.0
        # Quadratic (or linear) rows: c0 + c1 τ + c2 τ².
        quadratic = ~cubic
        inner = c1 * c1 - 4.0 * c2 * c0
        half = -0.5 * (c1 + np.copysign(np.sqrt(np.maximum(inner, 0.0)), c1))
        pair = quadratic & (inner >= 0.0) & (np.abs(c2) > 1e-12 * scale)
        roots[pair, 0] = (half / c2)[pair]
        roots[pair, 1] = (c0 / half)[pair]
        line = quadratic & (np.abs(c2) <= 1e-12 * scale)
        roots[line, 0] = (-c0 / c1)[line]
    return np.where(np.isfinite(roots), roots, np.nan)
