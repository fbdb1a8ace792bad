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
from traj_gen_ros.core.exact.unit_peaks import discriminant


def _unit_roots(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray, roots: np.ndarray) -> None:
    """
    Write the roots of ``c0 + c1 τ + c2 τ²`` clipped to ``[0, 1]`` into zeroed ``roots``.

    ``roots`` is ``(2,) + c0.shape``. A root outside ``[0, 1]`` clipped to an end only
    adds that end, which is checked anyway; a missing root is left at ``τ = 0``, likewise
    harmless.
    """
    delta, c0, c1, c2 = discriminant(c0, c1, c2)  # rescaled where it would overflow
    half = -0.5 * (c1 + np.copysign(np.sqrt(np.abs(delta)), c1))
    # No real root (or half = 0, then c1 = c0 = 0 or none): both divisions are skipped.
    real = (delta >= 0.0) & (half != 0.0)
    np.divide(half, c2, out=roots[0], where=real & (c2 != 0.0))
    np.divide(c0, half, out=roots[1], where=real)
    np.minimum(np.maximum(roots, 0.0, out=roots), 1.0, out=roots)


def _coefficient_matrix() -> np.ndarray:
    """
    ``(9, 3)``: the quintic's coefficients from ``(α, D/T, e0 = a0 T)``, linear in them.

    Row ``3·power + k``: the ascending coefficient ``power`` of ``w`` (``k = 0``: ``α, β,
    γ``), of ``E`` (``k = 1``: ``e0, e1, e2``; its roots are v's extrema) and of ``(1 -
    τ)E``'s derivative (``k = 2``: ``e1 - e0, 2(e2 - e1), -3 e2``, up to its sign; its
    roots are a's extrema), with ``β = 2α + e0``, ``γ = 30 D/T - 15α - 2.5 e0``,
    ``e1 = 2γ - 3β`` and ``e2 = -4γ``.
    """
    alpha, ratio, e0 = np.eye(3)
    beta = 2.0 * alpha + e0
    gamma = 30.0 * ratio - 15.0 * alpha - 2.5 * e0
    e1, e2 = 2.0 * gamma - 3.0 * beta, -4.0 * gamma
    return np.array([[alpha, e0, e1 - e0], [beta, e1, 2.0 * (e2 - e1)],
                     [gamma, e2, -3.0 * e2]]).reshape(9, 3)


_COEFFICIENTS = _coefficient_matrix()


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
    ratio = displacement * inverse
    # Every coefficient below is linear in (α, D/T, e0): one product gives them all.
    shape = np.broadcast(alpha, ratio, e0).shape
    basis = np.empty((3,) + shape)
    basis[0], basis[1], basis[2] = alpha, ratio, e0
    table = (_COEFFICIENTS @ basis.reshape(3, -1)).reshape((3, 3) + shape)
    # Each quadratic's two roots, then τ = 0 (where v = α and a = e0/T): v is checked at
    # E's roots, a at the other's; τ = 1 gives v = a = 0.
    points = np.zeros((3, 2) + shape)
    _unit_roots(*table[:, 1:], points[:2])
    # w at E's roots and E at the others, times (1 - τ)² and (1 - τ): v and a T.
    values = table[0, :2] + points * (table[1, :2] + points * table[2, :2])
    rest = 1.0 - points
    values *= rest
    values[:, 0] *= rest[:, 0]
    peak = np.maximum.reduce(np.abs(values, out=values))
    return peak[0], peak[1] * inverse
