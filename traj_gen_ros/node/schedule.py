"""
The motions on the node clock: which plan is in effect at a time, and its setpoint there.

Times are integer nanoseconds of the node clock (system time, or ``/clock`` with
``use_sim_time``). A motion spliced in at ``start_ns`` replaces everything from that time
on; until then the previous motion keeps running, so a delayed request (a future
``header.stamp``) does not interrupt the motion in progress. Once a plan's duration has
passed, the setpoint is exactly its end, at rest. No ROS here; not thread-safe (the
:class:`traj_gen_ros.node.stream.Stream` lock guards it).

Units: rad, rad/s, rad/s², ns.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.trajectory import state_at
from traj_gen_ros.node.motion import PlannedMotion, State

#: "Since forever": the start of the first motion (ns).
BEGINNING_NS = -(2 ** 62)


class Schedule:
    """The motion in effect and any delayed ones, each with its start time (ns)."""

    def __init__(self, motion: PlannedMotion) -> None:
        """Start with ``motion`` (usually a hold) in effect since forever."""
        self._segments: list[tuple[int, PlannedMotion]] = [(BEGINNING_NS, motion)]

    def _segment(self, time_ns: int) -> tuple[int, PlannedMotion]:
        for start, motion in reversed(self._segments):
            if start <= time_ns:
                return start, motion
        return self._segments[0]

    def setpoint(self, time_ns: int) -> State:
        """Return the setpoint at ``time_ns``."""
        start, motion = self._segment(time_ns)
        elapsed = (time_ns - start) * 1e-9
        if elapsed >= motion.plan.duration:
            zeros = np.zeros_like(motion.end)
            return State(motion.end.copy(), zeros, zeros.copy())
        return State(*state_at(motion.plan, elapsed))

    def moving_at(self, time_ns: int) -> bool:
        """Tell whether a motion is still under way at ``time_ns`` (not yet at its end)."""
        start, motion = self._segment(time_ns)
        return (time_ns - start) * 1e-9 < motion.plan.duration

    def end_position(self, before_ns: int) -> np.ndarray:
        """Where the schedule rests (rad) if nothing starting at or after ``before_ns`` runs."""
        kept = [segment for segment in self._segments if segment[0] < before_ns]
        return (kept or self._segments)[-1][1].end.copy()

    def splice(self, start_ns: int, motion: PlannedMotion, now_ns: int) -> None:
        """Run ``motion`` from ``start_ns``, dropping what would start at or after it."""
        kept = [segment for segment in self._segments if segment[0] < start_ns]
        current = [index for index, segment in enumerate(kept) if segment[0] <= now_ns]
        if current:
            kept = kept[current[-1]:]
        self._segments = kept + [(start_ns, motion)]

    @property
    def pending(self) -> int:
        """Return the number of motions kept (the running one and delayed ones)."""
        return len(self._segments)
