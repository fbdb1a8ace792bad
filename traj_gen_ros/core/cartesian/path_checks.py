"""
The checks of a joint path before it is given: joint limits, rates, and where a run ended.

- **Joint limits** and **rates** exactly on the quintic pieces of ``q(s)``: a joint's
  extremes from :meth:`~traj_gen_ros.core.trajectory.Trajectory.position_extrema`, its
  peak ``|dq/ds|`` from :meth:`~traj_gen_ros.core.trajectory.Trajectory.peaks_above`; where
  one is beyond its bound, the first ``s`` where it crosses is a root of the piece's
  polynomial minus the bound (:func:`~traj_gen_ros.core.exact.unit_roots.
  roots_in_unit_interval`), not a sampled guess.
- **Where a run ended** (the corrector found no point however short the step, or the
  rates, above :data:`~.continuation.RATE_LIMIT`, rose on to :data:`BEYOND_RATE` instead of
  falling back below it, as they do near a singularity that the path passes by): the
  inverse kinematics, with
  restarts, at :data:`PROBE` beyond the last point says which: no solution within the
  limits, the path is out of reach; a solution that is farther from the last point than
  the rate limit allows over that distance, the path beyond is reachable only with a
  jump, a configuration flip; else the singularity itself.
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.cartesian.continuation import Continuation, Point, RATE_LIMIT, Run
from traj_gen_ros.core.cartesian.path_refusal import (
    flip_refusal,
    limit_refusal,
    PathRefusal,
    reach_refusal,
    singular_refusal,
)
from traj_gen_ros.core.exact.piece_extrema import derivative
from traj_gen_ros.core.exact.unit_roots import roots_in_unit_interval
from traj_gen_ros.core.kinematics.inverse import UnreachablePoseError
from traj_gen_ros.core.trajectory import Trajectory

#: How far beyond the end of a run the inverse kinematics looks (units of path).
PROBE = 1e-3
#: Grid points a run may spend beyond a rate above the limit, to see where it leads, and
#: the rate (per unit of path) at which it counts as ended there: near a fold of the
#: inverse kinematics ``|q'| ~ k / sqrt(s* − s)``, so ``s*`` is then within ``(k/rate)²``.
BEYOND_BUDGET, BEYOND_RATE = 300, 1e4
#: A joint counts as beyond its limit or rate bound by more than this (rad, or per unit).
SLACK = 1e-12


def first_crossing(trajectory: Trajectory, order: int, joint: int, bound: float,
                   rising: bool) -> float | None:
    """
    Return the first ``s`` where ``joint``'s ``order``-th derivative crosses ``bound``.

    Upward (``rising``) or downward; None if it does not. A root of ``c(τ) − bound`` on
    each piece in unit time ``τ = (s − s_k) / h_k`` whose slope has the crossing's sign.
    """
    coefficients = trajectory.coefficients[:, :, joint:joint + 1]
    for _ in range(order):
        coefficients = derivative(coefficients)
    lengths = np.diff(trajectory.breakpoints)
    rows = coefficients[:, :, 0] * lengths[:, None] ** np.arange(coefficients.shape[1])
    rows[:, 0] -= bound
    roots, owners = roots_in_unit_interval(rows)
    powers = np.arange(1, rows.shape[1])
    slopes = np.array([float(rows[k, 1:] @ (powers * root ** (powers - 1)))
                       for root, k in zip(roots, owners, strict=True)])
    keep = slopes > 0.0 if rising else slopes < 0.0
    if not keep.any():
        return None
    return float((trajectory.breakpoints[owners] + roots * lengths[owners])[keep].min())


def limit_crossing(trajectory: Trajectory, lower: np.ndarray,
                   upper: np.ndarray) -> tuple[float, int, str, float] | None:
    """Return the first ``(s, joint, side, bound)`` where a joint leaves its limits, or None."""
    extrema = trajectory.position_extrema()
    found = []
    for joint in np.flatnonzero(extrema.maximum > upper + SLACK):
        s = first_crossing(trajectory, 0, int(joint), float(upper[joint]), True)
        found += [] if s is None else [(s, int(joint), 'upper', float(upper[joint]))]
    for joint in np.flatnonzero(extrema.minimum < lower - SLACK):
        s = first_crossing(trajectory, 0, int(joint), float(lower[joint]), False)
        found += [] if s is None else [(s, int(joint), 'lower', float(lower[joint]))]
    return min(found) if found else None


def rate_crossing(trajectory: Trajectory, limit: float) -> tuple[float, int] | None:
    """Return the first ``(s, joint)`` where a joint's ``|dq/ds|`` rises above ``limit``."""
    peaks = trajectory.peaks_above([np.full(trajectory.joint_count, limit)])[0]
    start = np.abs(trajectory.coefficients[0, 1])
    if (start > limit).any():
        return 0.0, int(np.argmax(start))
    found = []
    for joint in np.flatnonzero(peaks > limit + SLACK):
        for bound, rising in ((limit, True), (-limit, False)):
            s = first_crossing(trajectory, 1, int(joint), bound, rising)
            found += [] if s is None else [(s, int(joint))]
    return min(found) if found else None


class PathChecks:
    """The refusals of one run of :class:`~.continuation.Continuation` along a path."""

    def __init__(self, continuation: Continuation, lower: np.ndarray,
                 upper: np.ndarray) -> None:
        """Keep the continuation (its chain and path) and the joint limits."""
        self.continuation, self.lower, self.upper = continuation, lower, upper
        chain = continuation.chain
        self.names, self.angular = chain.joints, chain.angular
        self.length = float(continuation.path.length)

    def refusal(self, run: Run, trajectory: Trajectory | None) -> PathRefusal | None:
        """Return why the path of ``run`` (its pieces ``trajectory``) is refused, or None."""
        limit = rate = None
        if trajectory is not None:
            limit = limit_crossing(trajectory, self.lower, self.upper)
            rate = rate_crossing(trajectory, RATE_LIMIT)
        if limit is not None and (rate is None or limit[0] <= rate[0]):
            s, joint, side, bound = limit
            return limit_refusal(self.names, self.angular, joint, side, bound, s,
                                 self.length, trajectory.sample(s)[0][0])
        if run.stop == 'rate':
            beyond = self.continuation.run(run.last, BEYOND_RATE, False, BEYOND_BUDGET,
                                           RATE_LIMIT)
            if beyond.stop in ('end', 'rate'):
                return self._ended(beyond.last, trajectory, rate)
        if rate is not None:
            return self._singular(trajectory, *rate)
        if run.stop in ('end', 'rate'):  # ('rate': above the limit only at the slack)
            return self._ended(run.last, trajectory, None)
        if run.stop == 'limit':  # a grid point beyond a limit by less than the slack
            point = run.last
            joint = int(np.argmax(np.maximum(self.lower - point.q, point.q - self.upper)))
            side = 'lower' if point.q[joint] < self.lower[joint] else 'upper'
            bound = float(self.lower[joint] if side == 'lower' else self.upper[joint])
            return limit_refusal(self.names, self.angular, joint, side, bound, point.s,
                                 self.length, point.q)
        return None

    def unbounded_start(self, q: np.ndarray) -> PathRefusal:
        """Refuse a path whose start is singular with ``x'`` out of the Jacobian's range."""
        _, sigma, vt = np.linalg.svd(self.continuation.chain.jacobian(q))
        joint = int(np.argmax(np.abs(vt[sigma.size - 1])))  # the direction J cannot move
        return singular_refusal(self.names, self.angular, joint, math.inf, float(sigma[-1]),
                                RATE_LIMIT, 0.0, self.length, q)

    def _singular(self, trajectory: Trajectory, s: float, joint: int) -> PathRefusal:
        q, rates, _ = trajectory.sample(s)
        smallest = float(np.linalg.svd(self.continuation.chain.jacobian(q[0]),
                                       compute_uv=False)[-1])
        return singular_refusal(self.names, self.angular, joint, abs(float(rates[0, joint])),
                                smallest, RATE_LIMIT, s, self.length, q[0])

    def _ended(self, point: Point, trajectory: Trajectory | None,
               rate: tuple[float, int] | None) -> PathRefusal:
        """Say why the continuation ends at ``point``: out of reach, a flip, or singular."""
        chain, path = self.continuation.chain, self.continuation.path
        probe = min(self.length, point.s + PROBE)
        beyond = probe - point.s
        try:
            solution = chain.inverse(path.sample(probe).poses()[0], point.q,
                                     self.lower, self.upper)
        except UnreachablePoseError as error:
            stopped = ''
            if error.limited:
                stopped = ' (the joint limits of ' + ', '.join(
                    repr(name) for name in error.limited) + ' stop it)'
            return reach_refusal(error.position_error, error.orientation_error, point.s,
                                 self.length, beyond, stopped, point.q)
        jumps = solution.q - point.q
        if float(np.abs(jumps).max()) > RATE_LIMIT * beyond:
            return flip_refusal(self.names, self.angular, jumps, point.s, self.length, beyond,
                                point.q)
        if rate is not None and trajectory is not None:
            return self._singular(trajectory, *rate)
        joint = int(np.argmax(np.abs(point.rate)))
        fastest = abs(float(point.rate[joint]))  # the corrector cannot go on: unbounded
        return singular_refusal(self.names, self.angular, joint,
                                fastest if fastest > RATE_LIMIT else math.inf,
                                point.smallest, RATE_LIMIT, point.s, self.length, point.q)
