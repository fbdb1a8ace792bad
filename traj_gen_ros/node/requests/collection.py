"""
Garbage collection around a request: none while it is handled, then one between two ticks.

A collection holds the GIL from its start to its end, so the stream thread waits for it.
While lines were planned (``benchmarks/panda_stream.py``, 500 Hz), the request thread's
automatic collections took 0.07 ms p50 and up to 0.7 ms (generation 0), 0.3 ms p50 and up
to 1.6 ms (generation 1), each where an allocation crossed the threshold: anywhere in a
stream period. :meth:`QuietCollection.deferred` turns automatic collection off while a
request is read, planned and answered (the executor's ``~/stop`` meanwhile too: the switch
is the process's), then collects generations 0 and 1 once, at a time the stream thread
does not need the GIL: at once if its next tick is at least :data:`QUIET_NS` away, else
right after that tick's setpoint went out. Objects that lived through start-up are frozen
(``gc.freeze()`` in ``generator.main``) and not scanned.

Times are node-clock integer nanoseconds. No ROS here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
import contextlib
import gc

from traj_gen_ros.node.stream.stream import Stream

#: The young collection after a request starts at once if the stream's next tick is at
#: least this far away (ns), else right after that tick (one after a line: 0.07–0.08 ms
#: p50, 0.33 ms at most).
QUIET_NS = 1_000_000


class QuietCollection:
    """Automatic collection off while a request is handled; one young collection after."""

    def __init__(self, stream: Stream, now_ns: Callable[[], int],
                 timeout: Callable[[], float]) -> None:
        """Collect between the ticks of ``stream`` (clock ``now_ns``), waiting ``timeout()`` s."""
        self._stream, self._now_ns, self._timeout = stream, now_ns, timeout

    @contextlib.contextmanager
    def deferred(self) -> Iterator[None]:
        """Run the block without automatic collection; collect after it, between two ticks."""
        if not gc.isenabled():  # off already (by the caller, or an enclosing block)
            yield
            return
        gc.disable()
        try:
            yield
        finally:
            try:
                self._between_ticks()
                gc.collect(1)
            finally:
                gc.enable()

    def _between_ticks(self) -> None:
        """Return once the stream's next tick is at least :data:`QUIET_NS` away, or just out."""
        if self._stream.waiting:  # nothing is published until the measured state comes
            return
        tick_ns = self._stream.next_start()
        if tick_ns - self._now_ns() < QUIET_NS:
            self._stream.wait_published(tick_ns, self._timeout())
