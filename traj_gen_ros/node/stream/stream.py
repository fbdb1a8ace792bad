"""
Steps 4 and 5, *splice* and *publish*: the setpoint every ``1/rate_hz`` s, in a thread.

The :class:`Stream` owns the :class:`~traj_gen_ros.node.stream.schedule.Schedule` and the thread
that
samples it. Each tick has a deadline on a fixed grid of the node clock (absolute times, so
a late wake-up does not shift the ticks after it); at the deadline the thread samples the
schedule at the current time and publishes the ``JointState`` bytes. A new motion is
planned from the schedule's state at a tick the stream has not published yet
(:meth:`Stream.next_start`), or at the last setpoint it published
(:meth:`Stream.last_published`), and spliced in there (:meth:`Stream.splice`) if the
stream has published nothing after it. So every setpoint published is the old motion's
before the switch or the new one's after it (the last published setpoint, exactly both),
and position, velocity and acceleration are continuous at the switch.

Speed scaling (:mod:`traj_gen_ros.node.speed.time_map`): the schedule's scaled motions
run
on the plan clock of a :class:`~traj_gen_ros.node.speed.time_map.TimeMap`;
:meth:`Stream.set_factor`
ramps it toward a new factor from the next tick not yet published, every published tick
fixes the ramp up to it, and a request is planned from the running plan's own state
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
from traj_gen_ros.node.planning.motion import held, PlannedMotion, State
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.clock import StreamClock
from traj_gen_ros.node.stream.output import SetpointOutput
from traj_gen_ros.node.stream.schedule import BEGINNING_NS, Schedule
from traj_gen_ros.node.stream.ticker import Ticker

#: A factor change waits for a motion spliced to start within this long (ns).
FACTOR_DEFER_NS = 500_000_000


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
        self._time_map = time_map if time_map is not None else TimeMap(np.ones(1))
        self._schedule = Schedule(first, self._time_map)
        self._on_late = on_late
        self._output = SetpointOutput(joint_names, publish, publish_command, publish_factor)
        # Per thread: the ramp's version and the hold-back that start_state saw.
        self._versions: dict[int, tuple[int, int]] = {}
        self._last_position = first.end.copy()  # the last setpoint published (rad)
        self._now_ns = now_ns
        self._period_ns = period_ns
        self._on_error = on_error
        # Guards the schedule, the last published time and the next tick; notified when a
        # setpoint has been published.
        self._lock = threading.Lock()
        self._published = threading.Condition(self._lock)
        self._last_published_ns = BEGINNING_NS  # when the last setpoint was sampled
        self._sent_ns = -(2 ** 62)  # when the last setpoint sampled is also on the wire
        self._sent_moving = False  # whether the schedule moved at that setpoint
        self._last_tick_ns = -(2 ** 62)  # the tick (deadline) it was published for
        self._next_tick_ns = now_ns()
        self._waiting = waiting
        self._ticker = Ticker(now_ns, period_ns, self._next_deadline, self._publish_tick,
                              on_error)
        self._clock = StreamClock(self._ticker.behind_ns, simulated or (lambda: False),
                                  hold_back)
        self.stopping = self._ticker.stopping

    def start(self) -> str:
        """Start the streaming thread; return the priority it got (:class:`Ticker`)."""
        return self._ticker.start()

    def stop(self, timeout: float = 2.0) -> None:
        """Ask the thread to end and wait for it (s)."""
        self._ticker.stop(timeout)

    # ------------------------------------------------------------------ executor side

    def seed(self, position: np.ndarray) -> None:
        """Replace the schedule by a hold at ``position`` (rad) and start publishing."""
        with self._lock:
            self._schedule = Schedule(held(position), self._time_map)
            self._last_position = np.array(position, dtype=float)
            self._waiting = False

    @property
    def waiting(self) -> bool:
        """Whether the stream waits for its first setpoint (:meth:`seed`)."""
        return self._waiting

    def next_start(self, margin_ns: int = 0) -> int:
        """
        Return the first tick (ns) not yet published and at least ``margin_ns`` from now.

        A new motion spliced at that time is published by the stream at that tick. While
        the next setpoint is overdue (a late tick, :mod:`.clock`), the last one published:
        a motion spliced there is out at the late tick.
        """
        period_ns = self._period_ns()
        with self._lock:
            tick, last = self._next_tick_ns, self._last_published_ns
        now_ns = self._now_ns()
        if self._clock.overdue(now_ns, last, period_ns):
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
        with self._lock:
            schedule = self._schedule
            self._versions[threading.get_ident()] = (self._time_map.version,
                                                     self._clock.held_ns)
            at = self._clock.at(time_ns)
            if scaled:
                state = schedule.plan_state(schedule.scaled_start(at))
            else:
                state = schedule.setpoint(at)
            return state, schedule.end_position(at)

    def setpoint(self, time_ns: int) -> State:
        """Return the commanded setpoint at ``time_ns`` (not before the last published)."""
        with self._lock:
            return self._schedule.setpoint(self._clock.at(time_ns))

    def set_factor(self, factor: float) -> list[tuple[PlannedMotion, object]]:
        """
        Ramp the speed scaling toward ``factor`` (in [0, 1]) from the last setpoint on.

        From the first 1 ms grid time after the last setpoint published: the next tick
        already shows it.

        Returns the delayed motions dropped because the change moved the state they were
        planned from, with the ``tag`` each was spliced with (:meth:`Schedule.set_factor`).
        """
        with self._lock:
            from_ns = self._clock.at(self._last_published_ns) + 1
            return self._schedule.set_factor(factor, from_ns, FACTOR_DEFER_NS)

    def set_scaling_limits(self, max_acceleration: np.ndarray,
                           max_jerk: np.ndarray | None) -> None:
        """Ramp within ``max_acceleration`` (rad/s²) and ``max_jerk`` (rad/s³, or None)."""
        with self._lock:
            self._time_map.set_limits(max_acceleration, max_jerk)

    def factor_in_force(self) -> float:
        """Return the effective (ramped) factor at the last published setpoint."""
        with self._lock:
            return self._schedule.factor_at(max(self._clock.at(self._last_published_ns), 0))

    def time_left(self, time_ns: int) -> float:
        """Return the plan time (s) left at ``time_ns`` (:meth:`Schedule.time_left`)."""
        with self._lock:
            return self._schedule.time_left(
                self._clock.at(max(time_ns, self._last_published_ns)))

    def moving_at(self, time_ns: int) -> bool:
        """Tell whether the schedule is in motion at ``time_ns`` (a plan not yet at its end)."""
        with self._lock:
            return self._schedule.moving_at(self._clock.at(time_ns))

    def last_published(self) -> int:
        """
        Return when the last setpoint was sampled (ns): a start that nothing published follows.

        The schedule's state then is exactly that setpoint, so a motion planned from it
        and spliced there before the next tick (:meth:`splice`) continues it seamlessly.
        """
        with self._lock:
            return self._last_published_ns

    def last_sent(self) -> tuple[int, bool]:
        """
        Return when the last setpoint already on the wire was sampled (ns), and if it moved.

        At most :meth:`last_published`: a setpoint is sampled under the lock and sent after
        it. An answer judged on this one (an action goal's end) never reaches a client
        before the setpoint it was judged on has been sent. Whether the schedule was in
        motion there is recorded when it was sampled (the speed ramp commits the next tick
        before it is sent: asked later, the plan time there would be the next tick's).
        """
        with self._lock:
            return self._sent_ns, self._sent_moving

    def splice(self, start_ns: int, motion: PlannedMotion, tag: object = None) -> int | None:
        """
        Run ``motion`` from ``start_ns``; return the tick (ns) of its first setpoint.

        ``tag`` (the request) comes back from :meth:`set_factor` if the motion is dropped.

        That is ``start_ns`` itself if the stream has not got there yet, or the next tick
        if ``start_ns`` is the last setpoint published. ``None``, splicing nothing, if the
        stream has published a setpoint after ``start_ns``: the motion would jump. Nor if
        a late tick held the schedule back since :meth:`start_state`: planned again.
        """
        with self._lock:
            if self._last_published_ns > start_ns:
                return None
            if self._versions.pop(threading.get_ident(), None) not in (
                    None, (self._time_map.version, self._clock.held_ns)):
                return None  # the factor or the hold-back changed since: plan it again
            at = self._clock.at(start_ns)
            if not motion.unscaled and motion.plan.duration > 0.0:
                at = self._schedule.scaled_start(at)
                start_ns = self._clock.node(at)
            first_ns = start_ns
            if self._last_published_ns == start_ns:
                first_ns = self._next_tick_ns
                if first_ns <= self._last_tick_ns:  # the stream is between two ticks
                    first_ns = self._last_tick_ns + self._period_ns()
            # What ran before the last setpoint published is no longer needed.
            self._schedule.splice(at, motion, self._clock.at(self._last_published_ns), tag)
            return first_ns

    def wait_published(self, time_ns: int, timeout: float) -> bool:
        """
        Wait until the stream has published a setpoint at or after ``time_ns``.

        At most ``timeout`` s; True once published. The node answers a request after its
        first setpoint is out, so a client that reads the answer sees the motion started.
        """
        with self._published:
            return self._published.wait_for(
                lambda: self._sent_ns >= time_ns or self.stopping.is_set(), timeout)

    # ------------------------------------------------------------------ stream thread

    def _next_deadline(self, tick_ns: int) -> None:
        with self._lock:
            self._next_tick_ns = tick_ns

    def _publish_tick(self, tick_ns: int) -> None:
        """
        Sample the schedule now and publish it as the setpoint of tick ``tick_ns``.

        At the stream time of now: held back if this tick is late (:mod:`.clock`).
        """
        with self._lock:
            now_ns = self._now_ns()
            if now_ns <= self._last_published_ns or self._waiting:
                return  # the clock has not moved on (simulated time), or nothing to stream
            last_ns, held_ns = self._last_published_ns, self._clock.held_ns
            at = self._clock.sample(now_ns, last_ns, self._period_ns())
            late_ns = self._clock.held_ns - held_ns
            state = self._schedule.setpoint(at)
            moving = self._schedule.moving_at(at)
            self._schedule.commit(at)
            factor = self._schedule.factor_at(at) if self._output.wants_factor else 0.0
            position, velocity = state.position, state.velocity
            finite = np.count_nonzero(np.isfinite(position)) + \
                np.count_nonzero(np.isfinite(velocity)) == 2 * position.size
            if not finite:  # never published: hold the last setpoint from now on
                position, velocity = self._last_position, np.zeros_like(self._last_position)
                self._schedule.splice(at, held(position), at)
            self._last_position = position
            self._last_published_ns = now_ns
            self._last_tick_ns = tick_ns
        if not finite:
            self._on_error('stream: the schedule gave a non-finite setpoint: holding')
        self._output.joint_state(now_ns, position, velocity)
        try:
            self._output.command_and_factor(position, velocity, factor)
        finally:  # joint_states is out (a failure after it is logged by the ticker)
            with self._published:
                self._sent_ns, self._sent_moving = now_ns, moving and finite
                self._published.notify_all()
            if late_ns and self._on_late is not None:
                self._on_late(now_ns - last_ns, late_ns)
