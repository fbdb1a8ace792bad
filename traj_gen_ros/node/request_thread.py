"""
The request subscriptions' own thread: a request is taken as soon as DDS delivers it.

rclpy's executor rebuilds its wait set from every entity of the node on each round and
dispatches a callback through a task: from DDS arrival to the callback that costs about
0.3 ms more (p50, 0.6 against 0.3 ms; p90 0.9 against 0.6, measured side by side on 2
shared cores beside a 500 Hz publisher), a sixth of a 500 Hz period. So ``~/goal`` and
``~/via_points`` are created in a callback group the executor never runs
(:class:`NotForTheExecutor`), and :class:`RequestThread` waits on just those two and a
guard condition (its wake-up for shutdown), and calls each one's own callback with the
message it took. Everything else (``~/stop``, parameters, ``robot_description``, timers)
stays on the executor; the request handler serialises the two threads.

The wait set is rclpy's own (``rclpy_implementation.WaitSet``, what its executors use):
rclpy has no public wait set, and this wait needs nothing but the subscriptions' handles.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import contextlib
import threading

from rclpy.callback_groups import CallbackGroup
from rclpy.context import Context
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription
from traj_gen_ros.node.realtime import EXECUTOR_FIFO_PRIORITY, realtime_calling_thread

#: The thread wakes at least this often (ns) to see whether it should end.
WAIT_NS = 100_000_000


class NotForTheExecutor(CallbackGroup):
    """A callback group whose entities the executor neither waits on nor runs."""

    def can_execute(self, entity: object) -> bool:
        """Never: :class:`RequestThread` takes these entities' messages."""
        del entity
        return False

    def beginning_execution(self, entity: object) -> bool:
        """Never (see :meth:`can_execute`)."""
        del entity
        return False

    def ending_execution(self, entity: object) -> None:
        """Nothing began."""
        del entity


class RequestThread:
    """Wait on the request subscriptions and run their callbacks, in a thread of its own."""

    def __init__(self, context: Context, subscriptions: Sequence[Subscription],
                 log_error: Callable[[str], None]) -> None:
        """Prepare to serve ``subscriptions`` (created in a :class:`NotForTheExecutor`)."""
        self._context = context
        self._subscriptions = list(subscriptions)
        self._log_error = log_error
        self._wake = GuardCondition(None, None, context=context)
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name='requests', daemon=True)

    def start(self) -> None:
        """Start the thread (``SCHED_FIFO`` at the executor's priority, if permitted)."""
        self._thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        """Ask the thread to end, wake it and wait for it (s)."""
        self._stopping.set()
        try:
            self._wake.trigger()
        except Exception:  # noqa: BLE001 - the context may be shut down already
            pass
        if self._thread.is_alive():
            self._thread.join(timeout)
        self._wake.destroy()

    def _run(self) -> None:
        realtime_calling_thread(EXECUTOR_FIFO_PRIORITY)
        while not self._stopping.is_set():
            try:
                ready = self._wait()
                for subscription in ready:
                    self._take(subscription)
            except Exception as error:  # noqa: BLE001 - requests go on after any failure
                if self._stopping.is_set() or not self._context.ok():
                    return
                self._log_error(f'request thread: {error!r}')
                self._stopping.wait(0.01)

    def _wait(self) -> list[Subscription]:
        """Block until a request (or the wake-up) is ready; return the ready subscriptions."""
        subscriptions = self._subscriptions
        with contextlib.ExitStack() as handles:  # each handle stays valid while in use
            for entity in (self._context, self._wake, *subscriptions):
                handles.enter_context(entity.handle)
            wait_set = _rclpy.WaitSet(len(subscriptions), 1, 0, 0, 0, 0, self._context.handle)
            wait_set.clear_entities()
            for subscription in subscriptions:
                wait_set.add_subscription(subscription.handle)
            wait_set.add_guard_condition(self._wake.handle)
            wait_set.wait(WAIT_NS)
            ready = wait_set.get_ready_entities('subscription')
        return [s for s in subscriptions if s.handle.pointer in ready]

    @staticmethod
    def _take(subscription: Subscription) -> None:
        """Take one message and give it, with its info, to the subscription's callback."""
        with subscription.handle:
            taken = subscription.handle.take_message(subscription.msg_type, subscription.raw)
        if taken is not None:
            subscription.callback(*taken)
