"""
The ``trajectory_generator`` node: plans from its current setpoint and streams it.

Thin ROS layer over :mod:`traj_gen_ros.planning` (request checks, plans, schedule) and the
core solver. Each request is parsed, validated, planned, sampled and published by short
functions below; the stream timer only samples the schedule at the current time.

Interface (all names relative, so namespaces and remapping work):

* ``joint_states`` (``sensor_msgs/JointState``, reliable, depth 10): setpoint at ``rate_hz``.
* ``~/trajectory`` (``trajectory_msgs/JointTrajectory``, reliable, transient local, depth 1):
  each accepted plan sampled every ``1/rate_hz`` s.
* ``~/status`` (``diagnostic_msgs/DiagnosticStatus``): OK or ERROR with a reason, per request.
* ``~/goal`` (``sensor_msgs/JointState``), ``~/via_points`` (``trajectory_msgs/JointTrajectory``).
* ``~/stop`` (``std_srvs/Trigger``): brake within ``max_acceleration`` and hold.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from dataclasses import dataclass
import json
import multiprocessing
import signal
import struct
import sys
import threading
import time

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
import numpy as np
from rcl_interfaces.msg import (
    FloatingPointRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from rclpy.signals import SignalHandlerOptions
from rclpy.subscription import Subscription
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from traj_gen_ros import planning
from traj_gen_ros.trajectory_wire import joint_names_cdr, joint_state_cdr, joint_trajectory_cdr
from trajectory_msgs.msg import JointTrajectory

NODE_NAME = 'trajectory_generator'
DEFAULT_JOINTS = [f'joint_{index}' for index in range(1, 7)]
CONFIG_PARAMETERS = ('joints', 'rate_hz', 'profile', 'via_velocities', 'max_velocity',
                     'max_acceleration', 'lspb_acceleration')
PER_JOINT = 'one value for all joints, or one per joint'
#: The planner thread gets the GIL back this often (s) so the stream keeps its rate.
SWITCH_INTERVAL = 0.0001
#: The spin loop checks this often (s) whether SIGINT/SIGTERM asked it to end.
SIGNAL_POLL = 0.1
#: Look-ahead of a new plan's start: at least this many stream periods ...
LEAD_PERIODS = 2
#: ... and this multiple of the slowest of the recent planning times, at most MAX_LEAD s.
LEAD_FACTOR = 2.0
MAX_LEAD = 1.0
#: A plan whose start the stream passed while it was planned is re-planned this often.
PLAN_ATTEMPTS = 4
#: The planner rests at least as long as it planned before it plans again (at most half of
#: the GIL for planning while requests keep coming), and at least MIN_PLAN_GAP s.
MIN_PLAN_GAP = 0.002
#: A request whose planning takes longer is refused (the worker process is replaced).
PLAN_TIMEOUT = 5.0
#: Depth of the request subscriptions: a burst while the stream's thread waits is kept.
REQUEST_DEPTH = 1000
#: Request callbacks run at most this often (s): a flood is taken in batches (each drains
#: the backlog), so the executor thread holds the GIL less and the stream keeps its rate.
REQUEST_ROUND_PERIOD = 0.005
#: Requests superseded by newer ones are answered together, at most this late (s): under
#: a flood one status per window instead of one per request (publishing holds the GIL).
SUPERSEDED_WINDOW = 0.02


@dataclass
class _Request:
    """A parsed request waiting for the planner."""

    kind: str
    values: dict[str, str]
    stamp_ns: int
    request: planning.GoalRequest | planning.ViaRequest


def _descriptor(description: str, **extra: object) -> ParameterDescriptor:
    return ParameterDescriptor(description=description, **extra)


def _peek_via_points(data: bytes) -> tuple[str, int]:
    """
    Read ``header.frame_id`` and the number of points of a CDR ``JointTrajectory``.

    Layout after the 4-byte encapsulation header: stamp (2 x 4 bytes), ``frame_id``
    (uint32 length with the NUL, bytes), ``joint_names`` (uint32 count, strings), then the
    uint32 point count; each uint32 aligned to 4 from the end of the encapsulation header.
    """
    offset = 8

    def string() -> str:
        nonlocal offset
        offset = (offset + 3) & ~3
        (length,) = struct.unpack_from('<I', data, 4 + offset)
        text = data[4 + offset + 4:4 + offset + 4 + max(length - 1, 0)]
        offset += 4 + length
        return text.decode('utf-8', 'replace')

    frame_id = string()
    offset = (offset + 3) & ~3
    (names,) = struct.unpack_from('<I', data, 4 + offset)
    offset += 4
    for _ in range(names):
        string()
    offset = (offset + 3) & ~3
    (count,) = struct.unpack_from('<I', data, 4 + offset)
    return frame_id, count


def _seconds(duration: Duration) -> float:
    return duration.sec + duration.nanosec * 1e-9


class TrajectoryGenerator(Node):
    """Plan smooth joint motions from the current setpoint and stream the setpoint."""

    def __init__(self, **kwargs: object) -> None:
        """Declare parameters, check them, and create the interface; ValueError if invalid."""
        super().__init__(NODE_NAME, **kwargs)
        self._declare_parameters()
        self._config = self._read_config()
        initial = planning.initial_state(self._config.joints,
                                         self.get_parameter('initial_positions').value)
        start = planning.PlannedMotion(planning.Hold(initial), 'hold', initial)
        self._schedule = planning.Schedule(start)
        self._names = list(self._config.joints)
        self._names_cdr = joint_names_cdr(self._names)
        # The stream thread streams, the executor thread parses, the planner thread plans.
        # _lock guards the schedule, the last published time and the schedule version.
        self._lock = threading.Lock()
        self._last_published_ns = -(2 ** 62)
        self._version = 0
        self._received = 0
        self._plan_times = collections.deque([0.0], maxlen=8)
        # _wake guards the newest request waiting for the planner and the stop plans to send.
        self._wake = threading.Condition()
        self._inbox: _Request | None = None
        self._outbox: list[tuple[str, int, int, planning.PlannedMotion, dict]] = []
        self._superseded: list[_Request] = []  # executor thread only
        self._last_round = 0.0  # time.monotonic() of the last request callback's end
        # Set when the node closes or the context shuts down: stream and planner end.
        self._stopping = threading.Event()
        self.context.on_shutdown(self._stopping.set)
        reliable = ReliabilityPolicy.RELIABLE
        self._joint_states = self.create_publisher(
            JointState, 'joint_states', QoSProfile(depth=10, reliability=reliable))
        self._trajectory = self.create_publisher(
            JointTrajectory, '~/trajectory',
            QoSProfile(depth=1, reliability=reliable, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._status = self.create_publisher(
            DiagnosticStatus, '~/status', QoSProfile(depth=REQUEST_DEPTH, reliability=reliable))
        self._goal_subscription = self.create_subscription(
            JointState, '~/goal', self._on_goal, REQUEST_DEPTH)
        # Raw: the point count is read off the wire first, so a huge message is refused
        # without building one Python object per point on the executor thread.
        self._via_subscription = self.create_subscription(
            JointTrajectory, '~/via_points', self._on_via_points_raw, REQUEST_DEPTH, raw=True)
        self.create_service(Trigger, '~/stop', self._on_stop)
        self._superseded_timer = self.create_timer(SUPERSEDED_WINDOW, self._answer_superseded)
        self._superseded_timer.cancel()  # runs only while superseded requests wait
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._trajectory_message(0, start)  # warm up the message imports
        self._start_worker()
        self._planner = threading.Thread(target=self._run_planner, name='planner', daemon=True)
        self._planner.start()
        self._stream = threading.Thread(target=self._run_stream, name='stream', daemon=True)
        self._stream.start()
        self.get_logger().info(
            f'streaming {len(self._names)} joints at {self._config.rate_hz:g} Hz, '
            f'profile {self._config.profile}')

    # ------------------------------------------------------------------ parameters

    def _declare_parameters(self) -> None:
        dynamic = {'dynamic_typing': True}
        joints = self.declare_parameter('joints', DEFAULT_JOINTS, _descriptor(
            'Joint names: the joint set and its order (read only).', read_only=True,
            type=ParameterType.PARAMETER_STRING_ARRAY)).value
        self.declare_parameter('initial_positions', [0.0] * len(joints or []), _descriptor(
            'Start position per joint in rad (read only); empty means zeros.',
            read_only=True, **dynamic))
        self.declare_parameter('rate_hz', 100.0, _descriptor(
            'JointState stream rate and sample rate of ~/trajectory, Hz.',
            floating_point_range=[FloatingPointRange(
                from_value=planning.MIN_RATE_HZ, to_value=planning.MAX_RATE_HZ)], **dynamic))
        self.declare_parameter('profile', 'quintic', _descriptor(
            'Profile of the next plans.', additional_constraints='cubic | quintic | lspb'))
        self.declare_parameter('via_velocities', 'heuristic', _descriptor(
            'Velocities at via points for cubic/quintic when none are given.',
            additional_constraints='heuristic | continuous'))
        self.declare_parameter('max_velocity', 1.0, _descriptor(
            f'Velocity limit in rad/s, > 0: {PER_JOINT}. Used for timing; checked on '
            'every plan.', **dynamic))
        self.declare_parameter('max_acceleration', 2.0, _descriptor(
            f'Acceleration limit in rad/s^2, > 0: {PER_JOINT}. Used for timing, checked '
            'on every plan, and the braking rate of ~/stop.', **dynamic))
        self.declare_parameter('lspb_acceleration', 0.0, _descriptor(
            f'LSPB blend acceleration in rad/s^2, 0..max_acceleration: {PER_JOINT}; '
            '0 means max_acceleration.', **dynamic))

    def _parameter_values(self) -> dict[str, object]:
        return {name: self.get_parameter(name).value for name in CONFIG_PARAMETERS}

    def _read_config(self) -> planning.Config:
        return planning.make_config(**self._parameter_values())

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        values = self._parameter_values()
        values.update({p.name: p.value for p in parameters if p.name in CONFIG_PARAMETERS})
        try:
            planning.make_config(**values)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        del parameters
        self._config = self._read_config()  # the stream thread reads rate_hz every period

    # ------------------------------------------------------------------ stream

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _wait_until(self, deadline_ns: int, period_ns: int) -> bool:
        """
        Sleep until ``deadline_ns`` on the node clock; False once the node is closing.

        Waits on an event (one wake-up, no objects made per period, unlike
        ``Clock.sleep_until``) in steps of at most a period, so a simulated clock that
        runs faster or slower than the wall clock is followed too.
        """
        while True:
            remaining_ns = deadline_ns - self._now_ns()
            if remaining_ns <= 0:
                return not self._stopping.is_set()
            if self._stopping.wait(min(remaining_ns, period_ns) * 1e-9):
                return False

    def _run_stream(self) -> None:
        """
        Publish the setpoint every ``1/rate_hz`` s on the node clock, in its own thread.

        Neither requests nor planning share its thread, so a flood of requests cannot delay
        it beyond a GIL switch. A setpoint published by another thread (a plan's first)
        re-phases it: the next one comes a period after that. Late ticks are not caught up.
        """
        next_ns = self._now_ns()
        while True:
            period_ns = int(1e9 / self._config.rate_hz)
            next_ns += period_ns
            if not self._wait_until(next_ns, period_ns) or not self.context.ok():
                return
            with self._lock:
                last_ns = self._last_published_ns
            if last_ns > next_ns - period_ns // 2:  # another thread published just now
                next_ns = last_ns
                continue
            try:
                self._publish_setpoint()
            except Exception as error:  # noqa: BLE001 - the stream outlives any one failure
                if self._stopping.is_set() or not self.context.ok():
                    return  # shutting down (SIGINT/SIGTERM): the publisher is gone
                self.get_logger().error(f'stream: publishing failed: {error!r}')
            now_ns = self._now_ns()
            if now_ns - next_ns > period_ns:  # fell behind: restart the phase from now
                next_ns = now_ns

    def _publish_setpoint(self) -> None:
        with self._lock:  # the planner thread publishes too: keep the stamps in order
            now_ns = self._now_ns()
            state = self._schedule.state_at(now_ns)
            self._last_published_ns = now_ns
            self._joint_states.publish(joint_state_cdr(
                now_ns, self._names_cdr, state.position, state.velocity))

    def _trajectory_message(self, start_ns: int, motion: planning.PlannedMotion) -> bytes:
        """
        Serialise the plan, sampled every ``1/rate_hz`` s, as a ``JointTrajectory``.

        Written straight to CDR from the sample arrays (``trajectory_wire``): a 1000-point
        message costs a fraction of a millisecond instead of one rclpy object per point.
        """
        times, positions, velocities, accelerations = planning.sample_motion(
            motion, self._config.rate_hz)
        time_ns = np.round(times * 1e9).astype(np.int64)
        return joint_trajectory_cdr(start_ns, self._names, time_ns, positions, velocities,
                                    accelerations)

    # ------------------------------------------------------------------ requests
    #
    # Callbacks (executor thread) only parse: a malformed request is refused at once. A
    # well-formed one goes to the inbox, which holds only the newest: one still waiting
    # there is answered "superseded". The planner thread plans the newest request from the
    # setpoint a short look-ahead in the future (the stream keeps running meanwhile) and
    # splices it in only if the stream has not passed that start yet, so nothing jumps.

    def _request_values(self, kind: str, frame_id: str) -> dict[str, str]:
        self._received += 1
        return {'request': kind, 'request_id': str(self._received), 'frame_id': frame_id}

    def _on_goal(self, message: JointState) -> None:
        self._take_requests(self._goal_subscription, JointState, False, self._goal, message)

    def _on_via_points_raw(self, data: bytes) -> None:
        self._take_requests(self._via_subscription, JointTrajectory, True, self._via_points,
                            data)

    def _take_requests(self, subscription: Subscription, message_type: type, raw: bool,
                       parse: Callable[[object], _Request | None], first: object) -> None:
        """
        Parse ``first`` and every request waiting behind it; submit the newest valid one.

        Draining the backlog in one callback: only the newest can be planned, and one
        executor round per message would cost more than the parsing (a flood).
        """
        try:
            parsed = [parse(first)]
            with subscription.handle:
                for _ in range(REQUEST_DEPTH):
                    taken = subscription.handle.take_message(message_type, raw)
                    if taken is None:
                        break
                    parsed.append(parse(taken[0]))
            parsed = [request for request in parsed if request is not None]
            if parsed:
                self._submit(parsed[-1], parsed[:-1])
        finally:
            self._pace_requests()

    def _pace_requests(self) -> None:
        """
        End a request callback no sooner than ``REQUEST_ROUND_PERIOD`` after the last one.

        Under a flood the next callback then finds a batch to drain at once; a request
        after a quiet spell is not delayed. Other callbacks (``~/stop``) wait at most that.
        """
        rest = self._last_round + REQUEST_ROUND_PERIOD - time.monotonic()
        if rest > 0.0:
            time.sleep(rest)
        self._last_round = time.monotonic()

    def _goal(self, message: JointState) -> _Request | None:
        values = self._request_values('goal', message.header.frame_id)
        try:
            request = planning.parse_goal(self._names, message.name, message.position)
        except planning.RequestError as error:
            self._report(DiagnosticStatus.ERROR, f'goal refused: {error}', values)
            return None
        return _Request('goal', values, 0, request)

    def _via_points(self, data: bytes) -> _Request | None:
        try:
            frame_id, count = _peek_via_points(data)
        except (IndexError, ValueError, struct.error):
            frame_id, count = '', 0
        if count > planning.MAX_VIA_POINTS:
            self._report(DiagnosticStatus.ERROR, f'via_points refused: via_points has {count} '
                         f'points, above the limit of {planning.MAX_VIA_POINTS}: split the '
                         'path into several requests',
                         self._request_values('via_points', frame_id))
            return None
        return self._via_points_message(deserialize_message(data, JointTrajectory))

    def _via_points_message(self, message: JointTrajectory) -> _Request | None:
        values = self._request_values('via_points', message.header.frame_id)
        points = message.points
        if len(points) <= planning.MAX_VIA_POINTS:  # parse_via refuses longer ones unread
            points = [(p.positions, p.velocities, p.accelerations, _seconds(p.time_from_start))
                      for p in points]
        try:
            request = planning.parse_via(self._names, message.joint_names, points)
        except planning.RequestError as error:
            self._report(DiagnosticStatus.ERROR, f'via_points refused: {error}', values)
            return None
        stamp = message.header.stamp
        stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec  # may be negative: "now"
        return _Request('via_points', values, stamp_ns, request)

    def _submit(self, request: _Request, superseded: list[_Request] | None = None) -> None:
        with self._wake:
            older, self._inbox = self._inbox, request
            self._wake.notify()
        superseded = ([] if older is None else [older]) + (superseded or [])
        if superseded and not self._superseded:
            self._superseded_timer.reset()
        self._superseded += superseded

    def _answer_superseded(self) -> None:
        self._superseded_timer.cancel()
        requests, self._superseded = self._superseded, []
        if requests:
            self._supersede(requests, 'a newer request')

    def _supersede(self, requests: list[_Request], by: str) -> None:
        """Answer requests dropped unplanned: one status, listing them if several."""
        if len(requests) == 1:
            self._report(DiagnosticStatus.WARN, f'{requests[0].kind} superseded by {by} '
                         'before it was planned: not executed', requests[0].values, log=False)
            return
        kinds = sorted({request.kind for request in requests})
        self._report(DiagnosticStatus.WARN, f'{len(requests)} requests superseded by {by} '
                     'before they were planned: not executed', {
                         'request': ','.join(kinds), 'superseded': str(len(requests)),
                         'request_ids': json.dumps([int(r.values['request_id'])
                                                    for r in requests]),
                         'frame_ids': json.dumps([r.values['frame_id'] for r in requests])},
                     log=False)

    def _on_stop(self, request: Trigger.Request, response: Trigger.Response
                 ) -> Trigger.Response:
        del request
        with self._wake:
            pending, self._inbox = self._inbox, None
        with self._lock:
            now_ns = self._now_ns()
            motion = planning.plan_stop(self._config, self._schedule.state_at(now_ns))
            self._schedule.splice(now_ns, motion, now_ns)
            self._version += 1
        if pending is not None:
            self._supersede([pending], '~/stop')
        self._publish_setpoint()
        with self._wake:
            self._outbox.append(('stop', now_ns, now_ns, motion, {'request': 'stop'}))
            self._wake.notify()
        response.success = True
        response.message = f'stopping: at rest in {motion.plan.duration:.3f} s'
        return response

    # ------------------------------------------------------------------ planner thread

    def _run_planner(self) -> None:
        """Plan the newest request and publish plans, off the stream's thread."""
        while True:
            with self._wake:
                while not self._stopping.is_set() and self._inbox is None and not self._outbox:
                    self._wake.wait()
                if self._stopping.is_set():
                    return
                outbox, self._outbox = self._outbox, []
                request, self._inbox = self._inbox, None
            try:
                for kind, now_ns, start_ns, motion, values in outbox:
                    self._execute(kind, now_ns, start_ns, motion, values)
                if request is not None:
                    began = time.monotonic()
                    self._plan_request(request)
                    rest = max(MIN_PLAN_GAP, time.monotonic() - began)
                    with self._wake:
                        self._wake.wait_for(lambda: self._stopping.is_set() or self._outbox, rest)
            except Exception as error:  # noqa: BLE001 - the planner must outlive any request
                if self._stopping.is_set() or not self.context.ok():
                    return
                self.get_logger().error(f'planner: unexpected failure: {error!r}')

    def _start_worker(self) -> None:
        """Start the planning process (spawned: no ROS state is copied) and warm it up."""
        context = multiprocessing.get_context('spawn')
        self._worker = context.Pool(1, initializer=planning.worker_init)
        self._worker.apply_async(planning.worker_init)

    def _plan_in_worker(self, config: planning.Config, state: planning.State,
                        hold: np.ndarray, request: planning.GoalRequest | planning.ViaRequest
                        ) -> planning.PlannedMotion:
        """
        Plan in the worker process, so planning never holds this process's GIL.

        A plan that takes longer than ``PLAN_TIMEOUT`` s is refused and the worker replaced.
        """
        pending = self._worker.apply_async(planning.plan_request,
                                           (config, state, hold, request))
        try:
            return pending.get(PLAN_TIMEOUT)
        except multiprocessing.TimeoutError:
            self._worker.terminate()
            if not self._stopping.is_set():
                self._start_worker()
            raise planning.RequestError(
                f'planning took longer than {PLAN_TIMEOUT:g} s (the limit): send fewer via '
                'points or a shorter motion') from None

    def _lead_ns(self, config: planning.Config) -> int:
        """Look-ahead of a new plan's start: a few periods, more if planning is slow."""
        lead = max(LEAD_PERIODS / config.rate_hz, LEAD_FACTOR * max(self._plan_times))
        return int(min(lead, MAX_LEAD) * 1e9)

    def _plan_request(self, request: _Request) -> None:
        config = self._config
        lead_ns = self._lead_ns(config)
        for _ in range(PLAN_ATTEMPTS):
            with self._lock:
                now_ns = self._now_ns()
                version = self._version
                start_ns = max(request.stamp_ns, now_ns + lead_ns)
                state = self._schedule.state_at(start_ns)
                hold = self._schedule.end_position(start_ns)
            began = time.perf_counter()
            try:
                motion = self._plan_in_worker(config, state, hold, request.request)
            except planning.RequestError as error:
                self._report(DiagnosticStatus.ERROR, f'{request.kind} refused: {error}',
                             request.values)
                return
            except Exception as error:  # noqa: BLE001 - a bad request must never kill the node
                self.get_logger().error(f'unexpected failure planning {request.kind}: '
                                        f'{error!r}')
                self._report(DiagnosticStatus.ERROR, f'{request.kind} refused: internal '
                             f'error: {error}', request.values)
                return
            elapsed = time.perf_counter() - began
            self._plan_times.append(elapsed)
            with self._lock:
                stopped = self._version != version  # ~/stop came in while this was planned
                spliced = not stopped and self._last_published_ns < start_ns
                if spliced:
                    self._schedule.splice(start_ns, motion, self._now_ns())
                    self._version += 1
            if stopped:
                self._supersede([request], '~/stop')
                return
            if spliced:
                break
            lead_ns = int(min(max(2 * lead_ns, LEAD_FACTOR * elapsed * 1e9), MAX_LEAD * 1e9))
        else:
            self._report(DiagnosticStatus.ERROR, f'{request.kind} refused: the stream passed '
                         f'its start {PLAN_ATTEMPTS} times while it was planned (look-ahead '
                         f'up to {lead_ns * 1e-9:.3f} s); resend it', request.values)
            return
        delayed = request.stamp_ns > now_ns + lead_ns
        if not delayed and self._inbox is None:  # its first setpoint goes out as it starts
            time.sleep(max(0.0, min(start_ns - self._now_ns(), MAX_LEAD * 1e9) * 1e-9))
            self._publish_setpoint()
        self._execute(request.kind, now_ns, start_ns, motion, request.values, delayed)

    def _execute(self, kind: str, now_ns: int, start_ns: int,
                 motion: planning.PlannedMotion, values: dict[str, str] | None = None,
                 delayed: bool = False) -> None:
        self._trajectory.publish(self._trajectory_message(start_ns, motion))
        duration = motion.plan.duration
        text = (f'accepted: profile={motion.profile}, duration={duration:.3f} s, '
                f'joints={len(self._names)}')
        if delayed:
            text += f', starts in {(start_ns - now_ns) * 1e-9:.3f} s'
        if motion.note:
            text += f' ({motion.note})'
        self._report(DiagnosticStatus.OK, text, {
            **(values or {'request': kind}), 'profile': motion.profile,
            'duration': f'{duration:.6f}', 'joints': str(len(self._names)),
            'start_delay': f'{(start_ns - now_ns) * 1e-9:.6f}'})

    def _report(self, level: bytes, text: str, values: dict[str, str],
                log: bool = True) -> None:
        if log and level != DiagnosticStatus.OK:
            self.get_logger().warning(text)
        self._status.publish(DiagnosticStatus(
            level=level, name=self.get_fully_qualified_name(), message=text,
            values=[KeyValue(key=key, value=value) for key, value in values.items()]))

    def destroy_node(self) -> None:
        """Stop the planner thread, then destroy the node."""
        with self._wake:
            self._stopping.set()
            self._wake.notify()
        self._worker.terminate()
        self._planner.join(timeout=10.0)
        self._stream.join(timeout=2.0)
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """
    Run the generator until SIGINT/SIGTERM; return the exit status.

    The signal handlers only set a flag that the spin loop checks every ``SIGNAL_POLL``
    s: a signal that arrives while the node or the executor is being built interrupts
    nothing half-made, and the node is then destroyed in order (exit status 0).
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    sys.setswitchinterval(SWITCH_INTERVAL)
    node = None
    status = 0
    try:
        node = TrajectoryGenerator()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while not stop.is_set():
            executor.spin_once(timeout_sec=SIGNAL_POLL)
    except ExternalShutdownException:
        pass  # the context was shut down by someone else
    except (ValueError, ParameterException) as error:
        print(f'{NODE_NAME}: invalid parameters: {error}', file=sys.stderr)
        status = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
