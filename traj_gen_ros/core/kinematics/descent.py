"""
One start of inverse kinematics: Levenberg–Marquardt within the limits, then least motion.

:func:`descend` runs from one start (:mod:`.inverse` chooses the starts and the answer):

1. **Levenberg–Marquardt** on the pose error ``e = (p* − p, log3(R* Rᵀ))`` (m and rad, in
   ``base_frame`` axes) with Sugihara's damping (*Solvability-unconcerned inverse
   kinematics by the Levenberg–Marquardt method*, IEEE T-RO 27(5), 2011): ``Δq = Jᵀ (J Jᵀ
   + λ I)⁻¹ e`` (``V diag(σ / (σ² + λ)) Uᵀ e`` by the SVD), ``λ = μ (|e|² + 1e-6)``. A step that
   does not lower ``|e|`` is refused and ``μ`` raised eightfold; an accepted one halves it
   (down to 1). At most :data:`STEP_LIMIT` per joint and step; until ``|p* − p|`` and the
   angle are within the tolerances, or for the iterations given, or until it stalls
   (:data:`STALL`).
2. **Joint limits.** A step is cut short where a joint would leave its range, that joint
   put on its bound; a joint on a bound that the next step would push out is locked (the
   step solved again without it), so the other joints do the work. The locked joints of
   a failed start are the limits that stopped it.
3. **Least joint motion** where the chain has spare freedom (a null space: a 7-joint arm):
   the converged solution slides along the solutions toward the seed (:func:`slide`):
   a step along ``N (seed − q)``, the part of the way back to the seed that leaves the
   tool where it is, then Levenberg–Marquardt again, kept only if it converged nearer the
   seed, until ``N (seed − q)`` is below :data:`NULL_TOLERANCE`: ``|q − seed|`` is then
   stationary (a local minimum) on the joint positions that reach the pose.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

import numpy as np

#: Largest change of one joint in one step, rad (or m).
STEP_LIMIT = 0.5
#: Largest null-space move toward the seed in one step, rad (or m).
NULL_STEP_LIMIT = 0.2
#: The null-space step's length, in units of the pull: the smallest tried, the largest.
NULL_LENGTHS = (1.0 / 64.0, 4.0)
#: Iterations a slide toward the seed may spend, and each of its corrections.
SLIDE_ITERATIONS, SLIDE_CORRECTIONS = 60, 4
#: The null-space pull toward the seed counts as done below this, rad (or m).
NULL_TOLERANCE = 1e-5
#: A start has stalled when ``STALL[0]`` iterations lowered ``|e|²`` by less than the
#: fraction ``STALL[1]`` (the closest it can come: out of reach, or a local minimum).
STALL = (10, 1e-3)
#: Damping floor (m² or rad²) of the Levenberg–Marquardt step, against singularities.
DAMPING_FLOOR = 1e-6
#: Singular values below this fraction of the largest count as the null space.
RANK_TOLERANCE = 1e-6
_TURN = 2.0 * math.pi


@dataclass
class Attempt:
    """What one start reached: its joint positions, pose error, and the limits on it."""

    q: np.ndarray
    error: np.ndarray
    converged: bool
    iterations: int
    locked: np.ndarray


def _error(pin: Any, target: np.ndarray, rotation: np.ndarray,
           translation: np.ndarray) -> np.ndarray:
    error = np.empty(6)
    error[:3] = target[:3, 3] - translation
    error[3:] = pin.log3(target[:3, :3] @ rotation.T)
    return error


def _step(jacobian: np.ndarray, error: np.ndarray, damping: float, q: np.ndarray,
          lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the damped least-squares step on ``error`` at ``q`` and the joints it locks.

    ``Jᵀ (J Jᵀ + λ I)⁻¹ e``, the same as ``V diag(σ / (σ² + λ)) Uᵀ e`` from the SVD, in a
    6×6 solve. A joint at a limit that the step would push out is locked and the step
    solved again without it.
    """
    free = np.ones(q.size, dtype=bool)
    identity = damping * np.eye(jacobian.shape[0])
    while True:
        columns = jacobian if free.all() else jacobian[:, free]
        step = np.zeros(q.size)
        step[free] = columns.T @ np.linalg.solve(columns @ columns.T + identity, error)
        out = free & (((q <= lower) & (step < 0)) | ((q >= upper) & (step > 0)))
        if not out.any():
            return step, ~free
        free &= ~out
        if not free.any():
            return np.zeros(q.size), ~free


def _pull(jacobian: np.ndarray, q: np.ndarray, seed: np.ndarray, periodic: np.ndarray,
          lower: np.ndarray, upper: np.ndarray) -> np.ndarray | None:
    """
    Return the part of ``seed − q`` that leaves the tool where it is, or None.

    That is its projection on the Jacobian's null space (None where there is none), with
    the joints at a limit it would push out locked. Revolute and continuous joints count
    the short way round (``seed − q`` within ±π).
    """
    toward = seed - q
    toward[periodic] = (toward[periodic] + math.pi) % _TURN - math.pi
    free = np.ones(q.size, dtype=bool)
    while free.any():
        _, s, vt = np.linalg.svd(jacobian[:, free])
        rank = int(np.count_nonzero(s > RANK_TOLERANCE * max(s[0], 1e-300)))
        if rank == vt.shape[0]:
            return None
        pull = np.zeros(q.size)
        pull[free] = vt[rank:].T @ (vt[rank:] @ toward[free])
        out = free & (((q <= lower) & (pull < 0)) | ((q >= upper) & (pull > 0)))
        if not out.any():
            return pull
        free &= ~out
    return None


def _within(q: np.ndarray, step: np.ndarray, lower: np.ndarray,
            upper: np.ndarray, limit: float = STEP_LIMIT) -> np.ndarray:
    """
    Return ``q + τ step``, ``τ <= 1`` the largest that keeps every joint in its limits.

    The step is first cut to ``limit`` per joint; a joint that the cut step stops at its
    bound is put exactly on it (and locked by the next step if it pushes out).
    """
    largest = float(np.abs(step).max())
    if largest > limit:
        step = step * (limit / largest)
    trial = q + step
    if (trial >= lower).all() and (trial <= upper).all():
        return trial
    room = np.full(q.size, math.inf)
    rising, falling = step > 0, step < 0
    room[rising] = (upper[rising] - q[rising]) / step[rising]
    room[falling] = (lower[falling] - q[falling]) / step[falling]
    stop = int(np.argmin(room))
    if room[stop] >= 1.0:
        return q + step
    trial = np.clip(q + room[stop] * step, lower, upper)
    trial[stop] = upper[stop] if rising[stop] else lower[stop]
    return trial


def _converge(chain: Any, target: np.ndarray, start: np.ndarray, lower: np.ndarray,
              upper: np.ndarray, tolerances: tuple[float, float],
              iterations: int) -> Attempt:
    """Run Levenberg–Marquardt from ``start`` (within the limits) to the tolerances."""
    pin, q = chain._pin, start
    error = _error(pin, target, *chain._tool_pose(q))
    cost, mu = float(error @ error), 1.0
    locked = np.zeros(q.size, dtype=bool)
    costs = []
    for iteration in range(iterations):
        if (math.hypot(*error[:3]) <= tolerances[0]
                and math.hypot(*error[3:]) <= tolerances[1]):
            return Attempt(q, error, True, iteration, locked)
        costs.append(cost)
        if len(costs) > STALL[0] and cost > (1.0 - STALL[1]) * costs[-1 - STALL[0]]:
            break  # a local minimum: stalled
        jacobian = chain._pose_and_jacobian(q)[2]
        step, locked = _step(jacobian, error, mu * (cost + DAMPING_FLOOR), q, lower, upper)
        trial = _within(q, step, lower, upper)
        trial_error = _error(pin, target, *chain._tool_pose(trial))
        trial_cost = float(trial_error @ trial_error)
        if trial_cost < cost:
            q, error, cost, mu = trial, trial_error, trial_cost, max(mu * 0.5, 1.0)
        else:
            mu *= 8.0
            if mu > 1e12:
                break
    else:
        iteration = iterations
        if (math.hypot(*error[:3]) <= tolerances[0]
                and math.hypot(*error[3:]) <= tolerances[1]):
            return Attempt(q, error, True, iterations, locked)
    # Not converged: the joints that the limits hold where it ended.
    jacobian = chain._pose_and_jacobian(q)[2]
    locked = _step(jacobian, error, mu * (cost + DAMPING_FLOOR), q, lower, upper)[1]
    return Attempt(q, error, False, iteration, locked)


def _distance(q: np.ndarray, seed: np.ndarray, periodic: np.ndarray) -> float:
    apart = q - seed
    apart[periodic] = (apart[periodic] + math.pi) % _TURN - math.pi
    return float(apart @ apart)


def slide(chain: Any, target: np.ndarray, found: Attempt, seed: np.ndarray,
          lower: np.ndarray, upper: np.ndarray, tolerances: tuple[float, float]) -> Attempt:
    """
    Move a converged ``found`` along the solutions toward the seed (least joint motion).

    Each round steps along the null-space pull (:func:`_pull`) by a Barzilai–Borwein
    length ``sᵀs / sᵀy`` (``s`` the last move, ``y`` the change of the pull), converges
    again (:data:`SLIDE_CORRECTIONS` iterations at most) and keeps the result only if it
    is nearer the seed; else the length is quartered. It ends when the pull is below
    :data:`NULL_TOLERANCE`, the length below :data:`NULL_LENGTHS` [0], or after
    :data:`SLIDE_ITERATIONS`.
    """
    periodic, spent, length, memory = chain.periodic, 0, 1.0, None
    best, distance = found, _distance(found.q, seed, periodic)
    while spent < SLIDE_ITERATIONS:
        spent += 1
        pull = _pull(chain._pose_and_jacobian(best.q)[2], best.q, seed, periodic, lower, upper)
        if pull is None or np.abs(pull).max() <= NULL_TOLERANCE:
            break
        if memory is not None:
            moved = best.q - memory[0]
            curvature = float(moved @ (memory[1] - pull))
            if curvature > 0.0:
                length = min(float(moved @ moved) / curvature, NULL_LENGTHS[1])
        trial = _within(best.q, length * pull, lower, upper, NULL_STEP_LIMIT)
        corrected = _converge(chain, target, trial, lower, upper, tolerances,
                              SLIDE_CORRECTIONS)
        spent += corrected.iterations
        nearer = _distance(corrected.q, seed, periodic)
        if corrected.converged and nearer < distance:
            memory = (best.q, pull)
            best, distance = corrected, nearer
        else:
            memory, length = None, length / 4
            if length < NULL_LENGTHS[0]:
                break
    return Attempt(best.q, best.error, True, found.iterations + spent, best.locked)


def descend(chain: Any, target: np.ndarray, start: np.ndarray, seed: np.ndarray,
            lower: np.ndarray, upper: np.ndarray, tolerances: tuple[float, float],
            iterations: int) -> Attempt:
    """Converge from ``start``, then slide toward the seed where there is spare freedom."""
    found = _converge(chain, target, np.clip(start, lower, upper), lower, upper, tolerances,
                      iterations)
    if not found.converged:
        return found
    return slide(chain, target, found, seed, lower, upper, tolerances)
