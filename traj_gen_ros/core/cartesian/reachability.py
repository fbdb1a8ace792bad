"""
The time-optimal ``ṡ²`` on a grid: controllable sets backwards, the greedy pass forwards.

TOPP-RA (Pham & Pham, "A new approach to time-optimal path parameterization based on
reachability analysis", IEEE T-RO 34(3), 2018, §IV), written for the constraints of
:mod:`.path_constraints`: on interval ``i``, ``a u + b x_i <= c`` (``c >= 0``),
``x_i <= x_max[i]`` and ``x_{i+1} = x_i + 2 Δ_i u``.

``(u, x) = (0, 0)`` satisfies every constraint, so every controllable set is an interval
``[0, K_i]`` and only its top moves. With ``U_hi(x) = min`` over the rows with ``a > 0`` of
``(c - b x) / a`` and ``U_lo(x) = max`` over those with ``a < 0``, ``x`` is controllable iff
``U_lo(x) <= U_hi(x)`` (each pair of rows: one bound of ``x``), ``U_hi(x) >= -x / 2Δ``
(``x_{i+1} >= 0``: each row with ``a > 0``) and ``U_lo(x) <= (K_{i+1} - x) / 2Δ`` (each
row with ``a < 0`` at ``u = (K_{i+1} - x) / 2Δ``: ``x <= P + Q K_{i+1}``). The first two
do not depend on ``K_{i+1}`` and are found for every interval at once (numpy); the last
is the backward pass, ``K_i = min(S_i, min_l P_l + Q_l K_{i+1})``, a few float operations
per interval once the lines that can never be the lowest are dropped. The forward pass
takes the largest ``u`` at each ``x_i``: ``x_{i+1} = min(K_{i+1}, x_i + 2Δ U_hi(x_i))``,
where the top binds the ``u`` that lands on it exactly. Every stage is closed form: no
linear-programming solver. A coefficient of ``u`` at rounding level (a grid point on a
zero of a joint's ``dq/ds``) is taken as 0, a bound of ``x`` alone
(:func:`_without_negligible`).
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.cartesian.path_constraints import Stages

#: A row's coefficient of ``s̈`` below this share of its interval's largest counts as 0.
NEGLIGIBLE = 1e-12


def time_optimal_squared_speed(stages: Stages) -> np.ndarray:
    """
    Return the largest ``x = ṡ²`` at every grid point, ``(n + 1,)``, starting at rest.

    An interior grid point where ``x`` is 0 cannot be passed without stopping (the caller
    says so); the result is finite wherever the limits bound the speed.
    """
    stages = _without_negligible(stages)
    twice = 2.0 * stages.delta
    a, b, c = stages.a, stages.b, stages.c
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        upper = _rows(a > 0.0, a, b, c, stages.x_max[:-1], lowest=True)
        lower = _rows(a < 0.0, a, b, c, stages.x_max[:-1], lowest=False)
        tops = _static_tops(stages, upper, lower, twice)
        lines = _backward_lines(lower, tops, twice)
        slopes = _forward_lines(upper, tops, twice)
    return _forward(_backward(tops, *lines), twice.tolist(), *slopes)


def _without_negligible(stages: Stages) -> Stages:
    """
    Set a row's coefficient of ``s̈`` to 0 where it is at rounding level.

    Where a grid point falls on a zero of a joint's ``dq/ds`` its rows bound ``ṡ²`` alone;
    a coefficient left at ~1e-17 would make each a line so steep that the top of the
    set pins ``s̈`` there to whatever another row allows (a full deceleration for one
    interval). Below :data:`NEGLIGIBLE` of the interval's largest it is 0: the bound of
    ``ṡ²`` (:func:`_static_tops`) holds it.
    """
    a = stages.a
    negligible = (a != 0.0) & (np.abs(a) <= NEGLIGIBLE * np.abs(a).max(axis=1, keepdims=True))
    if not negligible.any():
        return stages
    return Stages(stages.x_max, np.where(negligible, 0.0, a), stages.b, stages.c, stages.delta)


def _rows(mask: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, reach: np.ndarray,
          lowest: bool) -> tuple[np.ndarray, ...]:
    """
    Keep the rows of one sign whose bound of ``u`` may be the tightest on ``[0, reach]``.

    ``(valid, a, b, c)``, compacted. Each row bounds ``u`` by the line ``(c - b x) / a``;
    a line that another one is tighter than at both ``x = 0`` and ``x = reach`` (for
    ``reach = inf``: in slope) is left out, which changes nothing on ``[0, reach]``.
    """
    start = c / a
    end = np.where(np.isfinite(reach)[:, None], (c - b * reach[:, None]) / a, -b / a)
    keep = _envelope(mask, start, end) if lowest else _envelope(mask, -start, -end)
    return _compact(keep, a, b, c)


def _envelope(valid: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """
    Mark the lines that may be the lowest between two abscissae where they are ``start``, ``end``.

    Exact without comparing every pair: a line is dropped only when the line lowest at
    the start, or the one lowest at the end, is at least as low at both.
    """
    start, end = np.where(valid, start, np.inf), np.where(valid, end, np.inf)
    first = np.argmin(start, axis=1)[:, None]
    last = np.argmin(end, axis=1)[:, None]
    rows = np.arange(len(valid))[:, None]
    crossing = (end < end[rows, first]) & (start < start[rows, last])
    index = np.arange(valid.shape[1])[None]
    return valid & (crossing | (index == first) | (index == last))


def _static_tops(stages: Stages, upper: tuple[np.ndarray, ...], lower: tuple[np.ndarray, ...],
                 twice: np.ndarray) -> np.ndarray:
    """
    Each point's bound of ``x`` that does not depend on the next controllable set.

    ``(n + 1,)``: ``x_max`` and, for ``i < n``, interval ``i``'s own feasibility: rows with
    ``a = 0``, and ``U_lo <= U_hi``: for rows ``k`` with ``a_k > 0`` and ``l`` with ``a_l <
    0``, ``x (a_k b_l - a_l b_k) <= a_k c_l - a_l c_k``; the row ``-2Δ u - x <= 0``
    (``x_{i+1} >= 0``) is one of the ``l``.
    """
    a, b, c = stages.a, stages.b, stages.c
    flat = np.where((a == 0.0) & (b > 0.0), c / b, np.inf).min(axis=1, initial=np.inf)
    up_valid, ak, bk, ck = (array[:, :, None] for array in upper)
    # The lower rows and x_{i+1} >= 0 as -2Δ u - x <= 0.
    rest = (np.ones_like(twice, dtype=bool), -twice, -np.ones_like(twice), np.zeros_like(twice))
    low_valid, al, bl, cl = (np.concatenate([array, extra[:, None]], axis=1)[:, None]
                             for array, extra in zip(lower, rest, strict=True))
    slope = ak * bl - al * bk
    pairs = np.where(up_valid & low_valid & (slope > 0.0),
                     (ak * cl - al * ck) / slope, np.inf)
    tops = stages.x_max.copy()
    own = np.minimum(flat, pairs.min(axis=(1, 2), initial=np.inf))
    np.minimum(tops[:-1], own, out=tops[:-1])
    return tops


def _backward_lines(lower: tuple[np.ndarray, ...], tops: np.ndarray, twice: np.ndarray
                    ) -> tuple[list[list[float]], list[list[float]]]:
    """
    Write the rows with ``a < 0`` as ``x_i <= P + Q K_{i+1}``, but those never lowest.

    ``P = 2Δ c / E``, ``Q = -a / E`` with ``E = 2Δ b - a > 0`` (else the row bounds
    nothing); only lines that may be the lowest for ``K_{i+1}`` in ``[0, S_{i+1}]`` and
    below ``S_i`` there are kept.
    """
    valid, a, b, c = lower
    twice = twice[:, None]
    rise = twice * b - a
    offset = np.where(rise > 0.0, twice * c / rise, np.inf)
    gain = np.where(rise > 0.0, -a / rise, 0.0)
    reach = tops[1:, None]
    end = np.where(np.isfinite(reach), offset + gain * reach, gain)
    keep = _envelope(valid & (rise > 0.0) & (offset < tops[:-1, None]), offset, end)
    return _lists(keep, offset, gain)


def _forward_lines(upper: tuple[np.ndarray, ...], tops: np.ndarray, twice: np.ndarray
                   ) -> tuple[list[list[float]], list[list[float]]]:
    """
    Write the rows with ``a > 0`` as ``u <= α + β x_i``, ``α = c / a``, ``β = -b / a``.

    A line above ``(S_{i+1} - x) / 2Δ`` on all of ``[0, S_i]`` never bounds ``u`` more than
    the next point's bound does: it is left out.
    """
    valid, a, b, c = upper
    offset = np.where(valid, c / a, np.inf)
    slope = np.where(valid, -b / a, 0.0)
    start, end = tops[:-1, None], tops[1:, None]
    cap = end / twice[:, None]
    above = (offset >= cap) & (offset + slope * start >= cap - start / twice[:, None])
    return _lists(valid & ~above, offset, slope)


def _lists(valid: np.ndarray, offset: np.ndarray, slope: np.ndarray
           ) -> tuple[list[list[float]], list[list[float]]]:
    """Compact the kept lines into Python lists per interval, padded with ``(inf, 0)``."""
    valid, offset, slope = _compact(valid, offset, slope)
    return np.where(valid, offset, np.inf).tolist(), np.where(valid, slope, 0.0).tolist()


def _compact(mask: np.ndarray, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """Move each row's masked entries to its front (in order) and cut the unused columns."""
    width = int(mask.sum(axis=1).max(initial=0))
    rows, columns = np.nonzero(mask)
    rank = (np.cumsum(mask, axis=1) - 1)[rows, columns]
    packed = np.zeros((len(mask), width), dtype=bool)
    packed[rows, rank] = True
    result = [packed]
    for array in arrays:
        out = np.zeros((len(mask), width))
        out[rows, rank] = array[rows, columns]
        result.append(out)
    return tuple(result)


def _backward(tops: np.ndarray, offsets: list[list[float]], gains: list[list[float]]
              ) -> list[float]:
    """Return the controllable sets' tops ``K_i``, from the end backwards."""
    static = tops.tolist()
    controllable = static[:]
    top = controllable[-1]
    for index in range(len(static) - 2, -1, -1):
        best = static[index]
        for offset, gain in zip(offsets[index], gains[index], strict=True):
            value = offset + gain * top
            if value < best:
                best = value
        top = best if best > 0.0 else 0.0
        controllable[index] = top
    return controllable


def _forward(controllable: list[float], twice: list[float], offsets: list[list[float]],
             slopes: list[list[float]]) -> np.ndarray:
    """Take the largest ``u`` at every step from rest: ``x``, ``(n + 1,)``."""
    squared = [0.0] * len(controllable)
    x = 0.0
    for index, step in enumerate(twice):
        reach = controllable[index + 1]
        for offset, slope in zip(offsets[index], slopes[index], strict=True):
            value = x + step * (offset + slope * x)
            if value < reach:
                reach = value
        x = reach if reach > 0.0 else 0.0
        squared[index + 1] = x
    return np.array(squared)
