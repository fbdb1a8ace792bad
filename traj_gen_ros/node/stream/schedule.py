"""
The motions on the node clock: which plan is in effect at a time, and its setpoint there.

Times are integer nanoseconds of the node clock (system time, or ``/clock`` with
``use_sim_time``). A motion spliced in at ``start_ns`` replaces everything from that time
on; until then the previous motion keeps running, so a delayed request (a future
``header.stamp``) does not interrupt the motion in progress. Once a plan's duration has
passed, the setpoint is exactly its end, at rest. No ROS here; not thread-safe (the
:class:`traj_gen_ros.node.stream.state.StreamState` lock guards it).

**Speed scaling** (:mod:`traj_gen_ros.node.speed.time_map`): a scaled motion's own time is
``τ(t) = P(t) - P(start)``, ``P`` the plan clock of the :class:`TimeMap`; its setpoint is
the commanded state ``(p(τ), f v(τ), f² a(τ) + ḟ v(τ))`` (:meth:`Schedule.setpoint`). A
new scaled motion is planned from the running plan's *own* state at ``τ``
(:meth:`Schedule.plan_state`: ``v(τ)``, ``a(τ)``, defined at ``f = 0`` too) and runs on
the same plan clock, so the composed command is continuous in position, velocity and
acceleration across the splice whatever ``f`` is. An ``unscaled`` motion (a brake) runs
on the node clock and is planned from the commanded state. A scaled motion asked for
while an unscaled brake still moves and ``f`` is not 1 starts where the brake is at rest
(:meth:`Schedule.scaled_start`): its own start velocity ``v_cmd / f`` would be undefined
at ``f = 0``.

Units: rad, rad/s, rad/s², ns.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.trajectory import state_at
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.speed.plan_window import PlanWindow
from traj_gen_ros.node.speed.time_map import TimeMap

#: "Since forever": the start of the first motion (ns).
BEGINNING_NS = -(2 ** 62)


class Segment:
    """
    A motion from ``start`` (ns) on; ``clock``: the plan clock there (s), scaled only.

    ``tag``: what the caller said it is for (the request), handed back if it is dropped.
    """

    __slots__ = ('start', 'motion', 'clock', 'tag', 'window')

    def __init__(self, start: int, motion: PlannedMotion, clock: float | None,
                 tag: object = None) -> None:
        """Run ``motion`` from ``start`` (ns); ``clock`` None runs it on the node clock."""
        self.start, self.motion, self.clock, self.tag = start, motion, clock, tag
        self.window: PlanWindow | None = None  # made when the ramp first asks


class Schedule:
    """The motion in effect and any delayed ones, each with its start time (ns)."""

    def __init__(self, motion: PlannedMotion, time_map: TimeMap | None = None) -> None:
        """Start with ``motion`` (usually a hold) in effect since forever."""
        self.time_map = time_map if time_map is not None else TimeMap(np.ones(1))
        self._segments = [Segment(BEGINNING_NS, motion, None)]

    def _segment(self, time_ns: int) -> Segment:
        for segment in reversed(self._segments):
            if segment.start <= time_ns:
                return segment
        return self._segments[0]

    def _elapsed(self, segment: Segment, time_ns: int) -> tuple[float, float, float]:
        """``(τ (s), f, ḟ)`` of ``segment`` at ``time_ns``: the plan's own time elapsed."""
        if segment.clock is None:
            return (time_ns - segment.start) * 1e-9, 1.0, 0.0
        clock, factor, rate, _ = self.time_map.at(time_ns, self._own_state)
        return clock - segment.clock, factor, rate

    def _own_state(self, time_ns: int, clock: float) -> tuple[PlanWindow, float] | None:
        """Give the time map the moving scaled plan (a window on it) and its own time."""
        segment = self._segment(time_ns)
        if segment.clock is None:
            return None
        elapsed = clock - segment.clock
        if elapsed >= segment.motion.plan.duration:
            return None
        if segment.window is None:
            segment.window = PlanWindow(segment.motion.plan)
        return segment.window, elapsed

    def setpoint(self, time_ns: int) -> State:
        """Return the commanded setpoint at ``time_ns`` (the factor applied)."""
        segment = self._segment(time_ns)
        elapsed, factor, rate = self._elapsed(segment, time_ns)
        own = self._own(segment, elapsed)
        if segment.clock is None or elapsed >= segment.motion.plan.duration:
            return own
        position, velocity, acceleration = own
        return State(position, factor * velocity,
                     factor * factor * acceleration + rate * velocity)

    @staticmethod
    def _own(segment: Segment, elapsed: float) -> State:
        """Return the plan's own state ``elapsed`` s into it; at its end, at rest there exactly."""
        motion = segment.motion
        if elapsed >= motion.plan.duration:
            zeros = np.zeros_like(motion.end)
            return State(motion.end.copy(), zeros, zeros.copy())
        return State(*state_at(motion.plan, elapsed))

    def running(self, time_ns: int) -> tuple[PlannedMotion, float]:
        """Return the motion in effect at ``time_ns`` and its own time there (s)."""
        segment = self._segment(time_ns)
        return segment.motion, self._elapsed(segment, time_ns)[0]

    def plan_state(self, time_ns: int) -> State:
        """
        Return the state a scaled motion starting at ``time_ns`` is planned from.

        The running scaled plan's own state at its ``τ`` (unscaled: its velocity is
        ``v(τ)``, not ``f v(τ)``); a brake's commanded state where ``f`` is 1 and
        settled (:meth:`scaled_start` moves a start off a moving brake otherwise).
        """
        segment = self._segment(time_ns)
        return self._own(segment, self._elapsed(segment, time_ns)[0])

    def scaled_start(self, time_ns: int) -> int:
        """
        Return when a scaled motion asked to start at ``time_ns`` starts (ns).

        ``time_ns`` itself, unless an unscaled brake still moves there while the factor
        is not exactly 1: then where the brake comes to rest.
        """
        segment = self._segment(time_ns)
        if segment.clock is not None:
            return time_ns
        end_ns = segment.start + int(np.ceil(segment.motion.plan.duration * 1e9))
        if end_ns <= time_ns:
            return time_ns
        _, factor, rate, curvature = self.time_map.at(time_ns, self._own_state)
        if factor == 1.0 and rate == 0.0 and curvature == 0.0:
            return time_ns
        return end_ns

    def moving_at(self, time_ns: int) -> bool:
        """Tell whether a motion is still under way at ``time_ns`` (not yet at its end)."""
        segment = self._segment(time_ns)
        return self._elapsed(segment, time_ns)[0] < segment.motion.plan.duration

    def end_position(self, before_ns: int) -> np.ndarray:
        """Where the schedule rests (rad) if nothing starting at or after ``before_ns`` runs."""
        kept = [segment for segment in self._segments if segment.start < before_ns]
        return (kept or self._segments)[-1].motion.end.copy()

    def time_left(self, time_ns: int) -> float:
        """
        Return the plan time (s) the motion in effect at ``time_ns`` has left, 0 at rest.

        ``duration - τ``, ``τ = P(t) - P(start)`` on the plan clock for a scaled motion
        (it stays put while paused, falls at ``f`` s per s), on the node clock for a brake.
        """
        segment = self._segment(time_ns)
        return max(segment.motion.plan.duration - self._elapsed(segment, time_ns)[0], 0.0)

    def splice(self, start_ns: int, motion: PlannedMotion, now_ns: int,
               tag: object = None) -> None:
        """Run ``motion`` from ``start_ns``, dropping what would start at or after it."""
        kept = [segment for segment in self._segments if segment.start < start_ns]
        current = [index for index, segment in enumerate(kept) if segment.start <= now_ns]
        if current:
            kept = kept[current[-1]:]
        clock = None
        if not motion.unscaled:
            clock = self.time_map.at(start_ns, self._own_state)[0]
        self._segments = kept + [Segment(start_ns, motion, clock, tag)]
        self.time_map.forget()  # the plans after start_ns changed

    def commit(self, time_ns: int) -> None:
        """Fix the ramp up to ``time_ns``, which the stream published."""
        self.time_map.commit(time_ns, self._own_state)

    def factor_at(self, time_ns: int) -> float:
        """Return the effective (ramped) factor ``f`` at ``time_ns``."""
        return self.time_map.at(time_ns, self._own_state)[1]

    def set_factor(self, factor: float, from_ns: int, defer_ns: int
                   ) -> list[tuple[PlannedMotion, object]]:
        """
        Ramp toward ``factor`` from ``from_ns``; return the delayed motions dropped.

        Each as ``(motion, tag)``, ``tag`` as :meth:`splice` was given it.

        The change waits for motions spliced to start within ``defer_ns`` after
        ``from_ns`` (planned from the state the old ramp gave there). A motion delayed
        further keeps its start (wall time) if the state it was planned from is still
        the one there (the motion before it at rest there, say); else it would jump, and
        it is dropped.
        """
        near = [s.start for s in self._segments if from_ns <= s.start <= from_ns + defer_ns]
        from_ns = max([from_ns] + near)
        self.time_map.set_target(factor, from_ns, self._own_state)
        later = [segment for segment in self._segments if segment.start > from_ns]
        self._segments = [segment for segment in self._segments if segment.start <= from_ns]
        for index, segment in enumerate(later):
            self.time_map.forget()
            scaled = segment.clock is not None
            start = self.plan_state(segment.start) if scaled else self.setpoint(segment.start)
            planned = state_at(segment.motion.plan, 0.0)
            if not (np.allclose(start.position, planned[0], rtol=0.0, atol=1e-9)
                    and np.allclose(start.velocity, planned[1], rtol=0.0, atol=1e-9)):
                return [(dropped.motion, dropped.tag)  # the rest were planned after it
                        for dropped in later[index:]]
            self.splice(segment.start, segment.motion, from_ns, segment.tag)
        return []

    @property
    def pending(self) -> int:
        """Return the number of motions kept (the running one and delayed ones)."""
        return len(self._segments)
