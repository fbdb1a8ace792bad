"""
ROS side of ``traj-gen``: send goals, via points and poses to a generator, record its plans.

:mod:`traj_gen_ros.cli.main` imports this module only when one of these commands runs (the
offline subcommands need no ROS). A status answers a request when it comes from the node
(``name`` is its full name) after the request was published, its ``request`` value names
the request's kind (``goal``, ``via_points``, ``pose_goal``, ``cartesian_path``, ...) and
its ``frame_id`` value echoes the request's ``header.frame_id``: for a goal or via points a
token of ``traj-gen``'s own (``traj-gen/<pid>/<random>``), for a pose, line or arc its frame
(``--frame``). A node that does not echo ``frame_id`` is matched on the kind alone.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator
import contextlib
import json
import math
import os
import re
import secrets
import time
from typing import TYPE_CHECKING

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from traj_gen_ros.cli.common import (
    EXIT_OK,
    EXIT_REFUSED,
    finite_number,
    NoAnswerError,
    report_plot,
    UsageError,
)
from traj_gen_ros.cli.pose_goal import answered_joints, pose_message
from traj_gen_ros.cli.tool_path_args import TOPICS
from traj_gen_ros.cli.tool_path_goal import path_message, plan_end
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

if TYPE_CHECKING:  # matplotlib is imported only when a plot is made
    from matplotlib.figure import Figure

_AT_GOAL = 1e-6  # rad: the motion has ended when the named joints are this close, at rest
_LEVELS = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
_SPIN_PERIOD = 0.05


def node_name(text: str) -> str:
    """Return the generator's full name, ``/ns/name``, from ``--node``."""
    name = '/' + text.strip('/')
    if not re.fullmatch(r'(/[A-Za-z_][A-Za-z0-9_]*)+', name):
        raise UsageError(f"--node '{text}' is not a node name such as /trajectory_generator")
    return name


def joint_states_topic(node: str) -> str:
    """Return ``joint_states`` in the namespace of ``node`` (the node's default topic)."""
    namespace = node.rsplit('/', 1)[0]
    return f'{namespace}/joint_states'


def _check_timeout(timeout: float) -> None:
    """Refuse a ``--timeout`` that is not > 0 s (UsageError)."""
    if not timeout > 0:
        raise UsageError('--timeout must be > 0 s')


def goal_from_args(items: list[str], degrees: bool) -> tuple[list[str], list[float]]:
    """
    Read ``traj-gen goal``'s ``JOINT=POSITION`` words into names and positions (rad).

    The command line's side only; the node reads the message it gets with
    :func:`traj_gen_ros.node.messages.parsing.parse_goal`.
    """
    names, positions = [], []
    scale = math.radians(1.0) if degrees else 1.0
    for item in items:
        name, sep, value = item.partition('=')
        if not sep or not name:
            raise UsageError(f"'{item}' is not JOINT=POSITION (e.g. joint_1=0.5)")
        names.append(name)
        positions.append(finite_number(value, name) * scale)
    return names, positions


def via_from_args(joints: list[str], points: list[list[str]],
                  degrees: bool) -> list[tuple[list[float], float]]:
    """
    Read ``traj-gen via``'s ``--point Q… [@T]`` groups: ``[(positions (rad), time (s)), …]``.

    Either every point has ``@T`` or none has; with none every time is 0, which the node
    reads as "time the path from the limits".
    """
    scale = math.radians(1.0) if degrees else 1.0
    parsed = []
    timed = [group[-1].startswith('@') for group in points]
    if any(timed) and not all(timed):
        raise UsageError('give @T on every --point, or on none (the node then times them)')
    for index, group in enumerate(points):
        values = group[:-1] if timed[index] else group
        when = finite_number(group[-1][1:], f'point {index} time') if timed[index] else 0.0
        if len(values) != len(joints):
            raise UsageError(f'point {index} has {len(values)} positions for {len(joints)} '
                             f'joints ({" ".join(joints)})')
        parsed.append(([finite_number(v, f'point {index}') * scale for v in values], when))
    return parsed


class _Session:
    """An rclpy context, node and executor for one command."""

    def __init__(self) -> None:
        self.context = rclpy.Context()
        rclpy.init(args=['traj-gen'], context=self.context)
        self.node = rclpy.create_node(f'traj_gen_cli_{os.getpid()}', context=self.context,
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def wait(self, condition: Callable[[], object], timeout: float, what: str) -> object:
        """Spin until ``condition()`` is truthy and return it; NoAnswerError after ``timeout``."""
        deadline = time.monotonic() + timeout
        while True:
            value = condition()
            if value:
                return value
            if time.monotonic() > deadline:
                raise NoAnswerError(f'no answer after {timeout:g} s: {what}')
            self.executor.spin_once(timeout_sec=_SPIN_PERIOD)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.context.try_shutdown()


@contextlib.contextmanager
def _session() -> Iterator[_Session]:
    session = _Session()
    try:
        yield session
    finally:
        session.close()


def _reliable(depth: int, transient_local: bool = False) -> object:
    durability = (DurabilityPolicy.TRANSIENT_LOCAL if transient_local
                  else DurabilityPolicy.VOLATILE)
    return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=durability)


def _status_dict(status: object) -> dict:
    level = status.level
    level = level[0] if isinstance(level, bytes) else int(level)
    return {'level': _LEVELS.get(level, str(level)), 'name': status.name,
            'message': status.message,
            'values': {pair.key: pair.value for pair in status.values}}


def _request_message(args: argparse.Namespace
                     ) -> tuple[object, str, list[str] | None, list[float] | None]:
    """
    Build the request; return it, its kind, the named joints and their final targets.

    A pose goal names no joints: its targets are the joint values the node's answer gives
    (a line's or an arc's: the end of the node's plan).
    """
    if args.command == 'pose':
        return pose_message(args), 'pose_goal', None, None
    if args.command in TOPICS:
        return path_message(args), TOPICS[args.command], None, None
    token = f'traj-gen/{os.getpid()}/{secrets.token_hex(4)}'
    if args.command == 'goal':
        names, positions = goal_from_args(args.positions, args.degrees)
        message = JointState(name=names, position=positions)
        message.header.frame_id = token
        return message, 'goal', names, positions
    points = via_from_args(args.joints, args.points, args.degrees)
    message = JointTrajectory(joint_names=list(args.joints))
    message.header.frame_id = token
    for positions, when in points:
        nanoseconds = int(round(when * 1e9))
        message.points.append(JointTrajectoryPoint(
            positions=positions, time_from_start=Duration(
                sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)))
    return message, 'via_points', list(args.joints), points[-1][0]


def run_request(args: argparse.Namespace) -> int:
    """``traj-gen goal`` / ``via`` / ``pose`` / ``line`` / ``arc``: send, print the answer."""
    node = node_name(args.node)
    _check_timeout(args.timeout)
    message, kind, names, targets = _request_message(args)
    with _session() as session:
        ros = session.node
        statuses: list = []
        states: list = []
        publisher = ros.create_publisher(type(message), f'{node}/{kind}', 10)
        status_sub = ros.create_subscription(
            DiagnosticStatus, f'{node}/status', statuses.append, _reliable(100))
        if args.wait:
            ros.create_subscription(JointState, args.joint_states or joint_states_topic(node),
                                    states.append, _reliable(10))
        plans: list = []
        if args.plot or (args.wait and args.command in TOPICS):
            ros.create_subscription(JointTrajectory, f'{node}/trajectory', plans.append,
                                    _reliable(1, transient_local=True))
        session.wait(lambda: publisher.get_subscription_count() > 0
                     and status_sub.get_publisher_count() > 0, args.timeout,
                     f'{node} is not subscribed to {node}/{kind} (is the node running, '
                     'with the same ROS_DOMAIN_ID?)')
        seen = len(statuses)
        sent_ns = time.time_ns()
        publisher.publish(message)

        def ours(status: object) -> bool:
            values = {pair.key: pair.value for pair in status.values}
            return (status.name == node and values.get('request') == kind
                    and values.get('frame_id', message.header.frame_id)
                    == message.header.frame_id)

        def answer() -> object:
            return next((s for s in statuses[seen:] if ours(s)), None)

        status = _status_dict(session.wait(answer, args.timeout,
                                           f'no {node}/status for the {kind} request'))
        # The node's answer, accepted or not, is the command's output (once, on
        # stdout); the exit status says which. stderr is for traj-gen's own errors.
        if args.json:
            print(json.dumps(status, indent=2))
        else:
            print(f"{status['level']}: {status['message']}")
        if status['level'] != 'OK':
            return EXIT_REFUSED
        if args.plot:
            _plot_plan(session, plans, sent_ns, message, args)
        if args.wait:
            if args.command in TOPICS:  # at rest where the node's plan of it ends
                names, targets = plan_end(_our_plan(session, plans, sent_ns, args))
            _wait_for_end(session, states, status, names, targets, args.timeout)
    return EXIT_OK


def _plot_plan(session: _Session, plans: list, sent_ns: int, message: object,
               args: argparse.Namespace) -> None:
    """
    ``--plot``: write the node's plan of ``message`` with the points sent marked.

    The plan is the first ``~/trajectory`` stamped after the request was sent (the node
    stamps it with its start tick, on the system clock unless ``use_sim_time``); an older
    plan, latched on the topic, is not it.
    """
    from traj_gen_ros.cli import plot as plotting  # matplotlib: loaded only when a plot is made

    plan = _our_plan(session, plans, sent_ns, args)
    figure = topic_figure(plan, f'{node_name(args.node)}/trajectory', args.degrees, args.size,
                          request=message)
    report_plot(plotting.write_png(figure, args.plot, len(plan.joint_names)), args.json)


def _our_plan(session: _Session, plans: list, sent_ns: int, args: argparse.Namespace) -> object:
    def ours() -> object:
        return next((plan for plan in plans if _stamp_ns(plan.header.stamp) >= sent_ns), None)

    return session.wait(ours, args.timeout, f'no {node_name(args.node)}/trajectory for the '
                        'request')


def _stamp_ns(stamp: object) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _wait_for_end(session: _Session, states: list, status: dict, names: list[str] | None,
                  targets: list[float] | None, timeout: float) -> None:
    """
    Wait until the stream holds the named joints at their targets, all at rest.

    ``names`` None (a pose goal): the joints of the stream that the answer's values name,
    at those values (the joint goal the node's inverse kinematics chose).
    """
    values = status['values']
    motion = float(values.get('duration', 0.0)) + float(values.get('start_delay', 0.0))
    target = None if names is None else dict(zip(names, targets, strict=True))
    seen = len(states)

    def ended() -> bool:
        if len(states) == seen:
            return False
        state = states[-1]
        position = dict(zip(state.name, state.position, strict=False))
        goal = target if target is not None else answered_joints(values, state.name)
        return (bool(goal) and not any(abs(v) > 0.0 for v in state.velocity)
                and all(abs(position.get(n, math.inf) - q) <= _AT_GOAL
                        for n, q in goal.items()))

    session.wait(ended, motion + timeout, 'the motion did not end on the joint_states stream '
                 '(see --joint-states)')


def run_plot_topic(args: argparse.Namespace) -> int:
    """``traj-gen plot --topic``: plot one JointTrajectory (transient local) from a topic."""
    from traj_gen_ros.cli import plot as plotting  # matplotlib: loaded only when a plot is made

    _check_timeout(args.timeout)
    topic = args.topic if args.topic.startswith('/') else '/' + args.topic
    received: list = []
    with _session() as session:
        session.node.create_subscription(JointTrajectory, topic, received.append,
                                         _reliable(1, transient_local=True))
        session.wait(lambda: received, args.timeout,
                     f'no trajectory_msgs/JointTrajectory on {topic}')
    message = received[0]
    if not message.points:
        raise UsageError(f'the trajectory on {topic} has no points')
    figure = topic_figure(message, topic, args.degrees, args.size)
    report_plot(plotting.write_png(figure, args.output, len(message.joint_names)), args.json)
    return EXIT_OK


def topic_figure(message: object, topic: str, degrees: bool, size: tuple[int, int],
                 request: object | None = None) -> Figure:
    """
    Return the figure of a JointTrajectory received on ``topic`` (``plot --topic``).

    Its start and end are marked. The message holds samples only, not the points of the
    request it was planned from; given that ``request`` (the ``JointTrajectory`` of via
    points sent, as ``traj-gen via --plot`` does), each of its points is marked too, at the
    time the plan comes closest to it (:func:`via_marks`).
    """
    from traj_gen_ros.cli import plot as plotting  # matplotlib: loaded only when a plot is made

    times, positions, velocities, accelerations = trajectory_arrays(message)
    scale = 180.0 / math.pi if degrees else 1.0
    marks = (times[[0, -1]], positions[[0, -1]])
    if isinstance(request, JointTrajectory) and request.points:
        marks = via_marks(times, positions, list(message.joint_names), request)
    return plotting.draw_samples(
        times, positions * scale, velocities * scale, accelerations * scale,
        unit='deg' if degrees else 'rad', marks=(marks[0], marks[1] * scale),
        size=size, title=f'{topic}: {len(times)} points, {times[-1]:.3g} s',
        joint_names=list(message.joint_names))


def via_marks(times: np.ndarray, positions: np.ndarray, joints: list[str], request: object
              ) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the start, the request's via points and the end as ``(times, positions)`` marks.

    Each point sent but the last (the goal: the plan's end) is marked at its own
    positions (the joints it names; the others at the plan's there), at the sample where
    the plan comes closest to it after the previous one: where a profile passes through
    its via points that is their time; where it rounds them (LSPB's blends, Craig 7.3)
    the mark shows by how much. Units: s, rad.
    """
    columns = [joints.index(name) for name in request.joint_names]
    mark_times, mark_positions = [times[0]], [positions[0]]
    first = 0
    for point in request.points[:-1]:
        wanted = np.asarray(point.positions, dtype=float)
        distance = np.abs(positions[first:, columns] - wanted).max(axis=1)
        first += int(np.argmin(distance))
        marked = positions[first].copy()
        marked[columns] = wanted
        mark_times.append(times[first])
        mark_positions.append(marked)
    mark_times.append(times[-1])
    mark_positions.append(positions[-1])
    return np.array(mark_times), np.array(mark_positions)


def trajectory_arrays(message: object
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return times ``(n,)`` and positions, velocities, accelerations ``(n, joints)``.

    Velocities and accelerations missing from the message are differentiated numerically.
    """
    times = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9
                      for p in message.points])
    positions = np.array([list(p.positions) for p in message.points], dtype=float)

    def derivative(values: np.ndarray) -> np.ndarray:
        if len(times) < 2:
            return np.zeros_like(values)
        return np.gradient(values, times, axis=0)

    velocities = (np.array([list(p.velocities) for p in message.points], dtype=float)
                  if all(len(p.velocities) == positions.shape[1] for p in message.points)
                  else derivative(positions))
    accelerations = (np.array([list(p.accelerations) for p in message.points], dtype=float)
                     if all(len(p.accelerations) == positions.shape[1] for p in message.points)
                     else derivative(velocities))
    return times, positions, velocities, accelerations
