"""
Test harness: run the generator as a subprocess and talk to it over DDS.

Importing this module isolates the test process: its own ROS_DOMAIN_ID and discovery
limited to localhost; the node subprocesses inherit the same environment. The domain is
claimed with a lock file, so that runs side by side on one machine (CI beside a
developer's ``make test``) never share one.
"""

import bisect
import contextlib
import fcntl
import os
from pathlib import Path
import signal
import subprocess
import sys
import tempfile
import time

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.srv import SetParameters
import rclpy
from rclpy.action import ActionClient
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from traj_gen_ros.node.stream.clock import LATE_PERIODS
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

REPO = Path(__file__).resolve().parents[2]
CONFIG = REPO / 'config' / 'generator.yaml'
JOINTS = [f'joint_{index}' for index in range(1, 7)]
MAX_VELOCITY = np.array([2.0, 2.0, 2.0, 3.0, 3.0, 3.0])
MAX_ACCELERATION = np.array([4.0, 4.0, 4.0, 6.0, 6.0, 6.0])

_DOMAIN_LOCKS = []  # open lock files: a domain is held while this process lives


def _claim_domain() -> int:
    """
    Return a ROS domain (1-100) that no other process importing this module holds.

    Each domain has a lock file in the temporary directory; the first one (from the pid
    on) whose exclusive lock this process gets is its domain until it exits (the lock
    goes with the process, also when it is killed; children do not inherit it).
    """
    first = os.getpid() % 100
    for offset in range(100):
        domain = 1 + (first + offset) % 100
        handle = open(Path(tempfile.gettempdir()) / f'traj_gen_ros_domain_{domain}.lock', 'w')
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        _DOMAIN_LOCKS.append(handle)
        return domain
    return 1 + first  # a hundred runs at once: share one


DOMAIN_ID = _claim_domain()
os.environ['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.pop('ROS_LOCALHOST_ONLY', None)


def node_env(extra_pythonpath: bool = True) -> dict:
    """Environment for a node subprocess: same domain, unbuffered, repo importable."""
    env = dict(os.environ)
    env['PYTHONUNBUFFERED'] = '1'
    if extra_pythonpath:
        env['PYTHONPATH'] = os.pathsep.join(
            [str(REPO)] + [p for p in env.get('PYTHONPATH', '').split(os.pathsep) if p])
    return env


def action_types():
    """
    Return ``(FollowJointTrajectory, JointTolerance)`` from control_msgs.

    Where control_msgs is not importable the node runs without the action: skip the
    calling test module, saying so (call it at module level).
    """
    try:
        from control_msgs.action import FollowJointTrajectory
        from control_msgs.msg import JointTolerance
    except ImportError as error:
        pytest.skip(f'control_msgs is not importable ({error}): the node runs without '
                    '~/follow_joint_trajectory', allow_module_level=True)
    return FollowJointTrajectory, JointTolerance


def speed_scaling_factor_type():
    """
    Return ``control_msgs/msg/SpeedScalingFactor``, or skip the calling test module.

    Without control_msgs the node runs without ``~/speed_scaling_input``: a module that
    sends factors on it is skipped, saying so (call it at module level).
    """
    try:
        from control_msgs.msg import SpeedScalingFactor
    except ImportError as error:
        pytest.skip(f'control_msgs is not importable ({error}): the node runs without '
                    '~/speed_scaling_input', allow_module_level=True)
    return SpeedScalingFactor


def end_process(process: subprocess.Popen, sig: int = signal.SIGTERM,
                timeout: float = 10.0) -> int:
    """
    Signal ``process`` and wait for it; kill it if it has not ended within ``timeout`` s.

    Always returns with the process gone, so a helper that hangs on a loaded machine
    cannot outlive its test and leak into the next one (a robot_description publisher
    left running once gave every later node in the domain its URDF limits).
    """
    if process.poll() is None:
        process.send_signal(sig)
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    return process.returncode


class NodeProcess:
    """A generator node subprocess; output goes to a temporary log file."""

    def __init__(self, *ros_args: str, command: list | None = None, env: dict | None = None,
                 params_file: Path | None = CONFIG, cwd: Path | None = None):
        self.log = tempfile.NamedTemporaryFile('w+', prefix='generator_', suffix='.log')
        args = ['--ros-args']
        if params_file is not None:
            args += ['--params-file', str(params_file)]
        args += list(ros_args)
        command = command or [sys.executable, '-m', 'traj_gen_ros.node.generator']
        self.process = subprocess.Popen(command + args, stdout=self.log,
                                        stderr=subprocess.STDOUT, env=env or node_env(),
                                        cwd=str(cwd or REPO))

    def output(self) -> str:
        """Everything the process printed so far."""
        self.log.flush()
        return Path(self.log.name).read_text()

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        """Signal the process and wait; kill it if it does not end in time."""
        return end_process(self.process, sig, timeout)

    def close(self) -> None:
        """Make sure the process is gone and the log is removed."""
        try:
            if self.process.poll() is None:
                self.process.kill()
                self.process.wait()
        finally:
            self.log.close()


def stamp_ns(stamp) -> int:
    """Nanoseconds of a ``builtin_interfaces/Time``."""
    return Time.from_msg(stamp).nanoseconds


def held_back_ns(stamps_ns, rate_hz) -> np.ndarray:
    """
    Rebuild how far the node's stream clock was behind each setpoint's stamp (ns).

    The node holds its schedule back at a late tick (``traj_gen_ros.node.stream.clock``):
    a setpoint published more than ``LATE_PERIODS`` periods after the one before it is the
    schedule only ``LATE_PERIODS`` periods later. Rebuilt exactly from consecutive stamps
    (every setpoint received, the node on the system clock) and the node's ``rate_hz``
    (Hz, or a function of the stamp in ns: the rate in force when it was published; the
    larger period of two setpoints counts, as in the node). 0 at the first stamp.
    """
    stamps = np.asarray(stamps_ns, dtype=np.int64)
    rate = rate_hz if callable(rate_hz) else (lambda stamp: rate_hz)
    periods = np.array([int(1e9 / rate(int(stamp))) for stamp in stamps], dtype=np.int64)
    if stamps.size == 0:
        return periods
    allowance = LATE_PERIODS * np.maximum(periods[:-1], periods[1:])
    held = np.maximum(np.diff(stamps) - allowance, 0)
    return np.concatenate([[0], np.cumsum(held)])


def seconds(duration: Duration) -> float:
    """Seconds of a ``builtin_interfaces/Duration``."""
    return duration.sec + duration.nanosec * 1e-9


def trajectory_arrays(message: JointTrajectory):
    """Return times, positions, velocities, accelerations of a JointTrajectory as arrays."""
    times = np.array([seconds(p.time_from_start) for p in message.points])
    positions = np.array([p.positions for p in message.points])
    velocities = np.array([p.velocities for p in message.points])
    accelerations = np.array([p.accelerations for p in message.points])
    return times, positions, velocities, accelerations


def via_message(names, points, stamp=None) -> JointTrajectory:
    """Build a JointTrajectory from ``[(positions, time, velocities?, accel?), ...]``."""
    message = JointTrajectory(joint_names=list(names))
    if stamp is not None:
        message.header.stamp = stamp
    for point in points:
        positions, time_from_start = point[0], point[1]
        sec = int(np.floor(time_from_start))
        message.points.append(JointTrajectoryPoint(
            positions=[float(x) for x in positions],
            velocities=[float(x) for x in (point[2] if len(point) > 2 else [])],
            accelerations=[float(x) for x in (point[3] if len(point) > 3 else [])],
            time_from_start=Duration(sec=sec, nanosec=int(round((time_from_start - sec) * 1e9)))))
    return message


class Probe(Node):
    """A second node that drives the generator and records what it publishes."""

    def __init__(self, generator: str = '/trajectory_generator',
                 joint_states: str = '/joint_states', name: str = 'probe',
                 goal: str | None = None):
        super().__init__(f'{name}_{os.getpid()}')
        reliable = ReliabilityPolicy.RELIABLE
        self.generator = generator
        self.states: list[JointState] = []
        self.trajectories: list[JointTrajectory] = []
        self.statuses: list[DiagnosticStatus] = []
        self.state_times: list[float] = []
        self.create_subscription(JointState, joint_states, self._on_state,
                                 QoSProfile(depth=1000, reliability=reliable))
        self.create_subscription(
            JointTrajectory, f'{generator}/trajectory', self.trajectories.append,
            QoSProfile(depth=1, reliability=reliable,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self.create_subscription(DiagnosticStatus, f'{generator}/status', self.statuses.append,
                                 QoSProfile(depth=100, reliability=reliable))
        self.goal_pub = self.create_publisher(JointState, goal or f'{generator}/goal', 10)
        self.via_pub = self.create_publisher(JointTrajectory, f'{generator}/via_points', 10)
        self.stop_client = self.create_client(Trigger, f'{generator}/stop')
        self.param_client = self.create_client(SetParameters, f'{generator}/set_parameters')

    def _on_state(self, message: JointState) -> None:
        self.state_times.append(time.monotonic())
        self.states.append(message)

    # -- spinning

    def spin_until(self, condition, timeout: float = 10.0, what: str = 'condition'):
        """Spin until ``condition()`` is truthy; return its value or fail after ``timeout``."""
        deadline = time.monotonic() + timeout
        while True:
            value = condition()
            if value:
                return value
            if time.monotonic() > deadline:
                raise AssertionError(f'timed out after {timeout} s waiting for {what}')
            rclpy.spin_once(self, timeout_sec=0.005)

    def wait_ready(self, timeout: float = 20.0) -> None:
        """Wait until the generator streams and all our endpoints are matched."""
        self.spin_until(lambda: len(self.states) > 2 and self.goal_pub.get_subscription_count()
                        and self.via_pub.get_subscription_count()
                        and self.count_publishers(f'{self.generator}/status')
                        and self.stop_client.service_is_ready()
                        and self.param_client.service_is_ready(), timeout, 'the generator')

    # -- state

    def latest(self) -> JointState:
        """Most recent JointState."""
        return self.states[-1]

    def position(self) -> np.ndarray:
        """Most recent positions."""
        return np.array(self.latest().position)

    def wait_at_rest(self, timeout: float = 10.0) -> np.ndarray:
        """
        Wait until the stream holds still (ten zero-velocity samples); return position.

        The samples must be stamped after the end of the last ``~/trajectory`` received: a
        motion's status and first setpoints travel on different topics, so the stream's
        tail may still be the rest before a motion that has just been accepted.
        """
        def resting():
            tail = self.states[-10:]
            return len(tail) == 10 and all(not any(s.velocity) for s in tail) and \
                len({tuple(s.position) for s in tail}) == 1 and \
                stamp_ns(tail[0].header.stamp) >= self._motion_end_ns()
        self.spin_until(resting, timeout, 'the stream to hold still')
        return self.position()

    def _motion_end_ns(self) -> int:
        """End of the last ``~/trajectory`` received, on the node's clock (ns); 0 if none."""
        if not self.trajectories or not self.trajectories[-1].points:
            return 0
        last = self.trajectories[-1]
        span = last.points[-1].time_from_start
        return stamp_ns(last.header.stamp) + span.sec * 1_000_000_000 + span.nanosec

    def states_between(self, start_ns: int, end_ns: int | None = None, rate_hz=None):
        """
        Stamps (s, relative to ``start_ns``), positions and velocities in a window.

        With the node's ``rate_hz`` (:func:`held_back_ns`): the times less what late ticks
        held the node's stream clock back since ``start_ns``, for a plan that starts at
        ``start_ns`` the plan's own time of each setpoint.
        """
        stamps = [stamp_ns(s.header.stamp) for s in self.states]
        index = [i for i, stamp in enumerate(stamps)
                 if stamp >= start_ns and (end_ns is None or stamp <= end_ns)]
        rows = [self.states[i] for i in index]
        times = np.array([(stamps[i] - start_ns) * 1e-9 for i in index])
        if rate_hz is not None and index:
            held = held_back_ns(stamps, rate_hz)
            times -= (held[index] - held[max(index[0] - 1, 0)]) * 1e-9
        return times, np.array([s.position for s in rows]), np.array([s.velocity for s in rows])

    def stream_ns(self, time_ns: int, rate_hz) -> int:
        """
        Return node time ``time_ns`` on the node's stream clock (ns, up to a constant).

        Less what late ticks held it back by the last setpoint at or before it
        (:func:`held_back_ns`, the node at ``rate_hz``): the difference of two such times
        is the plan time between them (a plan's start and its replacement's).
        """
        stamps = [stamp_ns(s.header.stamp) for s in self.states]
        held = held_back_ns(stamps, rate_hz)
        index = bisect.bisect_right(stamps, time_ns) - 1
        return time_ns - (int(held[index]) if index >= 0 else 0)

    # -- requests

    def _next_status(self, send, timeout: float) -> DiagnosticStatus:
        count = len(self.statuses)
        send()
        self.spin_until(lambda: len(self.statuses) > count, timeout, 'a status message')
        return self.statuses[count]

    def request(self, message, timeout: float = 10.0):
        """Publish a goal or via points; return ``(status, trajectory or None)``."""
        publisher = self.via_pub if isinstance(message, JointTrajectory) else self.goal_pub
        count = len(self.trajectories)
        status = self._next_status(lambda: publisher.publish(message), timeout)
        if status.level != DiagnosticStatus.OK:
            return status, None
        self.spin_until(lambda: len(self.trajectories) > count, timeout, 'the trajectory')
        return status, self.trajectories[-1]

    def goal(self, positions: dict, timeout: float = 10.0):
        """Send a goal ``{joint: position}``; return ``(status, trajectory)``."""
        message = JointState(name=list(positions),
                             position=[float(v) for v in positions.values()])
        return self.request(message, timeout)

    def stop(self, timeout: float = 10.0) -> Trigger.Response:
        """Call ``~/stop``."""
        future = self.stop_client.call_async(Trigger.Request())
        self.spin_until(future.done, timeout, 'the stop service')
        return future.result()

    def set_parameters(self, timeout: float = 10.0, **values):
        """Set generator parameters; return the list of SetParametersResult."""
        request = SetParameters.Request(parameters=[
            ParameterMsg(name=name, value=Parameter(name, value=value).get_parameter_value())
            for name, value in values.items()])
        future = self.param_client.call_async(request)
        self.spin_until(future.done, timeout, 'set_parameters')
        return future.result().results

    def require_parameters(self, **values) -> None:
        """Set parameters and assert they were accepted."""
        results = self.set_parameters(**values)
        assert all(r.successful for r in results), [r.reason for r in results]


@contextlib.contextmanager
def running_node(*ros_args: str, sig: int = signal.SIGINT):
    """
    Run a generator subprocess inside an rclpy context of this process; yield it.

    On exit the context is shut down and the node signalled with ``sig``; it must exit
    with status 0 and no traceback.
    """
    rclpy.init()
    node = NodeProcess(*ros_args)
    try:
        yield node
    finally:
        rclpy.shutdown()
        code = node.stop(sig)
        output = node.output()
        node.close()
    assert code == 0, output
    assert 'Traceback' not in output, output


@contextlib.contextmanager
def generator_session(*ros_args: str, generator: str = '/trajectory_generator',
                      joint_states: str = '/joint_states', goal: str | None = None):
    """Run a generator subprocess and a ready Probe; on exit check a clean shutdown."""
    with running_node(*ros_args):
        probe = Probe(generator, joint_states, goal=goal)
        try:
            probe.wait_ready()
            yield probe
        finally:
            probe.destroy_node()


@contextlib.contextmanager
def action_session(*ros_args: str):
    """Run a generator and a ready Probe with a ready FollowJointTrajectory client."""
    follow_joint_trajectory, _ = action_types()
    with generator_session(*ros_args) as probe:
        client = ActionClient(probe, follow_joint_trajectory,
                              '/trajectory_generator/follow_joint_trajectory')
        try:
            probe.spin_until(lambda: client.server_is_ready(), 20.0, 'the action server')
            yield probe, client
        finally:
            client.destroy()


@contextlib.contextmanager
def in_process_node(name: str):
    """Yield an rclpy node in this process, in a context of its own (shut down after)."""
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node(name, context=context)
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


@contextlib.contextmanager
def busy_processes(count: int | None = None):
    """
    Run ``count`` (default: one per core) busy-looping processes; always end them.

    The load a shared machine puts beside the node: each takes a whole core if it can.
    """
    processes = []
    try:
        for _ in range(count or os.cpu_count() or 1):
            processes.append(subprocess.Popen([sys.executable, '-c', 'while True: pass']))
        yield processes
    finally:
        for process in processes:
            process.kill()
        for process in processes:
            process.wait()


def stamp_gaps(probe: 'Probe', start_ns: int, end_ns: int | None = None) -> np.ndarray:
    """Periods (s) between consecutive ``joint_states`` stamps in a window."""
    times, _, _ = probe.states_between(start_ns, end_ns)
    return np.diff(times)
