"""
A request from its callback to the stream, in the six steps of docs/node-design.md.

The goal and via-point callbacks run on the request thread
(:mod:`traj_gen_ros.node.requests.thread`), ``~/stop`` on the executor's; a lock lets one
request through at a time.

1. *take* (:meth:`RequestHandler.take`): the request that woke the callback and every
   request waiting behind it (a burst is drained in one callback: only the newest runs);
2. *read* (:mod:`traj_gen_ros.node.requests.reading`; :mod:`traj_gen_ros.node.messages.parsing`,
   the bytes read by :mod:`traj_gen_ros.node.messages.wire`): a malformed one is refused at once;
   the older valid ones are answered "superseded";
3. *validate and plan* the newest (a :class:`Planner`: :data:`PIPELINE`, :func:`plan_request` of
   :mod:`traj_gen_ros.node.planning.pipeline`, or :data:`BRAKE` for ``~/stop``) from the
   schedule's setpoint at the start: the stream's next tick not yet published (or the
   request's future ``header.stamp``), refusing with a reason;
4. *splice* it into the schedule at the start (:meth:`Stream.splice`);
5. the stream thread *publishes* its first setpoint at that tick
   (:mod:`traj_gen_ros.node.stream.stream`);
6. *sample* the plan for ``~/trajectory`` from its start and publish it, then the OK
   status once the stream has published that setpoint (a client reading the answer sees
   it started; a delayed start is answered at once) (:mod:`traj_gen_ros.node.requests.answers`).

Sampling comes after the splice so that it does not delay the start (a plan that reaches
the splice has finite coefficients and finite, checked peaks, so its samples are finite),
and after the first setpoint when that is due within ``SAMPLE_AFTER_FIRST_NS``, so that it
does not hold the GIL while the stream thread publishes it.

The start tick is the first one at least the median planning time of the last requests
alike (kind, profile, and from rest or a moving state) away (so the plan is usually ready
by then). If the stream published it while the request was being planned anyway (a cold
cache, a long path, a loaded machine), the request is
planned again from the setpoint the stream published last, exactly as published, and
takes over at the next tick if ready by then: one period later, not a re-plan far ahead.
After ``PLAN_ATTEMPTS`` such misses it is refused.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import threading
import time

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
import numpy as np
from rclpy.subscription import Subscription
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from traj_gen_ros.node.planning.motion import held, PlannedMotion, State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop
from traj_gen_ros.node.planning.pose_goal import plan_pose
from traj_gen_ros.node.planning.tool_motion import CARTESIAN_PATH, CIRCULAR_GOAL, plan_tool_path
from traj_gen_ros.node.requests.answers import Answers
from traj_gen_ros.node.requests.collection import QuietCollection
from traj_gen_ros.node.requests.reading import (
    goal_request,
    pose_request,
    tool_path_request,
    via_request,
)
from traj_gen_ros.node.requests.request import Request, RequestListener
from traj_gen_ros.node.requests.start_tick import PLAN_ATTEMPTS, Planner, StartTick
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.stream import Stream
from trajectory_msgs.msg import JointTrajectory

#: Depth of the request subscriptions: a burst while the executor is busy is kept.
REQUEST_DEPTH = 1000
#: Rounds of request callbacks closer than this (s) are spaced out to it: under a flood
#: the next round then drains a batch at once, so the executor thread holds the GIL less
#: and the stream keeps its rate. A request after a quiet spell is not delayed.
REQUEST_ROUND_PERIOD = 0.005
#: The OK status waits at most this long (s) for the motion's first setpoint.
ANSWER_WAIT = 0.1
#: A motion whose first setpoint is due within this long (ns) is sampled for
#: ``~/trajectory`` only once the stream has published that setpoint: sampling holds the
#: GIL, which the stream thread needs at that tick (it went out 0.17 ms p50, 0.44 ms at
#: worst after its tick when they overlapped, against 0.09 and 0.11 ms otherwise).
SAMPLE_AFTER_FIRST_NS = 1_500_000


class RequestHandler:
    """Take requests off the subscriptions, plan the newest, splice it into the stream."""

    def __init__(self, config: Callable[[], Config], stream: Stream, answers: Answers,
                 now_ns: Callable[[], int], log_error: Callable[[str], None],
                 elapsed_ns: Callable[[], int] = time.perf_counter_ns, *,
                 refusal: Callable[[], str | None] = lambda: None,
                 on_plan: Callable[[int, PlannedMotion], None] = lambda start_ns, motion: None
                 ) -> None:
        """
        Handle requests with ``config()`` on the node clock ``now_ns()``.

        ``elapsed_ns`` times planning; ``refusal()``: a reason to refuse every request now,
        or ``None``; ``on_plan(start_ns, motion)``: every motion spliced in.
        """
        self._elapsed_ns, self._refusal, self._on_plan = elapsed_ns, refusal, on_plan
        self._config, self._stream, self._answers = config, stream, answers
        self._now_ns, self._log_error = now_ns, log_error
        self._last_round = 0.0  # time.monotonic() at the end of the last request callback
        self._lock = threading.Lock()  # one request at a time (the request thread, the action)
        self._start_tick = StartTick(stream, answers, now_ns, log_error, elapsed_ns)
        self._listeners: list[RequestListener] = []
        self._collection = QuietCollection(  # no collection while the GIL is in demand
            stream, now_ns, lambda: min(2e-9 * config().period_ns, ANSWER_WAIT))

    def add_listener(self, listener: RequestListener) -> None:
        """Tell ``listener`` of every request spliced in and every one dropped (the action)."""
        self._listeners.append(listener)

    # ------------------------------------------------------------------ take and parse

    def take(self, subscription: Subscription, topic: str, first: tuple[bytes, dict]) -> None:
        """
        Parse ``first`` and every request waiting behind it; execute the newest valid one.

        Each is a raw ``(message, info)`` pair; the info's ``received_timestamp`` (ns, system
        clock) goes into the answer as ``received``.
        """
        reader = READERS[topic]
        message_type, parse, planner = reader.message_type, reader.read, reader.planner
        try:
            with self._collection.deferred(), self._lock:
                self._take_newest(subscription, message_type, first, parse, planner)
        finally:
            self._pace()

    def _take_newest(self, subscription: Subscription, message_type: type,
                     first: tuple[bytes, dict],
                     parse: Callable[[bytes, int, Sequence[str], Answers], Request | None],
                     planner: Planner) -> None:
        """Drain the subscription after ``first``; execute the newest valid request."""
        waiting = [first]
        with subscription.handle:
            for _ in range(REQUEST_DEPTH):
                taken = subscription.handle.take_message(message_type, True)
                if taken is None:
                    break
                waiting.append(taken)
        joints = self._config().joints
        parsed = [parse(message, info.get('received_timestamp', 0), joints, self._answers)
                  for message, info in waiting]
        parsed = [request for request in parsed if request is not None]
        if parsed:
            self._answers.superseded(parsed[:-1])
            newest = parsed[-1]
            self.execute(newest, planner)

    def _pace(self) -> None:
        """End a request callback no sooner than ``REQUEST_ROUND_PERIOD`` after the last one."""
        rest = self._last_round + REQUEST_ROUND_PERIOD - time.monotonic()
        if rest > 0.0:
            time.sleep(rest)
        self._last_round = time.monotonic()

    # ------------------------------------------------------------------ plan and splice

    def execute(self, request: Request, plan: Planner) -> PlannedMotion | None:
        """
        Plan ``request`` from the stream's next tick, splice it in, sample it, answer it.

        Returns the motion spliced in, or ``None`` when it was refused (answered ERROR).
        """
        config = self._config()
        reason = self._refusal()
        if reason is not None:
            self._answers.refused(request, reason)
            return None

        def spliced(start_ns: int, motion: PlannedMotion) -> None:
            self._on_plan(start_ns, motion)
            for listener in self._listeners:
                listener.accepted(request, start_ns)

        placed = self._start_tick.plan_and_splice(request, plan, config, spliced)
        if placed is None:
            return None
        motion, now_ns, start_ns, first_ns = placed
        waited = first_ns - self._now_ns() <= SAMPLE_AFTER_FIRST_NS
        if waited:
            self._stream.wait_published(first_ns, ANSWER_WAIT)
        try:
            message = self._answers.trajectory(start_ns, motion, config.rate_hz)
        except Exception as error:  # noqa: BLE001 - checked plans are finite: a bug if not
            self._log_error(f'sampling an accepted {request.kind} failed: {error!r}; braking')
            self._brake(config)
            self._answers.refused(request, f'internal error: {error}')
            return None
        self._answers.publish_trajectory(message)
        chain = config.kinematics.chain
        if chain is not None:
            self._answers.publish_tool_path(start_ns, motion, chain.base_frame)
        if not waited and first_ns - now_ns <= ANSWER_WAIT * 1e9:
            self._stream.wait_published(first_ns, ANSWER_WAIT)
        self._answers.accepted(request, motion, now_ns, first_ns)
        return motion

    def submit(self, request: Request, plan: Planner) -> PlannedMotion | None:
        """:meth:`execute`, one request at a time with the others (for the action server)."""
        with self._collection.deferred(), self._lock:
            return self.execute(request, plan)

    def dropped(self, requests: Sequence[object], reason: str) -> None:
        """
        Answer accepted requests the stream dropped before their start: ERROR, ``reason``.

        Under the request lock, so the answer follows the request's own OK. Tags that are
        not a :class:`Request` (holds, brakes) are skipped.
        """
        with self._lock:
            for request in requests:
                if isinstance(request, Request):
                    self._answers.report(DiagnosticStatus.ERROR,
                                         f'{request.kind} dropped: {reason}', request.values)
                    for listener in self._listeners:
                        listener.dropped(request, reason)

    def _brake(self, config: Config) -> None:
        """Brake from the next tick (after a failure, or when the measured state is lost)."""
        with self._start_tick.guard:
            for _ in range(PLAN_ATTEMPTS):
                start_ns = self._stream.next_start()
                state, _ = self._stream.start_state(start_ns, scaled=False)
                try:
                    motion = plan_stop(config, state, self._stream.running_at(start_ns))
                except ValueError as error:  # a non-finite state: the stream holds its last
                    self._log_error(f'braking failed: {error!r}')
                    return
                if self._stream.splice(start_ns, motion) is not None:
                    self._on_plan(start_ns, motion)
                    return

    def brake(self) -> None:
        """
        Brake within the limits from the next tick and hold (no answer: no request).

        It does not wait for a request being planned: that one is dropped.
        """
        with self._start_tick.guard:
            self._start_tick.preempt()
            self._brake(self._config())

    def reseed(self, target: Callable[[State, bool], np.ndarray | None]) -> bool:
        """
        Re-seed the setpoint where ``target(state at the next tick, moving)`` says (rad).

        How the measured state re-seeds the setpoint: one step to that position at the
        next tick, then a hold there (a plan of no duration). ``target`` runs under the
        request lock, so no request is planned meanwhile; ``None`` leaves the schedule
        alone. True once spliced in.
        """
        with self._lock:
            for _ in range(PLAN_ATTEMPTS):
                start_ns = self._stream.next_start()
                state, _ = self._stream.start_state(start_ns, scaled=False)
                position = target(state, self._stream.moving_at(start_ns))
                if position is None:
                    return False
                motion = held(position, 'hold', 're-seeded at the measured state')
                if self._stream.splice(start_ns, motion) is not None:
                    self._on_plan(start_ns, motion)
                    return True
        return False

    def stop(self, response: Trigger.Response) -> Trigger.Response:
        """
        ``~/stop``: brake within ``max_acceleration`` from the next tick, then hold.

        The response says when it is at rest, or why it was refused (as ``~/status``
        does: ``stop refused: <reason>``, e.g. while the measured state is awaited).
        """
        with self._start_tick.guard:  # not the request lock: a request being planned
            self._start_tick.preempt()  # is dropped, and does not delay the brake
            request = Request('stop', self._answers.values('stop', ''), 0, None)
            motion = self.execute(request, BRAKE)
        response.success = motion is not None
        response.message = (f'stopping: at rest in {motion.plan.duration:.3f} s' if motion
                            else f'stop refused: {request.refusal or "unknown reason"}')
        return response


def _brake(config: Config, state: State, hold_at: np.ndarray,
           running: tuple[PlannedMotion, float]) -> PlannedMotion:
    """Plan ``~/stop``: brake from ``state`` to rest (:func:`plan_stop`), along a path."""
    del hold_at  # a stop ends where braking ends
    return plan_stop(config, state, running)


#: Every request that moves somewhere: the one pipeline
#: (:func:`~traj_gen_ros.node.planning.pipeline.plan_request`).
PIPELINE = Planner(plan_request)
#: ``~/stop`` and the action's cancel: a brake from the commanded state, never slowed. It
#: shares the splice, not the checks: it always runs.
BRAKE = Planner(_brake, commanded=True)
#: A pose goal: its joint goal by inverse kinematics, then the pipeline as ``~/goal``.
POSE = Planner(plan_pose)
#: A line or an arc of the tool: its joint path, then the pipeline with its timing.
TOOL_PATH = Planner(plan_tool_path)


@dataclass(frozen=True)
class Reader:
    """A request topic's message type, how its messages are read and how they are planned."""

    message_type: type
    read: Callable[[bytes, int, Sequence[str], Answers], Request | None]
    planner: Planner


#: Each request topic (``~/<name>``): its reader.
READERS = {
    'goal': Reader(JointState, goal_request, PIPELINE),
    'via_points': Reader(JointTrajectory, via_request, PIPELINE),
    'pose_goal': Reader(PoseStamped, pose_request, POSE),
    CARTESIAN_PATH: Reader(Path, tool_path_request(CARTESIAN_PATH), TOOL_PATH),
    CIRCULAR_GOAL: Reader(Path, tool_path_request(CIRCULAR_GOAL), TOOL_PATH),
}
