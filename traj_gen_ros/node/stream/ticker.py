"""
A thread that drives a :class:`TickTarget` at every tick of a fixed grid of the node clock.

Deadlines are absolute (``t0 + k · period``, the period read before each tick: ``rate_hz``
may change), so a late wake-up does not shift the ticks after it; a tick a period or more
late (a stalled machine, a simulated clock that jumps) restarts the grid from now and no
tick is caught up. The thread asks for a real-time priority first
(:func:`traj_gen_ros.node.stream.realtime.raise_priority`). It also notes on the
monotonic clock when it was last on time (waiting for a deadline still ahead, or at a
tick's sample), so :meth:`Ticker.behind_ns` tells how long it has been kept from its
schedule: a late tick of a stalled thread (:mod:`traj_gen_ros.node.stream.clock`), not of
a simulated clock that moves in big steps while the thread waits on time. Times are
integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Callable
import threading
import time
from typing import Protocol

from traj_gen_ros.node.stream.realtime import raise_priority


class TickTarget(Protocol):
    """What the ticker drives at each deadline (ns): the stream's tick (``TickPublisher``)."""

    def next_deadline(self, tick_ns: int) -> None:
        """Take the next deadline, before the thread waits for it."""

    def tick(self, tick_ns: int) -> None:
        """Do the work of the tick due at ``tick_ns``; what it raises is logged."""


class Ticker:
    """The stream's thread: ``tick(deadline)`` at each deadline of a fixed grid (ns)."""

    def __init__(self, now_ns: Callable[[], int], period_ns: Callable[[], int],
                 on_error: Callable[[str], None]) -> None:
        """
        Prepare the thread; :meth:`start` starts it, driving a :class:`TickTarget`.

        :param now_ns: the node clock (ns).
        :param period_ns: the period (ns), read before each tick.
        :param on_error: logs what a tick raised (the ticks go on).
        """
        self._now_ns, self._period_ns, self._on_error = now_ns, period_ns, on_error
        self._target: TickTarget | None = None
        self.stopping = threading.Event()
        self.priority = 'not started'
        self._started = threading.Event()
        self._thread = threading.Thread(target=self._run, name='stream', daemon=True)
        #: The monotonic clock (ns) on which the thread notes when it was on time.
        self.monotonic_ns: Callable[[], int] = time.monotonic_ns
        self._on_time_ns = self.monotonic_ns()

    def behind_ns(self, peek: bool = False) -> int:
        """
        Return how long the thread has been behind its schedule (ns, monotonic clock).

        Since it last waited for a deadline still ahead, or since its last tick's sample,
        whichever is later: short while it keeps its ticks (and while a simulated clock
        stands still), long when it was stopped, preempted or blocked. The tick calls it
        at its sample, which counts as on time from then; with ``peek`` (another thread
        asking) nothing is noted.
        """
        now_ns = self.monotonic_ns()
        behind_ns = now_ns - self._on_time_ns
        if not peek:
            self._on_time_ns = now_ns
        return behind_ns

    def _on_time(self) -> None:
        """Note that the thread waits for a deadline still ahead (the stream thread)."""
        self._on_time_ns = self.monotonic_ns()

    def start(self, target: TickTarget) -> str:
        """Start the thread, ticking ``target``; return its priority (:func:`raise_priority`)."""
        self._target = target
        self._thread.start()
        self._started.wait(1.0)
        return self.priority

    def stop(self, timeout: float = 2.0) -> None:
        """Ask the thread to end and wait for it (s)."""
        self.stopping.set()
        if self._thread.is_alive():
            self._thread.join(timeout)

    def _wait_until(self, deadline_ns: int, period_ns: int) -> bool:
        """
        Sleep until ``deadline_ns`` on the node clock; False once stopping.

        Waits on an event in steps of at most a period, so a simulated clock that runs
        faster or slower than the wall clock is followed too.
        """
        while True:
            remaining_ns = deadline_ns - self._now_ns()
            if remaining_ns <= 0:
                return not self.stopping.is_set()
            self._on_time()
            if self.stopping.wait(min(remaining_ns, period_ns) * 1e-9):
                return False

    def _run(self) -> None:
        target = self._target
        self.priority = raise_priority()
        self._started.set()
        next_ns = self._now_ns()
        while True:
            period_ns = self._period_ns()
            next_ns += period_ns
            target.next_deadline(next_ns)
            if not self._wait_until(next_ns, period_ns):
                return
            try:
                target.tick(next_ns)
            except Exception as error:  # noqa: BLE001 - the ticks outlive any one failure
                if self.stopping.is_set():
                    return  # shutting down (SIGINT/SIGTERM): the publisher is gone
                self._on_error(f'stream: publishing failed: {error!r}')
            now_ns = self._now_ns()
            if now_ns - next_ns >= period_ns:
                next_ns = now_ns
