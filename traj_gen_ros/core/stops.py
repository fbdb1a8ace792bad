"""
Braking to rest at the acceleration limit: the second-order stop of the node's ``~/stop``.

Each joint decelerates as the final blend of an LSPB does (Craig §7.3: a parabola at the
blend acceleration, here the limit), to rest at ``q0 + v0 |v0| / (2 a_max)``. The
jerk-limited counterpart is :func:`traj_gen_ros.core.jerk_limited.brake.scurve_brake`.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike


@validation.refuses_overflow('brake')
def brake(q0: ArrayLike, v0: ArrayLike, max_acceleration: ArrayLike) -> Trajectory:
    """
    Stop every joint as fast as its ``max_acceleration`` allows, then hold.

    Joint ``j`` decelerates at ``-sgn(v0) a_max`` for ``|v0|/a_max`` s (one parabolic blend
    to rest, as at the end of an LSPB) and stops at ``q0 + v0 |v0| / (2 a_max)``; the result
    lasts until the last joint has stopped. Position and velocity are continuous; the
    acceleration steps to the limit at once. Units: rad, rad/s, rad/s², s.
    """
    rows = validation.per_joint_rows(q0=q0, v0=v0)
    start, velocity = rows
    limit = validation.per_joint('max_acceleration', max_acceleration, rows.shape[1])
    stop_times = np.abs(velocity) / limit
    deceleration = -np.sign(velocity) * limit
    breakpoints = np.empty((3, start.size))
    breakpoints[0], breakpoints[1], breakpoints[2] = 0.0, stop_times, stop_times.max()
    coefficients = np.zeros((2, 3, start.size))
    coefficients[0, 0], coefficients[0, 1] = start, velocity
    coefficients[0, 2] = 0.5 * deceleration
    coefficients[1, 0] = start + 0.5 * velocity * stop_times
    return Trajectory(breakpoints, coefficients)
