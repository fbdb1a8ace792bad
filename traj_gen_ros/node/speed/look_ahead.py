"""
The speed override's look-ahead under a jerk limit: a plan's exact ranges, the brake check.

Exact bounds of a plan over plan-time intervals, and the check that a ramp step can
always be followed by a brake of ``ḟ``.

The ramp (:class:`traj_gen_ros.node.speed.time_map.TimeMap`) commands, from a plan's own
``v(τ)``, ``a(τ)``, ``j(τ)`` at ``dτ/dt = f``, the acceleration ``f² a + ḟ v`` and jerk
``f³ j + 3 f ḟ a + f̈ v``. A state with ``ḟ = 0`` held (``f̈ = 0``) is safe forever:
``|f² a| <= |a|``, ``|f³ j| <= |j|`` (``0 <= f <= 1``). So a step ``f̈ = c`` is taken only
if, after it, the *brake* ``f̈ = -sign(ḟ) min(K, |ḟ|/h)`` (``h`` the step) brings ``ḟ`` to
0 with every joint within ``max_acceleration`` and ``max_jerk`` all along, ``f`` within
``[0, 1]`` (:func:`first_feasible`). That brake is then a verified continuation: if no new
step passes the next time, the ramp follows it (its tail is the same brake), so the limits
hold at every instant by induction, however the factor asked for changes and whatever
the plan's own jerk phases do ahead (they are looked at up to where ``ḟ`` is 0 again).

The check is exact interval arithmetic, never sampling: on each chunk of the brake
``f``, ``ḟ``, ``f̈`` are monotone or constant (their ranges are their ends), ``τ`` is
increasing, and :class:`~traj_gen_ros.node.speed.plan_window.PlanWindow` gives the range of
the plan's ``v``, ``a``, ``j`` over a ``τ`` interval (exact for cubic pieces, Bernstein
bounds for higher degrees). Products of ranges bound the commanded terms from above:
sufficient, somewhat conservative over a long chunk.

Cost (the stream thread runs it, 1 ms steps while a ramp runs): the whole step and
brake is first bounded as one range, in plain floats (:func:`envelope`,
:func:`keeps_limits`, about 30 µs); only if that fails is one candidate checked chunk
by chunk, in arrays (:func:`_rows`, :func:`_within`). A candidate the one range passes
passes every chunk (``test/node/speed/test_look_ahead.py``), so the cheap answer is never wrong.

No ROS here. Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
import math

import numpy as np
from traj_gen_ros.node.speed.plan_window import PlanWindow
from traj_gen_ros.node.speed.ramp_bounds import jerk_bounds, rate_bounds

#: Chunks the brake after a step is bounded on (its steps grouped evenly).
CHUNKS = 24
#: The brakes tried under a jerk limit, as fractions of the strongest (:func:`ramp_candidates`).
CANDIDATES = 4.0 ** -np.arange(6)
#: Relative slack of the check on the limits (rounding only).
SLACK = 1e-9
#: A brake longer than this many steps is not taken (the check would be too coarse).
LONGEST_BRAKE = 100_000


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
    a, b, c, d = xl * yl, xl * yh, xh * yl, xh * yh
    return np.minimum(np.minimum(a, b), np.minimum(c, d)), \
        np.maximum(np.maximum(a, b), np.maximum(c, d))


def _rows(tau: float, factor: float, rate: float, c: np.ndarray, k: np.ndarray, h: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the ranges on each chunk of the step and brake, and which candidates have one.

    ``(q, chunks, 8)``: ``f``, ``ḟ``, ``f̈`` and ``τ`` as (low, high) pairs, columns
    ``f_lo, f_hi, ḟ_lo, ḟ_hi, f̈_lo, f̈_hi, τ_a, τ_b`` (lows even, highs odd). Chunk 0 is
    the step at ``f̈ = c``, then :data:`CHUNKS` chunks of whole steps at ``-sign(ḟ) K``,
    then the one step to rest. On each, ``f̈`` is constant, ``ḟ`` linear, ``f`` quadratic
    (monotone, but for the step where ``ḟ`` turns: its vertex), ``τ`` increasing.
    """
    r1 = rate + c * h
    f1 = factor + rate * h + c * h * h / 2.0
    t1 = tau + factor * h + rate * h * h / 2.0 + c * h ** 3 / 6.0
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        vertex = np.where(rate * r1 < 0.0, factor - rate * rate / (2.0 * c), f1)
        whole = np.floor(np.abs(r1) / (k * h))
    good = (r1 == 0.0) | (np.isfinite(whole) & (whole <= LONGEST_BRAKE) & (k > 0.0))
    whole = np.where(good, whole, 0.0)
    times = np.round(np.linspace(0.0, 1.0, CHUNKS + 1)[None, :] * whole[:, None]) * h
    ks = (np.sign(r1) * k)[:, None]
    fs = f1[:, None] + r1[:, None] * times - ks * times ** 2 / 2.0
    rs = r1[:, None] - ks * times
    ts = t1[:, None] + f1[:, None] * times + r1[:, None] * times ** 2 / 2.0 - \
        ks * times ** 3 / 6.0
    fm, rm, tm = fs[:, -1], rs[:, -1], ts[:, -1]
    fe, te = fm + rm * h / 2.0, tm + fm * h + rm * h * h / 3.0
    rows = np.empty((c.size, CHUNKS + 2, 8))
    rows[:, 0] = np.stack([np.minimum(np.minimum(factor, f1), vertex),
                           np.maximum(np.maximum(factor, f1), vertex),
                           np.minimum(rate, r1), np.maximum(rate, r1), c, c,
                           np.full_like(c, tau), t1], axis=1)
    chunk = rows[:, 1:-1]
    chunk[..., 0], chunk[..., 1] = np.minimum(fs[:, :-1], fs[:, 1:]), \
        np.maximum(fs[:, :-1], fs[:, 1:])
    chunk[..., 2], chunk[..., 3] = np.minimum(rs[:, :-1], rs[:, 1:]), \
        np.maximum(rs[:, :-1], rs[:, 1:])
    chunk[..., 4] = chunk[..., 5] = -ks
    chunk[..., 6], chunk[..., 7] = ts[:, :-1], ts[:, 1:]
    rows[:, -1] = np.stack([np.minimum(fm, fe), np.maximum(fm, fe), np.minimum(rm, 0.0),
                            np.maximum(rm, 0.0), -rm / h, -rm / h, tm, te], axis=1)
    return rows, good


def _within(window: PlanWindow, rows: np.ndarray, max_acceleration: np.ndarray,
            max_jerk: np.ndarray) -> np.ndarray:
    """
    Tell, per row of ranges ``(m, 8)`` (as :func:`_rows`), whether it provably keeps the limits.

    Bounds ``|f² a + ḟ v|`` and ``|f³ j + 3 f ḟ a + f̈ v|`` from above by products of
    ranges, with ``v, a, j`` the plan's exact ranges over ``[τ_a, τ_b]``; and ``f`` within
    ``[0, 1]``. ``(m,)`` booleans.
    """
    fl, fh, rl, rh, cl, ch, ta, tb = (rows[:, i, None] for i in range(8))
    vl, vh, al, ah, jl, jh = window.ranges(ta[:, 0], np.maximum(ta, tb)[:, 0])
    f0 = np.maximum(fl, 0.0)
    lo1, hi1 = _product(f0 * f0, fh * fh, al, ah)
    lo2, hi2 = _product(rl, rh, vl, vh)
    acceleration = np.maximum(np.abs(lo1 + lo2), np.abs(hi1 + hi2))
    frl, frh = _product(f0, fh, rl, rh)
    lo3, hi3 = _product(f0 ** 3, fh ** 3, jl, jh)
    lo4, hi4 = _product(3.0 * frl, 3.0 * frh, al, ah)
    lo5, hi5 = _product(cl, ch, vl, vh)
    jerk = np.maximum(np.abs(lo3 + lo4 + lo5), np.abs(hi3 + hi4 + hi5))
    return (np.all(acceleration <= max_acceleration * (1.0 + SLACK), axis=1)
            & np.all(jerk <= max_jerk * (1.0 + SLACK), axis=1)
            & (fl[:, 0] >= -SLACK) & (fh[:, 0] <= 1.0 + SLACK))


def _span(xl: float, xh: float, yl: float, yh: float) -> tuple[float, float]:
    """Return the range of ``x y`` for ``x`` in ``[xl, xh]`` and ``y`` in ``[yl, yh]``."""
    a, b, c, d = xl * yl, xl * yh, xh * yl, xh * yh
    return min(a, b, c, d), max(a, b, c, d)


def envelope(tau: float, factor: float, rate: float, c: float, k: float, h: float
             ) -> tuple[float, ...] | None:
    """
    Return the ranges of ``f``, ``ḟ``, ``f̈`` and ``τ`` over a whole step and brake.

    As one row of :func:`_rows` spanning all of its chunks, in closed form: the step
    (``f`` quadratic, its vertex where ``ḟ`` turns), then the brake, over which ``ḟ``
    keeps its sign and goes to 0 (so ``f`` is monotone). None if the brake is too long
    or has no strength.
    """
    r1 = rate + c * h
    f1 = factor + rate * h + c * h * h / 2.0
    t1 = tau + factor * h + rate * h * h / 2.0 + c * h ** 3 / 6.0
    f_lo, f_hi = min(factor, f1), max(factor, f1)
    if rate * r1 < 0.0:
        vertex = factor - rate * rate / (2.0 * c)
        f_lo, f_hi = min(f_lo, vertex), max(f_hi, vertex)
    c_lo = c_hi = c
    fm, rm, tm = f1, r1, t1
    if r1 != 0.0:
        if not k > 0.0:
            return None
        whole = math.floor(abs(r1) / (k * h))
        if whole > LONGEST_BRAKE:
            return None
        if whole:
            kick, span = math.copysign(k, r1), whole * h
            fm = f1 + r1 * span - kick * span * span / 2.0
            rm = r1 - kick * span
            tm = t1 + f1 * span + r1 * span * span / 2.0 - kick * span ** 3 / 6.0
            c_lo, c_hi = min(c_lo, -kick), max(c_hi, -kick)
        c_lo, c_hi = min(c_lo, -rm / h), max(c_hi, -rm / h)
    fe, te = fm + rm * h / 2.0, tm + fm * h + rm * h * h / 3.0
    return (min(f_lo, fe), max(f_hi, fe), min(rate, r1, 0.0), max(rate, r1, 0.0),
            c_lo, c_hi, tau, te)


def keeps_limits(window: PlanWindow, row: tuple[float, ...], max_acceleration: list[float],
                 max_jerk: list[float]) -> bool:
    """
    Tell whether one row of ranges (as :func:`envelope`) provably keeps the limits.

    :func:`_within` for one row, in plain floats: stops at the first joint that fails.
    """
    fl, fh, rl, rh, cl, ch, ta, tb = row
    if fl < -SLACK or fh > 1.0 + SLACK:
        return False
    f0 = max(fl, 0.0)
    f2 = (f0 * f0, fh * fh)
    f3 = (f0 ** 3, fh ** 3)
    frl, frh = _span(f0, fh, rl, rh)
    for (vl, vh, al, ah, jl, jh), a_max, j_max in zip(
            window.joint_ranges(ta, max(ta, tb)), max_acceleration, max_jerk, strict=True):
        lo1, hi1 = _span(*f2, al, ah)
        lo2, hi2 = _span(rl, rh, vl, vh)
        if max(abs(lo1 + lo2), abs(hi1 + hi2)) > a_max * (1.0 + SLACK):
            return False
        lo3, hi3 = _span(*f3, jl, jh)
        lo4, hi4 = _span(3.0 * frl, 3.0 * frh, al, ah)
        lo5, hi5 = _span(cl, ch, vl, vh)
        if max(abs(lo3 + lo4 + lo5), abs(hi3 + hi4 + hi5)) > j_max * (1.0 + SLACK):
            return False
    return True


def first_feasible(window: PlanWindow, tau: float, factor: float, rate: float,
                   candidates: Iterable[tuple[float, float, bool]], step: float,
                   max_acceleration: np.ndarray, max_jerk: np.ndarray, chunked: bool = True
                   ) -> tuple[float, float] | None:
    """
    Return the first candidate ``(f̈, K)`` whose step then brake provably keep the limits.

    From ``(f, ḟ) = (factor, rate)`` at the plan's own time ``tau`` (s): one step of
    ``step`` s at ``f̈ = c`` (1/s²), then ``f̈ = -sign(ḟ) min(K, |ḟ|/h)`` until ``ḟ = 0``.
    Every joint's ``|f² a + ḟ v| <= max_acceleration`` and ``|f³ j + 3 f ḟ a + f̈ v| <=
    max_jerk`` over the whole of it, and ``0 <= f <= 1``. Candidates ``(c, K, _)`` in
    order of preference (an iterator: made only as far as asked); the first ``(c, K)``
    that provably does, or None.

    Each candidate is first bounded as one range over its whole step and brake (cheap;
    when it passes, so do all its chunks). The first that this does not pass is then
    checked chunk by chunk (:data:`CHUNKS`: finer, and dearer); at most one per call, so
    a call costs at most one chunked check (a later candidate it might have passed is
    not taken: the ramp is slower there, never outside the limits). ``chunked`` False:
    none at all.
    """
    accelerations, jerks = max_acceleration.tolist(), max_jerk.tolist()
    chunk_left = chunked  # the one chunked check of this call is still to be made
    for c, k, _ in candidates:
        row = envelope(tau, factor, rate, c, k, step)
        if row is None:
            continue
        if keeps_limits(window, row, accelerations, jerks):
            return c, k
        if chunk_left:
            chunk_left = False
            rows, good = _rows(tau, factor, rate, np.array([c]), np.array([k]), step)
            if good[0] and _within(window, rows[0], max_acceleration, max_jerk).all():
                return c, k
    return None


def ramp_candidates(f: float, rate: float, state: tuple[np.ndarray, np.ndarray, np.ndarray],
                    error: float, h: float, strongest: float, max_jerk: np.ndarray,
                    max_acceleration: np.ndarray) -> Iterator[tuple[float, float, bool]]:
    """
    Yield ``(f̈, K, True)`` in order of preference, made only as they are asked for.

    ``f``, ``rate`` (``ḟ``) are the ramp's at the step's start, ``state`` the plan's own
    velocity, acceleration and jerk there, ``error`` ``f* - f``, ``h`` the step (s),
    ``strongest`` ``K₀``. The landing first (``(f̈, K, False)``, a step and one more to
    rest at ``f*`` exactly), if its first instant keeps ``max_jerk``; then for
    ``K = K₀ 4⁻ⁱ`` (:data:`CANDIDATES`) the step toward the slope whose grid brake at
    ``K`` ends at ``f*`` (:func:`brake_rate`).
    """
    velocity, acceleration, jerk = state
    landing = (error - 1.5 * rate * h) / (h * h)
    reach = jerk_bounds(f, rate, velocity, acceleration, jerk, max_jerk, 1.0)
    if reach[0] <= landing <= reach[1]:  # else its first instant breaks max_jerk
        yield landing, max(abs(rate + landing * h) / h, strongest), False
    low, high = rate_bounds(f, velocity, acceleration, max_acceleration)
    c_low, c_high = jerk_bounds(f, rate, velocity, acceleration, jerk, max_jerk)
    for brake in (strongest * CANDIDATES).tolist():
        wanted = rate
        for _ in range(2):  # the error after the step, f moving at (ḟ + wanted) / 2
            left = error - h * (rate + wanted) / 2.0
            wanted = math.copysign(brake_rate(abs(left), brake, h), left)
        wanted = min(max(wanted, low), high)
        yield min(max((wanted - rate) / h, c_low, -brake), c_high, brake), brake, True
