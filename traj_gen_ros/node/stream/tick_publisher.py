"""
The stream thread's tick: the schedule sampled under the lock, the setpoint sent after it.

At each tick of the :class:`~traj_gen_ros.node.stream.ticker.Ticker` (a
:class:`~traj_gen_ros.node.stream.ticker.TickTarget`), :meth:`TickPublisher.tick` samples
the schedule at the current node time (the stream time: held back if the tick is late,
:mod:`traj_gen_ros.node.stream.clock`), fixes the speed ramp up to it and notes it as the
last setpoint published, all under the stream's lock
(:class:`~traj_gen_ros.node.stream.state.StreamState`). Outside the lock it sends it
(:class:`~traj_gen_ros.node.stream.output.SetpointOutput`: ``joint_states`` first), then
marks it sent and wakes whoever waits for it. A setpoint that is not finite is never
published: the stream holds the last one from then on.

Times are node-clock integer nanoseconds; positions rad, velocities rad/s. No ROS here.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from traj_gen_ros.node.planning.motion import held
from traj_gen_ros.node.stream.output import SetpointOutput
from traj_gen_ros.node.stream.state import StreamState


class TickPublisher:
    """What the stream thread does at each tick (see the module doc)."""

    def __init__(self, state: StreamState, output: SetpointOutput, now_ns: Callable[[], int],
                 period_ns: Callable[[], int], on_error: Callable[[str], None],
                 on_late: Callable[[int, int], None] | None = None) -> None:
        """
        Sample ``state``'s schedule and send it through ``output``.

        :param now_ns: the node clock, integer nanoseconds.
        :param period_ns: the current stream period (ns, read every tick).
        :param on_error: logs a non-finite setpoint (held instead).
        :param on_late: told each late tick (after it was sent): the gap since the
            setpoint before and how much of it was held back (ns), or None.
        """
        self._state, self._output = state, output
        self._now_ns, self._period_ns = now_ns, period_ns
        self._on_error, self._on_late = on_error, on_late

    def next_deadline(self, tick_ns: int) -> None:
        """Note the tick (ns) the thread waits for next: a motion spliced for it starts there."""
        with self._state.lock:
            self._state.next_tick_ns = tick_ns

    def tick(self, tick_ns: int) -> None:
        """
        Sample the schedule now and publish it as the setpoint of tick ``tick_ns``.

        At the stream time of now: held back if this tick is late (:mod:`.clock`).
        """
        state = self._state
        with state.lock:
            now_ns = self._now_ns()
            if now_ns <= state.last_published_ns or state.waiting:
                return  # the clock has not moved on (simulated time), or nothing to stream
            last_ns, held_ns = state.last_published_ns, state.clock.held_ns
            at = state.clock.sample(now_ns, last_ns, self._period_ns())
            late_ns = state.clock.held_ns - held_ns
            schedule = state.schedule
            setpoint = schedule.setpoint(at)
            moving = schedule.moving_at(at)
            schedule.commit(at)
            factor = schedule.factor_at(at) if self._output.wants_factor else 0.0
            position, velocity = setpoint.position, setpoint.velocity
            finite = np.count_nonzero(np.isfinite(position)) + \
                np.count_nonzero(np.isfinite(velocity)) == 2 * position.size
            if not finite:  # never published: hold the last setpoint from now on
                position, velocity = state.last_position, np.zeros_like(state.last_position)
                schedule.splice(at, held(position), at)
            state.last_position = position
            state.last_published_ns = now_ns
            state.last_tick_ns = tick_ns
        if not finite:
            self._on_error('stream: the schedule gave a non-finite setpoint: holding')
        self._output.joint_state(now_ns, position, velocity)
        try:
            self._output.command_and_factor(position, velocity, factor)
        finally:  # joint_states is out (a failure after it is logged by the ticker)
            with state.published:
                state.sent_ns, state.sent_moving = now_ns, moving and finite
                state.published.notify_all()
            if late_ns and self._on_late is not None:
                self._on_late(now_ns - last_ns, late_ns)
