"""
The S-curve's state-to-state problem, shared by its Ruckig backend and its fallbacks.

:class:`Move` holds one problem as Python floats (what Ruckig's input takes), one list
entry per joint; :data:`DURATION_TOLERANCE` is when a plan's duration meets the one asked
for. :mod:`traj_gen_ros.core.jerk_limited.ruckig_backend` and
:mod:`traj_gen_ros.core.jerk_limited.fallback` both import this module, and it imports
neither: the dependency runs one way.

Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

#: Relative: a plan this close to the asked duration (s) meets it.
DURATION_TOLERANCE = 1e-13
#: Ruckig's absolute precision in position (rad or m) and velocity at a plan's end
#: (profile.hpp: p_precision, v_precision): a step no larger is no motion to it.
PRECISION = 1e-8
#: The limits' parameter names, in the order of :attr:`Move.limits`.
LIMIT_NAMES = ('max_velocity', 'max_acceleration', 'max_jerk')

Floats = list[float]


class Move:
    """One state-to-state problem as Python floats, one list entry per joint."""

    __slots__ = ('start', 'goal', 'v0', 'a0', 'vf', 'limits', 'duration')

    def __init__(self, start: Floats, goal: Floats, v0: Floats, a0: Floats, vf: Floats,
                 limits: tuple[Floats, Floats, Floats], duration: float | None) -> None:
        self.start, self.goal, self.v0, self.a0, self.vf = start, goal, v0, a0, vf
        self.limits = limits  # (v_max, a_max, j_max)
        self.duration = duration  # the exact duration asked for, or None for minimum time

    def joint(self, index: int) -> Move:
        """Return the same problem for one joint alone."""
        pick = slice(index, index + 1)
        return Move(self.start[pick], self.goal[pick], self.v0[pick], self.a0[pick],
                    self.vf[pick], tuple(limit[pick] for limit in self.limits),
                    self.duration)

    def minimum_time(self) -> Move:
        """Return the same problem without its duration: the minimum-time problem."""
        return Move(self.start, self.goal, self.v0, self.a0, self.vf, self.limits, None)
