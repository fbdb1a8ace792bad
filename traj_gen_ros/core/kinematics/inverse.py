"""
Inverse kinematics: the joint positions within limits nearest a seed that reach a pose.

:func:`solve` (``Chain.inverse``):

1. **From the seed** first: :func:`~.descent.descend` (Levenberg–Marquardt within the
   limits, then least joint motion), at most :data:`SEED_ITERATIONS` iterations.
2. **Restarts** only if that does not converge: :data:`RESTARTS` fixed starts,
   :data:`RESTART_ITERATIONS` each: the middle of every joint's range, then the first
   points of the Halton sequence (bases 2, 3, 5, … per joint) scaled to the ranges. An
   unbounded range counts as the seed ± π (revolute, continuous) or ± 1 m (prismatic);
   a bound on one side only, as that bound and 2π (2 m) beyond it.
3. **The answer.** Revolute and continuous joints are moved by whole turns (2πk) to the
   value nearest the seed within their limits (the same pose; not a joint that another
   mimics); of the converged solutions, the one whose largest joint difference from the
   seed is smallest wins (then the smaller sum of squares). None converged:
   :class:`UnreachablePoseError`, saying how close the best start came (mm, mrad) and
   which joint limits stopped it.

Converged means within ``position_tolerance`` (m, default 0.01 mm) and
``orientation_tolerance`` (rad, default 0.1 mrad) of the target.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

import numpy as np
from traj_gen_ros.core.kinematics.descent import Attempt, descend
from traj_gen_ros.core.kinematics.poses import check_pose

#: Iterations from the seed, and from each restart.
SEED_ITERATIONS, RESTART_ITERATIONS = 100, 60
#: How many fixed restarts are tried when the seed's descent fails.
RESTARTS = 24
_TURN = 2.0 * math.pi


@dataclass(frozen=True)
class IkSolution:
    """
    Inverse kinematics' answer.

    :ivar q: joint positions ``(joints,)``, rad or m, inside the limits.
    :ivar position_error: distance of the tool from the target, m.
    :ivar orientation_error: angle of the tool's rotation from the target's, rad.
    :ivar iterations: iterations spent, over every start tried.
    :ivar start: the start that gave ``q``: ``'seed'`` or ``'restart k'`` (1 to
        :data:`RESTARTS`).
    """

    q: np.ndarray
    position_error: float
    orientation_error: float
    iterations: int
    start: str


class UnreachablePoseError(ValueError):
    """
    No start converged: the pose is out of reach, or the limits forbid it.

    :ivar position_error: how close the best attempt came, m.
    :ivar orientation_error: likewise, rad.
    :ivar q: the best attempt's joint positions.
    :ivar limited: the joints whose limits stopped the best attempt, by name.
    """

    def __init__(self, message: str, position_error: float, orientation_error: float,
                 q: np.ndarray, limited: tuple[str, ...]) -> None:
        """Keep the message and what it reports."""
        super().__init__(message)
        self.position_error, self.orientation_error = position_error, orientation_error
        self.q, self.limited = q, limited


def _limits(chain: Any, lower: Any, upper: Any) -> tuple[np.ndarray, np.ndarray]:
    count = len(chain.joints)
    bounds = []
    for name, values in (('lower', lower), ('upper', upper)):
        try:
            array = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            array = np.full(1, math.nan)
        if array.shape != (count,) or np.isnan(array).any():
            raise ValueError(f'{name} limits must be {count} numbers (rad or m, ±inf: none), '
                             f'one per joint of {", ".join(chain.joints)}; got {values!r}')
        bounds.append(array)
    crossed = np.flatnonzero(bounds[0] > bounds[1])
    if crossed.size:
        k = int(crossed[0])
        raise ValueError(f'joint {chain.joints[k]!r}: lower limit {bounds[0][k]:g} > upper '
                         f'limit {bounds[1][k]:g}')
    return bounds[0], bounds[1]


def _halton(index: int, base: int) -> float:
    fraction, value = 1.0, 0.0
    while index:
        fraction /= base
        index, digit = divmod(index, base)
        value += digit * fraction
    return value


def _primes(count: int) -> list[int]:
    primes, candidate = [], 2
    while len(primes) < count:
        if all(candidate % prime for prime in primes):
            primes.append(candidate)
        candidate += 1
    return primes


def restarts(chain: Any, seed: np.ndarray, lower: np.ndarray,
             upper: np.ndarray) -> np.ndarray:
    """Return the :data:`RESTARTS` fixed starts, ``(RESTARTS, joints)`` (see the module)."""
    half = np.where(chain.angular, math.pi, 1.0)
    low = np.where(np.isfinite(lower), lower,
                   np.where(np.isfinite(upper), upper - 2 * half, seed - half))
    high = np.where(np.isfinite(upper), upper, low + 2 * half)
    primes = _primes(seed.size)
    fractions = [[0.5] * seed.size]
    fractions += [[_halton(k, p) for p in primes] for k in range(1, RESTARTS)]
    return low + np.array(fractions) * (high - low)


def _nearest_turns(q: np.ndarray, seed: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                   periodic: np.ndarray) -> np.ndarray:
    """Move each periodic joint by the whole turns that bring it nearest ``seed`` in limits."""
    turns = np.where(periodic, np.round((seed - q) / _TURN), 0.0)
    options = q + _TURN * (turns + np.array([[0.0], [-1.0], [1.0]]) * periodic)
    options = np.where((options >= lower) & (options <= upper), options, q)
    return options[np.argmin(np.abs(options - seed), axis=0), np.arange(q.size)]


def _refusal(chain: Any, best: Attempt, starts: int, lower: np.ndarray,
             upper: np.ndarray) -> UnreachablePoseError:
    position, orientation = math.hypot(*best.error[:3]), math.hypot(*best.error[3:])
    limited, stops = [], []
    for k in np.flatnonzero(best.locked):
        side, bound = ('lower', lower[k]) if best.q[k] <= lower[k] else ('upper', upper[k])
        limited.append(chain.joints[k])
        unit = 'rad' if chain.angular[k] else 'm'
        stops.append(f'joint {chain.joints[k]!r} at its {side} limit {bound:g} {unit}')
    why = ('; stopped by ' + ', '.join(stops)) if stops else '; no joint limit stopped it'
    return UnreachablePoseError(
        f'no joint positions within the limits put {chain.tool_frame!r} at the target pose: '
        f'the closest found (from the seed and {starts - 1} restarts) is '
        f'{position * 1e3:.3f} mm and {orientation * 1e3:.3f} mrad from it{why}',
        position, orientation, best.q, tuple(limited))


def solve(chain: Any, target: np.ndarray, seed: np.ndarray, lower: Any, upper: Any,
          position_tolerance: float = 1e-5, orientation_tolerance: float = 1e-4
          ) -> IkSolution:
    """
    Return the joint positions nearest ``seed`` that put the chain's tool at ``target``.

    :param chain: a :class:`~traj_gen_ros.core.kinematics.chain.Chain`.
    :param target: the tool pose in ``base_frame``, ``(4, 4)``, m.
    :param seed: ``(joints,)`` rad or m (clipped into the limits to start).
    :param lower: lower position limits ``(joints,)`` (-inf: none).
    :param upper: upper position limits ``(joints,)`` (+inf: none).
    :param position_tolerance: m (> 0).
    :param orientation_tolerance: rad (> 0).
    :raises UnreachablePoseError: no start converged.
    :raises ValueError: a target that is no rigid transform, a seed that is not one
        finite value per joint, limits that are not, or tolerances that are not > 0.
    """
    target = check_pose(target, 'target pose')
    if seed.ndim != 1:
        raise ValueError(f'seed has shape {seed.shape}: expected ({len(chain.joints)},)')
    lower, upper = _limits(chain, lower, upper)
    tolerances = (float(position_tolerance), float(orientation_tolerance))
    if not all(math.isfinite(value) and value > 0 for value in tolerances):
        raise ValueError(f'tolerances must be > 0 (m, rad), not {tolerances}')
    attempts = [descend(chain, target, seed, seed, lower, upper, tolerances,
                        SEED_ITERATIONS)]
    labels = ['seed']
    if not attempts[0].converged:
        for k, start in enumerate(restarts(chain, seed, lower, upper), start=1):
            attempts.append(descend(chain, target, start, seed, lower, upper, tolerances,
                                    RESTART_ITERATIONS))
            labels.append(f'restart {k}')
    spent = sum(attempt.iterations for attempt in attempts)
    found = [(_nearest_turns(attempt.q, seed, lower, upper, chain.periodic), attempt, label)
             for attempt, label in zip(attempts, labels, strict=True) if attempt.converged]
    if not found:
        best = min(attempts, key=lambda attempt: float(attempt.error @ attempt.error))
        raise _refusal(chain, best, len(attempts), lower, upper)
    q, attempt, label = min(found, key=lambda item: (float(np.abs(item[0] - seed).max()),
                                                     float(np.sum((item[0] - seed) ** 2))))
    return IkSolution(q, math.hypot(*attempt.error[:3]), math.hypot(*attempt.error[3:]),
                      spent, label)
