"""
The joints of a path in time from its path parameter ``s(t)``: sampled into quintics.

The jerk-limited timing (:mod:`.jerk_limited_timing`) and brake (:mod:`.jerk_limited_brake`)
plan ``s(t)`` as cubic pieces (an S-curve, a brake); :func:`sample_motion` turns
``q(s(t))`` into the core's quintic :class:`~traj_gen_ros.core.trajectory.Trajectory`,
sampled at the phase boundaries of ``s(t)`` (``s⃛`` steps there), where it crosses a
breakpoint of the joint path (``q'''`` steps there) and at most :data:`SAMPLE_STEP`
apart, with ``q``, ``q̇ = q' ṡ`` and ``q̈ = q' s̈ + q'' ṡ²`` (the chain rule) at each
sample. :func:`used_limits` says what such a motion uses of every limit (the joints'
exactly), :func:`scaled` slows one down exactly.

Units: units of path, s; rad (or m), rad/s, rad/s², rad/s³.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.cartesian.bound_report import Bound, TOOL_KINDS
from traj_gen_ros.core.cartesian.path_constraints import joint_states
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.exact.unit_roots import roots_in_unit_interval
from traj_gen_ros.core.kinematic_limits import limit_ratios
from traj_gen_ros.core.polynomial import quintic_hermite
from traj_gen_ros.core.trajectory import Trajectory

#: The longest interval between two samples of the joints, s.
SAMPLE_STEP = 0.004
#: The shortest one: a quintic over a shorter interval would amplify the rounding of its
#: end positions into its jerk (``60 ε / Δt³``), s.
SHORTEST_STEP = 5e-4


def sample_motion(joint_path: JointPath, profile: Trajectory, low: float, high: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Trajectory]:
    """
    Sample ``q(s(t))`` into quintics: the times, ``s``, ``ṡ`` and the joint trajectory.

    ``profile`` is ``s(t)`` (one axis, cubic pieces from 0) within ``[low, high]``; the
    samples are its phase boundaries, the times it crosses a breakpoint of the joint
    path, and at most :data:`SAMPLE_STEP` apart (no two closer than
    :data:`SHORTEST_STEP`, but the first and the last).
    """
    breaks = profile.breakpoints
    crossings = _crossings(profile, joint_path.joints.breakpoints, low, high)
    times = _sample_times(breaks, crossings)
    steps = np.maximum(np.ceil(np.diff(times) / SAMPLE_STEP).astype(int), 1)
    times = np.concatenate([np.linspace(first, last, count + 1)[:-1] for first, last, count
                            in zip(times[:-1], times[1:], steps.tolist(), strict=True)]
                           + [times[-1:]])
    s, speed, acceleration = (state[:, 0] for state in profile.sample(times))
    s = np.clip(s, low, high)
    q, velocity, joint_acceleration = path_states(joint_path, s, speed, acceleration)
    trajectory = quintic_hermite(times, q, velocity, joint_acceleration[:-1],
                                 joint_acceleration[1:])
    return times, s, speed, trajectory


def _sample_times(boundaries: np.ndarray, crossings: np.ndarray) -> np.ndarray:
    """
    Merge the phase boundaries and the crossings, no two closer than :data:`SHORTEST_STEP`.

    The first and the last boundary are kept exactly, then the boundaries in order, then
    the crossings that are far enough from every time kept.
    """
    boundaries = np.unique(boundaries)
    kept = [boundaries[0]]
    for time in boundaries[1:-1].tolist():
        if time - kept[-1] >= SHORTEST_STEP and boundaries[-1] - time >= SHORTEST_STEP:
            kept.append(time)
    kept = np.array(kept + [boundaries[-1]])
    added: list[float] = []
    for time in np.sort(crossings).tolist():
        index = int(np.searchsorted(kept, time))
        after = kept[min(index, len(kept) - 1)]
        gap = min(abs(time - kept[max(index - 1, 0)]), abs(after - time))
        if gap >= SHORTEST_STEP and (not added or time - added[-1] >= SHORTEST_STEP):
            added.append(time)
    return np.union1d(kept, added)


def _crossings(profile: Trajectory, breaks: np.ndarray, low: float, high: float
               ) -> np.ndarray:
    """Return the times where ``s(t)`` passes a breakpoint strictly inside ``(low, high)``."""
    inside = breaks[(breaks > low) & (breaks < high)]
    if not inside.size:
        return np.zeros(0)
    lengths = np.diff(profile.breakpoints)
    unit = profile.coefficients[:, :, 0] * lengths[:, None] ** np.arange(4)
    reach = np.abs(unit[:, 1:]).sum(axis=1)  # |s - s_start| <= this on the piece
    rows, owners = [], []
    for piece in np.flatnonzero(lengths > 0.0).tolist():
        near = inside[np.abs(inside - unit[piece, 0]) <= reach[piece]]
        for value in near.tolist():
            row = unit[piece].copy()
            row[0] -= value
            rows.append(row)
            owners.append(piece)
    if not rows:
        return np.zeros(0)
    roots, which = roots_in_unit_interval(np.array(rows))
    pieces = np.array(owners)[which]
    return profile.breakpoints[pieces] + roots * lengths[pieces]


def scaled(trajectory: Trajectory, factor: float) -> Trajectory:
    """Return ``trajectory`` ``factor`` times slower: breakpoints ×k, ``c_n`` ÷ ``kⁿ``."""
    powers = float(factor) ** -np.arange(trajectory.coefficients.shape[1])
    return Trajectory(trajectory.breakpoints * factor,
                      trajectory.coefficients * powers[None, :, None])


def used_limits(path: IdealPath, profile: Trajectory, times: np.ndarray, s: np.ndarray,
                trajectory: Trajectory, limits: list[np.ndarray], tool: np.ndarray
                ) -> dict[Bound, float]:
    """
    Return what a sampled motion uses of every limit: peak / limit, by :class:`Bound`.

    The joints' from :func:`~traj_gen_ros.core.kinematic_limits.limit_ratios` (exact
    above 1, else a bound never below the peak), the tool's from :func:`tool_ratios`.
    """
    ratios = limit_ratios(trajectory, *limits)
    used = {Bound(kind, joint): float(value) for kind, row in
            zip(('velocity', 'acceleration', 'jerk'), ratios, strict=True)
            for joint, value in enumerate(row.tolist())}
    used.update(zip((Bound(kind) for kind in TOOL_KINDS),
                    tool_ratios(path, profile, times, s, tool).tolist(), strict=True))
    return used


def tool_ratios(path: IdealPath, profile: Trajectory, times: np.ndarray, s: np.ndarray,
                tool: np.ndarray) -> np.ndarray:
    """
    Return the tool's peak speed, acceleration and angular speed over their limits, ``(3,)``.

    At the samples and the middles between them (the S-curve's ``ṡ`` and ``s̈`` are
    extreme at its phase boundaries, which are samples): ``|p'| ṡ``, ``|p' s̈ + p'' ṡ²|``,
    ``|ω_s| ṡ``; 0 where a limit is ``inf``.
    """
    if not np.isfinite(tool).any():
        return np.zeros(3)
    middles = 0.5 * (times[1:] + times[:-1])
    at, speed, acceleration = (state[:, 0] for state in profile.sample(middles))
    at = np.concatenate([s, np.clip(at, s.min(), s.max())])
    speed = np.concatenate([profile.sample(times)[1][:, 0], speed])
    acceleration = np.concatenate([profile.sample(times)[2][:, 0], acceleration])
    samples = path.sample(at, 'right')
    rates = np.array([
        (np.linalg.norm(samples.velocity, axis=1) * np.abs(speed)).max(),
        np.linalg.norm(samples.velocity * acceleration[:, None]
                       + samples.acceleration * (speed ** 2)[:, None], axis=1).max(),
        (np.linalg.norm(samples.angular, axis=1) * np.abs(speed)).max()])
    return rates / tool


def path_states(joint_path: JointPath, s: np.ndarray, speed: np.ndarray,
                acceleration: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``q``, ``q' ṡ`` and ``q' s̈ + q'' ṡ²`` at ``s``, ``(len(s), joints)`` each."""
    q, dq, ddq = joint_states(joint_path.joints, s, 'right')
    return q, dq * speed[:, None], dq * acceleration[:, None] + ddq * (speed ** 2)[:, None]
