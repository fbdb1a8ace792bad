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
the replaced ones) is a :class:`~traj_gen_ros.node.action.goal_book.GoalBook`; a goal is
watched once it is fully started, and an end decided before its handle exists is applied
as soon as it does.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import GoalEvent, ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from traj_gen_ros.node.action.active_goal import ActiveGoal, read_goal_message
from traj_gen_ros.node.action.goal_book import GoalBook, KIND, OWN_KINDS
from traj_gen_ros.node.action.goal_points import (
    GoalError,
    INVALID_GOAL,
    plan_trajectory_goal,
    TrajectoryGoal,
)
from traj_gen_ros.node.action.monitor import GoalMonitor, MeasuredArm, MONITOR_PERIOD
from traj_gen_ros.node.action.tolerance_parameters import ToleranceParameters
from traj_gen_ros.node.action.tolerances import ABORTED, CANCELED, SUCCEEDED
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


@dataclass(frozen=True)
class GoalOutcome:
    """What the goal callback made of a goal: running (``active``, ``motion``) or refused."""

    active: ActiveGoal | None = None
    motion: PlannedMotion | None = None
    code: int = INVALID_GOAL
    reason: str = 'internal error: not planned'

    @property
    def running(self) -> bool:
        """Whether the goal was planned and spliced in."""
        return self.active is not None and self.motion is not None


def mark_executing(handle: ServerGoalHandle) -> None:
    """
    Move an accepted goal to EXECUTING without scheduling an execute callback.

    rclpy 7.1.6 (Jazzy) has no public call for it: ``ServerGoalHandle.execute()`` also
    schedules the execute callback on the executor, which Jazzy's executor resumes on
    every spin while it waits (a busy loop beside the stream thread); the terminal state
    is scheduled once, when the goal ends (:meth:`FollowJointTrajectoryServer.end`). The
    one use of rclpy's private ``_update_state``, here.
    """
    handle._update_state(GoalEvent.EXECUTE)


class FollowJointTrajectoryServer:
    """The action server and the life cycle of its goals (see the module doc)."""

    def __init__(self, node: Node, handler: RequestHandler, stream: Stream, answers: Answers,
                 config: Callable[[], Config], now_ns: Callable[[], int], *,
                 tolerances: ToleranceParameters, arrival_ns: Callable[[], int],
                 arm: MeasuredArm | None = None,
                 callback_group: CallbackGroup | None = None) -> None:
        """
        Serve ``~/follow_joint_trajectory`` on ``node`` through ``handler``.

        :param tolerances: the tolerance parameters in force.
        :param arrival_ns: when a goal arrived (system ns: the request thread's wake-up).
        :param arm: the measured state (``JointFeedback``), None when standalone.
        :param callback_group: the action server's (a ``NotForTheExecutor``, whose
            thread then serves :attr:`action_server`); default the node's.
        """
        self._node, self._handler, self._stream, self._answers = node, handler, stream, answers
        self._config, self._now_ns, self._arrival_ns = config, now_ns, arrival_ns
        self._tolerances, self._arm = tolerances, arm
        self._log = node.get_logger()
        self._book = GoalBook()
        self._lock = self._book.lock
        self._pending: tuple[object, GoalOutcome] | None = None  # (message, its outcome)
        self._server = ActionServer(
            node, FollowJointTrajectory, '~/follow_joint_trajectory', _never_executed,
            goal_callback=self._on_goal, handle_accepted_callback=self._start,
            cancel_callback=self._on_cancel,
            callback_group=callback_group)
        self.monitor = GoalMonitor(stream, config, now_ns, self._book, brake=self._brake,
                                   arm=arm, log=self._log, end=self._schedule_end,
                                   feedback=FollowJointTrajectory.Feedback)
        self._timer = node.create_timer(MONITOR_PERIOD, self._watch)
        self._timer.cancel()
        handler.add_listener(self._book)

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
        received = self._arrival_ns()  # as ~/goal's 'received': system ns
        self._end_orphan()
        trajectory = message.trajectory
        request = Request(KIND, self._answers.values(KIND, trajectory.header.frame_id,
                                                     received), 0, None)
        outcome = GoalOutcome()
        try:
            active = read_goal_message(message, request, self._config().joints,
                                       self._tolerances.defaults[1], self._now_ns())
            self._book.starting = active
            motion = self._handler.submit(request, self._planner(active))
            if motion is None:  # refused (answered on ~/status already): say why here too
                refusal = active.goal.refusal or GoalError(
                    INVALID_GOAL, request.refusal or 'refused: resend it')
                outcome = GoalOutcome(code=refusal.code, reason=str(refusal))
            else:
                outcome = GoalOutcome(active, motion)
        except GoalError as error:
            self._answers.refused(request, str(error))
            outcome = GoalOutcome(code=error.code, reason=str(error))
        except Exception as error:  # noqa: BLE001 - a goal must never kill the node
            self._log.error(f'{KIND}: unexpected failure: {error!r}')
            outcome = GoalOutcome(reason=f'internal error: {error}')
        finally:
            self._book.starting = None
            self._pending = (message, outcome)
        return GoalResponse.ACCEPT

    def _end_orphan(self) -> None:
        """End a goal planned in :meth:`_on_goal` whose handle rclpy never made."""
        pending, self._pending = self._pending, None
        if pending is not None and pending[1].running:
            # rclpy could not send its response (the client went away): nobody owns it.
            self._log.warning(f'{KIND}: a goal whose response could not be sent was '
                              'running: ended; its motion goes on as any other')
            self.monitor.finish(pending[1].active, ABORTED, INVALID_GOAL,
                                'the goal response failed')

    def _start(self, handle: ServerGoalHandle) -> None:
        """Mark the accepted goal executing; end it if it was refused or ended (request thread)."""
        pending, self._pending = self._pending, None
        if pending is None or pending[0] is not handle.request:  # not seen by _on_goal
            self._on_goal(handle.request)
            pending, self._pending = self._pending, None
        mark_executing(handle)
        outcome = pending[1]
        if not outcome.running:  # refused: logged and answered on ~/status already
            self._schedule_end(handle, ABORTED, outcome.code, outcome.reason)
            return
        active, motion = outcome.active, outcome.motion
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
            measured = None if self._arm is None else self._arm.positions()
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
        self._wake()

    def _wake(self) -> None:
        """Start watching now (a goal was started)."""
        self._timer.reset()
        if self._node.executor is not None:
            self._node.executor.wake()  # its wait began without the monitor's timer

    def _watch(self) -> None:
        """Run the monitor's round (executor thread); stop the timer when no goal is left."""
        if not self.monitor.watch():
            self._timer.cancel()

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

    def _brake(self) -> None:
        """Brake to rest within the limits: after a path-tolerance violation, without an arm."""
        request = Request(OWN_KINDS[1], self._answers.values(OWN_KINDS[1], ''), 0, None)
        self._handler.submit(request, BRAKE)

    def _schedule_end(self, handle: ServerGoalHandle, status: str, code: int, text: str
                      ) -> None:
        """Set the goal's terminal state and result from the executor (``notify_execute``)."""
        result = FollowJointTrajectory.Result(error_code=code, error_string=text)

        def finish(goal_handle: ServerGoalHandle) -> object:
            if status == SUCCEEDED:
                goal_handle.succeed()
            elif status == CANCELED and goal_handle.is_cancel_requested:
                goal_handle.canceled()
            else:
                goal_handle.abort()
            return result
        self._server.notify_execute(handle, finish)

    def destroy(self) -> None:
        """Destroy the action server (before the node: rclpy does not do it for waitables)."""
        self._timer.cancel()
        self._server.destroy()


def _never_executed(handle: ServerGoalHandle) -> object:
    """Never scheduled (each goal's end is scheduled on its own): abort."""
    handle.abort()
    return FollowJointTrajectory.Result(error_code=INVALID_GOAL, error_string='internal')


def create_server(node: Node, handler: RequestHandler, stream: Stream, answers: Answers,
                  config: Callable[[], Config], now_ns: Callable[[], int], **options: object
                  ) -> FollowJointTrajectoryServer | None:
    """
    Create the action server, or say once (info) why there is none and return None.

    ``options`` are :class:`FollowJointTrajectoryServer`'s keyword arguments.
    """
    if FollowJointTrajectory is None:
        node.get_logger().info(f'control_msgs is not importable ({UNAVAILABLE}): running '
                               'without ~/follow_joint_trajectory')
        return None
    return FollowJointTrajectoryServer(node, handler, stream, answers, config, now_ns,
                                       **options)
