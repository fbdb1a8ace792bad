"""
A plan's own velocity, acceleration and jerk at a time, and their ranges over intervals.

For the speed override's look-ahead (:mod:`traj_gen_ros.node.speed.look_ahead`): the ramp
commands ``f v(τ)``, ``f² a(τ) + ḟ v(τ)`` and ``f³ j(τ) + 3 f ḟ a(τ) + f̈ v(τ)`` from
the plan's own ``v``, ``a``, ``j`` at its own time ``τ``. :class:`PlanWindow` gives
them at a time and their ranges over a ``τ`` interval: exact for cubic pieces (every
``scurve`` plan: ``j`` constant per piece, ``a`` linear, ``v`` quadratic; extrema at the
interval's ends, the breakpoints inside and the roots of ``a``), and for pieces of a
higher degree (an action goal's quintics) bounds from the Bernstein coefficients of
each piece's part in the interval (convex hull property: never narrower than the range;
Farouki, "The Bernstein polynomial basis: a centennial retrospective", CAGD 29, 2012).

No ROS here. Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
import math

import numpy as np
from traj_gen_ros.core.trajectory import state_at, Trajectory


def jerk_at(plan: Trajectory, time: float) -> np.ndarray:
    """Return the plan's own jerk (rad/s³) at ``time`` (s, clipped to the plan), ``(joints,)``."""
    time = min(max(float(time), 0.0), plan.duration)
    coefficients = plan.coefficients
    size = coefficients.shape[1]
    if size < 4:
        return np.zeros(plan.joint_count)
    breakpoints = plan.breakpoints
    joints = np.arange(plan.joint_count)
    if breakpoints.ndim == 1:
        piece = np.full(plan.joint_count, np.searchsorted(breakpoints[1:-1], time, side='right'))
        local = time - breakpoints[piece]
    else:
        piece = np.count_nonzero(breakpoints[1:-1] <= time, axis=0)
        local = time - breakpoints[piece, joints]
    powers = np.arange(3, size)
    factors = powers * (powers - 1) * (powers - 2)
    gathered = coefficients[piece, 3:, joints]  # (joints, size - 3)
    return np.sum(gathered * factors * local[:, None] ** (powers - 3), axis=1)


class PlanWindow:
    """A scaled plan's own ``(v, a, j)`` at a time and its exact ranges over intervals."""

    def __init__(self, plan: Trajectory) -> None:
        """Tabulate ``plan``'s pieces per joint (breakpoints, coefficients, extremum points)."""
        self.plan = plan
        self.duration = plan.duration
        joints = plan.joint_count
        self.joints = np.arange(joints)
        breakpoints = plan.breakpoints
        if breakpoints.ndim == 1:
            breakpoints = np.repeat(breakpoints[:, None], joints, axis=1)
        self._breakpoints = breakpoints  # (pieces + 1, joints)
        #: The plan's own peak ``|j|`` per joint (exact): the ramp is never held to less.
        self.peak_jerk = plan.peak_jerk()
        #: Whether the ranges are exact (degree <= 3) and :meth:`ranges` serves; else
        #: :meth:`joint_ranges` bounds them (Bernstein).
        self.cubic = plan.degree <= 3
        self._starts = breakpoints[:-1].T.tolist()  # (joints, pieces)
        if not self.cubic:
            ends = breakpoints[1:].T.tolist()
            rows = plan.coefficients.transpose(2, 0, 1).tolist()  # (joints, pieces, n + 1)
            self._general = [list(zip(starts, piece_ends, joint_rows, strict=True))
                             for starts, piece_ends, joint_rows
                             in zip(self._starts, ends, rows, strict=True)]
            return
        pieces = plan.piece_count
        table = np.zeros((pieces, 4, joints))
        table[:, :plan.degree + 1] = plan.coefficients
        self._table = table.transpose(0, 2, 1).copy()  # (pieces, joints, 4)
        c1, c2, c3 = self._table[..., 1], self._table[..., 2], self._table[..., 3]
        self._jerk = 6.0 * c3  # (pieces, joints)
        lengths = breakpoints[1:] - breakpoints[:-1]
        with np.errstate(divide='ignore', invalid='ignore'):
            root = np.where(c3 != 0.0, -c2 / (3.0 * np.where(c3 != 0.0, c3, 1.0)), -1.0)
        inside = (root > 0.0) & (root < lengths)
        root = np.where(inside, root, 0.0)
        # Where v may have an extremum inside an interval: interior breakpoints, a = 0.
        self._points = np.concatenate(
            [breakpoints[1:-1], np.where(inside, breakpoints[:-1] + root, math.inf)])
        self._point_v = np.concatenate(
            [c1[1:], c1 + root * (2.0 * c2 + 3.0 * c3 * root)])
        self._point_a = np.concatenate([2.0 * c2[1:], np.zeros_like(c1)])
        # The same pieces as Python floats, per joint, for one interval at a time.
        columns = (breakpoints[:-1].T, breakpoints[1:].T, c1.T, c2.T, c3.T)  # (joints, pieces)
        self._pieces = [list(zip(*(column[j].tolist() for column in columns), strict=True))
                        for j in range(joints)]

    def state(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return the plan's own ``(v, a, j)`` at ``tau`` (s, clipped to the plan)."""
        if self.cubic:
            v, a, j = self._evaluate(np.array([min(max(float(tau), 0.0), self.duration)]))
            return v[0], a[0], j[0]
        _, velocity, acceleration = state_at(self.plan, tau)
        return velocity, acceleration, jerk_at(self.plan, tau)

    def _evaluate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(v, a, j)`` at ``times`` ``(m,)`` within the plan, each ``(m, joints)``."""
        piece = np.count_nonzero(self._breakpoints[None, 1:-1] <= times[:, None, None], axis=1)
        local = times[:, None] - self._breakpoints[piece, self.joints]
        rows = self._table[piece, self.joints]  # (m, joints, 4)
        c1, c2, c3 = rows[..., 1], rows[..., 2], rows[..., 3]
        return c1 + local * (2.0 * c2 + 3.0 * c3 * local), 2.0 * c2 + 6.0 * c3 * local, \
            6.0 * c3

    def ranges(self, start: np.ndarray, end: np.ndarray) -> list[np.ndarray]:
        """
        Return ``[v_min, v_max, a_min, a_max, j_min, j_max]`` over ``[start, end]`` (s).

        Each ``(m, joints)`` for intervals ``start <= end`` ``(m,)``; exact (cubic
        pieces). Past the plan's end nothing moves: 0 is in every range there.
        """
        low = np.clip(start, 0.0, self.duration)
        high = np.clip(end, 0.0, self.duration)
        v0, a0, j0 = self._evaluate(low)
        v1, a1, j1 = self._evaluate(high)
        inside = (self._points[None] > low[:, None, None]) & \
            (self._points[None] < high[:, None, None])
        overlap = (self._breakpoints[None, :-1] < high[:, None, None]) & \
            (self._breakpoints[None, 1:] > low[:, None, None])
        result = []
        for ends, points, mask in ((v0, v1), self._point_v, inside), \
                ((a0, a1), self._point_a, inside), ((j0, j1), self._jerk, overlap):
            result.append(np.minimum(np.minimum(*ends),
                                     np.where(mask, points[None], math.inf).min(axis=1)))
            result.append(np.maximum(np.maximum(*ends),
                                     np.where(mask, points[None], -math.inf).max(axis=1)))
        past = (end > self.duration)[:, None]
        if past.any():
            result = [np.where(past, np.minimum(r, 0.0) if k % 2 == 0 else np.maximum(r, 0.0),
                               r) for k, r in enumerate(result)]
        return result

    def joint_ranges(self, start: float, end: float) -> list[tuple[float, ...]]:
        """
        Return per joint ``(v_min, v_max, a_min, a_max, j_min, j_max)`` over ``[start, end]``.

        As :meth:`ranges` for one interval (s, ``start <= end``), in plain floats: the
        pieces it overlaps (bisection), their ends, the breakpoints and the roots of ``a``
        inside. Past the plan's end nothing moves: 0 is in every range there.
        """
        low = min(max(start, 0.0), self.duration)
        high = min(max(end, 0.0), self.duration)
        past = end > self.duration
        if not self.cubic:
            return self._bounded_ranges(low, high, past)
        result = []
        for starts, pieces in zip(self._starts, self._pieces, strict=True):
            first = max(bisect_right(starts, low) - 1, 0)
            last = max(bisect_left(starts, high) - 1, first)
            v_lo = a_lo = j_lo = math.inf
            v_hi = a_hi = j_hi = -math.inf
            for piece_start, piece_end, c1, c2, c3 in pieces[first:last + 1]:
                u0 = max(low, piece_start) - piece_start
                u1 = min(high, piece_end) - piece_start
                v0, v1 = c1 + u0 * (2.0 * c2 + 3.0 * c3 * u0), c1 + u1 * (2.0 * c2 + 3.0 * c3 * u1)
                a0, a1 = 2.0 * c2 + 6.0 * c3 * u0, 2.0 * c2 + 6.0 * c3 * u1
                v_lo, v_hi = min(v_lo, v0, v1), max(v_hi, v0, v1)
                a_lo, a_hi = min(a_lo, a0, a1), max(a_hi, a0, a1)
                j_lo, j_hi = min(j_lo, 6.0 * c3), max(j_hi, 6.0 * c3)
                if c3 != 0.0:
                    root = -c2 / (3.0 * c3)  # a = 0: v's extremum
                    if u0 < root < u1:
                        peak = c1 + root * (2.0 * c2 + 3.0 * c3 * root)
                        v_lo, v_hi = min(v_lo, peak), max(v_hi, peak)
            if past:
                v_lo, a_lo, j_lo = min(v_lo, 0.0), min(a_lo, 0.0), min(j_lo, 0.0)
                v_hi, a_hi, j_hi = max(v_hi, 0.0), max(a_hi, 0.0), max(j_hi, 0.0)
            result.append((v_lo, v_hi, a_lo, a_hi, j_lo, j_hi))
        return result

    def _bounded_ranges(self, low: float, high: float, past: bool
                        ) -> list[tuple[float, ...]]:
        """:meth:`joint_ranges` for pieces of any degree: Bernstein bounds of each part."""
        result = []
        for starts, pieces in zip(self._starts, self._general, strict=True):
            first = max(bisect_right(starts, low) - 1, 0)
            last = max(bisect_left(starts, high) - 1, first)
            bounds = [math.inf, -math.inf] * 3 if not past else [0.0, 0.0] * 3
            for piece_start, piece_end, position in pieces[first:last + 1]:
                u0 = max(low, piece_start) - piece_start
                width = min(high, piece_end) - piece_start - u0
                series = position
                for order in range(3):  # v, a, j
                    series = [k * c for k, c in enumerate(series)][1:] or [0.0]
                    lo, hi = bernstein_range(series, u0, width)
                    bounds[2 * order] = min(bounds[2 * order], lo)
                    bounds[2 * order + 1] = max(bounds[2 * order + 1], hi)
            result.append(tuple(bounds))
        return result


def bernstein_range(coefficients: list[float], start: float, width: float
                    ) -> tuple[float, float]:
    """
    Bound ``p(u)`` for ``u`` in ``[start, start + width]``: the Bernstein coefficients' range.

    ``p(start + width s) = Σ d_j s^j`` with ``d_j = Σ_k c_k C(k, j) start^(k-j) width^j``
    (ascending ``coefficients`` ``c_k``); on ``[0, 1]`` it is a convex combination of
    ``b_i = Σ_{j<=i} C(i, j) / C(n, j) d_j``, so ``min b <= p <= max b`` (the ends ``b_0``,
    ``b_n`` are ``p``'s own values there).
    """
    n = len(coefficients) - 1
    shifted = [sum(coefficients[k] * math.comb(k, j) * start ** (k - j) for k in range(j, n + 1))
               * width ** j for j in range(n + 1)]
    values = [sum(math.comb(i, j) / math.comb(n, j) * shifted[j] for j in range(i + 1))
              for i in range(n + 1)]
    return min(values), max(values)
