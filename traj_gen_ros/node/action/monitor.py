"""
The running ``~/follow_joint_trajectory`` goal watched, and every goal ended once.

A timer on the executor (every ``MONITOR_PERIOD`` s while a goal is active or replaced
ones wait for their end) publishes the feedback (:meth:`ActiveGoal.feedback`, at most once
per stream period), checks the tolerances against a measured state no older than
``STALE_AFTER`` and ends the goal: SUCCEEDED once the stream has sent the trajectory's end
(and the arm is within ``goal_tolerance`` and still), CANCELED once a cancel's brake is at
rest, ABORTED when a tolerance is violated or another request replaced it.

A goal's end is decided once (the first decided counts: the monitor may end a goal the
request thread has just replaced); before rclpy has made its handle it is kept and applied
when it has. The terminal state and result are set by an execute callback scheduled on the
executor (``ActionServer.notify_execute``). What the request thread and the executor share
is a :class:`GoalBook` under its lock.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
import threading

import numpy as np
from rclpy.action import ActionServer
from rclpy.action.server import ServerGoalHandle
from rclpy.node import Node
from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.action.goal_points import INVALID_GOAL, PATH_TOLERANCE_VIOLATED, SUCCESSFUL
from traj_gen_ros.node.action.tolerances import ABORTED, CANCELED, outcome, SUCCEEDED
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.stream import Stream

try:
    from control_msgs.action import FollowJointTrajectory
except ImportError:  # no control_msgs: nothing creates a monitor
    FollowJointTrajectory = None

KIND = 'follow_joint_trajectory'
#: The monitor's period (s): feedback rate and how soon a result follows its cause.
MONITOR_PERIOD = 0.02
#: A measured state older than this (s) is not checked against the tolerances: until
#: ``joint_topic_timeout`` says it is lost, it would pass for a deviation.
STALE_AFTER = 0.1


@dataclass
class GoalBook:
    """The goals both threads see, under ``lock``: the active one, those replaced."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    active: ActiveGoal | None = None
    replaced: list[ActiveGoal] = field(default_factory=list)


class GoalMonitor:
    """Feedback, tolerances and the end of the goals (see the module doc)."""

    def __init__(self, node: Node, stream: Stream, config: Callable[[], Config],
                 now_ns: Callable[[], int], book: GoalBook, hold: Callable[[], None]) -> None:
        """
        Watch ``book``'s goals on ``node``'s executor; :attr:`server` is set by its owner.

        ``hold`` brakes to rest: what a path-tolerance violation does without a measured
        state's own re-seed (:attr:`reseed_to_measured`).
        """
        self._stream, self._config, self._now_ns, self._book = stream, config, now_ns, book
        self._log = node.get_logger()
        self.server: ActionServer | None = None
        #: Where the arm is (rad, joint-set order) and how fast (rad/s), or None without
        #: a measured state; s since it arrived; hold where it is (attributes).
        self.measured_positions: Callable[[], np.ndarray | None] = lambda: None
        self.measured_velocities: Callable[[], np.ndarray | None] = lambda: None
        self.measured_age: Callable[[], float] = lambda: 0.0
        self.reseed_to_measured: Callable[[], None] = hold
        self._timer = node.create_timer(MONITOR_PERIOD, self._monitor)
        self._timer.cancel()

    def wake(self, node: Node) -> None:
        """Start watching now (a goal was started)."""
        self._timer.reset()
        if node.executor is not None:
            node.executor.wake()  # its wait began without the monitor timer

    def destroy(self) -> None:
        """Stop the timer."""
        self._timer.cancel()

    def _monitor(self) -> None:
        """End the replaced goals, watch the active one (executor thread, a timer)."""
        book = self._book
        try:
            with book.lock:
                replaced, book.replaced = book.replaced, []
                active = book.active
            for goal in replaced:
                status = CANCELED if goal.cancel is not None else ABORTED
                self.end_goal(goal, status, INVALID_GOAL if status == ABORTED
                              else SUCCESSFUL, goal.replaced)
            if active is not None and active.target is not None:  # started
                self._watch(active)
            if book.active is None and not book.replaced:
                self._timer.cancel()
        except Exception as error:  # noqa: BLE001 - the monitor must never kill the node
            self._log.error(f'{KIND}: monitor failed: {error!r}')

    def _watch(self, active: ActiveGoal) -> None:
        now_ns = self._now_ns()
        # Judged on what a client can already have: the last setpoint sent, and if it moved.
        published_ns, moving = self._stream.last_sent()
        if active.cancel is not None:
            start = active.brake_start_ns
            if start is not None and published_ns >= start and not moving:
                self.finish(active, CANCELED, SUCCESSFUL, 'canceled: braked to rest')
            return
        desired = self._stream.setpoint(max(now_ns, published_ns))  # commanded: scaled
        measured = self.measured_positions()
        self._feedback(active, now_ns, desired, measured)
        if measured is not None and self.measured_age() > STALE_AFTER:
            return  # judged on a fresh one, or ended by the timeout (abort_active)
        end_ns = active.end(now_ns, published_ns, moving)
        ended = outcome(active.tolerances, active.goal.points.joints, self._config().joints,
                        (active.start_ns, end_ns, now_ns, published_ns),
                        desired.position, active.target, measured,
                        self.measured_velocities, active.goal.slowed)
        if ended is not None:
            self.finish(active, *ended)
            if ended[1] == PATH_TOLERANCE_VIOLATED:
                self.reseed_to_measured()

    def _feedback(self, active: ActiveGoal, now_ns: int, desired: State,
                  measured: np.ndarray | None) -> None:
        if now_ns - active.feedback_ns < self._config().period_ns:
            return
        active.feedback_ns = now_ns
        active.handle.publish_feedback(active.feedback(
            FollowJointTrajectory.Feedback(), now_ns, desired, measured))

    def abort_active(self, reason: str) -> None:
        """End the running goal ABORTED with ``reason``: the measured state was lost."""
        with self._book.lock:
            active = self._book.active
        if active is not None:
            self.finish(active, ABORTED, PATH_TOLERANCE_VIOLATED, reason)

    def finish(self, active: ActiveGoal, status: str, code: int, text: str) -> None:
        """End ``active`` (:meth:`end_goal`); it is no longer the active goal."""
        with self._book.lock:
            if self._book.active is active:
                self._book.active = None
        self.end_goal(active, status, code, text)

    def end_goal(self, goal: ActiveGoal, status: str, code: int, text: str) -> None:
        """End ``goal`` once; before its handle exists, when it does (``early_end``)."""
        with self._book.lock:
            if goal.ended:
                return
            goal.ended = True
            if goal.handle is None:
                goal.early_end = (status, code, text)
                return
        self.end(goal.handle, status, code, text)

    def end(self, handle: ServerGoalHandle, status: str, code: int, text: str) -> None:
        """Schedule the goal's terminal state and result (see the module doc)."""
        result = FollowJointTrajectory.Result(error_code=code, error_string=text)
        if status == SUCCEEDED:
            self._log.info(f'{KIND} goal succeeded{": " + text if text else ""}')
        else:
            self._log.warning(f'{KIND} goal {status} (error_code {code}): {text}')

        def finish(goal_handle: ServerGoalHandle) -> object:
            if status == SUCCEEDED:
                goal_handle.succeed()
            elif status == CANCELED and goal_handle.is_cancel_requested:
                goal_handle.canceled()
            else:
                goal_handle.abort()
            return result
        self.server.notify_execute(handle, finish)

    @staticmethod
    def unexpected(handle: ServerGoalHandle) -> object:
        """Never scheduled (:meth:`end` gives each goal its own): abort."""
        handle.abort()
        return FollowJointTrajectory.Result(error_code=INVALID_GOAL, error_string='internal')
