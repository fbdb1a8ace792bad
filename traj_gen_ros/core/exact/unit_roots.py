"""
Real roots on ``[0, 1]`` of many polynomials of degree ≤ 9 at once.

The timing of a cubic or quintic from a moving state needs the roots in normalised time
``τ ∈ [0, 1]`` of a few dozen resultant polynomials
(:mod:`traj_gen_ros.core.exact.polynomial_durations`).
An eigenvalue problem per polynomial costs ~15 µs each; this module isolates the roots in
a handful of vectorised steps instead:

1. Bernstein coefficients on 32 equal pieces of ``[0, 1]`` (one matrix product). A
   polynomial's values on a piece lie in the convex hull of its Bernstein coefficients
   there, and the number of roots in the piece is at most the number of sign changes of
   those coefficients, with the same parity (Descartes' rule of signs in the Bernstein
   basis; Lane and Riesenfeld, "Bounds on a polynomial", BIT 21, 1981; Farouki and
   Rajan, CAGD 5, 1988). So a piece whose coefficients share a sign has no root, and one
   with exactly one sign change has exactly one.
2. Every piece that may hold a root is split into eighths (pieces of 1/256); parts that
   are still unresolved (close roots, such as the near-double ones of the quintic's
   acceleration resultant near τ = (3 ± √3)/6, whose pairs close up as the start nears
   rest) are split into eighths again, up to three times (parts of 1/131072): a level
   costs only where a part is left, ~35 µs, against ~340 µs for the eigenvalues below.
   A quintic from 0.02 s into a 3.7 s move from rest is resolved by the last level.
3. Each part with one root: Newton's method inside it, from where its control polygon
   crosses zero, to machine precision (or, when the caller asks, until the last step is
   below its own ``last_step``: see :func:`column_roots`).

Polynomials are stored as columns ``(size, count)`` so that every per-piece test is a
reduction over axis 0, which numpy does in one pass over contiguous rows.

A polynomial that still has an unresolved piece (close roots, a root at a piece's end, a
double root) has all its roots computed by its companion matrix's eigenvalues instead,
counting roots within 1e-6 of the real axis as real. So every root where the polynomial
changes sign is found, and touching roots that the rounded polynomial still reaches; a
root of even multiplicity that rounding lifts off zero can be missed, and there the sign
does not change.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from traj_gen_ros.core.exact.unit_peaks import discriminant

_PIECES = 32  # first subdivision of [0, 1]
_SPLIT = 8  # each piece that may hold a root is split into this many
_LEVELS = 4  # splits before an eigenvalue problem takes over
_MARGIN = 1e-13  # normalised Bernstein coefficients this close to 0 count as 0
_IMAGINARY_SLACK = 1e-6  # eigenvalues this close to the real axis count as real
_NEWTON_STEPS = 12  # unguarded steps from the start at most, then a safeguarded search
# Newton's method converges quadratically: after a step of size s the error is about
# C·s² (C = |p''/2p'|, ~1-100 here), so a last step below 1e-8 leaves ~1e-16·C.
_LAST_STEP = 1e-8
_ORDERS = np.arange(16.0)  # derivative factors


@functools.cache
def _bernstein(size: int) -> np.ndarray:
    """Map ascending coefficients (degree ``size - 1``) to Bernstein ones on ``[0, 1]``."""
    degree = size - 1
    matrix = np.zeros((size, size))
    for power in range(size):
        for index in range(power, size):
            matrix[power, index] = math.comb(index, power) / math.comb(degree, power)
    return matrix


@functools.cache
def _pieces(size: int, pieces: int) -> np.ndarray:
    """``(size, pieces·size)``: ascending coefficients → Bernstein ones on each piece."""
    width = 1.0 / pieces
    blocks = []
    for piece in range(pieces):
        start = piece * width
        # c_i (start + width s)^i = Σ_j c_i C(i, j) start^(i-j) width^j s^j
        shift = np.zeros((size, size))
        for power in range(size):
            for local in range(power + 1):
                shift[power, local] = math.comb(power, local) * \
                    start ** (power - local) * width ** local
        blocks.append(shift @ _bernstein(size))
    return np.concatenate(blocks, axis=1)


@functools.cache
def _split(size: int) -> np.ndarray:
    """``(size, _SPLIT·size)``: Bernstein coefficients on a piece → on each of its parts."""
    return np.linalg.inv(_bernstein(size)) @ _pieces(size, _SPLIT)


@functools.cache
def _by_columns(size: int, kind: str) -> np.ndarray:
    """
    :func:`_pieces` (``kind`` "pieces") or :func:`_split` for polynomials stored as columns.

    Row ``k·parts + part`` gives coefficient ``k`` on ``part``, so ``matrix @ columns``
    reshaped to ``(size, parts·count)`` holds one piece per column (``part·count + row``)
    and every test of a piece is a reduction over axis 0 (fast in numpy, unlike axis 1).
    """
    matrix = _pieces(size, _PIECES) if kind == 'pieces' else _split(size)
    parts = matrix.shape[1] // size
    return np.ascontiguousarray(
        matrix.reshape(size, parts, size).transpose(2, 1, 0).reshape(size * parts, size))


def _may_hold_roots(coefficients: np.ndarray) -> np.ndarray:
    """Pieces (columns) whose Bernstein coefficients are not all beyond ``±_MARGIN``, one side."""
    return ((np.minimum.reduce(coefficients) <= _MARGIN) &
            (np.maximum.reduce(coefficients) >= -_MARGIN)).nonzero()[0]


def _classify(coefficients: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Pieces (columns of Bernstein coefficients) with exactly one root, and unresolved ones.

    A piece whose coefficients all lie beyond ``±_MARGIN`` on one side has no root; one
    with no coefficient within the margin and one sign change has exactly one; any other
    piece (more changes, or a coefficient within rounding of 0) is unresolved.
    """
    positive = coefficients > _MARGIN
    clear = np.logical_and.reduce(positive | (coefficients < -_MARGIN))
    # Sign changes of a clear piece; 2 (unresolved) for one with a coefficient near 0.
    changes = np.where(clear, np.add.reduce(positive[1:] != positive[:-1]), 2)
    return (changes == 1).nonzero()[0], (changes > 1).nonzero()[0]


def roots_in_unit_interval(polynomials: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Real roots in ``[0, 1]`` of ascending polynomials ``(count, size)``, ``size ≤ 10``.

    Returns the roots and the row each belongs to. Rows that are identically zero have
    no isolated roots and give none.
    """
    return column_roots(polynomials.T)


def column_roots(polynomials: np.ndarray,
                 last_step: float = _LAST_STEP) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`roots_in_unit_interval` of polynomials stored as columns, ``(size, count)``.

    Newton's method stops once every last step is below ``last_step`` (at least two steps
    each); the default leaves the roots to machine precision. A larger one leaves an error
    of about ``C·last_step²`` (``C = |p''/2p'|``), for callers that need less.
    """
    size = polynomials.shape[0]
    scale = np.maximum.reduce(np.abs(polynomials))
    count = np.count_nonzero(scale)
    if count == scale.size:  # usually: no row to leave out
        nonzero = None
        normalised = polynomials / scale
    else:
        nonzero = scale.nonzero()[0]
        normalised = polynomials[:, nonzero] / scale[nonzero]
    coefficients = (_by_columns(size, 'pieces') @ normalised).reshape(size, -1)
    # Every piece that may hold a root is split into eighths (one product) and classified;
    # unresolved parts are split again, _LEVELS splits in all. Pending parts: owner row,
    # start, coefficients.
    pending = _may_hold_roots(coefficients)
    starts, owners = np.divmod(pending, count)
    starts = starts / _PIECES
    coefficients = coefficients[:, pending]
    found: list[tuple] = []  # parts with one root: (owners, starts, widths, coefficients)
    for level in range(1, _LEVELS + 1):
        width = 1.0 / (_PIECES * _SPLIT ** level)
        parts = (_by_columns(size, 'split') @ coefficients).reshape(size, -1)
        single, unresolved = _classify(parts)
        part, parent = np.divmod(single, owners.size)  # part p of column c: p·size + c
        found.append((owners[parent], starts[parent] + part * width, width, parts[:, single]))
        if not unresolved.size:
            owners = unresolved
            break
        part, parent = np.divmod(unresolved, owners.size)
        owners, starts = owners[parent], starts[parent] + part * width
        coefficients = parts[:, unresolved]
    if len(found) == 1:  # usually: every root isolated at the first split
        roots_of, at, widths, bernstein = found[0]
    else:
        roots_of, at, bernstein = (np.concatenate(part, axis=-1) for part in
                                   zip(*((a, b, d) for a, b, _, d in found), strict=True))
        widths = np.repeat([part[2] for part in found], [part[0].size for part in found])
    pairs = (_with_slopes(size) @ normalised[:, roots_of]).reshape(2, size, -1)
    roots = _newton(pairs, at, widths, bernstein, last_step)
    if owners.size:
        hard = np.bincount(owners, minlength=count).nonzero()[0]
        easy = np.bincount(hard, minlength=count)[roots_of] == 0
        hard_roots, hard_rows = _eigenvalue_roots(normalised[:, hard].T)
        roots = np.concatenate([roots[easy], hard_roots])
        roots_of = np.concatenate([roots_of[easy], hard[hard_rows]])
    return roots, roots_of if nonzero is None else nonzero[roots_of]


def ascending_powers(points: np.ndarray, size: int) -> np.ndarray:
    """``(size, n)``: ``points⁰ … points^(size-1)``, by running products (``**`` is slower)."""
    table = np.empty((size,) + points.shape)
    table[0] = 1.0
    table[1:] = points
    return np.multiply.accumulate(table, axis=0, out=table)


@functools.cache
def _with_slopes(size: int) -> np.ndarray:
    """
    ``(2·size, size)``: ascending coefficients (columns) → themselves, then their derivative.

    The product with polynomials stored as columns, reshaped to ``(2, size, count)``, holds
    each polynomial and its derivative (padded with 0), as :func:`_newton` takes them.
    """
    matrix = np.zeros((2 * size, size))
    matrix[:size] = np.eye(size)
    matrix[size + np.arange(size - 1), np.arange(1, size)] = _ORDERS[1:size]
    return matrix


def quadratic_roots_in_unit_interval(polynomials: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Real roots in ``[0, 1]`` of ascending ``c0 + c1 τ + c2 τ²`` (rows), and their rows.

    The stable quadratic formula (``q = -(c1 + sgn(c1) √Δ)/2``, roots ``q/c2`` and
    ``c0/q``); a double root counts (``Δ`` within rounding of 0), linear rows give
    ``-c0/c1``. Identically zero rows give none.
    """
    delta, c0, c1, c2 = discriminant(polynomials[:, 0], polynomials[:, 1], polynomials[:, 2])
    real = delta >= -1e-12 * (c1 * c1 + np.abs(4.0 * c2 * c0))
    half = -0.5 * (c1 + np.copysign(np.sqrt(np.maximum(delta, 0.0)), c1))
    usable = real & (half != 0.0)
    half = np.where(usable, half, 1.0)
    roots = np.stack([np.where(usable & (c2 != 0.0), half / np.where(c2 != 0.0, c2, 1.0),
                               np.nan),
                      np.where(usable, c0 / half, np.nan)])
    inside = (roots >= 0.0) & (roots <= 1.0)
    which, rows = np.nonzero(inside)
    return roots[which, rows], rows


def _newton(pair: np.ndarray, starts: np.ndarray, widths: np.ndarray | float,
            bernstein: np.ndarray, last_step: float = _LAST_STEP) -> np.ndarray:
    """
    Return the one root of polynomial ``k`` in ``[starts[k], starts[k] + widths[k]]``.

    ``pair`` holds each polynomial and its derivative as columns, ``(2, size, count)``
    (:func:`_with_slopes`); ``bernstein`` each part's Bernstein coefficients (columns),
    with one sign change (the first and last are the values at the part's ends). Newton's
    method from where the control polygon crosses zero: two steps for all,
    more (for all) while some last step was not yet below ``last_step``. Columns that
    have not converged inside their part by then (rare) continue safeguarded: a step
    leaving the bracket bisects it.
    """
    size = pair.shape[1]
    # Start where the control polygon (the Bernstein coefficients at k/(size - 1)) crosses
    # zero: its one sign change, between coefficients k and k + 1, where k + 1 is the
    # number of coefficients with the first one's sign. (The chord between the part's ends
    # is cheaper but a worse start: Newton's method left the part from it in 40 % of
    # random plans.)
    positive = bernstein > 0.0
    change = np.add.reduce(positive)
    change = np.where(positive[0], change - 1, size - 1 - change)
    columns = np.arange(change.size)
    before, after = bernstein[change, columns], bernstein[change + 1, columns]
    point = starts + widths * (change + before / (before - after)) / (size - 1)
    converged = False
    for step_count in range(_NEWTON_STEPS):
        both = np.einsum('jkn,kn->jn', pair, ascending_powers(point, size))
        step = both[0] / both[1]
        point -= step
        if step_count and np.maximum.reduce(np.abs(step), initial=0.0) <= last_step:
            converged = True
            break
    ends = starts + widths
    settled = (point >= starts) & (point <= ends)
    if not converged:
        settled &= np.abs(step) <= last_step
    if not settled.all():
        again = (~settled).nonzero()[0]
        point[again] = _safeguarded(pair[0, :, again], pair[1, :-1, again], starts[again],
                                    ends[again], bernstein[0, again] < 0.0)
    return point


def _safeguarded(coefficients: np.ndarray, slopes: np.ndarray, low: np.ndarray,
                 high: np.ndarray, rising: np.ndarray) -> np.ndarray:
    """Bracketed Newton: the root in ``[low, high]``, where the value rises if ``rising``."""
    powers = np.arange(coefficients.shape[1])
    point = 0.5 * (low + high)
    for _ in range(80):
        power = point[:, None] ** powers
        terms = coefficients * power
        value = terms.sum(axis=1)
        slope = (slopes * power[:, :-1]).sum(axis=1)
        short = (value < 0.0) == rising
        low = np.where(short, point, low)
        high = np.where(short, high, point)
        flat = slope == 0.0
        step = point - value / np.where(flat, 1.0, slope)
        step = np.where((step >= low) & (step <= high) & ~flat, step, 0.5 * (low + high))
        # Converged, or the value is within its own rounding (then the root is known to
        # what the coefficients allow: steps would only follow the rounding noise).
        done = (np.abs(step - point) <= 1e-15) | \
            (np.abs(value) <= 1e-15 * np.abs(terms).sum(axis=1))
        point = step
        if done.all():
            break
    return point


def _eigenvalue_roots(polynomials: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Real roots in ``[0, 1]`` by companion matrices, batched by effective degree."""
    scale = np.max(np.abs(polynomials), axis=1)
    significant = np.abs(polynomials) > 1e-13 * scale[:, None]
    size = polynomials.shape[1]
    degrees = np.where(significant.any(axis=1),
                       size - 1 - np.argmax(significant[:, ::-1], axis=1), 0)
    roots, owners = [np.zeros(0)], [np.zeros(0, dtype=np.intp)]
    # (np.unique would import numpy.ma on first use: 14 ms in a node's first plan.)
    for degree in np.flatnonzero(np.bincount(degrees)):
        if degree < 1:
            continue
        members = np.flatnonzero(degrees == degree)
        monic = polynomials[members, :degree] / polynomials[members, degree:degree + 1]
        companion = np.zeros((members.size, degree, degree))
        companion[:, 1:, :-1] = np.eye(degree - 1)
        companion[:, :, -1] = -monic
        values = np.linalg.eigvals(companion)
        real = (np.abs(values.imag) <= _IMAGINARY_SLACK * (1.0 + np.abs(values.real))) & \
            (values.real >= -1e-9) & (values.real <= 1.0 + 1e-9)
        rows, columns = np.nonzero(real)
        roots.append(np.clip(values.real[rows, columns], 0.0, 1.0))
        owners.append(members[rows])
    return np.concatenate(roots), np.concatenate(owners)


# Build the degree-9 tables (~1 ms) and make the first eigenvalue call at import rather
# than in the node's first plan from a moving state.
_by_columns(10, 'pieces')
_by_columns(10, 'split')
np.linalg.eigvals(np.eye(2)[None])
