"""
``~/follow_joint_trajectory`` (``control_msgs/action/FollowJointTrajectory``): a goal's life.

So that MoveIt's simple controller manager (``type: FollowJointTrajectory``, ``action_ns:
follow_joint_trajectory``) can use the node as its controller. The points are parsed,
checked and planned in :mod:`traj_gen_ros.node.action.goal_points`, the tolerances in
:mod:`traj_gen_ros.node.action.tolerances`; this module is the rclpy glue:

* a goal is read, planned and spliced in the goal callback, before rclpy makes its handle
  and sends the response and status; then accepted and marked executing. One refused is
  aborted at once with its ``error_code`` and reason, and changes nothing;
* a valid goal goes the one way every request goes (``RequestHandler.submit``): planned
  from the stream's next tick and spliced there, continuing the setpoint without a jump;
* a newer goal, ``~/goal``, ``~/via_points`` or ``~/stop`` ends the active goal ABORTED
  saying what replaced it; a cancel brakes to rest (``plan_stop``), then CANCELED;
* the feedback, the tolerances and every goal's end are the
  :class:`~traj_gen_ros.node.action.monitor.GoalMonitor`'s (a timer on the executor).

The goal, cancel and result services are served by the request thread
(:mod:`traj_gen_ros.node.requests.thread`), as ``~/goal`` is. The terminal state and
result are set by an execute callback scheduled on the executor only when the goal ends
(:meth:`ActionServer.notify_execute`): Jazzy's executor resumes an ``async`` one on every
spin, a busy loop beside the stream thread. What the two threads share (the active goal,
the replaced ones) is a :class:`~traj_gen_ros.node.action.monitor.GoalBook`; a goal is
watched once it is fully started, and an end decided before its handle exists is applied
as soon as it does.
"""

from __future__ import annotations

from collections.abc import Callable
import time

import numpy as np
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import GoalEvent, ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from traj_gen_ros.node.action.active_goal import ActiveGoal, read_goal_message
from traj_gen_ros.node.action.goal_points import (
    GoalError,
    INVALID_GOAL,
    plan_trajectory_goal,
    TrajectoryGoal,
)
from traj_gen_ros.node.action.monitor import GoalBook, GoalMonitor, KIND
from traj_gen_ros.node.action.tolerance_parameters import ToleranceParameters
from traj_gen_ros.node.action.tolerances import ABORTED
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.requests.answers import Answers
from traj_gen_ros.node.requests.handler import BRAKE, RequestHandler
from traj_gen_ros.node.requests.request import Request
from traj_gen_ros.node.requests.start_tick import Planner
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.stream import Stream

try:
    from control_msgs.action import FollowJointTrajectory
    UNAVAILABLE = ''
except ImportError as _error:  # no control_msgs: the node runs without the action
    FollowJointTrajectory = None
    UNAVAILABLE = str(_error)

#: The requests the action itself makes (braking on a cancel or a path violation).
OWN_KINDS = ('follow_joint_trajectory_cancel', 'follow_joint_trajectory_hold')
_REPLACED_BY = {'goal': 'a ~/goal request', 'via_points': 'a ~/via_points request',
                'stop': 'a ~/stop call', KIND: 'a newer follow_joint_trajectory goal'}


class FollowJointTrajectoryServer:
    """The action server and the life cycle of its goals (see the module doc)."""

    def __init__(self, node: Node, handler: RequestHandler, stream: Stream, answers: Answers,
                 config: Callable[[], Config], now_ns: Callable[[], int],
                 callback_group: CallbackGroup | None = None) -> None:
        """
        Serve ``~/follow_joint_trajectory`` on ``node`` through ``handler``.

        :param callback_group: the action server's (a ``NotForTheExecutor``, whose
            thread then serves :attr:`action_server`); default the node's.

        The measured state, where there is one, is the :attr:`monitor`'s.
        """
        self._node, self._handler, self._stream, self._answers = node, handler, stream, answers
        self._config, self._now_ns = config, now_ns
        #: When the goal arrived (system ns): the request thread's wake-up (attribute).
        self.arrival_ns: Callable[[], int] = time.time_ns
        self._log = node.get_logger()
        self._book = GoalBook()
        self._lock = self._book.lock
        self._starting: ActiveGoal | None = None
        self._pending: tuple | None = None  # (goal message, outcome) from _on_goal
        self.monitor = GoalMonitor(node, stream, config, now_ns, self._book, self._hold)
        self._tolerances = ToleranceParameters(node, lambda: len(self._config().joints))
        previous = handler.on_accepted

        def on_accepted(request: Request, start_ns: int) -> None:
            previous(request, start_ns)
            self._on_request_accepted(request, start_ns)
        handler.on_accepted = on_accepted
        handler.on_dropped = self._on_request_dropped
        self._server = ActionServer(
            node, FollowJointTrajectory, '~/follow_joint_trajectory', self.monitor.unexpected,
            goal_callback=self._on_goal, handle_accepted_callback=self._start,
            cancel_callback=self._on_cancel,
            callback_group=callback_group)
        self.monitor.server = self._server

    @property
    def action_server(self) -> ActionServer:
        """Give the rclpy action server (a waitable for the thread that serves it)."""
        return self._server

    # ------------------------------------------------------------------ a new goal

    def _on_goal(self, message: object) -> GoalResponse:
        """
        Read, plan and splice a goal before rclpy answers it (request thread): sooner.

        Every goal is accepted; one refused is aborted in :meth:`_start`, with its reason.
        """
        received = self.arrival_ns()  # as ~/goal's 'received': system ns
        self._end_orphan()
        trajectory = message.trajectory
        request = Request(KIND, self._answers.values(KIND, trajectory.header.frame_id,
                                                     received), 0, None)
        outcome: tuple = (INVALID_GOAL, 'internal error: not planned')
        try:
            active = read_goal_message(message, request, self._config().joints,
                                       self._tolerances.defaults[1], self._now_ns())
            self._starting = active
            motion = self._handler.submit(request, self._planner(active))
            if motion is None:  # refused (answered on ~/status already): say why here too
                refusal = active.goal.refusal or GoalError(
                    INVALID_GOAL, request.refusal or 'refused: resend it')
                outcome = (refusal.code, str(refusal))
            else:
                outcome = (active, motion)
        except GoalError as error:
            self._answers.refused(request, str(error))
            outcome = (error.code, str(error))
        except Exception as error:  # noqa: BLE001 - a goal must never kill the node
            self._log.error(f'{KIND}: unexpected failure: {error!r}')
            outcome = (INVALID_GOAL, f'internal error: {error}')
        finally:
            self._starting = None
            self._pending = (message, outcome)
        return GoalResponse.ACCEPT

    def _end_orphan(self) -> None:
        """End a goal planned in :meth:`_on_goal` whose handle rclpy never made."""
        pending, self._pending = self._pending, None
        if pending is not None and isinstance(pending[1][0], ActiveGoal):
            # rclpy could not send its response (the client went away): nobody owns it.
            self._log.warning(f'{KIND}: a goal whose response could not be sent was '
                              'running: ended; its motion goes on as any other')
            self.monitor.finish(pending[1][0], ABORTED, INVALID_GOAL,
                                'the goal response failed')

    def _start(self, handle: ServerGoalHandle) -> None:
        """Mark the accepted goal executing; end it if it was refused or ended (request thread)."""
        pending, self._pending = self._pending, None
        if pending is None or pending[0] is not handle.request:  # not seen by _on_goal
            self._on_goal(handle.request)
            pending, self._pending = self._pending, None
        handle._update_state(GoalEvent.EXECUTE)  # what execute() does, minus scheduling
        outcome = pending[1]
        if not isinstance(outcome[0], ActiveGoal):
            self.monitor.end(handle, ABORTED, *outcome)
            return
        active, motion = outcome
        with self._lock:
            active.handle = handle
            early_end = active.early_end
        if early_end is not None:  # replaced or aborted before rclpy made its handle
            self.monitor.end(handle, *early_end)
            return
        self._started(active, motion)

    def _planner(self, active: ActiveGoal) -> Planner:
        tolerance = self._tolerances.defaults[0]

        def plan(config: Config, state: State, hold_at: np.ndarray,
                 goal: TrajectoryGoal) -> PlannedMotion:
            measured = self.monitor.measured_positions()
            reference = state.position if measured is None else measured
            return plan_trajectory_goal(config, state, hold_at, goal, reference,
                                        tolerance if tolerance > 0.0 else np.inf,
                                        measured is not None)
        return Planner(plan)

    def _started(self, active: ActiveGoal, motion: PlannedMotion) -> None:
        active.end_ns = active.start_ns + int(round(motion.plan.duration * 1e9))
        active.target = motion.end
        goal = active.goal
        if goal.factor > 1.0:
            self._log.warning(f'{KIND} goal: {goal.slowed}: lasts '
                              f'{motion.plan.duration:.4g} s instead of {goal.duration:.4g} s')
        self.monitor.wake(self._node)

    def _on_request_accepted(self, request: Request, start_ns: int) -> None:
        """Any request spliced in (any thread): the one it replaces ends (:meth:`_monitor`)."""
        book = self._book
        with self._lock:
            active, starting = book.active, self._starting
            if request.kind in OWN_KINDS:
                if active is not None and request is active.cancel:
                    active.brake_start_ns = start_ns
                return
            if starting is not None and request is starting.request:
                starting.start_ns = start_ns
                book.active = starting
            else:
                book.active = None
            if active is not None:
                active.replaced = (f'replaced by {_REPLACED_BY.get(request.kind, request.kind)} '
                                   f'(request_id {request.values.get("request_id", "?")}); '
                                   'the motion continues from the setpoint')
                book.replaced.append(active)

    def _on_request_dropped(self, request: Request, reason: str) -> None:
        """Abort the active goal if its request was dropped before its start."""
        book = self._book
        with self._lock:
            active = book.active
            if active is not None and request is active.request:
                active.replaced = f'dropped: {reason}'
                book.replaced.append(active)
                book.active = None

    # ------------------------------------------------------------------ cancel

    def _on_cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        """Accept a cancel of the active goal and brake to rest (request thread)."""
        try:
            with self._lock:
                active = self._book.active
                if active is None or active.handle is not handle:
                    return CancelResponse.REJECT  # ended, or ending
                if active.cancel is not None:
                    return CancelResponse.ACCEPT
                active.cancel = Request(OWN_KINDS[0], self._answers.values(OWN_KINDS[0], ''),
                                        0, None)
            if self._handler.submit(active.cancel, BRAKE) is None:
                active.brake_start_ns = self._stream.last_published()
            return CancelResponse.ACCEPT
        except Exception as error:  # noqa: BLE001 - a cancel must never kill the node
            self._log.error(f'{KIND}: cancel failed: {error!r}')
            return CancelResponse.REJECT

    def _hold(self) -> None:
        """Brake to rest within the limits: the default after a path-tolerance violation."""
        request = Request(OWN_KINDS[1], self._answers.values(OWN_KINDS[1], ''), 0, None)
        self._handler.submit(request, BRAKE)

    def destroy(self) -> None:
        """Destroy the action server (before the node: rclpy does not do it for waitables)."""
        self.monitor.destroy()
        self._server.destroy()


def create_server(node: Node, handler: RequestHandler, stream: Stream, answers: Answers,
                  config: Callable[[], Config], now_ns: Callable[[], int],
                  callback_group: CallbackGroup | None = None
                  ) -> FollowJointTrajectoryServer | None:
    """Create the action server, or say once (info) why there is none and return None."""
    if FollowJointTrajectory is None:
        node.get_logger().info(f'control_msgs is not importable ({UNAVAILABLE}): running '
                               'without ~/follow_joint_trajectory')
        return None
    return FollowJointTrajectoryServer(node, handler, stream, answers, config, now_ns,
                                       callback_group=callback_group)
