"""
Exact peak velocity and acceleration of a cubic or quintic move to rest, in closed form.

A move of ``D`` in ``T`` from velocity ``v0`` (and acceleration ``a0`` for the quintic) to
rest has, in normalised time ``τ = t/T`` (Craig eqs. (7.9) and (7.3)-(7.5) with the
final velocity and acceleration zero):

- cubic: ``v(τ) = (1 - τ)(α + βτ)`` with ``α = v0``, ``β = 6D/T - 3v0``, and
  ``a(τ) = ((β - α) - 2βτ)/T``, a line;
- quintic: ``v(τ) = (1 - τ)² w(τ)`` with ``w = α + βτ + γτ²``, ``α = v0``,
  ``β = 2v0 + a0 T``, ``γ = 30D/T - 15v0 - 5a0 T/2``, and ``a(τ) = (1 - τ) E(τ)/T``
  with ``E = (1 - τ)w' - 2w = (β - 2α) + (2γ - 3β)τ - 4γτ²``.

So every extremum lies at an end or at a root of a polynomial of degree ≤ 2 (``E`` for
the quintic's velocity, ``(e1 - e0) + 2(e2 - e1)τ - 3e2τ²`` for its acceleration), and the
peaks are exact: nothing is sampled. Arrays are flat, one entry per move; units rad,
rad/s, rad/s², s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.polynomial_peaks import discriminant


def _unit_roots(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray) -> np.ndarray:
    """
    Roots of ``c0 + c1 τ + c2 τ²`` clipped to ``[0, 1]``, ``(2, count)``; 0 where none.

    A root outside ``[0, 1]`` clipped to an end only adds that end, which is checked
    anyway; a missing root is replaced by ``τ = 0``, likewise harmless.
    """
    delta, c0, c1, c2 = discriminant(c0, c1, c2)  # rescaled where it would overflow
    half = -0.5 * (c1 + np.copysign(np.sqrt(np.abs(delta)), c1))
    # No real root (or half = 0, then c1 = c0 = 0 or none): both divisions are skipped.
    real = (delta >= 0.0) & (half != 0.0)
    roots = np.zeros((2,) + c0.shape)
    np.divide(half, c2, out=roots[0], where=real & (c2 != 0.0))
    np.divide(c0, half, out=roots[1], where=real)
    return np.minimum(np.maximum(roots, 0.0), 1.0)


def peaks(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
          start_acceleration: np.ndarray, duration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the peak ``|v|`` and ``|a|`` of each move (``duration > 0``).

    The arrays broadcast together: flat ones give one move per entry, a column of moves
    and a row of durations every move at every duration.
    """
    inverse = 1.0 / duration
    alpha = start_velocity
    if profile == 'cubic':
        beta = 6.0 * displacement * inverse - 3.0 * alpha
        # dv/dτ = (β - α) - 2βτ: one interior extremum.
        extremum = (beta - alpha) / np.where(beta == 0.0, 1.0, 2.0 * beta)
        extremum = np.minimum(np.maximum(extremum, 0.0), 1.0)
        velocity = (1.0 - extremum) * (alpha + beta * extremum)
        peak_velocity = np.maximum(np.abs(alpha), np.abs(velocity))
        peak_acceleration = np.maximum(np.abs(beta - alpha), np.abs(beta + alpha)) * inverse
        return peak_velocity, peak_acceleration
    e0 = start_acceleration * duration  # = β - 2α
    beta = 2.0 * alpha + e0
    gamma = 30.0 * displacement * inverse - 15.0 * alpha - 2.5 * e0
    e1, e2 = 2.0 * gamma - 3.0 * beta, -4.0 * gamma
    # Extrema of v (roots of E) and of a (roots of (1 - τ)E's derivative), both at once.
    quadratics = np.empty((3, 2) + e2.shape)
    quadratics[0, 0], quadratics[1, 0], quadratics[2, 0] = e0, e1, e2
    quadratics[0, 1], quadratics[1, 1], quadratics[2, 1] = e1 - e0, 2.0 * (e2 - e1), -3.0 * e2
    points = np.zeros((5,) + e2.shape)  # the last row: τ = 0, where v = α and a = e0/T
    points[:4] = _unit_roots(*quadratics).reshape(points[:4].shape)
    rest = 1.0 - points
    w = alpha + points * (beta + points * gamma)
    e = e0 + points * (e1 + points * e2)
    return (np.maximum.reduce(np.abs(rest * rest * w)),
            np.maximum.reduce(np.abs(rest * e)) * inverse)
