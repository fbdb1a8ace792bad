"""
The continuation of the inverse kinematics along an ideal tool path, on an adaptive grid.

A predictor–corrector continuation of ``F(q) = x(s)`` (Allgower and Georg, *Introduction
to Numerical Continuation Methods*, ch. 2), one grid point ``s_i`` at a time, every knot
of the path among them:

- **Rates.** ``q' = J⁺ x'`` and ``q'' = d(J⁺x')/ds = J⁺ (x'' − J̇q') + N J̇ᵀ (J⁺)ᵀ q'``
  with ``x' = (p', ω_s)``, ``x'' = (p'', dω_s/ds)`` (the path's derivatives by ``s``),
  ``J̇`` :meth:`~traj_gen_ros.core.kinematics.chain.Chain.jacobian_rate` and ``N = I −
  J⁺J`` (the derivative of the pseudo-inverse, Golub and Pereyra, SIAM J. Numer. Anal.
  10(2), 1973, for a full row rank; ``N = 0`` without a null space). ``J⁺`` is the
  pseudo-inverse by
  the SVD with the singular values below :data:`RANK_TOLERANCE` of the largest dropped,
  so an exactly singular point whose ``x'`` is in the Jacobian's range (checked: the
  residual ``|J q' − x'|``) still has bounded rates; on a redundant arm it is the least
  joint motion (no part in the Jacobian's null space).
- **Predictor** ``q̃ = q_i + h q'_i + ½ h² q''_i``; **corrector**: Newton's method with the
  minimum-norm step ``Δq = J⁺ e``, ``e = (p* − p, log(R* Rᵀ))``, to :data:`CONVERGED`.
  Where ``J`` has a null space (a 7-joint arm) the point is also moved along it onto the
  Hermite–Obreschkoff relation ``q_{i+1} − q_i = h/2 (q'_i + q'_{i+1}) − h²/12 (q''_{i+1} −
  q''_i)`` (local error ``h⁵ q⁽⁵⁾/720``), so that the grid points lie on the solution of
  ``dq/ds = J⁺x'`` and no null-space drift builds up from step to step.
- **Step size.** The quintic Hermite interpolant of the two ends' ``(q, q', q'')`` is
  checked at the middle of the interval (where its error ``∝ (τ(1 − τ))³`` peaks) against
  the ideal pose: within :data:`SAFETY` of :data:`TOLERANCE`, else the step is shortened;
  the next step is scaled by ``(tolerance / error)^(1/6)`` (the error is ``O(h⁶)``), so
  the grid is fine where ``q'`` changes fast (near singularities) and coarse elsewhere.

:meth:`Continuation.run` stops at the path's end, at a grid point beyond the joint
limits, at a rate above its limit, or where the corrector finds no point however short
the step (the branch ends: a fold of the inverse kinematics, the edge of the reach).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from traj_gen_ros.core.cartesian.samples import IdealPath

#: How far (m, rad) the tool may stray from the ideal path between grid points.
TOLERANCE = (2e-5, 2e-4)
#: The interval's middle must be within this fraction of :data:`TOLERANCE`.
SAFETY = 0.5
#: A grid point is on the path within these (m, rad).
CONVERGED = (1e-7, 1e-6)
#: Highest ``|dq/ds|`` of any joint (rad or m per unit of path): above, the path is singular.
RATE_LIMIT = 100.0
#: The interpolant's ``dq/ds`` must be within this of ``J⁺ x'`` at the middle of an
#: interval, relative to the larger of 1 and ``|J⁺ x'|`` (per unit of path).
RATE_TOLERANCE = 1e-3
#: Singular values below this fraction of the largest count as zero (the null space).
RANK_TOLERANCE = 1e-9
#: ``x'`` is in the Jacobian's range when ``|J q' − x'|`` is below this (per unit of path).
RANGE_TOLERANCE = 1e-6
#: Newton iterations per grid point, and the ratio of successive errors it must beat.
ITERATIONS, CONTRACTION = 10, 0.5
#: The null-space correction of a redundant arm counts as done below this (rad or m).
NULL_TOLERANCE = 1e-7
#: Largest predicted change of any joint in one step (rad or m).
LARGEST_JOINT_STEP = 0.5
#: Shortest step (units of path): where no step this short succeeds, the branch ends.
SHORTEST_STEP = 1e-9


@dataclass
class Point:
    """One grid point: ``q``, ``dq/ds``, ``d²q/ds²`` at ``s`` on one side of a knot."""

    s: float
    q: np.ndarray
    rate: np.ndarray
    curvature: np.ndarray
    smallest: float  # the Jacobian's smallest singular value at q
    jacobian: np.ndarray
    basis: tuple  # (U, σ, Vᵀ, rank) of the Jacobian


@dataclass
class Run:
    """The grid points per piece of the path, and why the run stopped (None: the end)."""

    spans: list[list[Point]]
    stop: str | None

    @property
    def last(self) -> Point:
        """Return the last grid point reached."""
        return self.spans[-1][-1]


def _solve(basis: tuple, vector: np.ndarray) -> np.ndarray:
    """Return ``J⁺ vector`` from the Jacobian's SVD ``(U, σ, Vᵀ, rank)``."""
    u, sigma, vt, rank = basis
    return vt[:rank].T @ ((u[:, :rank].T @ vector) / sigma[:rank])


def _svd(jacobian: np.ndarray) -> tuple:
    u, sigma, vt = np.linalg.svd(jacobian, full_matrices=False)
    return u, sigma, vt, int(np.count_nonzero(sigma > RANK_TOLERANCE * sigma[0]))


def pose_error(rotation: np.ndarray, position: np.ndarray,
               pose: np.ndarray) -> tuple[np.ndarray, float, float]:
    """
    Return ``e = (p* − p, log(R* Rᵀ))`` of ``pose`` from the target, and its two sizes.

    The rotation's log by ``θ = atan2(|vee|/2, (tr − 1)/2)``, ``vee`` the skew part of
    ``R* Rᵀ`` (accurate for the small errors of a corrector; not near π).
    """
    error = np.empty(6)
    error[:3] = position - pose[:3, 3]
    m = rotation @ pose[:3, :3].T
    vee = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    sine = 0.5 * math.sqrt(float(vee @ vee))
    angle = math.atan2(sine, 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0))
    error[3:] = vee * (0.5 if sine < 1e-12 else 0.5 * angle / sine)
    return error, math.sqrt(float(error[:3] @ error[:3])), angle


def hermite_middle(first: Point, second: Point) -> tuple[np.ndarray, np.ndarray]:
    """Return ``q`` and ``dq/ds`` of the quintic Hermite interpolant at the middle (τ = ½)."""
    h = second.s - first.s
    q = (0.5 * (first.q + second.q) + (5.0 / 32.0) * h * (first.rate - second.rate)
         + (h * h / 64.0) * (first.curvature + second.curvature))
    rate = ((15.0 / 8.0 / h) * (second.q - first.q) - (7.0 / 16.0) * (first.rate + second.rate)
            + (h / 32.0) * (second.curvature - first.curvature))
    return q, rate


class Continuation:
    """The continuation of ``chain``'s inverse kinematics along ``path``."""

    def __init__(self, chain: Any, path: IdealPath, lower: np.ndarray,
                 upper: np.ndarray) -> None:
        """Keep the chain, the path and the joint limits that stop a run."""
        self.chain, self.path, self.lower, self.upper = chain, path, lower, upper
        self.knots = np.asarray(path.knots, dtype=float)
        self.step = float(path.length)  # the next step's length, kept from run to run

    def _rates(self, s: float, q: np.ndarray, jacobian: np.ndarray, basis: tuple,
               samples: Any, row: int) -> Point | None:
        """Return the point at ``q`` with its rates, or None where ``x'`` is out of range."""
        velocity = np.concatenate((samples.velocity[row], samples.angular[row]))
        rate = _solve(basis, velocity)
        residual = jacobian @ rate - velocity
        if float(residual @ residual) > RANGE_TOLERANCE ** 2:
            return None
        acceleration = np.concatenate((samples.acceleration[row],
                                       samples.angular_acceleration[row]))
        turning = self.chain.jacobian_rate(q, rate)
        curvature = _solve(basis, acceleration - turning @ rate)
        u, sigma, vt, rank = basis
        if rank < q.size:  # the null-space part of d(J⁺x')/ds: N J̇ᵀ (J⁺)ᵀ q'
            pull = turning.T @ (u[:, :rank] @ ((vt[:rank] @ rate) / sigma[:rank]))
            curvature += pull - vt[:rank].T @ (vt[:rank] @ pull)
        return Point(s, q, rate, curvature, float(sigma[-1]), jacobian, basis)

    def start(self, s: float, q: np.ndarray, side: str) -> Point | None:
        """Return the grid point at ``q`` (no correction) with ``side``'s rates at ``s``."""
        _, jacobian = self.chain.pose_and_jacobian(q)
        return self._rates(s, q, jacobian, _svd(jacobian), self.path.sample(s, side), 0)

    def turn(self, point: Point) -> Point | None:
        """Return a knot's grid point with the rates of the piece that starts there."""
        return self._rates(point.s, point.q, point.jacobian, point.basis,
                           self.path.sample(point.s, 'right'), 0)

    def correct(self, s: float, samples: Any, row: int, guess: np.ndarray,
                anchor: Point) -> Point | None:
        """Converge ``guess`` onto the path pose at ``s`` (Newton, minimum norm); None: fail."""
        rotation, position = samples.rotation[row], samples.position[row]
        q, previous, h = guess, math.inf, s - anchor.s
        for _ in range(ITERATIONS):
            pose, jacobian = self.chain.pose_and_jacobian(q)
            error, distance, angle = pose_error(rotation, position, pose)
            size = distance + angle
            if not size < 1.0:  # far off (or not finite): the step was too long
                return None
            basis = _svd(jacobian)
            if distance > CONVERGED[0] or angle > CONVERGED[1]:
                if size > CONTRACTION * previous:
                    return None
                previous = size
                q = q + _solve(basis, error)
                continue
            point = self._rates(s, q, jacobian, basis, samples, row)
            if point is None or basis[3] == q.size:
                return point
            # A null space: move along it onto the Hermite–Obreschkoff relation.
            target = (anchor.q + 0.5 * h * (anchor.rate + point.rate)
                      - (h * h / 12.0) * (point.curvature - anchor.curvature))
            vt = basis[2][:basis[3]]
            move = (target - q) - vt.T @ (vt @ (target - q))
            if float(np.abs(move).max()) <= NULL_TOLERANCE:
                return point
            q, previous = q + move, math.inf
        return None

    def _middle_error(self, first: Point, second: Point, samples: Any) -> tuple[float, float]:
        """
        Return how far the interpolant is off at the middle, in tolerances: pose and rate.

        The pose's distance from the path in :data:`SAFETY` · :data:`TOLERANCE`; its
        ``dq/ds`` from ``J⁺ x'`` there in :data:`RATE_TOLERANCE` (relative, at least 1).
        """
        q, rate = hermite_middle(first, second)
        pose, jacobian = self.chain.pose_and_jacobian(q)
        _, distance, angle = pose_error(samples.rotation[0], samples.position[0], pose)
        exact = _solve(_svd(jacobian), np.concatenate((samples.velocity[0],
                                                       samples.angular[0])))
        off = float(np.abs(rate - exact).max())
        return (max(distance / (SAFETY * TOLERANCE[0]), angle / (SAFETY * TOLERANCE[1])),
                off / (RATE_TOLERANCE * max(1.0, float(np.abs(exact).max()))))

    def _outside(self, q: np.ndarray) -> bool:
        return bool(np.count_nonzero((q < self.lower) | (q > self.upper)))

    def run(self, first: Point, rate_limit: float = RATE_LIMIT, limits: bool = True,
            budget: int | None = None, recover: float | None = None) -> Run:
        """
        Continue from ``first`` to the path's end, or until a stop.

        Stops (``Run.stop``): ``'limit'`` (with ``limits``, a grid point outside them),
        ``'rate'`` (a joint's ``|q'|`` above ``rate_limit``), ``'recovered'`` (with
        ``recover``, every ``|q'|`` back below it), ``'budget'`` (``budget`` grid points),
        ``'end'`` (no step however short: the branch of the inverse kinematics ends).
        """
        spans, point, h, steps = [[first]], first, self.step, 0
        # The piece that ends at or after first.s: a point on a knot (with the rates of the
        # piece before it) turns to the next piece first.
        piece = max(int(np.searchsorted(self.knots, first.s, side='left')) - 1, 0)
        while True:
            end = float(self.knots[piece + 1])
            if point.s >= end:
                if piece + 2 == len(self.knots):
                    self.step = h
                    return Run(spans, None)
                piece += 1
                point = self.turn(point)
                if point is None:
                    return Run(spans, 'end')
                spans.append([point])
                continue
            h = min(h, LARGEST_JOINT_STEP / max(float(np.abs(point.rate).max()), 1e-300))
            remaining = end - point.s
            step = remaining if h >= remaining else min(h, 0.5 * remaining)
            s = end if step == remaining else point.s + step
            samples = self.path.sample(np.array([point.s + 0.5 * step, s]),
                                       'left' if s == end else 'right')
            guess = point.q + step * point.rate + (0.5 * step * step) * point.curvature
            candidate = self.correct(s, samples, 1, guess, point)
            if candidate is None:
                h = 0.25 * step
                if h < SHORTEST_STEP:
                    return Run(spans, 'end')
                continue
            pose_ratio, rate_ratio = self._middle_error(point, candidate, samples)
            # The interpolant's errors are O(h⁶) in q (the pose) and O(h⁵) in dq/ds.
            scale = 0.9 * min(max(pose_ratio, 1e-12) ** (-1 / 6),
                              max(rate_ratio, 1e-12) ** (-1 / 5))
            if pose_ratio > 1.0 or rate_ratio > 1.0:
                h = step * max(0.2, scale)
                if h < SHORTEST_STEP:
                    return Run(spans, 'end')
                continue
            spans[-1].append(candidate)
            point, steps = candidate, steps + 1
            h = self.step = step * min(4.0, scale)
            fastest = float(np.abs(point.rate).max())
            if limits and self._outside(point.q):
                return Run(spans, 'limit')
            if fastest > rate_limit:
                return Run(spans, 'rate')
            if recover is not None and fastest < recover:
                return Run(spans, 'recovered')
            if budget is not None and steps >= budget:
                return Run(spans, 'budget')
