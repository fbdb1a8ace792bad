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


def limit_violation(
    trajectory: Trajectory,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray | None = None,
) -> Violation | None:
    """
    Return the worst excess over the limits (``(joints,)`` arrays), or ``None`` if within.

    The excess is measured relative to the limit; ``LIMIT_TOLERANCE`` of it is allowed.
    The exact peaks are found only where the pieces' Bernstein bounds (never below the
    peaks: :meth:`Trajectory.peak_bounds`) are not already within the limits.
    """
    limits = [np.asarray(max_velocity, dtype=float), np.asarray(max_acceleration, dtype=float)]
    names = ['velocity', 'acceleration']
    if max_jerk is not None:
        limits.append(np.asarray(max_jerk, dtype=float))
    bounds = trajectory.peak_bounds(len(limits))
    if all(np.count_nonzero(bound <= limit) == bound.size
           for bound, limit in zip(bounds, limits, strict=True)):
        return None
    if max_jerk is None:
        peaks = list(trajectory.peaks()[:2])
    else:
        peaks = list(trajectory.peaks_with_jerk())
        names.append('jerk')
    ratios = np.array([peak / limit for peak, limit in zip(peaks, limits, strict=True)])
    if np.count_nonzero(ratios <= 1.0 + LIMIT_TOLERANCE) == ratios.size:
        return None
    quantity, joint = divmod(int(ratios.argmax()), ratios.shape[1])
    return Violation(int(joint), names[quantity], float(peaks[quantity][joint]),
                     float(limits[quantity][joint]))


def within_limits(
    trajectory: Trajectory,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray | None = None,
) -> bool:
    """Tell whether no joint's exact peak exceeds its limits (relative ``LIMIT_TOLERANCE``)."""
    return limit_violation(trajectory, max_velocity, max_acceleration, max_jerk) is None
