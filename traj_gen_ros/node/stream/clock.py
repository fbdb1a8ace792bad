"""
The schedule's clock: node time held back by late ticks, so that the command never jumps.

The stream samples its schedule at the current node time ``t``. When a setpoint goes out
long after the one before it (the stream thread could not run: a stalled machine, a
SIGSTOP, a DDS call that blocked it, eProsima/Fast-DDS#6535), sampling at ``t`` would
jump by what the plan moved meanwhile: on a robot behind a position controller, that
much motion at once. So the schedule, and the speed override's plan clock with it
(:class:`~traj_gen_ros.node.speed.time_map.TimeMap`), run on the *stream clock*
``s = t - h``: at a late tick the hold-back ``h`` grows by the gap minus
:data:`LATE_PERIODS` periods, so the setpoint published after the stall is the
schedule's state :data:`LATE_PERIODS` periods after the last one, as if only that much
time had passed. Position, velocity and acceleration continue from the last setpoint
published, and everything after it (a motion's end, a delayed request's start, the
speed ramp) happens ``h`` later in node time.

A tick is late when both hold:

* the node clock moved on more than :data:`LATE_PERIODS` periods since the last setpoint
  (``t - t_last``), and
* the stream thread itself went that long without running (the monotonic clock, as
  :meth:`~traj_gen_ros.node.stream.ticker.Ticker.idle_ns` measures it): a simulated
  clock (``use_sim_time``) that moves in steps larger than that is followed, not held
  back, since the thread was awake all along and the robot runs on that clock.

Integer nanoseconds; no ROS here; not thread-safe (the stream's lock guards it).
"""

from __future__ import annotations

#: The stream clock advances at most this many periods between two setpoints published
#: one after the other: a tick later than that is held back by the rest.
LATE_PERIODS = 2


class StreamClock:
    """Node time → the schedule's time, held back by late ticks (ns)."""

    def __init__(self) -> None:
        """Start with no hold-back: the stream clock is the node clock."""
        #: How far the stream clock is behind the node clock (ns), the late ticks' sum.
        self.held_ns = 0
        #: How many ticks were late (held back).
        self.late_ticks = 0

    def at(self, node_ns: int) -> int:
        """
        Return the stream time (ns) of node time ``node_ns`` at the current hold-back.

        Exact for the last setpoint published and every time after it (ticks to come are
        on the node clock's grid until a late tick holds them back too).
        """
        return node_ns - self.held_ns

    def node(self, stream_ns: int) -> int:
        """Return the node time (ns) of stream time ``stream_ns`` at the current hold-back."""
        return stream_ns + self.held_ns

    @staticmethod
    def allowance(period_ns: int) -> int:
        """Return the most the stream clock advances between two setpoints (ns)."""
        return LATE_PERIODS * period_ns

    def overdue(self, now_ns: int, last_ns: int, period_ns: int, idle_ns: int) -> bool:
        """
        Tell whether the next setpoint will be a late tick, seen at node time ``now_ns``.

        ``last_ns``: when the last setpoint was sampled (node clock); ``idle_ns``: how
        long the stream thread has not run (monotonic clock). Nothing is overdue before
        the first setpoint.
        """
        allowance = self.allowance(period_ns)
        return last_ns > -(2 ** 61) and now_ns - last_ns > allowance and idle_ns > allowance

    def sample(self, now_ns: int, last_ns: int, period_ns: int, idle_ns: int) -> int:
        """
        Return the stream time (ns) to sample a setpoint published at node time ``now_ns``.

        ``last_ns`` is when the one before it was sampled (node clock) and ``idle_ns`` the
        longest the stream thread went without running since (monotonic). A late tick
        (:meth:`overdue`) holds the clock back: the result is the last setpoint's stream
        time plus :meth:`allowance`, and :attr:`held_ns` grows by the rest of the gap.
        """
        if self.overdue(now_ns, last_ns, period_ns, idle_ns):
            self.held_ns += now_ns - last_ns - self.allowance(period_ns)
            self.late_ticks += 1
        return now_ns - self.held_ns
