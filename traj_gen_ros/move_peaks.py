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
    Roots of ``c0 + c1 τ + c2 τ²`` clipped to ``[0, 1]``, ``(count, 2)``; 0 where none.

    A root outside ``[0, 1]`` clipped to an end only adds that end, which is checked
    anyway; a missing root is replaced by ``τ = 0``, likewise harmless.
    """
    delta, c0, c1, c2 = discriminant(c0, c1, c2)  # rescaled where it would overflow
    root = np.sqrt(np.abs(delta))
    half = -0.5 * (c1 + np.copysign(root, c1))
    real = (delta >= 0.0) & (half != 0.0)
    square = real & (c2 != 0.0)
    safe_half = np.where(real, half, 1.0)
    first = np.where(square, safe_half / np.where(square, c2, 1.0), 0.0)
    second = np.where(real, c0 / safe_half, 0.0)
    return np.clip(np.stack([first, second], axis=1), 0.0, 1.0)


def peaks(profile: str, displacement: np.ndarray, start_velocity: np.ndarray,
          start_acceleration: np.ndarray, duration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the peak ``|v|`` and ``|a|`` of each move (flat arrays, ``duration > 0``)."""
    inverse = 1.0 / duration
    alpha = start_velocity
    if profile == 'cubic':
        beta = 6.0 * displacement * inverse - 3.0 * alpha
        # dv/dτ = (β - α) - 2βτ: one interior extremum.
        extremum = np.clip((beta - alpha) / np.where(beta == 0.0, 1.0, 2.0 * beta), 0.0, 1.0)
        velocity = (1.0 - extremum) * (alpha + beta * extremum)
        peak_velocity = np.maximum(np.abs(alpha), np.abs(velocity))
        peak_acceleration = np.maximum(np.abs(beta - alpha), np.abs(beta + alpha)) * inverse
        return peak_velocity, peak_acceleration
    beta = 2.0 * alpha + start_acceleration * duration
    gamma = 30.0 * displacement * inverse - 15.0 * alpha - 2.5 * start_acceleration * duration
    e0, e1, e2 = beta - 2.0 * alpha, 2.0 * gamma - 3.0 * beta, -4.0 * gamma
    points = np.concatenate([_unit_roots(e0, e1, e2),
                             _unit_roots(e1 - e0, 2.0 * (e2 - e1), -3.0 * e2)], axis=1)
    rest = 1.0 - points
    w = alpha[:, None] + points * (beta[:, None] + points * gamma[:, None])
    e = e0[:, None] + points * (e1[:, None] + points * e2[:, None])
    velocity = np.abs(rest * rest * w).max(axis=1)
    acceleration = np.abs(rest * e).max(axis=1) * inverse
    return np.maximum(velocity, np.abs(alpha)), np.maximum(acceleration, np.abs(e0) * inverse)
