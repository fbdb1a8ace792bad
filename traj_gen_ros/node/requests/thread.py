"""
The request subscriptions' own thread: a request is taken as soon as DDS delivers it.

rclpy's executor rebuilds its wait set from every entity of the node on each round and
dispatches a callback through a task: from DDS arrival to the callback that costs about
0.3 ms more (p50, 0.6 against 0.3 ms; p90 0.9 against 0.6, measured side by side on 2
shared cores beside a 500 Hz publisher), a sixth of a 500 Hz period. So ``~/goal`` and
``~/via_points`` are created in a callback group the executor never runs
(:class:`NotForTheExecutor`), and :class:`RequestThread` waits on just those two and a
guard condition (its wake-up for shutdown), and calls each one's own callback with the
message it took. ``~/follow_joint_trajectory``'s action server is served the same way
(:meth:`RequestThread.serve`): rclpy's executor would take a goal through its wait set
rebuild, a task for the goal request and another for the accepted callback (5.5 ms p50
from sending to the first setpoint at 500 Hz, against a 4 ms target). Its services (goal,
cancel, result) are taken here and the waitable's own ``execute`` is run at once; the
goal's end (``notify_execute``) stays a task on the executor. Everything else
(``~/stop``, parameters, ``robot_description``, timers) stays on the executor; the request
handler serialises the two threads.

The wait set is rclpy's own (``rclpy_implementation.WaitSet``, what its executors use):
rclpy 7.1.6 (Jazzy) has no public wait set, and this wait needs nothing but the
subscriptions' handles. This module is the one place that uses it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
import contextlib
import threading
import time

from rclpy.callback_groups import CallbackGroup
from rclpy.context import Context
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription
from rclpy.waitable import NumberOfEntities, Waitable
from traj_gen_ros.node.stream.realtime import EXECUTOR_FIFO_PRIORITY, realtime_calling_thread

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
        self._waitables: list[Waitable] = []
        self._log_error = log_error
        self._wake = GuardCondition(None, None, context=context)
        #: When the last wait returned (system ns): an action goal's arrival.
        self.ready_ns = 0
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name='requests', daemon=True)

    def serve(self, waitable: Waitable) -> None:
        """Also serve ``waitable`` (created in a :class:`NotForTheExecutor`); before start."""
        self._waitables.append(waitable)

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
                ready, waitables = self._wait()
                for subscription in ready:
                    self._take(subscription)
                for waitable in waitables:
                    self._execute(waitable)
            except Exception as error:  # noqa: BLE001 - requests go on after any failure
                if self._stopping.is_set() or not self._context.ok():
                    return
                self._log_error(f'request thread: {error!r}')
                self._stopping.wait(0.01)

    def _wait(self) -> tuple[list[Subscription], list[Waitable]]:
        """Block until a request (or the wake-up) is ready; return what is ready."""
        subscriptions, waitables = self._subscriptions, self._waitables
        with contextlib.ExitStack() as handles:  # each handle stays valid while in use
            for entity in (self._context, self._wake, *subscriptions):
                handles.enter_context(entity.handle)
            count = NumberOfEntities(len(subscriptions), 1)
            for waitable in waitables:
                handles.enter_context(waitable)
                count += waitable.get_num_entities()
            wait_set = _rclpy.WaitSet(
                count.num_subscriptions, count.num_guard_conditions, count.num_timers,
                count.num_clients, count.num_services, count.num_events,
                self._context.handle)
            wait_set.clear_entities()
            for subscription in subscriptions:
                wait_set.add_subscription(subscription.handle)
            wait_set.add_guard_condition(self._wake.handle)
            for waitable in waitables:
                waitable.add_to_wait_set(wait_set)
            wait_set.wait(WAIT_NS)
            self.ready_ns = time.time_ns()
            ready = wait_set.get_ready_entities('subscription')
            ready_waitables = [w for w in waitables if w.is_ready(wait_set)]
        return [s for s in subscriptions if s.handle.pointer in ready], ready_waitables

    def _execute(self, waitable: Waitable) -> None:
        """Take what is ready and run the waitable's ``execute`` to its end, here."""
        coroutine = waitable.execute(waitable.take_data())
        try:
            coroutine.send(None)
        except StopIteration:
            return
        coroutine.close()  # its callbacks are plain functions: it never waits on anything
        self._log_error(f'request thread: {type(waitable).__name__} waited: not served')

    @staticmethod
    def _take(subscription: Subscription) -> None:
        """Take one message and give it, with its info, to the subscription's callback."""
        with subscription.handle:
            taken = subscription.handle.take_message(subscription.msg_type, subscription.raw)
        if taken is not None:
            subscription.callback(*taken)
