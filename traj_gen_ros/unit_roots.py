"""
Real roots on ``[0, 1]`` of many polynomials of degree ≤ 9 at once.

The timing of a cubic or quintic from a moving state needs the roots in normalised time
``τ ∈ [0, 1]`` of a few dozen resultant polynomials (:mod:`traj_gen_ros.polynomial_timing`).
An eigenvalue problem per polynomial costs ~15 µs each; this module isolates the roots in
a handful of vectorised steps instead:

1. Bernstein coefficients on 32 equal pieces of ``[0, 1]`` (one matrix product). A
   polynomial's values on a piece lie in the convex hull of its Bernstein coefficients
   there, and the number of roots in the piece is at most the number of sign changes of
   those coefficients, with the same parity (Descartes' rule of signs in the Bernstein
   basis; Lane and Riesenfeld, "Bounds on a polynomial", BIT 21, 1981; Farouki and
   Rajan, CAGD 5, 1988). So a piece whose coefficients share a sign has no root, and one
   with exactly one sign change has exactly one.
2. Pieces with more changes (close roots, near-double roots) are split into eighths once
   (pieces of 1/256).
3. Each piece with one root: Newton's method inside it, to machine precision.

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
from traj_gen_ros.polynomial_peaks import discriminant

_PIECES = 32  # first subdivision of [0, 1]
_SPLIT = 8  # each unresolved piece is split into this many
_LEVELS = 1  # splits before an eigenvalue problem takes over
_MARGIN = 1e-13  # normalised Bernstein coefficients this close to 0 count as 0
_IMAGINARY_SLACK = 1e-6  # eigenvalues this close to the real axis count as real
_NEWTON_STEPS = 12  # unguarded steps from the secant point at most, then a check


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


def roots_in_unit_interval(polynomials: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Real roots in ``[0, 1]`` of ascending polynomials ``(count, size)``, ``size ≤ 10``.

    Returns the roots and the row each belongs to. Rows that are identically zero have
    no isolated roots and give none.
    """
    size = polynomials.shape[1]
    scale = np.abs(polynomials).max(axis=1)
    nonzero = np.flatnonzero(scale)
    normalised = polynomials[nonzero] / scale[nonzero, None]
    coefficients = (normalised @ _pieces(size, _PIECES)).reshape(-1, size)
    owners = np.repeat(np.arange(nonzero.size), _PIECES)
    starts = np.tile(np.arange(_PIECES) / _PIECES, nonzero.size)
    width = 1.0 / _PIECES
    found: list[tuple] = []
    for level in range(_LEVELS + 1):
        # Signs with near-zero coefficients as 0; sums by matrix products (row reductions
        # of short rows are slow in numpy).
        signs = np.sign(coefficients)
        signs[np.abs(coefficients) <= _MARGIN] = 0.0
        clear = np.abs(signs) @ np.ones(size) == size
        changes = (size - 1 - (signs[:, 1:] * signs[:, :-1]) @ np.ones(size - 1)) / 2
        single = clear & (changes == 1)
        found.append((owners[single], starts[single], width, coefficients[single]))
        unresolved = ~clear | (changes > 1)
        if not unresolved.any():
            hard = np.zeros(0, dtype=np.intp)
            break
        if level == _LEVELS:
            hard = np.flatnonzero(np.bincount(owners[unresolved], minlength=nonzero.size))
            break
        coefficients = (coefficients[unresolved] @ _split(size)).reshape(-1, size)
        owners = np.repeat(owners[unresolved], _SPLIT)
        width /= _SPLIT
        starts = (starts[unresolved][:, None] + width * np.arange(_SPLIT)).reshape(-1)
    rows = np.concatenate([part[0] for part in found])
    is_hard = np.zeros(nonzero.size, dtype=bool)
    is_hard[hard] = True
    easy = ~is_hard[rows]
    roots = _newton(normalised[rows[easy]],
                    np.concatenate([part[1] for part in found])[easy],
                    np.concatenate([np.full(part[0].size, part[2]) for part in found])[easy],
                    np.concatenate([part[3] for part in found])[easy])
    rows = rows[easy]
    if hard.size:
        hard_roots, hard_rows = _eigenvalue_roots(normalised[hard])
        roots = np.concatenate([roots, hard_roots])
        rows = np.concatenate([rows, hard[hard_rows]])
    return roots, nonzero[rows]


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


def _newton(coefficients: np.ndarray, starts: np.ndarray, widths: np.ndarray,
            bernstein: np.ndarray) -> np.ndarray:
    """
    Return the one root of polynomial row ``k`` in ``[starts[k], starts[k] + widths[k]]``.

    ``bernstein`` holds each piece's Bernstein coefficients. The piece is split once more
    and the part whose end values (first Bernstein coefficients) change sign taken; then
    Newton's method from the secant point there, a few steps. Rows that have not
    converged inside their part by then (rare) continue safeguarded: a step leaving the
    bracket bisects it, and the bracket shrinks to the iterate.
    """
    if not starts.size:
        return np.zeros(0)
    size = coefficients.shape[1]
    powers = np.arange(size)
    slopes = coefficients[:, 1:] * powers[1:]
    # A better bracket first: the part of the piece (one of _SPLIT) where the sign changes,
    # from the values at the parts' ends (their first Bernstein coefficients).
    parts = (bernstein @ _split(size)).reshape(-1, _SPLIT, size)
    ends = np.concatenate([parts[:, :, 0], bernstein[:, -1:]], axis=1)
    part = np.argmax(ends[:, :-1] * ends[:, 1:] <= 0.0, axis=1)
    widths = widths / _SPLIT
    starts = starts + part * widths
    chosen = np.arange(part.size)
    at_low, at_high = ends[chosen, part], ends[chosen, part + 1]
    span = at_low - at_high  # not 0: the values differ in sign (or one is 0)
    point = starts + widths * at_low / np.where(span == 0.0, 1.0, span)
    # Value and slope by one product: rows (coefficients, slopes padded with a 0).
    pair = np.zeros((point.size, 2, size))
    pair[:, 0] = coefficients
    pair[:, 1, :-1] = slopes
    for index in range(_NEWTON_STEPS):
        both = pair @ (point[:, None] ** powers)[:, :, None]
        step = both[:, 0, 0] / both[:, 1, 0]
        point = point - step
        if index % 2 and np.abs(step).max() <= 1e-12:
            break
    settled = (np.abs(step) <= 1e-12) & (point >= starts) & (point <= starts + widths)
    if not settled.all():
        again = np.flatnonzero(~settled)
        point[again] = _safeguarded(coefficients[again], slopes[again], starts[again],
                                    starts[again] + widths[again], at_low[again] < 0.0)
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
_pieces(10, _PIECES)
_split(10)
np.linalg.eigvals(np.eye(2)[None])
