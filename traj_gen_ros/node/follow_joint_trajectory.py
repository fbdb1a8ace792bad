"""
``~/follow_joint_trajectory`` (``control_msgs/action/FollowJointTrajectory``): a goal's life.

So that MoveIt's simple controller manager (``type: FollowJointTrajectory``, ``action_ns:
follow_joint_trajectory``) can use the node as its controller. The points are parsed,
checked and planned in :mod:`traj_gen_ros.node.trajectory_goal`, the tolerances in
:mod:`traj_gen_ros.node.trajectory_tolerances`; this module is the rclpy glue:

* a goal is read, planned and spliced in the goal callback, before rclpy makes its handle
  and sends the response and status; then accepted and marked executing. One refused is
  aborted at once with its ``error_code`` and reason, and changes nothing;
* a valid goal goes the one way every request goes (``RequestHandler.submit``): planned
  from the stream's next tick and spliced there, continuing the setpoint without a jump;
* a newer goal, ``~/goal``, ``~/via_points`` or ``~/stop`` ends the active goal ABORTED
  saying what replaced it; a cancel brakes to rest (``plan_stop``), then CANCELED;
* a monitor timer on the executor (every ``MONITOR_PERIOD`` s while a goal is active)
  publishes the feedback (:meth:`ActiveGoal.feedback`, at most once per stream period),
  checks the tolerances against a measured state no older than ``STALE_AFTER`` and ends
  the goal: SUCCEEDED once the stream has sent the trajectory's end (and the arm is
  within ``goal_tolerance`` and still).

The goal, cancel and result services are served by the request thread
(:mod:`traj_gen_ros.node.request_thread`), as ``~/goal`` is. The terminal state and
result are set by an execute callback scheduled on the executor only when the goal ends
(:meth:`ActionServer.notify_execute`): Jazzy's executor resumes an ``async`` one on every
spin, a busy loop beside the stream thread. What the two threads share (the active goal,
the replaced ones) is kept under a lock; a goal is watched once it is fully started, and
an end decided before its handle exists is applied as soon as it does.
"""

from __future__ import annotations

from collections.abc import Callable
import threading
import time

import numpy as np
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import GoalEvent, ServerGoalHandle
from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from traj_gen_ros.node.answers import Answers, Request
from traj_gen_ros.node.config import Config
from traj_gen_ros.node.motion import PlannedMotion, State
from traj_gen_ros.node.request_handler import brake_planner, RequestHandler
from traj_gen_ros.node.running_goal import ActiveGoal, read_goal_message
from traj_gen_ros.node.stream import Stream
from traj_gen_ros.node.tolerance_parameters import ToleranceParameters
from traj_gen_ros.node.trajectory_goal import (
    GoalError,
    INVALID_GOAL,
    PATH_TOLERANCE_VIOLATED,
    plan_trajectory_goal,
    SUCCESSFUL,
    TrajectoryGoal,
)
from traj_gen_ros.node.trajectory_tolerances import (
    ABORTED,
    CANCELED,
    outcome,
    SUCCEEDED,
)

try:
    from control_msgs.action import FollowJointTrajectory
    UNAVAILABLE = ''
except ImportError as _error:  # no control_msgs: the node runs without the action
    FollowJointTrajectory = None
    UNAVAILABLE = str(_error)

KIND = 'follow_joint_trajectory'
#: The requests the action itself makes (braking on a cancel or a path violation).
OWN_KINDS = ('follow_joint_trajectory_cancel', 'follow_joint_trajectory_hold')
#: The monitor's period (s): feedback rate and how soon a result follows its cause.
MONITOR_PERIOD = 0.02
#: A measured state older than this (s) is not checked against the tolerances: until
#: ``joint_topic_timeout`` says it is lost, it would pass for a deviation.
STALE_AFTER = 0.1
_REPLACED_BY = {'goal': 'a ~/goal request', 'via_points': 'a ~/via_points request',
                'stop': 'a ~/stop call', KIND: 'a newer follow_joint_trajectory goal'}


class FollowJointTrajectoryServer:
    """The action server and the life cycle of its goals (see the module doc)."""

    def __init__(self, node: Node, handler: RequestHandler, stream: Stream, answers: Answers,
                 config: Callable[[], Config], now_ns: Callable[[], int],
                 measured_positions: Callable[[], np.ndarray | None] = lambda: None,
                 measured_velocities: Callable[[], np.ndarray | None] = lambda: None,
                 reseed_to_measured: Callable[[], None] | None = None,
                 callback_group: CallbackGroup | None = None) -> None:
        """
        Serve ``~/follow_joint_trajectory`` on ``node`` through ``handler``.

        :param measured_positions: where the arm is (rad, joint-set order), or None
            without a measured state (then the setpoint stands for it).
        :param measured_velocities: the measured velocities (rad/s), or None.
        :param reseed_to_measured: hold where the arm is after a path-tolerance violation;
            default: brake to rest within the limits. ``measured_age`` (attribute): s
            since the measured state arrived.
        :param callback_group: the action server's (a ``NotForTheExecutor``, whose
            thread then serves :attr:`action_server`); default the node's.
        """
        self._node, self._handler, self._stream, self._answers = node, handler, stream, answers
        self._config, self._now_ns = config, now_ns
        self.measured_positions, self.measured_velocities = measured_positions, \
            measured_velocities
        self.measured_age: Callable[[], float] = lambda: 0.0
        #: When the goal arrived (system ns): the request thread's wake-up (attribute).
        self.arrival_ns: Callable[[], int] = time.time_ns
        self.reseed_to_measured = reseed_to_measured or self._hold
        self._log = node.get_logger()
        self._lock = threading.Lock()
        self._active: ActiveGoal | None = None
        self._starting: ActiveGoal | None = None
        self._pending: tuple | None = None  # (goal message, outcome) from _on_goal
        self._replaced: list[ActiveGoal] = []
        self._tolerances = ToleranceParameters(node, lambda: len(self._config().joints))
        previous = handler.on_accepted

        def on_accepted(request: Request, start_ns: int) -> None:
            previous(request, start_ns)
            self._on_request_accepted(request, start_ns)
        handler.on_accepted = on_accepted
        handler.on_dropped = self._on_request_dropped
        self._timer = node.create_timer(MONITOR_PERIOD, self._monitor)
        self._timer.cancel()
        self._server = ActionServer(
            node, FollowJointTrajectory, '~/follow_joint_trajectory', self._unexpected,
            goal_callback=self._on_goal, handle_accepted_callback=self._start,
            cancel_callback=self._on_cancel,
            callback_group=callback_group)

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
            self._finish(pending[1][0], ABORTED, INVALID_GOAL, 'the goal response failed')

    def _start(self, handle: ServerGoalHandle) -> None:
        """Mark the accepted goal executing; end it if it was refused or ended (request thread)."""
        pending, self._pending = self._pending, None
        if pending is None or pending[0] is not handle.request:  # not seen by _on_goal
            self._on_goal(handle.request)
            pending, self._pending = self._pending, None
        handle._update_state(GoalEvent.EXECUTE)  # what execute() does, minus scheduling
        outcome = pending[1]
        if not isinstance(outcome[0], ActiveGoal):
            self._end(handle, ABORTED, *outcome)
            return
        active, motion = outcome
        with self._lock:
            active.handle = handle
            early_end = active.early_end
        if early_end is not None:  # replaced or aborted before rclpy made its handle
            self._end(handle, *early_end)
            return
        self._started(active, motion)

    def _planner(self, active: ActiveGoal) -> Callable[..., PlannedMotion]:
        tolerance = self._tolerances.defaults[0]

        def plan(config: Config, state: State, hold_at: np.ndarray,
                 goal: TrajectoryGoal) -> PlannedMotion:
            measured = self.measured_positions()
            reference = state.position if measured is None else measured
            return plan_trajectory_goal(config, state, hold_at, goal, reference,
                                        tolerance if tolerance > 0.0 else np.inf,
                                        measured is not None)
        return plan

    def _started(self, active: ActiveGoal, motion: PlannedMotion) -> None:
        active.end_ns = active.start_ns + int(round(motion.plan.duration * 1e9))
        active.target = motion.end
        goal = active.goal
        if goal.factor > 1.0:
            self._log.warning(f'{KIND} goal: {goal.slowed}: lasts '
                              f'{motion.plan.duration:.4g} s instead of {goal.duration:.4g} s')
        self._timer.reset()
        executor = self._node.executor
        if executor is not None:
            executor.wake()  # its wait began without the monitor timer

    def _on_request_accepted(self, request: Request, start_ns: int) -> None:
        """Any request spliced in (any thread): the one it replaces ends (:meth:`_monitor`)."""
        with self._lock:
            active, starting = self._active, self._starting
            if request.kind in OWN_KINDS:
                if active is not None and request is active.cancel:
                    active.brake_start_ns = start_ns
                return
            if starting is not None and request is starting.request:
                starting.start_ns = start_ns
                self._active = starting
            else:
                self._active = None
            if active is not None:
                active.replaced = (f'replaced by {_REPLACED_BY.get(request.kind, request.kind)} '
                                   f'(request_id {request.values.get("request_id", "?")}); '
                                   'the motion continues from the setpoint')
                self._replaced.append(active)

    def _on_request_dropped(self, request: Request, reason: str) -> None:
        """Abort the active goal if its request was dropped before its start."""
        with self._lock:
            active = self._active
            if active is not None and request is active.request:
                active.replaced = f'dropped: {reason}'
                self._replaced.append(active)
                self._active = None

    # ------------------------------------------------------------------ cancel

    def _on_cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        """Accept a cancel of the active goal and brake to rest (request thread)."""
        try:
            with self._lock:
                active = self._active
                if active is None or active.handle is not handle:
                    return CancelResponse.REJECT  # ended, or ending
                if active.cancel is not None:
                    return CancelResponse.ACCEPT
                active.cancel = Request(OWN_KINDS[0], self._answers.values(OWN_KINDS[0], ''),
                                        0, None)
            if self._handler.submit(active.cancel, brake_planner) is None:
                active.brake_start_ns = self._stream.last_published()
            return CancelResponse.ACCEPT
        except Exception as error:  # noqa: BLE001 - a cancel must never kill the node
            self._log.error(f'{KIND}: cancel failed: {error!r}')
            return CancelResponse.REJECT

    def _hold(self) -> None:
        """Brake to rest within the limits: the default after a path-tolerance violation."""
        request = Request(OWN_KINDS[1], self._answers.values(OWN_KINDS[1], ''), 0, None)
        self._handler.submit(request, brake_planner)

    # ------------------------------------------------------------------ monitor and end

    def _monitor(self) -> None:
        """Feedback, tolerances and the end of the goals (executor thread, a timer)."""
        try:
            with self._lock:
                replaced, self._replaced = self._replaced, []
                active = self._active
            for goal in replaced:
                status = CANCELED if goal.cancel is not None else ABORTED
                self._end_goal(goal, status, INVALID_GOAL if status == ABORTED
                               else SUCCESSFUL, goal.replaced)
            if active is not None and active.target is not None:  # started (_started)
                self._watch(active)
            if self._active is None and not self._replaced:
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
                self._finish(active, CANCELED, SUCCESSFUL, 'canceled: braked to rest')
            return
        desired = self._stream.setpoint(max(now_ns, published_ns))  # commanded: scaled
        measured = self.measured_positions()
        self._feedback(active, now_ns, desired, measured)
        if measured is not None and self.measured_age() > STALE_AFTER:
            return  # judged on a fresh one, or ended by the timeout (abort_active)
        end_ns = active.end(now_ns, published_ns, moving)
        ended = outcome(active.tolerances, active.goal.request.joints, self._config().joints,
                        (active.start_ns, end_ns, now_ns, published_ns),
                        desired.position, active.target, measured,
                        self.measured_velocities, active.goal.slowed)
        if ended is not None:
            self._finish(active, *ended)
            if ended[1] == PATH_TOLERANCE_VIOLATED:
                self.reseed_to_measured()

    def destroy(self) -> None:
        """Destroy the action server (before the node: rclpy does not do it for waitables)."""
        self._timer.cancel()
        self._server.destroy()

    def abort_active(self, reason: str) -> None:
        """End the running goal ABORTED with ``reason``: the measured state was lost."""
        with self._lock:
            active = self._active
        if active is not None:
            self._finish(active, ABORTED, PATH_TOLERANCE_VIOLATED, reason)

    def _feedback(self, active: ActiveGoal, now_ns: int, desired: State,
                  measured: np.ndarray | None) -> None:
        if now_ns - active.feedback_ns < self._config().period_ns:
            return
        active.feedback_ns = now_ns
        active.handle.publish_feedback(active.feedback(
            FollowJointTrajectory.Feedback(), now_ns, desired, measured))

    def _finish(self, active: ActiveGoal, status: str, code: int, text: str) -> None:
        with self._lock:
            if self._active is active:
                self._active = None
        self._end_goal(active, status, code, text)

    def _end_goal(self, goal: ActiveGoal, status: str, code: int, text: str) -> None:
        """
        End ``goal`` once; before its handle exists, in :meth:`_start`.

        The first end decided counts: the monitor may end a goal that the request thread
        has just replaced.
        """
        with self._lock:
            if goal.ended:
                return
            goal.ended = True
            if goal.handle is None:
                goal.early_end = (status, code, text)
                return
        self._end(goal.handle, status, code, text)

    def _end(self, handle: ServerGoalHandle, status: str, code: int, text: str) -> None:
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
        self._server.notify_execute(handle, finish)

    def _unexpected(self, handle: ServerGoalHandle) -> object:
        """Never scheduled (:meth:`_end` gives each goal its own): abort."""
        handle.abort()
        return FollowJointTrajectory.Result(error_code=INVALID_GOAL, error_string='internal')


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
