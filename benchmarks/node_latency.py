"""
Cross-process latency and jitter of the generator node (issue 3, `make bench`).

Measured from a second process over DDS (isolated domain, localhost discovery):

* request -> first JointState of the new motion, and request -> full ~/trajectory received,
  for a 6-joint, 10 s plan at 100 Hz (1001 points); many repetitions.
* JointState period at 500 Hz (p50/p99/max), against a bare rclpy timer publishing the same
  message from its own process in the same run.

Usage: python benchmarks/node_latency.py [--repeats N] [--seconds S] [--json]
Run `python benchmarks/node_latency.py --bare RATE` to start only the bare timer node.
"""

import argparse
import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

REPO = Path(__file__).resolve().parents[1]
# One isolated domain per run; the bare-timer child inherits the parent's choice.
DOMAIN = os.environ.setdefault('NODE_LATENCY_DOMAIN', str(1 + os.getpid() % 100))
os.environ['ROS_DOMAIN_ID'] = DOMAIN
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'

from builtin_interfaces.msg import Duration  # noqa: E402
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from rclpy.time import Time  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

JOINTS = [f'joint_{index}' for index in range(1, 7)]
RELIABLE = ReliabilityPolicy.RELIABLE


def bare_timer(rate: float) -> None:
    """Publish the same JointState from a bare rclpy timer, as the reference."""
    rclpy.init()
    node = Node('bare_timer')
    publisher = node.create_publisher(JointState, 'joint_states',
                                      QoSProfile(depth=10, reliability=RELIABLE))
    position = np.zeros(6)

    def tick():
        now = node.get_clock().now()
        message = JointState(name=JOINTS, position=position.tolist(),
                             velocity=position.tolist())
        message.header.stamp = now.to_msg()
        publisher.publish(message)

    node.create_timer(1.0 / rate, tick)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


class Recorder(Node):
    def __init__(self):
        super().__init__(f'latency_probe_{os.getpid()}')
        self.states = []  # (receive monotonic ns, stamp ns)
        self.trajectories = []  # (receive monotonic ns, message)
        self.create_subscription(JointState, '/joint_states', self.on_state,
                                 QoSProfile(depth=1000, reliability=RELIABLE))
        # raw=True: the time the whole serialized message arrived; deserializing it into
        # Python objects is the consumer's cost and is timed separately.
        self.create_subscription(
            JointTrajectory, '/trajectory_generator/trajectory', self.on_trajectory,
            QoSProfile(depth=1, reliability=RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL), raw=True)
        self.via = self.create_publisher(JointTrajectory, '/trajectory_generator/via_points',
                                         10)

    def on_state(self, message):
        self.states.append((time.monotonic_ns(), Time.from_msg(message.header.stamp).nanoseconds))

    def on_trajectory(self, data):
        self.trajectories.append((time.monotonic_ns(), data))

    def spin_until(self, condition, timeout=20.0):
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise TimeoutError('benchmark timed out')
            rclpy.spin_once(self, timeout_sec=0.001)


def start(command):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO), os.environ.get('PYTHONPATH', '')]))
    return subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def stop(process):
    process.send_signal(signal.SIGINT)
    try:
        process.wait(10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def generator(rate):
    return start([sys.executable, '-m', 'traj_gen_ros.generator_node', '--ros-args',
                  '--params-file', str(REPO / 'config' / 'generator.yaml'),
                  '-p', f'rate_hz:={rate}'])


def percentiles(values):
    values = np.asarray(values)
    return {'p50': float(np.percentile(values, 50)), 'p99': float(np.percentile(values, 99)),
            'max': float(values.max())}


def measure_latency(recorder, repeats):
    first_state, full_trajectory, deserialize, points = [], [], [], 0
    for repeat in range(repeats):
        target = 0.5 if repeat % 2 == 0 else -0.5
        message = JointTrajectory(joint_names=JOINTS, points=[JointTrajectoryPoint(
            positions=[target] * 6, time_from_start=Duration(sec=10))])
        count = len(recorder.trajectories)
        sent = time.monotonic_ns()
        recorder.via.publish(message)
        recorder.spin_until(lambda count=count: len(recorder.trajectories) > count)
        received, data = recorder.trajectories[-1]
        begin = time.perf_counter()
        trajectory = deserialize_message(data, JointTrajectory)
        deserialize.append((time.perf_counter() - begin) * 1e3)
        start_ns = Time.from_msg(trajectory.header.stamp).nanoseconds
        recorder.spin_until(lambda start_ns=start_ns: any(
            stamp >= start_ns for _, stamp in recorder.states[-50:]))
        first = next(arrival for arrival, stamp in recorder.states if stamp >= start_ns
                     and arrival >= sent)
        first_state.append((first - sent) * 1e-6)
        full_trajectory.append((received - sent) * 1e-6)
        points = len(trajectory.points)
        settle = time.monotonic() + 0.05
        recorder.spin_until(lambda settle=settle: time.monotonic() > settle)
    return first_state, full_trajectory, deserialize, points


def measure_periods(recorder, seconds):
    recorder.spin_until(lambda: len(recorder.states) > 50)
    begin = len(recorder.states)
    end_time = time.monotonic() + seconds
    recorder.spin_until(lambda: time.monotonic() > end_time, timeout=seconds + 10)
    window = np.array(recorder.states[begin:], dtype=np.int64)
    return (np.diff(window[:, 1]) * 1e-6).tolist(), (np.diff(window[:, 0]) * 1e-6).tolist()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--repeats', type=int, default=20)
    parser.add_argument('--seconds', type=float, default=5.0)
    parser.add_argument('--json', action='store_true', help='print one JSON object')
    parser.add_argument('--bare', type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.bare:
        bare_timer(args.bare)
        return 0

    rclpy.init()
    results = {}
    try:
        node = generator(100.0)
        recorder = Recorder()
        try:
            recorder.spin_until(lambda: len(recorder.states) > 10
                                and recorder.via.get_subscription_count() > 0)
            first, full, deserialize, points = measure_latency(recorder, args.repeats)
        finally:
            stop(node)
            recorder.destroy_node()
        results['latency'] = {'points': points, 'period_ms': 10.0,
                              'first_joint_state_ms': percentiles(first),
                              'full_trajectory_ms': percentiles(full),
                              'python_deserialize_ms': percentiles(deserialize)}
        for name, command in (
                ('generator', None),
                ('bare_timer', [sys.executable, __file__, '--bare', '500'])):
            process = generator(500.0) if command is None else start(command)
            recorder = Recorder()
            try:
                stamp_periods, receive_periods = measure_periods(recorder, args.seconds)
            finally:
                stop(process)
                recorder.destroy_node()
            results[f'jitter_500hz_{name}'] = {'stamp_period_ms': percentiles(stamp_periods),
                                               'receive_period_ms': percentiles(receive_periods),
                                               'samples': len(stamp_periods)}
    finally:
        rclpy.try_shutdown()

    latency = results['latency']
    ours = results['jitter_500hz_generator']['receive_period_ms']
    bare = results['jitter_500hz_bare_timer']['receive_period_ms']
    results['targets'] = {
        'first_joint_state_within_period_plus_1ms':
            latency['first_joint_state_ms']['p99'] <= latency['period_ms'] + 1.0,
        'trajectory_within_25ms': latency['full_trajectory_ms']['p99'] <= 25.0,
        'p99_period_within_10pct_of_bare': ours['p99'] <= bare['p99'] * 1.10,
    }
    if args.json:
        print(json.dumps(results))
        return 0
    print(f'request -> first new JointState (ms, {args.repeats} runs): '
          f'{latency["first_joint_state_ms"]}')
    print(f'request -> full ~/trajectory, {latency["points"]} points (ms): '
          f'{latency["full_trajectory_ms"]}')
    print(f'  then deserializing it in Python (ms): {latency["python_deserialize_ms"]}')
    for name in ('generator', 'bare_timer'):
        entry = results[f'jitter_500hz_{name}']
        print(f'500 Hz {name}: receive period (ms) {entry["receive_period_ms"]}, '
              f'stamp period (ms) {entry["stamp_period_ms"]}, {entry["samples"]} samples')
    print(f'targets: {results["targets"]}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
