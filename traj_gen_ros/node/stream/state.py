"""
What the stream's parts share under one lock: the schedule, its clock, what was published.

The request side (:class:`~traj_gen_ros.node.stream.stream.Stream`: a motion planned from
the schedule and spliced into it), the stream thread
(:class:`~traj_gen_ros.node.stream.tick_publisher.TickPublisher`: a setpoint sampled and
sent every tick) and the speed override
(:class:`~traj_gen_ros.node.stream.speed_view.SpeedView`: the ramp's factor) read and
change a :class:`StreamState` only while they hold its :attr:`~StreamState.lock`;
:attr:`~StreamState.published`, a condition on the same lock, is notified when a setpoint
is on the wire. A plain record: the rules of its use are its users'.

Times are node-clock integer nanoseconds (:attr:`~StreamState.clock` turns them into the
schedule's, :mod:`traj_gen_ros.node.stream.clock`); positions rad. No ROS here.
"""

from __future__ import annotations

import threading

import numpy as np
from traj_gen_ros.node.planning.motion import held, PlannedMotion
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.clock import StreamClock
from traj_gen_ros.node.stream.schedule import BEGINNING_NS, Schedule

#: "Never": the marks before the first setpoint is sent (ns).
NEVER_NS = -(2 ** 62)


class StreamState:
    """The schedule, its clock and the marks of the last setpoint, guarded by :attr:`lock`."""

    def __init__(self, first: PlannedMotion, time_map: TimeMap, clock: StreamClock,
                 next_tick_ns: int, waiting: bool = False) -> None:
        """
        Start with ``first`` (a hold) in effect and nothing published.

        :param time_map: the speed ramp and plan clock the schedule's motions run on.
        :param clock: node time → the schedule's time, held back by late ticks.
        :param next_tick_ns: the first tick to come (ns).
        :param waiting: publish nothing until :meth:`seed` gives the first setpoint.
        """
        #: Guards every field; :attr:`published` waits on it.
        self.lock = threading.Lock()
        #: Notified when a setpoint has been sent (:attr:`sent_ns`).
        self.published = threading.Condition(self.lock)
        self.time_map = time_map
        self.schedule = Schedule(first, time_map)
        self.clock = clock
        #: Whether the stream waits for its first setpoint (:meth:`seed`).
        self.waiting = waiting
        #: The last setpoint published (rad).
        self.last_position = first.end.copy()
        #: When the last setpoint was sampled (ns).
        self.last_published_ns = BEGINNING_NS
        #: When the last setpoint sampled is also on the wire (ns), and whether the
        #: schedule moved at it (noted when it was sampled).
        self.sent_ns, self.sent_moving = NEVER_NS, False
        #: The tick (deadline, ns) the last setpoint was published for, and the next one.
        self.last_tick_ns, self.next_tick_ns = NEVER_NS, next_tick_ns

    def seed(self, position: np.ndarray) -> None:
        """Replace the schedule by a hold at ``position`` (rad); stop waiting (lock held)."""
        self.schedule = Schedule(held(position), self.time_map)
        self.last_position = np.array(position, dtype=float)
        self.waiting = False

    def published_at(self) -> int:
        """Return the stream time (ns) of the last setpoint published (lock held)."""
        return self.clock.at(self.last_published_ns)
