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

A tick is late when the node clock moved on more than :data:`LATE_PERIODS` periods since
the last setpoint (``t - t_last``). On a simulated clock (``use_sim_time``: ``/clock`` may
move in steps of any size, and the robot runs on it) only if the stream thread itself was
kept from its schedule that long too (the monotonic clock, as
:meth:`~traj_gen_ros.node.stream.ticker.Ticker.behind_ns` measures it: since it last
waited on time for a deadline): a clock that jumps while the thread waits on time is
followed, a stalled node is held back.

Integer nanoseconds; no ROS here; not thread-safe (the stream's lock guards it).
"""

from __future__ import annotations

from collections.abc import Callable

#: The stream clock advances at most this many periods between two setpoints published
#: one after the other: a tick later than that is held back by the rest.
LATE_PERIODS = 2


class StreamClock:
    """Node time → the schedule's time, held back by late ticks (ns)."""

    def __init__(self, behind_ns: Callable[[bool], int] = lambda peek: 0,
                 simulated: Callable[[], bool] = lambda: False, hold_back: bool = True) -> None:
        """
        Start with no hold-back: the stream clock is the node clock.

        :param behind_ns: how long the stream thread has been behind its schedule (ns,
            monotonic; its argument ``peek``: False at a sample, which starts it again):
            :meth:`~traj_gen_ros.node.stream.ticker.Ticker.behind_ns`.
        :param simulated: whether the node clock is a simulated one now (``/clock``).
        :param hold_back: False: never hold back (the plans go to a controller that runs
            them on its own clock: holding the stream back would put it behind them).
        """
        self._behind_ns, self._simulated, self._hold_back = behind_ns, simulated, hold_back
        self._period_ns = 0  # the period when the last setpoint was sampled
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

    def _late(self, now_ns: int, last_ns: int, period_ns: int, behind_ns: int) -> bool:
        # A rate_hz change: the gap is the old period's (the tick was due on its grid).
        allowance = self.allowance(max(period_ns, self._period_ns))
        return (self._hold_back and last_ns > -(2 ** 61) and now_ns - last_ns > allowance
                and (not self._simulated() or behind_ns > allowance))

    def overdue(self, now_ns: int, last_ns: int, period_ns: int) -> bool:
        """
        Tell whether a setpoint sampled at node time ``now_ns`` would be a late tick.

        ``last_ns``: when the last setpoint was sampled (node clock). Nothing is overdue
        before the first setpoint.
        """
        return self._late(now_ns, last_ns, period_ns, self._behind_ns(True))

    def sample(self, now_ns: int, last_ns: int, period_ns: int) -> int:
        """
        Return the stream time (ns) to sample a setpoint published at node time ``now_ns``.

        ``last_ns`` is when the one before it was sampled (node clock). A late tick
        (:meth:`overdue`) holds the clock back: the result is the last setpoint's stream
        time plus :meth:`allowance`, and :attr:`held_ns` grows by the rest of the gap.
        """
        if self._late(now_ns, last_ns, period_ns, self._behind_ns(False)):
            self.held_ns += now_ns - last_ns - self.allowance(max(period_ns, self._period_ns))
            self.late_ticks += 1
        self._period_ns = period_ns
        return now_ns - self.held_ns
