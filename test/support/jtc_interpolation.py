"""Interpolate a JointTrajectory's points as joint_trajectory_controller does (Hermite)."""

import numpy as np


def hermite(times, positions, velocities, accelerations, at):
    """
    Evaluate JTC's spline through the points at times ``at`` (s): positions ``(at, joints)``.

    Quintic Hermite between consecutive points when accelerations are given, cubic Hermite
    with positions and velocities only (JTC's ``interpolate_between_points``).
    """
    at = np.asarray(at, dtype=float)
    segment = np.clip(np.searchsorted(times, at, side='right') - 1, 0, len(times) - 2)
    t0, t1 = times[segment], times[segment + 1]
    big_t = (t1 - t0)[:, None]
    tau = (at - t0)[:, None]
    p0, p1 = positions[segment], positions[segment + 1]
    v0, v1 = velocities[segment], velocities[segment + 1]
    if accelerations is None:
        c2 = (3 * (p1 - p0) - (2 * v0 + v1) * big_t) / big_t ** 2
        c3 = (2 * (p0 - p1) + (v0 + v1) * big_t) / big_t ** 3
        return p0 + v0 * tau + c2 * tau ** 2 + c3 * tau ** 3
    a0, a1 = accelerations[segment], accelerations[segment + 1]
    c3 = (20 * (p1 - p0) - (8 * v1 + 12 * v0) * big_t - (3 * a0 - a1) * big_t ** 2) \
        / (2 * big_t ** 3)
    c4 = (30 * (p0 - p1) + (14 * v1 + 16 * v0) * big_t + (3 * a0 - 2 * a1) * big_t ** 2) \
        / (2 * big_t ** 4)
    c5 = (12 * (p1 - p0) - 6 * (v1 + v0) * big_t - (a0 - a1) * big_t ** 2) / (2 * big_t ** 5)
    return p0 + v0 * tau + a0 / 2 * tau ** 2 + c3 * tau ** 3 + c4 * tau ** 4 + c5 * tau ** 5
