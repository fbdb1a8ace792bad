"""
Steps 4 and 5, *splice* and *publish*: the setpoint every ``1/rate_hz`` s, in a thread.

The :class:`Stream` owns the :class:`~traj_gen_ros.node.stream.schedule.Schedule` (in a
:class:`~traj_gen_ros.node.stream.state.StreamState`, under its lock) and the thread that
samples it. Each tick has a deadline on a fixed grid of the node clock (absolute times, so
a late wake-up does not shift the ticks after it); at the deadline the thread samples the
schedule at the current time and publishes the ``JointState`` bytes
(:mod:`traj_gen_ros.node.stream.tick_publisher`). A new motion is planned from the
schedule's state at a tick the stream has not published yet (:meth:`Stream.next_start`),
or at the last setpoint it published (:meth:`Stream.last_published`), and spliced in
there (:meth:`Stream.splice`) if the stream has published nothing after it. So every
setpoint published is the old motion's before the switch or the new one's after it (the
last published setpoint, exactly both), and position, velocity and acceleration are
continuous at the switch.

Speed scaling (:mod:`traj_gen_ros.node.speed.time_map`): the schedule's scaled motions
run on the plan clock of a :class:`~traj_gen_ros.node.speed.time_map.TimeMap`;
:attr:`Stream.speed` (:mod:`traj_gen_ros.node.stream.speed_view`) ramps it toward a new
factor from the next tick not yet published, every published tick fixes the ramp up to
it, and a request is planned from the running plan's own state
(:meth:`Stream.start_state`). A plan whose start state a factor change moved since it was
planned is not spliced (the request is planned again).

Late ticks (:mod:`traj_gen_ros.node.stream.clock`): the schedule and the ramp run on the
stream clock, held back at a late tick so that the setpoint after a stall continues from
the last one. Times in and out of :class:`Stream` are node times; a plan whose start
state a late tick moved is planned again, as for a factor change.

The thread is a :class:`~traj_gen_ros.node.stream.ticker.Ticker` (a fixed grid of the node
clock). On a busy machine it asks for a real-time priority (``SCHED_FIFO``) and, if that
is not permitted, a lower nice value; if neither is, it runs as it is
(:func:`traj_gen_ros.node.stream.realtime.raise_priority`). Requests and planning run on the
request thread: they hold the GIL for at most the interpreter's switch interval at a time
while the stream waits for it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import threading

import numpy as np
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.clock import StreamClock
from traj_gen_ros.node.stream.output import SetpointOutput
from traj_gen_ros.node.stream.speed_view import SpeedView
from traj_gen_ros.node.stream.state import StreamState
from traj_gen_ros.node.stream.tick_publisher import TickPublisher
from traj_gen_ros.node.stream.ticker import Ticker


class Stream:
    """The schedule of motions and the thread that publishes its setpoint every period."""

    def __init__(self, first: PlannedMotion, joint_names: Sequence[str],
                 now_ns: Callable[[], int], period_ns: Callable[[], int],
                 publish: Callable[[bytes], None], on_error: Callable[[str], None],
                 waiting: bool = False,
                 publish_command: Callable[[np.ndarray, np.ndarray], None] | None = None,
                 time_map: TimeMap | None = None,
                 publish_factor: Callable[[float], None] | None = None,
                 on_late: Callable[[int, int], None] | None = None,
                 hold_back: bool = True,
                 simulated: Callable[[], bool] | None = None) -> None:
        """
        Prepare to stream ``first`` (a hold); :meth:`start` starts the thread.

        ``waiting``: publish nothing until :meth:`seed` gives the first setpoint (the
        measured state of ``joint_topic``).

        :param now_ns: the node clock, integer nanoseconds.
        :param period_ns: the current stream period (read every tick: ``rate_hz`` may change).
        :param publish: sends one serialised ``JointState``.
        :param publish_command: sends the command of the same setpoint, given its positions
            (rad) and velocities (rad/s): ``command_out_topic``'s ``Float64MultiArray``
            (:mod:`traj_gen_ros.node.robot.commands_out` writes it), or None.
        :param on_error: logs a failed publish (the stream goes on).
        :param time_map: the speed scaling ramp and plan clock (None: a factor of 1).
        :param publish_factor: forwards the effective factor when it changes (from the
            stream thread; ``speed_scaling_output_topic``), or None.
        :param on_late: told each late tick (the stream thread, after it published): the
            gap since the setpoint before and how much of it was held back (ns), or None.
        :param hold_back: hold the schedule back at late ticks (:mod:`.clock`); False:
            sample it at the node time whatever the gap.
        :param simulated: whether the node clock is a simulated one (``/clock``) now;
            None: never.
        """
        self._ticker = Ticker(now_ns, period_ns, on_error)
        clock = StreamClock(self._ticker.behind_ns, simulated or (lambda: False), hold_back)
        self._state = StreamState(first, time_map if time_map is not None
                                  else TimeMap(np.ones(1)), clock, now_ns(), waiting)
        self._ticks = TickPublisher(
            self._state, SetpointOutput(joint_names, publish, publish_command, publish_factor),
            now_ns, period_ns, on_error, on_late)
        #: The speed override's side: the factor, the ramp's limits, the plan time left.
        self.speed = SpeedView(self._state)
        # Per thread: the ramp's version and the hold-back that start_state saw.
        self._versions: dict[int, tuple[int, int]] = {}
        self._now_ns, self._period_ns = now_ns, period_ns
        self.stopping = self._ticker.stopping

    def start(self) -> str:
        """Start the streaming thread; return the priority it got (:class:`Ticker`)."""
        return self._ticker.start(self._ticks)

    def stop(self, timeout: float = 2.0) -> None:
        """Ask the thread to end and wait for it (s)."""
        self._ticker.stop(timeout)

    def seed(self, position: np.ndarray) -> None:
        """Replace the schedule by a hold at ``position`` (rad) and start publishing."""
        with self._state.lock:
            self._state.seed(position)

    @property
    def waiting(self) -> bool:
        """Whether the stream waits for its first setpoint (:meth:`seed`)."""
        return self._state.waiting

    def next_start(self, margin_ns: int = 0) -> int:
        """
        Return the first tick (ns) not yet published and at least ``margin_ns`` from now.

        A new motion spliced at that time is published by the stream at that tick. While
        the next setpoint is overdue (a late tick, :mod:`.clock`), the last one published:
        a motion spliced there is out at the late tick.
        """
        period_ns = self._period_ns()
        state = self._state
        with state.lock:
            tick, last = state.next_tick_ns, state.last_published_ns
        now_ns = self._now_ns()
        if state.clock.overdue(now_ns, last, period_ns):
            return last
        earliest = max(last + 1, now_ns + margin_ns)
        if tick < earliest:
            tick += -(-(earliest - tick) // period_ns) * period_ns
        return tick

    def start_state(self, time_ns: int, scaled: bool = True) -> tuple[State, np.ndarray]:
        """
        Return the state to plan from at ``time_ns`` and where the schedule rests (rad).

        ``scaled`` (a goal, via points): the running plan's own state, where a scaled
        motion spliced at ``time_ns`` starts (:meth:`Schedule.scaled_start`); else (a
        brake) the commanded setpoint. The ramp's version and the hold-back are noted
        for :meth:`splice`.
        """
        state = self._state
        with state.lock:
            schedule = state.schedule
            self._versions[threading.get_ident()] = (state.time_map.version,
                                                     state.clock.held_ns)
            at = state.clock.at(time_ns)
            if scaled:
                start = schedule.plan_state(schedule.scaled_start(at))
            else:
                start = schedule.setpoint(at)
            return start, schedule.end_position(at)

    def running_at(self, time_ns: int) -> tuple[PlannedMotion, float]:
        """Return the motion in effect at ``time_ns`` and its own time there (s)."""
        state = self._state
        with state.lock:
            return state.schedule.running(state.clock.at(time_ns))

    def setpoint(self, time_ns: int) -> State:
        """Return the commanded setpoint at ``time_ns`` (not before the last published)."""
        with self._state.lock:
            return self._state.schedule.setpoint(self._state.clock.at(time_ns))

    def moving_at(self, time_ns: int) -> bool:
        """Tell whether the schedule is in motion at ``time_ns`` (a plan not yet at its end)."""
        with self._state.lock:
            return self._state.schedule.moving_at(self._state.clock.at(time_ns))

    def last_published(self) -> int:
        """
        Return when the last setpoint was sampled (ns): a start that nothing published follows.

        The schedule's state then is exactly that setpoint, so a motion planned from it
        and spliced there before the next tick (:meth:`splice`) continues it seamlessly.
        """
        with self._state.lock:
            return self._state.last_published_ns

    def last_sent(self) -> tuple[int, bool]:
        """
        Return when the last setpoint already on the wire was sampled (ns), and if it moved.

        At most :meth:`last_published`: a setpoint is sampled under the lock and sent after
        it. An answer judged on this one (an action goal's end) never reaches a client
        before the setpoint it was judged on has been sent. Whether the schedule was in
        motion there is recorded when it was sampled (the speed ramp commits the next tick
        before it is sent: asked later, the plan time there would be the next tick's).
        """
        with self._state.lock:
            return self._state.sent_ns, self._state.sent_moving

    def splice(self, start_ns: int, motion: PlannedMotion, tag: object = None) -> int | None:
        """
        Run ``motion`` from ``start_ns``; return the tick (ns) of its first setpoint.

        ``tag`` (the request) comes back from :meth:`SpeedView.set_factor` if the motion
        is dropped.

        That is ``start_ns`` itself if the stream has not got there yet, or the next tick
        if ``start_ns`` is the last setpoint published. ``None``, splicing nothing, if the
        stream has published a setpoint after ``start_ns``: the motion would jump. Nor if
        a late tick held the schedule back since :meth:`start_state`: planned again.
        """
        state = self._state
        with state.lock:
            if state.last_published_ns > start_ns:
                return None
            if self._versions.pop(threading.get_ident(), None) not in (
                    None, (state.time_map.version, state.clock.held_ns)):
                return None  # the factor or the hold-back changed since: plan it again
            at = state.clock.at(start_ns)
            if not motion.unscaled and motion.plan.duration > 0.0:
                at = state.schedule.scaled_start(at)
                start_ns = state.clock.node(at)
            first_ns = start_ns
            if state.last_published_ns == start_ns:
                first_ns = state.next_tick_ns
                if first_ns <= state.last_tick_ns:  # the stream is between two ticks
                    first_ns = state.last_tick_ns + self._period_ns()
            # What ran before the last setpoint published is no longer needed.
            state.schedule.splice(at, motion, state.published_at(), tag)
            return first_ns

    def wait_published(self, time_ns: int, timeout: float) -> bool:
        """
        Wait until the stream has published a setpoint at or after ``time_ns``.

        At most ``timeout`` s; True once published. The node answers a request after its
        first setpoint is out, so a client that reads the answer sees the motion started.
        """
        state = self._state
        with state.published:
            return state.published.wait_for(
                lambda: state.sent_ns >= time_ns or self.stopping.is_set(), timeout)
