"""
The speed ramp's closed-form bounds at a step's start: the slope and curvature of ``f``.

A scaled plan commands ``f · v``, ``f² a + ḟ v`` and ``f³ j + 3 f ḟ a + f̈ v``
(:mod:`traj_gen_ros.node.speed.time_map`); for each joint that moves, a bound on the
commanded acceleration (jerk) is an interval of ``ḟ`` (``f̈``), and the ramp takes the
intersection over the joints. Each holds 0, so waiting is always possible. No ROS here.

Units: 1/s (``ḟ``), 1/s² (``f̈``); rad/s, rad/s², rad/s³.
"""

from __future__ import annotations

import math

import numpy as np

#: The fraction ``σ`` of ``max_acceleration`` / ``max_jerk`` a ramp may use.
MARGIN = 0.95


#: Below this speed (rad/s) a joint sets no bound on ``ḟ``.
RESTING = 1e-9


def _interval(base: np.ndarray, bound: np.ndarray, velocity: np.ndarray
              ) -> tuple[float, float]:
    """Return the ``x`` with ``|base + x v| <= bound`` for every moving joint (∩)."""
    moving = np.abs(velocity) > RESTING
    if not moving.any():
        return -math.inf, math.inf
    v = velocity[moving]
    low = (-bound[moving] - base[moving]) / v
    high = (bound[moving] - base[moving]) / v
    return float(np.max(np.minimum(low, high))), float(np.min(np.maximum(low, high)))


def rate_bounds(f: float, velocity: np.ndarray, acceleration: np.ndarray,
                max_acceleration: np.ndarray, margin: float = MARGIN) -> tuple[float, float]:
    """
    Return the interval of ``ḟ`` (1/s) keeping the commanded acceleration within its bound.

    Per moving joint ``|f² a + ḟ v| <= B`` with ``B = max(σ a_max, f² |a|)`` (never worse
    than the plan itself), i.e. ``ḟ`` between ``(±B - f² a) / v``; the intersection over
    the joints. It always holds 0 (``|f² a| <= B``).
    """
    base = f * f * acceleration
    bound = np.maximum(margin * max_acceleration, np.abs(base))
    low, high = _interval(base, bound, velocity)
    return min(low, 0.0), max(high, 0.0)


def jerk_bounds(f: float, rate: float, velocity: np.ndarray, acceleration: np.ndarray,
                jerk: np.ndarray, max_jerk: np.ndarray, margin: float = MARGIN
                ) -> tuple[float, float]:
    """
    Return the interval of ``f̈`` (1/s²) keeping the commanded jerk within its bound.

    Per moving joint ``|f³ j + 3 f ḟ a + f̈ v| <= B`` with ``B = max(σ j_max,
    |f³ j + 3 f ḟ a|)``: ``f̈`` between ``(±B - f³ j - 3 f ḟ a) / v``. It holds 0.
    """
    base = f ** 3 * jerk + 3.0 * f * rate * acceleration
    bound = np.maximum(margin * max_jerk, np.abs(base))
    low, high = _interval(base, bound, velocity)
    return min(low, 0.0), max(high, 0.0)
