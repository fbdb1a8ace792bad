"""
Acceleration-limited (second-order) moves from a moving start to rest, in closed form.

The LSPB of a moving joint: a blend at ``±a`` from ``v0`` to a cruise velocity ``vc``, a
linear part at ``vc``, a blend at ``±a`` to rest at the goal (Craig §7.3's single segment,
started from ``v0``). Everything here is per joint, vectorised over joints.

Minimum time (time-optimal bang-bang, as Ruckig's second-order Step 1): with
``D = qf - q0`` the profile first accelerates towards ``s = sgn(2aD - v0|v0|)`` (towards the
goal, unless the joint cannot stop before it and must brake through it and come back), to
the peak ``vp = sqrt(a s D + v0²/2)`` in that direction, then brakes to rest; a peak above
``v_max`` is cut by a cruise at ``v_max``. A start faster than ``v_max`` first brakes to
``v_max`` at ``a`` (Ruckig's brake pre-profile).

Fitting a duration ``T``: the displacement ``D(vc) = vc T - (vc - v0)|vc - v0|/(2a)
- vc|vc|/(2a)`` grows with ``vc`` on ``[(v0 - aT)/2, (v0 + aT)/2]`` and is a quadratic or
linear in ``vc`` between its breakpoints ``0`` and ``v0``, so ``vc`` is the root of that
piece. Every duration from the minimum on can be fitted (the reachable displacements
only widen with ``T``): a moving start makes no gap in the second-order case.

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.kinematic_limits import JointError


def brake_to_limit(
    start_velocity: np.ndarray, max_velocity: np.ndarray, acceleration: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Brake pre-phase of joints faster than ``max_velocity``: ``(time, displacement, velocity)``.

    Lasts ``(|v0| - v_max)/a`` s and leaves the joint at ``sgn(v0) v_max``; zero elsewhere.
    """
    excess = np.maximum(np.abs(start_velocity) - max_velocity, 0.0)
    time = excess / acceleration
    velocity = np.where(excess > 0.0, np.sign(start_velocity) * max_velocity, start_velocity)
    displacement = 0.5 * (start_velocity + velocity) * time
    return time, displacement, velocity


def minimum_times(
    displacement: np.ndarray,
    start_velocity: np.ndarray,
    max_velocity: np.ndarray,
    acceleration: np.ndarray,
) -> np.ndarray:
    """
    Return each joint's time-optimal duration (s) to rest ``displacement`` away, |v0| ≤ v_max.

    ``s = sgn(2aD - v0|v0|)``; ``vp = sqrt(a s D + v0²/2)``; without a cruise
    ``T = (2 vp - s v0)/a``; with one (``vp > v_max``)
    ``T = (2 v_max - s v0)/a + (s D - (2 v_max² - v0²)/(2a))/v_max``.
    """
    speed, twice = np.abs(start_velocity), 2.0 * acceleration
    direction = np.where(twice * displacement >= start_velocity * speed, 1.0, -1.0)
    towards = direction * start_velocity
    reach = direction * displacement
    squared = start_velocity**2
    peak = np.sqrt(np.maximum(acceleration * reach + 0.5 * squared, 0.0))
    cruising = peak > max_velocity
    times = (2.0 * np.minimum(peak, max_velocity) - towards) / acceleration
    if np.count_nonzero(cruising):
        cruise = (reach - (2.0 * max_velocity**2 - squared) / twice) / max_velocity
        times += np.where(cruising, np.maximum(cruise, 0.0), 0.0)
    # Never shorter than braking alone (|v0|/a): it holds even where v0² underflows.
    return np.maximum(times, speed / acceleration)


def displacement_at(
    cruise: np.ndarray, start_velocity: np.ndarray, duration: np.ndarray,
    acceleration: np.ndarray,
) -> np.ndarray:
    """Displacement of blend ``v0 → vc``, cruise at ``vc``, blend ``vc → 0`` in ``duration``."""
    change = cruise - start_velocity
    return (cruise * duration - change * np.abs(change) / (2.0 * acceleration)
            - cruise * np.abs(cruise) / (2.0 * acceleration))


def reachable(
    start_velocity: np.ndarray, duration: np.ndarray, acceleration: np.ndarray,
    max_velocity: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest displacement (rad) reachable in ``duration`` from ``v0``."""
    low = 0.5 * (start_velocity - acceleration * duration)
    high = 0.5 * (start_velocity + acceleration * duration)
    if max_velocity is not None:
        low, high = np.maximum(low, -max_velocity), np.minimum(high, max_velocity)
    return (displacement_at(low, start_velocity, duration, acceleration),
            displacement_at(high, start_velocity, duration, acceleration))


def cruise_velocity(
    displacement: np.ndarray, start_velocity: np.ndarray, duration: np.ndarray,
    acceleration: np.ndarray,
) -> np.ndarray:
    """
    Return the cruise velocity ``vc`` (rad/s) that moves ``displacement`` in ``duration``.

    Above the breakpoints (``vc ≥ max(0, v0)``): ``vc² - (aT + v0) vc + v0²/2 + aD = 0``,
    the smaller root, taken as ``2c / (b + sqrt(b² - 4c))``; below them, the mirror image;
    between them, the linear ``vc = (D - v0|v0|/(2a)) / (T - |v0|/a)``. The caller has
    checked that ``displacement`` is reachable.
    """
    upper = displacement_at(np.maximum(start_velocity, 0.0), start_velocity, duration,
                            acceleration)
    lower = displacement_at(np.minimum(start_velocity, 0.0), start_velocity, duration,
                            acceleration)
    sign = np.where(displacement >= upper, 1.0, -1.0)
    towards, reach = sign * start_velocity, sign * displacement
    b = acceleration * duration + towards
    c = 0.5 * towards**2 + acceleration * reach
    root = np.sqrt(np.maximum(b * b - 4.0 * c, 0.0))
    with np.errstate(divide='ignore', invalid='ignore'):
        outer = sign * np.where(b + root > 0.0, 2.0 * c / (b + root), 0.5 * b)
        between = (displacement - start_velocity * np.abs(start_velocity)
                   / (2.0 * acceleration)) / (duration - np.abs(start_velocity) / acceleration)
    inside = (displacement < upper) & (displacement > lower)
    return np.where(inside & np.isfinite(between), between, outer)


def check_reachable(
    displacement: np.ndarray, start_velocity: np.ndarray, duration: float,
    acceleration: np.ndarray, max_velocity: np.ndarray | None = None,
) -> None:
    """
    Raise :class:`JointError` for the first joint that cannot move ``displacement`` in time.

    The slack is ``1e-12`` of the displacement scale ``a T² + |v0| T`` of the move, so
    rounding passes and a real gap, however small the move, does not.
    """
    durations = np.full(displacement.shape, float(duration))
    scale = acceleration * durations**2 + np.abs(start_velocity) * durations
    low, high = reachable(start_velocity, durations, acceleration, max_velocity)
    slack = 1e-12 * scale
    fits = (np.abs(start_velocity) <= acceleration * durations * (1.0 + 1e-12)) & \
        (low - slack <= displacement) & (displacement <= high + slack)
    if np.count_nonzero(fits) == fits.size:
        return
    joint = int(np.argmin(fits))
    shortest = minimum_times(displacement[joint:joint + 1], start_velocity[joint:joint + 1],
                             np.full(1, np.inf) if max_velocity is None
                             else max_velocity[joint:joint + 1],
                             acceleration[joint:joint + 1])[0]
    raise JointError(
        f'lspb: {{joint}}: cannot move {displacement[joint]:g} in {duration:g} s from '
        f'velocity {start_velocity[joint]:g} with acceleration {acceleration[joint]:g}; '
        f'the shortest duration that works is {shortest:.9g} s', joint)
