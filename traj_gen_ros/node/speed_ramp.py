"""
The speed override's look-ahead under a jerk limit: a plan's exact ranges, the brake check.

Exact bounds of a plan over plan-time intervals, and the check that a ramp step can
always be followed by a brake of ``ḟ``.

The ramp (:class:`traj_gen_ros.node.speed_scaling.TimeMap`) commands, from a plan's own
``v(τ)``, ``a(τ)``, ``j(τ)`` at ``dτ/dt = f``, the acceleration ``f² a + ḟ v`` and jerk
``f³ j + 3 f ḟ a + f̈ v``. A state with ``ḟ = 0`` held (``f̈ = 0``) is safe forever:
``|f² a| <= |a|``, ``|f³ j| <= |j|`` (``0 <= f <= 1``). So a step ``f̈ = c`` is taken only
if, after it, the *brake* ``f̈ = -sign(ḟ) min(K, |ḟ|/h)`` (``h`` the step) brings ``ḟ`` to
0 with every joint within ``max_acceleration`` and ``max_jerk`` all along, ``f`` within
``[0, 1]`` (:func:`feasible`). That brake is then a verified continuation: if no new step
passes the next time, the ramp follows it (its tail is the same brake), so the limits
hold at every instant by induction, however the factor asked for changes and whatever
the plan's own jerk phases do ahead (they are looked at up to where ``ḟ`` is 0 again).

The check is exact interval arithmetic, never sampling: on each chunk of the brake
``f``, ``ḟ``, ``f̈`` are monotone or constant (their ranges are their ends), ``τ`` is
increasing, and :class:`PlanWindow` gives the exact range of the plan's ``v``, ``a``,
``j`` over a ``τ`` interval (cubic pieces, as every ``scurve`` plan: ``j`` constant per
piece, ``a`` linear, ``v`` quadratic; extrema at the interval's ends, the breakpoints
inside and the roots of ``a``). Products of ranges bound the commanded terms from above:
sufficient, somewhat conservative over a long chunk.

No ROS here. Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.trajectory import state_at, Trajectory

#: Chunks the brake after a step is bounded on (its steps grouped evenly).
CHUNKS = 24
#: Relative slack of the check on the limits (rounding only).
SLACK = 1e-9
#: A brake longer than this many steps is not taken (the check would be too coarse).
LONGEST_BRAKE = 100_000


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
        #: Whether the ranges are exact (degree <= 3); else only :meth:`state` is.
        self.cubic = plan.degree <= 3
        if not self.cubic:
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

    def state(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return the plan's own ``(v, a, j)`` at ``tau`` (s, clipped to the plan)."""
        if self.cubic:
            v, a, j = self._evaluate(np.array([min(max(float(tau), 0.0), self.duration)]))
            return v[0], a[0], j[0]
        from traj_gen_ros.node.speed_scaling import jerk_at  # the general degree
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


def brake_rate(distance: float, brake: float, step: float) -> float:
    """
    Return the largest ``|ḟ|`` (1/s) the grid brake ``min(K, |ḟ|/h)`` stops within ``distance``.

    That brake covers ``K h² (m²/2 + φ (m + ½))`` from ``|ḟ| = (m + φ) K h`` (``m`` whole
    steps at ``K``, then one step to rest): ``x²/2`` interpolated linearly between integer
    ``x = |ḟ| / (K h)``; inverted here.
    """
    if distance <= 0.0:
        return 0.0
    units = distance / (brake * step * step)
    whole = math.floor(math.sqrt(2.0 * units))
    fraction = min(max((units - whole * whole / 2.0) / (whole + 0.5), 0.0), 1.0)
    return (whole + fraction) * brake * step


def _product(xl: np.ndarray, xh: np.ndarray, yl: np.ndarray, yh: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Return the range of ``x y`` for ``x`` in ``[xl, xh]`` and ``y`` in ``[yl, yh]``."""
    products = (xl * yl, xl * yh, xh * yl, xh * yh)
    return np.minimum.reduce(products), np.maximum.reduce(products)


def feasible(window: PlanWindow, tau: float, factor: float, rate: float,
             curvature: np.ndarray, brake: np.ndarray, step: float,
             max_acceleration: np.ndarray, max_jerk: np.ndarray) -> np.ndarray:
    """
    Tell, per candidate, whether the step ``f̈ = curvature`` then the brake ``K`` keep the limits.

    From ``(f, ḟ) = (factor, rate)`` at the plan's own time ``tau`` (s): one step of
    ``step`` s at ``f̈ = c`` (1/s²), then ``f̈ = -sign(ḟ) min(K, |ḟ|/h)`` until ``ḟ = 0``.
    Every joint's ``|f² a + ḟ v| <= max_acceleration`` and ``|f³ j + 3 f ḟ a + f̈ v| <=
    max_jerk`` over the whole of it (interval bounds on chunks) and ``0 <= f <= 1``.
    ``curvature`` and ``brake`` ``(q,)``; returns ``(q,)`` booleans.
    """
    h = step
    c = np.asarray(curvature, dtype=float)
    k = np.asarray(brake, dtype=float)
    # The step: f quadratic (its vertex where ḟ changes sign), ḟ linear.
    r1 = rate + c * h
    f1 = factor + rate * h + c * h * h / 2.0
    t1 = tau + factor * h + rate * h * h / 2.0 + c * h ** 3 / 6.0
    with np.errstate(divide='ignore', invalid='ignore'):
        vertex = factor - rate * rate / (2.0 * c)
    turns = (rate * r1 < 0.0)
    rows = [(np.minimum.reduce([np.full_like(c, factor), f1, np.where(turns, vertex, f1)]),
             np.maximum.reduce([np.full_like(c, factor), f1, np.where(turns, vertex, f1)]),
             np.minimum(rate, r1), np.maximum(rate, r1), c, c, np.full_like(c, tau), t1)]
    # The brake: whole steps at -sign(ḟ) K on CHUNKS chunks, then one step to rest.
    sign = np.sign(r1)
    with np.errstate(divide='ignore', invalid='ignore'):
        whole = np.floor(np.abs(r1) / (k * h))
    good = (r1 == 0.0) | (np.isfinite(whole) & (whole <= LONGEST_BRAKE) & (k > 0.0))
    whole = np.where(good, whole, 0.0)
    times = np.linspace(0.0, 1.0, CHUNKS + 1)[None, :] * (np.round(whole)[:, None] * h)
    times = np.round(times / h) * h  # on the grid
    ks = (sign * k)[:, None]
    fs = f1[:, None] + r1[:, None] * times - ks * times ** 2 / 2.0
    rs = r1[:, None] - ks * times
    ts = t1[:, None] + f1[:, None] * times + r1[:, None] * times ** 2 / 2.0 - \
        ks * times ** 3 / 6.0
    rows.append((np.minimum(fs[:, :-1], fs[:, 1:]), np.maximum(fs[:, :-1], fs[:, 1:]),
                 np.minimum(rs[:, :-1], rs[:, 1:]), np.maximum(rs[:, :-1], rs[:, 1:]),
                 np.broadcast_to(-ks, rs[:, 1:].shape), np.broadcast_to(-ks, rs[:, 1:].shape),
                 ts[:, :-1], ts[:, 1:]))
    fm, rm, tm = fs[:, -1], rs[:, -1], ts[:, -1]
    fe, te = fm + rm * h / 2.0, tm + fm * h + rm * h * h / 3.0
    rows.append((np.minimum(fm, fe), np.maximum(fm, fe), np.minimum(rm, 0.0),
                 np.maximum(rm, 0.0), -rm / h, -rm / h, tm, te))
    fl, fh, rl, rh, cl, ch, ta, tb = (np.concatenate([np.reshape(row[i], (c.size, -1))
                                                      for row in rows], axis=1).ravel()
                                      for i in range(8))
    vl, vh, al, ah, jl, jh = window.ranges(ta, np.maximum(ta, tb))
    fl, fh, rl, rh, cl, ch = (x[:, None] for x in (fl, fh, rl, rh, cl, ch))
    f0 = np.maximum(fl, 0.0)
    lo1, hi1 = _product(f0 * f0, fh * fh, al, ah)
    lo2, hi2 = _product(rl, rh, vl, vh)
    acceleration = np.maximum(np.abs(lo1 + lo2), np.abs(hi1 + hi2))
    frl, frh = _product(f0, fh, rl, rh)
    lo3, hi3 = _product(f0 ** 3, fh ** 3, jl, jh)
    lo4, hi4 = _product(3.0 * frl, 3.0 * frh, al, ah)
    lo5, hi5 = _product(cl, ch, vl, vh)
    jerk = np.maximum(np.abs(lo3 + lo4 + lo5), np.abs(hi3 + hi4 + hi5))
    ok = (np.all(acceleration <= max_acceleration * (1.0 + SLACK), axis=1)
          & np.all(jerk <= max_jerk * (1.0 + SLACK), axis=1)
          & (fl[:, 0] >= -SLACK) & (fh[:, 0] <= 1.0 + SLACK))
    return ok.reshape(c.size, -1).all(axis=1) & good
