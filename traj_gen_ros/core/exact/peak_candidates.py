"""
Every duration at which a cubic or quintic move to rest can start or stop meeting a limit.

A cubic (Craig eq. (7.9), from ``v0``) or quintic (eqs. (7.3)-(7.5), from ``v0``, ``a0``)
moving ``D`` in ``T`` has, in normalised time ``τ = t/T``, velocity and acceleration with

``T v - σVT = a0 m_a'(τ) T² + (v0 m_v'(τ) - σV) T + D m_D'(τ)`` and
``T² a - σAT² = (a0 m_a''(τ) - σA) T² + v0 m_v''(τ) T + D m_D''(τ)``, ``σ = ±1``,

where ``m_v``, ``m_a``, ``m_D`` are the columns of the profile's boundary-condition
matrix: quadratics ``P(τ, T)`` in ``T``. The peak ``|v|`` (or ``|a|``) equals its limit
at a duration ``T`` either at an end (``P(0, T) = 0`` or ``P(1, T) = 0``), or where an
extremum enters at an end (``∂P/∂τ = 0`` there), or at an interior extremum:
``P = ∂P/∂τ = 0`` together, whose resultant in ``T`` (the Sylvester determinant) is a
polynomial in ``τ``. Those resultants, divided by their known factors, are linear in a
few products of the inputs; the tables below hold their ascending coefficients in ``τ``
(derived symbolically; ``test/core/test_polynomial_candidates.py`` rebuilds them from the
definition). Their roots in ``[0, 1]`` (:mod:`traj_gen_ros.core.exact.unit_roots`) give ``τ``, and
``P(τ, T) = 0`` gives the durations. Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.exact.unit_peaks import discriminant
from traj_gen_ros.core.exact.unit_roots import (
    ascending_powers,
    column_roots,
    quadratic_roots_in_unit_interval,
)
from traj_gen_ros.core.polynomial import CUBIC_MATRIX, QUINTIC_MATRIX


def _padded(*rows: list[float]) -> np.ndarray:
    """Rows of ascending coefficients padded to degree 9."""
    table = np.zeros((len(rows), 10))
    for index, row in enumerate(rows):
        table[index, :len(row)] = row
    return table


#: Quintic velocity, resultant / (60 D a0 τ (τ - 1)²); rows: v0², σ V v0, a0 D, V².
QUINTIC_VELOCITY = _padded([1, -10, 44, -100, 110, -16, -100, 116, -55, 10],
                           [-2, 20, -70, 120, -110, 52, -10],
                           [0, 0, 0, 15, -90, 225, -300, 225, -90, 15],
                           [1, -10, 26, -20])
#: a0 = 0: resultant of the linear P / (60 D τ (τ - 1)); rows: v0, σ V.
QUINTIC_VELOCITY_NO_A0 = _padded([-1, 2, 0, -2, 1], [1, -2])
#: D = 0: resultant of P/T / (a0 (1 - τ)); rows: v0, σ V.
QUINTIC_VELOCITY_NO_D = _padded([-1, 8, -28, 46, -35, 10], [1, -8, 10])
#: Quintic acceleration, resultant / (720 D); rows: v0² a0, σ A v0², a0² D, σ A a0 D, A² D.
QUINTIC_ACCELERATION = _padded([0, 0, 36, -264, 816, -1344, 1236, -600, 120],
                               [0, 0, -36, 264, -600, 552, -180],
                               [5, -60, 330, -1060, 2145, -2760, 2180, -960, 180],
                               [-10, 120, -570, 1420, -1920, 1320, -360],
                               [5, -60, 240, -360, 180])
#: D = 0: resultant of P/T / (-12 v0); rows: a0, σ A.
QUINTIC_ACCELERATION_NO_D = _padded([3, -16, 33, -30, 10], [-3, 16, -15])
#: Cubic velocity, resultant of the linear P / (6 D); rows: v0, σ V. (Its acceleration
#: is linear in τ: no interior extremum.)
CUBIC_VELOCITY = _padded([1, -2, 1], [-1, 2])


def _shape_derivatives(matrix: np.ndarray, columns: tuple[int | None, ...]) -> np.ndarray:
    """``(2 orders, 3 shapes a/v/D, 6)``: ascending m', m'' of the shapes (zero if None)."""
    shapes = np.zeros((3, 6))
    for row, column in zip((1, 0, 2), columns, strict=True):
        if column is not None:
            shapes[row, :matrix.shape[0]] = matrix[:, column]
    first = np.zeros_like(shapes)
    first[:, :-1] = shapes[:, 1:] * np.arange(1, 6)
    second = np.zeros_like(shapes)
    second[:, :-1] = first[:, 1:] * np.arange(1, 6)
    return np.stack([first, second])


# Shapes in the order (a0 T² term, v0 T term, D term), matching P's powers T², T, 1.
_SHAPES = {
    'cubic': _shape_derivatives(CUBIC_MATRIX, (1, None, 2)),
    'quintic': _shape_derivatives(QUINTIC_MATRIX, (1, 2, 3)),
}


def _end_table(shapes: np.ndarray) -> np.ndarray:
    """
    ``(3 powers · 2 signs · 2 orders · 4 conditions, 5 inputs)``: the ends' quadratics in T.

    Conditions: ``P`` at ``τ = 0`` and ``τ = 1``, ``∂P/∂τ`` at ``τ = 0`` and ``τ = 1``;
    powers ``T², T, 1``; inputs ``(a0, v0, D, v_max, a_max)``. The limit enters ``P``
    (conditions 0 and 1) as ``-σ v_max T`` (velocity) or ``-σ a_max T²`` (acceleration).
    """
    slopes = np.zeros_like(shapes)
    slopes[..., :-1] = shapes[..., 1:] * np.arange(1, 6)
    # (2 orders, 4 conditions, 3 shapes)
    ends = np.stack([shapes[..., 0], shapes.sum(axis=-1), slopes[..., 0],
                     slopes.sum(axis=-1)], axis=1)
    table = np.zeros((3, 2, 2, 4, 5))
    for power in range(3):
        table[power, :, :, :, power] = ends[None, :, :, power]
    for order, power in enumerate(_LIMIT_POWER):
        table[power, :, order, :2, 3 + order] = -_SIGNS[:, None]
    return table.reshape(-1, 5)


def _useful_ends(table: np.ndarray) -> np.ndarray:
    """
    ``(3 powers · ends, 5 inputs)``: the end quadratics of ``table`` that can give a duration.

    A quadratic with one power of ``T`` at most, for every input (``c Tᵏ = 0``), has no
    root but ``T = 0``: the quintic's velocity and acceleration at both ends, and the
    cubic's velocity there, are fixed (``v0``, ``a0``, rest), whatever ``T``, and so is
    where the quintic's extrema enter (``∂P/∂τ = a0 T²`` or ``0`` at some ends). Those
    are left out, and so are repeats (``∂P/∂τ`` does not depend on ``σ``).
    """
    quadratics = table.reshape(3, -1, 5).transpose(1, 0, 2)  # (ends, 3 powers, 5 inputs)
    kept: list[np.ndarray] = []
    for quadratic in quadratics:
        if np.count_nonzero(quadratic.any(axis=1)) >= 2 and \
                not any(np.array_equal(quadratic, other) for other in kept):
            kept.append(quadratic)
    return np.ascontiguousarray(np.array(kept).transpose(1, 0, 2).reshape(-1, 5))


_LIMIT_POWER = (1, 0)  # the limit term multiplies T (velocity), T² (acceleration)
_SIGNS = np.array([1.0, -1.0])  # σ
_END_TABLES = {profile: _useful_ends(_end_table(shapes)) for profile, shapes in _SHAPES.items()}


def _value_table(shapes: np.ndarray) -> np.ndarray:
    """
    ``(4 kinds · 3 powers · 5 inputs, 6)``: ``P(τ, T)``'s coefficients as polynomials in τ.

    Kind ``2·order + sign``; powers ``T², T, 1``; inputs ``(a0, v0, D, v_max, a_max)``:
    the coefficient of ``T^(2-p)`` is ``Σ_i input_i · table[kind, p, i](τ)``.
    """
    table = np.zeros((2, 2, 3, 5, 6))
    for power in range(3):
        table[:, :, power, power] = shapes[:, None, power]
    for order, power in enumerate(_LIMIT_POWER):
        table[order, :, power, 3 + order, 0] = -_SIGNS
    return table.reshape(-1, 6)


# The same by power, degree in τ and kind (rows), so that one product with the inputs
# gives every column's P(τ, T) as (3 powers, 6 degrees, 4·joints columns).
_COEFFICIENT_TABLES = {
    profile: np.ascontiguousarray(
        _value_table(shapes).reshape(4, 3, 5, 6).transpose(1, 3, 0, 2).reshape(-1, 5))
    for profile, shapes in _SHAPES.items()}


def _positive_roots(p2: np.ndarray, p1: np.ndarray, p0: np.ndarray) -> np.ndarray:
    """
    Real roots of ``p2 T² + p1 T + p0`` (flat), ``(2, count)``; NaN where there is none.

    Stable pair: ``q = -(p1 + sgn(p1) √Δ)/2``, ``T = q/p2`` and ``p0/q`` (``p2 = 0``: the
    linear root ``-p0/p1`` is the second). A negative ``Δ`` within rounding counts as a
    double root; complex pairs and divisions by zero give NaN or ±inf, which the caller
    drops with the negative roots.
    """
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        square, product = p1 * p1, 4.0 * p2 * p0
        delta = square - product
        if np.count_nonzero(np.isfinite(delta)) != delta.size:  # rescaled where it overflows
            delta, p0, p1, p2 = discriminant(p0, p1, p2)
            square, product = p1 * p1, 4.0 * p2 * p0
        half = -0.5 * (p1 + np.copysign(np.sqrt(np.maximum(delta, 0.0)), p1))
        half[delta < -1e-12 * (square + np.abs(product))] = np.nan  # complex pair
        roots = np.empty((2, half.size))
        np.divide(half, p2, out=roots[0])
        np.divide(p0, half, out=roots[1])
    return roots


def _block_table(blocks: list[tuple[int, np.ndarray, list[int]]], rows: int) -> np.ndarray:
    """
    ``(10 · 2 orders · 2 signs, rows)``: one product with the monomials gives every resultant.

    Each block ``(order, table, odd)`` places ``table`` (monomial rows) into both sign
    columns of its order, with the rows listed in ``odd`` (odd powers of ``σ``) negated
    for ``σ = -1``. Blocks take consecutive monomial rows. The product's rows are ordered
    (coefficient, order, sign), so it reshapes to polynomials as columns ``(10, 4·joints)``,
    column ``(2·order + sign)·joints + joint``.
    """
    big = np.zeros((rows, 2, 2, 10))
    row = 0
    for order, table, odd in blocks:
        signs = np.ones((table.shape[0], 1))
        signs[odd] = -1.0
        big[row:row + table.shape[0], order, 0] = table
        big[row:row + table.shape[0], order, 1] = table * signs
        row += table.shape[0]
    return np.ascontiguousarray(big.transpose(3, 1, 2, 0).reshape(-1, rows))


# Monomial columns: see _monomials.
_TABLES = {
    'cubic': _block_table([(0, CUBIC_VELOCITY, [1])], 2),
    'quintic': _block_table([(0, QUINTIC_VELOCITY, [1]), (0, QUINTIC_VELOCITY_NO_A0, [1]),
                             (0, QUINTIC_VELOCITY_NO_D, [1]), (1, QUINTIC_ACCELERATION, [1, 3]),
                             (1, QUINTIC_ACCELERATION_NO_D, [1])], 15),
}


def _monomials(profile: str, displacement: np.ndarray, velocity: np.ndarray,
               acceleration: np.ndarray, max_velocity: np.ndarray,
               max_acceleration: np.ndarray) -> np.ndarray:
    """
    ``(rows, joints)``: the products the resultants are linear in (with ``σ = +1``).

    Degenerate inputs take their own resultant (a0 = 0 or D = 0: ``P`` loses a power of
    ``T``); where none is defined the peak does not depend on ``T`` and the row is zero.
    Without a degenerate joint (the usual case) the degenerate rows are zero.
    """
    if profile == 'cubic':
        return np.array([velocity, max_velocity]) * (displacement != 0.0)
    rows = np.zeros((15, displacement.size))
    v0_squared = np.multiply(velocity, velocity, out=rows[0])
    np.multiply(max_velocity, velocity, out=rows[1])
    a_d = np.multiply(acceleration, displacement, out=rows[2])
    np.multiply(max_velocity, max_velocity, out=rows[3])
    np.multiply(v0_squared, acceleration, out=rows[8])
    np.multiply(max_acceleration, v0_squared, out=rows[9])
    np.multiply(a_d, acceleration, out=rows[10])
    np.multiply(max_acceleration, a_d, out=rows[11])
    np.multiply(max_acceleration * max_acceleration, displacement, out=rows[12])
    if np.count_nonzero(a_d) == a_d.size:  # no degenerate joint: the general rows only
        return rows
    general = list(rows[:4]) + list(rows[8:13])
    has_d, has_a0 = displacement != 0.0, acceleration != 0.0
    products = np.array(general[:4] + [
        velocity, max_velocity,  # a0 = 0
        velocity, max_velocity] + general[4:] + [  # D = 0
        acceleration, max_acceleration])  # D = 0 (acceleration)
    both = has_d & has_a0
    no_d = ~has_d & has_a0
    no_a0 = has_d & ~has_a0
    no_d_acceleration = ~has_d & (velocity != 0.0)
    every = np.ones_like(has_d)
    return products * np.array([both, both, both, both, no_a0, no_a0, no_d, no_d,
                                has_d, has_d, every, every, every, no_d_acceleration,
                                no_d_acceleration])


def _interior_columns(profile: str, *moves: np.ndarray) -> np.ndarray:
    """Resultant polynomials in τ as columns, ``(10, 4·joints)`` (see :func:`_block_table`)."""
    return (_TABLES[profile] @ _monomials(profile, *moves)).reshape(10, -1)


def _interior_polynomials(profile: str, *moves: np.ndarray) -> np.ndarray:
    """Resultant polynomials in τ, ``(2 orders, 2 signs, joints, 10)``."""
    return _interior_columns(profile, *moves).reshape(10, 2, 2, -1).transpose(1, 2, 3, 0)


# At a resultant's root τ*, P and ∂P/∂τ vanish at the extremum's duration T*, so there
# dT/dτ = -P_τ/P_T = 0: an error ε in τ moves T* by ~P_ττ ε²/(2 P_T), second order. This
# step leaves ε ≈ C·step² (C = |r''/2r'|): ~1e-9 usually, up to ~1e-7 in random trials,
# so T* moves by ~1e-18 to ~1e-14 relative, except where P_T ≈ 0 too (T* a near-double
# root of P, whose rounding is as large already).
# The quadratic's other root is no extremum (it only adds a candidate where feasibility
# does not change) and moves with ε to first order: harmless.
_TAU_STEP = 1e-5

_INPUT_TABLES = {profile: np.concatenate([_END_TABLES[profile], _COEFFICIENT_TABLES[profile]])
                 for profile in _SHAPES}


def durations(profile: str, displacement: np.ndarray, velocity: np.ndarray,
              acceleration: np.ndarray, max_velocity: np.ndarray,
              max_acceleration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Every root of the quadratics in ``T`` (flat; NaN, ±inf and ``T ≤ 0`` included).

    The ends' quadratics come first (quadratic ``k``'s joint is ``k`` modulo the joint
    count), then one per resultant root, whose column of :func:`_interior_columns`
    (``kind·joints + joint``) is returned too. Roots ``k`` and ``k + count`` come from
    quadratic ``k``. The ends' quadratics are :data:`_END_TABLES`' products with the
    inputs; at a root τ of a resultant, ``P(τ, T)``'s coefficients are a product of
    :data:`_COEFFICIENT_TABLES` with the inputs, evaluated at τ.
    """
    inputs = np.array([acceleration, velocity, displacement, max_velocity, max_acceleration])
    columns = _interior_columns(profile, displacement, velocity, acceleration, max_velocity,
                                max_acceleration)
    if profile == 'cubic':  # quadratics in τ (velocity only): closed form
        taus, owners = quadratic_roots_in_unit_interval(columns[:3, :2 * displacement.size].T)
    else:
        taus, owners = column_roots(columns, _TAU_STEP)
    # The ends' quadratics (3 powers · ends, joints), then P's coefficients as polynomials
    # in τ (3 powers, 6 degrees, 4·joints columns): one product.
    products = _INPUT_TABLES[profile] @ inputs
    ends = products[:-72]
    count = ends.size // 3
    quadratics = np.empty((3, count + taus.size))
    quadratics[:, :count] = ends.reshape(3, -1)
    shapes = products[-72:].reshape(3, 6, -1)
    np.einsum('pdr,dr->pr', shapes[:, :, owners], ascending_powers(taus, 6),
              out=quadratics[:, count:])
    return _positive_roots(*quadratics).reshape(-1), owners


def candidates(profile: str, displacement: np.ndarray, velocity: np.ndarray,
               acceleration: np.ndarray, max_velocity: np.ndarray, max_acceleration: np.ndarray,
               shortest: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    Every duration above ``shortest`` where a joint's peak can equal its limit, and its joint.

    Each is a positive root of a quadratic in ``T``: ``P(τ, T)`` at the ends (τ = 0, 1,
    from :data:`_END_TABLES`) or at a root τ of a resultant, all solved at once
    (:func:`durations`).
    """
    joints = displacement.size
    found, columns = durations(profile, displacement, velocity, acceleration, max_velocity,
                               max_acceleration)
    ends = found.size // 2 - columns.size
    owners = np.concatenate([np.arange(ends) % joints, columns % joints])
    owners = np.concatenate([owners, owners])
    keep = (found > shortest) & (found < np.inf)
    return found[keep], owners[keep]
