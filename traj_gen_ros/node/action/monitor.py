"""
The running ``~/follow_joint_trajectory`` goal watched, and every goal ended once.

On a timer of the executor's (every ``MONITOR_PERIOD`` s while a goal is active or replaced
ones wait for their end: :meth:`GoalMonitor.watch`) the monitor publishes the feedback
(:meth:`ActiveGoal.feedback`, at most once per stream period), checks the tolerances
against a measured state no older than ``STALE_AFTER`` and ends the goal: SUCCEEDED once
the stream has sent the trajectory's end (and the arm is within ``goal_tolerance`` and
still), CANCELED once a cancel's brake is at rest, ABORTED when a tolerance is violated or
another request replaced it.

A goal's end is decided once (the first decided counts: the monitor may end a goal the
request thread has just replaced); before rclpy has made its handle it is kept and applied
when it has. The terminal state and result are set by the server (``end``: an execute
callback scheduled on the executor). What the request thread and the executor share is a
:class:`GoalBook` under its lock. No ROS objects are made here: the server gives the
monitor what it uses (the measured arm, the brake, the logger, how to end a goal).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np
from rclpy.action.server import ServerGoalHandle
from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.action.goal_book import GoalBook, KIND
from traj_gen_ros.node.action.goal_points import INVALID_GOAL, PATH_TOLERANCE_VIOLATED, SUCCESSFUL
from traj_gen_ros.node.action.tolerances import ABORTED, CANCELED, outcome
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.stream import Stream

#: The monitor's period (s): feedback rate and how soon a result follows its cause.
MONITOR_PERIOD = 0.02
#: A measured state older than this (s) is not checked against the tolerances: until
#: ``joint_topic_timeout`` says it is lost, it would pass for a deviation.
STALE_AFTER = 0.1


class Logger(Protocol):
    """What the monitor logs through (an rclpy node's logger is one)."""

    def info(self, message: str) -> bool:
        """Log ``message`` at INFO."""

    def warning(self, message: str) -> bool:
        """Log ``message`` at WARN."""

    def error(self, message: str) -> bool:
        """Log ``message`` at ERROR."""


class MeasuredArm(Protocol):
    """Where the arm is, as the goal's tolerances need it (``JointFeedback`` is one)."""

    def positions(self) -> np.ndarray | None:
        """Return where the arm is, in rad and joint-set order; None if unknown or lost."""

    def velocities(self) -> np.ndarray | None:
        """Return how fast the arm moves, in rad/s; None if its driver says nothing of it."""

    def age(self) -> float:
        """Return the seconds since the last valid measured state arrived."""

    def reseed_to_measured(self, reason: str) -> bool:
        """Hold where the arm is from the next tick (logged with ``reason``)."""


#: Schedules a goal's terminal state and result: ``(handle, status, error code, text)``.
EndGoal = Callable[[ServerGoalHandle, str, int, str], None]


class GoalMonitor:
    """Feedback, tolerances and the end of the goals (see the module doc)."""

    def __init__(self, stream: Stream, config: Callable[[], Config],
                 now_ns: Callable[[], int], book: GoalBook, *, brake: Callable[[], None],
                 arm: MeasuredArm | None, log: Logger, end: EndGoal,
                 feedback: Callable[[], object]) -> None:
        """
        Watch ``book``'s goals (:meth:`watch`, on the executor's timer).

        ``brake`` brakes to rest: what a path-tolerance violation does without a measured
        ``arm`` (with one, the setpoint is re-seeded where the arm is). ``end`` schedules a
        goal's terminal state; ``feedback()`` makes an empty feedback message.
        """
        self._stream, self._config, self._now_ns, self._book = stream, config, now_ns, book
        self._brake, self._arm, self._log = brake, arm, log
        self._end, self._new_feedback = end, feedback

    def watch(self) -> bool:
        """
        End the replaced goals, watch the active one; return whether any goal is left.

        Executor thread (a timer every ``MONITOR_PERIOD`` s while one is).
        """
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
        except Exception as error:  # noqa: BLE001 - the monitor must never kill the node
            self._log.error(f'{KIND}: monitor failed: {error!r}')
        return book.active is not None or bool(book.replaced)

    def goal_waits(self) -> bool:
        """
        Tell whether a started goal runs or waits at its end for its tolerances (any thread).

        While one does, the node keeps commanding its trajectory's end, as
        ``joint_trajectory_controller`` does: the measured state does not re-seed the
        setpoint (the arm is the reference once no goal waits).
        """
        with self._book.lock:
            active = self._book.active
            return active is not None and active.target is not None and active.cancel is None

    def _measured(self) -> tuple[np.ndarray | None, float]:
        if self._arm is None:
            return None, 0.0
        return self._arm.positions(), self._arm.age()

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
        measured, age = self._measured()
        velocities = None if self._arm is None else self._arm.velocities
        self._feedback(active, now_ns, desired, measured,
                       None if velocities is None else velocities())
        if measured is not None and age > STALE_AFTER:
            return  # judged on a fresh one, or ended by the timeout (measured_state_lost)
        end_ns = active.end(now_ns, published_ns, moving)
        ended = outcome(active.tolerances, active.goal.points.joints, self._config().joints,
                        (active.start_ns, end_ns, now_ns, published_ns),
                        desired.position, active.target, measured,
                        velocities or (lambda: None), active.goal.slowed)
        if ended is not None:
            self.finish(active, *ended)
            if ended[1] == PATH_TOLERANCE_VIOLATED:
                if self._arm is None or not self._arm.reseed_to_measured(
                        'path tolerance violated'):
                    self._brake()

    def _feedback(self, active: ActiveGoal, now_ns: int, desired: State,
                  measured: np.ndarray | None, velocities: np.ndarray | None) -> None:
        if now_ns - active.feedback_ns < self._config().period_ns:
            return
        active.feedback_ns = now_ns
        active.handle.publish_feedback(active.feedback(
            self._new_feedback(), now_ns, desired, measured, velocities))

    def measured_state_lost(self, reason: str) -> None:
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
        """Log how the goal ends, a failure at WARN, else INFO; schedule its terminal state."""
        if status == ABORTED:
            self._log.warning(f'{KIND} goal aborted (error_code {code}): {text}')
        else:
            self._log.info(f'{KIND} goal {status}{": " + text if text else ""}')
        self._end(handle, status, code, text)
