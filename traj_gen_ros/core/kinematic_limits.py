"""
The one limit check of the package, with its one tolerance.

A plan is within its limits when no joint's exact peak ``|velocity|``, ``|acceleration|``
(and ``|jerk|`` where a jerk limit is given) exceeds the limit by more than
``LIMIT_TOLERANCE`` relative. Peaks are the exact extrema of the piecewise polynomial
(:meth:`Trajectory.peaks`), not sampled estimates.

Errors about one joint are :class:`JointError`: the core knows joints by index, a caller
that knows their names (the node) asks for the message with names.

Units: rad, rad/s, rad/s², rad/s³.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory

#: Relative slack on every limit: rounding in the solvers, never a real excess.
LIMIT_TOLERANCE = 1e-9
#: The quantities of :func:`limit_ratios`' rows.
QUANTITIES = ('velocity', 'acceleration', 'jerk')

_UNITS = {'velocity': 'rad/s', 'acceleration': 'rad/s^2', 'jerk': 'rad/s^3'}


class JointError(ValueError):
    """
    A refusal about one joint, known by its index ``joint``.

    ``template`` holds ``{joint}`` where the joint is named; ``str(error)`` says
    ``joint 2``, :meth:`named` says ``joint 'joint_3'``.
    """

    def __init__(self, template: str, joint: int) -> None:
        """Keep the message ``template`` and the joint index it names."""
        self.template = template
        self.joint = int(joint)
        super().__init__(template.format(joint=f'joint {self.joint}'))

    def named(self, names: Sequence[str]) -> str:
        """Return the message with the joint given by its name in ``names``."""
        return self.template.format(joint=f'joint {names[self.joint]!r}')


@dataclass(frozen=True)
class Violation:
    """The largest excess of a plan over its limits: which joint, what, how much."""

    joint: int
    quantity: str
    peak: float
    limit: float

    def describe(self, names: Sequence[str] | None = None) -> str:
        """Say which joint exceeds which limit, by name when ``names`` are given."""
        joint = f'joint {self.joint}' if names is None else f'joint {names[self.joint]!r}'
        unit = _UNITS[self.quantity]
        return (f'{joint} would reach {self.quantity} {self.peak:.6g} {unit}, above '
                f'max_{self.quantity} {self.limit:.6g} {unit}')


def limit_ratios(
    trajectory: Trajectory,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray | None = None,
) -> np.ndarray:
    """
    Return ``peak / limit`` per quantity (velocity, acceleration[, jerk]) and joint.

    ``(2 or 3, joints)``. Exact wherever above 1; within 1 it may be a bound of the ratio
    (never below it): the exact peaks are found only on pieces whose Bernstein bound is
    above the limit (:meth:`Trajectory.peaks_above`).
    """
    limits = [np.asarray(max_velocity, dtype=float), np.asarray(max_acceleration, dtype=float)]
    if max_jerk is not None:
        limits.append(np.asarray(max_jerk, dtype=float))
    peaks = trajectory.peaks_above(limits)
    return np.array([peak / limit for peak, limit in zip(peaks, limits, strict=True)])


def limit_violation(
    trajectory: Trajectory,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray | None = None,
) -> Violation | None:
    """
    Return the worst excess over the limits (``(joints,)`` arrays), or ``None`` if within.

    The excess is measured relative to the limit; ``LIMIT_TOLERANCE`` of it is allowed.
    The exact peaks are found only on the pieces whose Bernstein bounds (never below the
    peaks) are not already within the limits (:func:`limit_ratios`).
    """
    ratios = limit_ratios(trajectory, max_velocity, max_acceleration, max_jerk)
    if np.count_nonzero(ratios <= 1.0 + LIMIT_TOLERANCE) == ratios.size:
        return None
    limits = [max_velocity, max_acceleration, max_jerk]
    quantity, joint = divmod(int(ratios.argmax()), ratios.shape[1])
    limit = float(np.broadcast_to(np.asarray(limits[quantity], dtype=float),
                                  (ratios.shape[1],))[joint])
    return Violation(int(joint), QUANTITIES[quantity], float(ratios[quantity, joint] * limit),
                     limit)


def within_limits(
    trajectory: Trajectory,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray | None = None,
) -> bool:
    """Tell whether no joint's exact peak exceeds its limits (relative ``LIMIT_TOLERANCE``)."""
    return limit_violation(trajectory, max_velocity, max_acceleration, max_jerk) is None
