"""
Jerk-limited braking: each joint to rest as fast as ``|a| ≤ a_max``, ``|j| ≤ j_max`` allow.

The third-order counterpart of :func:`traj_gen_ros.core.stops.brake` (the node's ``~/stop`` with
the S-curve profile), in closed form. Bringing the acceleration to zero at once would leave
the joint at ``v_zero = v0 + a0|a0|/(2 j_max)``; the velocity must change against the sign
``d`` of that. In the frame where that change is downwards (``v = d v0``, ``a = d a0``) the
acceleration ramps at ``-j_max`` from ``a`` to ``-P``, holds ``-P``, and ramps back to 0 at
``+j_max``, where ``P = sqrt(a²/2 + j_max v)`` (the velocity change of the two ramps equals
``-v``) when that is at most ``a_max``; otherwise ``P = a_max`` and the hold lasts
``(v + (a² - 2 a_max²)/(2 j_max)) / a_max``. This is the time-optimal stop (bang-bang in
jerk, Biagiotti & Melchiorri §3.4; Ruckig's velocity interface computes the same). A start
acceleration beyond ``a_max`` (limits lowered mid-motion) may keep its level while it
brakes. Joints stop independently and then hold; acceleration is continuous throughout.

Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.trajectory import JerkLimitedTrajectory
from traj_gen_ros.core.validation import ArrayLike


@validation.refuses_overflow('scurve_brake')
def scurve_brake(
    q0: ArrayLike,
    v0: ArrayLike,
    a0: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
) -> JerkLimitedTrajectory:
    """
    Stop every joint from ``(q0, v0, a0)`` with bounded jerk, then hold (closed form above).

    Returns four cubic pieces per joint (ramp, hold, ramp, rest) with per-joint breakpoints;
    the trajectory lasts until the last joint has stopped.
    """
    rows = validation.per_joint_rows(q0=q0, v0=v0, a0=a0, max_acceleration=max_acceleration,
                                     max_jerk=max_jerk)
    validation.require_positive(rows[3:], ('max_acceleration', 'max_jerk'))
    start, velocity, acceleration, limit, jerk = rows
    limit = np.maximum(limit, np.abs(acceleration))
    zero_velocity = velocity + acceleration * np.abs(acceleration) / (2.0 * jerk)
    direction = np.where(zero_velocity >= 0.0, 1.0, -1.0)
    v, a = direction * velocity, direction * acceleration
    peak = np.sqrt(np.maximum(0.5 * a * a + jerk * v, 0.0))
    capped = np.minimum(peak, limit)
    hold = np.where(peak > limit, (v + (a * a - 2.0 * capped**2) / (2.0 * jerk)) / limit, 0.0)
    lengths = np.stack([np.maximum(a + capped, 0.0) / jerk, np.maximum(hold, 0.0),
                        capped / jerk])
    jerks = direction * np.stack([-jerk, 0.0 * jerk, jerk])
    return _pieces(start, velocity, acceleration, lengths, jerks)


def _pieces(start: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray,
            lengths: np.ndarray, jerks: np.ndarray) -> JerkLimitedTrajectory:
    """Propagate the state through the three jerk phases; the fourth piece holds at rest."""
    joints = start.size
    coefficients = np.zeros((4, 4, joints))
    breakpoints = np.zeros((5, joints))
    position = start.copy()
    for phase in range(3):
        coefficients[phase] = position, velocity, 0.5 * acceleration, jerks[phase] / 6.0
        time = lengths[phase]
        cubic_term = time * jerks[phase] / 6.0
        position = position + time * (velocity + time * (0.5 * acceleration + cubic_term))
        velocity = velocity + time * (acceleration + 0.5 * time * jerks[phase])
        acceleration = acceleration + time * jerks[phase]
        breakpoints[phase + 1] = breakpoints[phase] + time
    coefficients[3, 0] = position
    breakpoints[4] = breakpoints[3].max()
    return JerkLimitedTrajectory(breakpoints, coefficients)
