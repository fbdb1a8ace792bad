"""
Flood the generator node with goals while it streams, and report what it kept up with.

Default: 1,000 goals per second for 10 s at ``rate_hz`` 500, from a second process over
DDS (isolated domain, localhost discovery; the node is a subprocess). Reported: requests
sent and the achieved request rate; statuses by kind (accepted, superseded, refused);
JointState period mean/p50/p99/max from the node's stamps during the flood (from its first
goal on; the longest gap while the flooding process started is reported apart), between
setpoints published one after the other (DDS publication sequence numbers: a sample the
recorder lost in transport is not taken for a late tick), and the samples published but
not received; the node's RSS
(``VmRSS`` in ``/proc/<pid>/status``) before and after; the largest position/velocity
step against what the limits allow; whether the final setpoint is the newest goal.

Usage: python benchmarks/flood.py [--rate 500] [--requests 1000] [--seconds 10] [--json]
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import time

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'support'))

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402
from node_harness import (  # noqa: E402
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    node_env,
    NodeProcess,
    stamp_ns,
)
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402


def rss_kib(pid: int) -> int:
    """Resident set size of ``pid`` in KiB, from /proc/<pid>/status."""
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1])
    raise RuntimeError(f'no VmRSS for {pid}')


def answered(status: DiagnosticStatus) -> dict:
    """Map each request a status answers (by frame_id) to (status, request_id)."""
    values = {kv.key: kv.value for kv in status.values}
    if 'frame_ids' in values:  # several superseded requests in one status
        return dict(zip(json.loads(values['frame_ids']),
                        ((status, i) for i in json.loads(values['request_ids'])),
                        strict=True))
    return {values.get('frame_id'): (status, int(values.get('request_id', -1)))}


def goal(k: int) -> JointState:
    """Make the k-th goal: every joint somewhere new, within +-1 rad."""
    phase = np.arange(6) * 0.7 + k * 0.013
    message = JointState(name=JOINTS, position=np.round(np.sin(phase) * 0.9, 6).tolist())
    message.header.frame_id = f'flood-{k}'
    return message


def flood(node: Node, publisher, request_hz: float, seconds: float, tag: str
          ) -> tuple[int, float, int]:
    """
    Publish goals on a fixed schedule, spinning in between.

    Returns (sent, elapsed s, system time of the first goal in ns).

    The goals are serialised beforehand, so that sending them costs this process (which
    shares the machine with the node) little.
    """
    period = 1.0 / request_hz
    wire = []
    for k in range(int(seconds * request_hz) + 1):
        message = goal(k)
        message.header.frame_id = f'{tag}-{k}'
        wire.append(serialize_message(message))
    began = time.monotonic()
    began_ns = time.time_ns()
    sent = 0
    while True:
        elapsed = time.monotonic() - began
        if elapsed >= seconds:
            break
        due = int(elapsed / period) + 1
        while sent < min(due, len(wire)):
            publisher.publish(wire[sent])
            sent += 1
        rclpy.spin_once(node, timeout_sec=max(0.0, due * period - elapsed))
    return sent, time.monotonic() - began, began_ns


def flooder(tag: str, request_hz: float, seconds: float) -> dict:
    """
    Send the goals from this process and collect every answer (the ``--flooder`` role).

    A separate process from the stream recorder, so that neither starves the other.
    """
    # node_harness picked a domain from this pid on import: use the recorder's instead.
    os.environ['ROS_DOMAIN_ID'] = os.environ['FLOOD_DOMAIN_ID']
    rclpy.init()
    node = Node(f'flooder_{os.getpid()}')
    statuses = {}
    reliable = ReliabilityPolicy.RELIABLE
    node.create_subscription(DiagnosticStatus, '/trajectory_generator/status',
                             lambda status: statuses.update(answered(status)),
                             QoSProfile(depth=20000, reliability=reliable))
    publisher = node.create_publisher(JointState, '/trajectory_generator/goal',
                                      QoSProfile(depth=1000, reliability=reliable))
    deadline = time.monotonic() + 20.0
    while not (publisher.get_subscription_count() and
               node.count_publishers('/trajectory_generator/status')):
        rclpy.spin_once(node, timeout_sec=0.01)
        if time.monotonic() > deadline:
            raise RuntimeError('the generator did not match')
    sent, elapsed, began_ns = flood(node, publisher, request_hz, seconds, tag)
    last = f'{tag}-{sent - 1}'
    deadline = time.monotonic() + 30.0
    while last not in statuses and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.01)
    node.destroy_node()
    rclpy.shutdown()
    answers = [statuses.get(f'{tag}-{k}', (None, None)) for k in range(sent)]
    ids = sorted(i for _, i in answers if i is not None)
    levels = {'accepted': DiagnosticStatus.OK, 'superseded': DiagnosticStatus.WARN,
              'refused': DiagnosticStatus.ERROR}
    counts = {name: sum(1 for a, _ in answers if a is not None and a.level == level)
              for name, level in levels.items()}
    counts['unanswered'] = sum(1 for a, _ in answers if a is None)
    counts['lost_before_the_node'] = counts['unanswered'] - (ids[-1] - ids[0] + 1 - len(ids))
    last_status = statuses.get(last, (None, None))[0]
    return {'began_ns': began_ns, 'requests_sent': sent,
            'request_hz_achieved': round(sent / elapsed, 1),
            **counts, 'status_messages': len({id(a) for a, _ in answers if a is not None}),
            'last_request': None if last_status is None else {
                'level': int.from_bytes(last_status.level, 'little'),
                'message': last_status.message},
            'newest_goal': list(goal(sent - 1).position)}


class Recorder(Node):
    """
    Record the stream as it arrives, cheaply; decode it afterwards.

    Keeps the raw bytes and the publication sequence number of each message, so that the
    recorder keeps up on a busy machine and lost samples can be counted.
    """

    def __init__(self) -> None:
        super().__init__(f'recorder_{os.getpid()}')
        self.raw: list[bytes] = []
        self.sequence: list[int] = []
        self.create_subscription(
            JointState, '/joint_states', self._record,
            QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE), raw=True)

    def _record(self, data: bytes, info: dict) -> None:
        self.raw.append(data)
        self.sequence.append(info['publication_sequence_number'])

    def rows(self, first: int = 0, stop: int | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Decode the recorded messages ``[first:stop]``: stamps (ns), positions, velocities."""
        messages = [deserialize_message(data, JointState) for data in self.raw[first:stop]]
        return (np.array([stamp_ns(m.header.stamp) for m in messages], dtype=np.int64),
                np.array([m.position for m in messages]),
                np.array([m.velocity for m in messages]))

    def spin_until(self, condition, timeout: float, what: str) -> None:
        """Spin until ``condition()``; raise after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise RuntimeError(f'timed out waiting for {what}')
            rclpy.spin_once(self, timeout_sec=0.01)

    def wait_at_rest(self, timeout: float) -> np.ndarray:
        """Wait for ten identical zero-velocity samples; return the position."""
        def resting() -> bool:
            if len(self.raw) < 10:
                return False
            _, q, v = self.rows(len(self.raw) - 10)
            return not v.any() and (q == q[-1]).all()
        self.spin_until(resting, timeout, 'the stream to hold still')
        return self.rows(len(self.raw) - 1)[1][-1]


def run_flooder(recorder: Recorder, tag: str, request_hz: float, seconds: float) -> dict:
    """Run the flooder in its own process while ``recorder`` records the stream."""
    process = subprocess.Popen(
        [sys.executable, __file__, '--flooder', tag, '--requests', str(request_hz),
         '--seconds', str(seconds)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        env={**node_env(), 'FLOOD_DOMAIN_ID': os.environ['ROS_DOMAIN_ID']}, text=True)
    try:
        recorder.spin_until(lambda: process.poll() is not None, seconds + 90.0, 'the flooder')
        output = process.stdout.read()
    finally:
        if process.poll() is None:
            process.kill()
        process.wait()
        process.stdout.close()
    if process.returncode != 0:
        raise RuntimeError(f'the flooder failed: {output}')
    return json.loads(output.strip().splitlines()[-1])


def run(rate_hz: float = 500.0, request_hz: float = 1000.0, seconds: float = 10.0) -> dict:
    """Start a node at ``rate_hz``, flood it, return the figures (see module docstring)."""
    rclpy.init()
    generator = NodeProcess('-p', f'rate_hz:={rate_hz}')
    try:
        recorder = Recorder()
        recorder.spin_until(lambda: len(recorder.raw) > 10, 30.0, 'the stream')
        pid = generator.process.pid
        # Warm up (imports, first plans), then measure from rest.
        run_flooder(recorder, 'warm', 200.0, 1.0)
        recorder.wait_at_rest(timeout=30.0)
        idle_first = len(recorder.raw)
        recorder.spin_until(lambda: len(recorder.raw) >= idle_first + int(2 * rate_hz),
                            10.0, 'two idle seconds')
        idle = np.diff(recorder.rows(idle_first)[0]) * 1e-9
        in_order = np.diff(recorder.sequence[idle_first:]) == 1
        idle = idle[in_order] if in_order.any() else idle
        rss_before = rss_kib(pid)
        first = len(recorder.raw)
        figures = run_flooder(recorder, 'flood', request_hz, seconds)
        start_ns = figures.pop('began_ns')  # the flood's window: from its first goal on
        end_ns = start_ns + int(seconds * 1e9)
        final = recorder.wait_at_rest(timeout=30.0)
        rss_after = rss_kib(pid)
        recorder.destroy_node()
    finally:
        rclpy.shutdown()
        code = generator.stop()
        output = generator.output()
        generator.close()
    stamps, q, v = recorder.rows(first)
    stamps = stamps * 1e-9
    sequence = np.diff(np.array(recorder.sequence[first:]))
    lost = int((sequence - 1).sum())  # published, not received
    window = (stamps >= start_ns * 1e-9) & (stamps <= end_ns * 1e-9)
    joining = np.diff(stamps[stamps <= start_ns * 1e-9])  # while the flooder started
    steps = np.diff(stamps)
    # The node's period: between setpoints published one after the other (a sample that a
    # starved recorder lost in transport is not a late tick).
    consecutive = sequence == 1
    if not consecutive.any():  # an RMW without publication sequence numbers
        consecutive[:], sequence = True, np.ones_like(sequence)
    during = steps[window[1:] & window[:-1] & consecutive]
    published = int(sequence[window[1:] & window[:-1]].sum())
    position_step = (np.abs(np.diff(q, axis=0)) / (MAX_VELOCITY * steps[:, None])).max()
    velocity_step = (np.abs(np.diff(v, axis=0)) / (MAX_ACCELERATION * steps[:, None])).max()
    newest = np.array(figures.pop('newest_goal'))
    return {
        'rate_hz': rate_hz, 'request_hz_target': request_hz, 'seconds': seconds,
        **figures,
        'final_is_newest_goal': bool(np.allclose(final, newest, atol=1e-12)),
        'period_ms': {'nominal': round(1e3 / rate_hz, 3),
                      'mean': round(float(during.mean()) * 1e3, 3),
                      'p50': round(float(np.percentile(during, 50)) * 1e3, 3),
                      'p99': round(float(np.percentile(during, 99)) * 1e3, 3),
                      'max': round(float(during.max()) * 1e3, 3),
                      'idle_p50': round(float(np.percentile(idle, 50)) * 1e3, 3),
                      'idle_p99': round(float(np.percentile(idle, 99)) * 1e3, 3),
                      'idle_max': round(float(idle.max()) * 1e3, 3),
                      'flooder_joining_max': round(float(joining.max(initial=0.0)) * 1e3, 3)},
        'samples_during_flood': int(window.sum()),
        'rate_during_flood_hz': round(float(published / np.ptp(stamps[window])), 1),
        'samples_lost_in_transport': lost,
        'max_position_step_vs_limit': round(float(position_step), 4),
        'max_velocity_step_vs_limit': round(float(velocity_step), 4),
        'finite': bool(np.isfinite(q).all() and np.isfinite(v).all()),
        'rss_kib': {'before': rss_before, 'after': rss_after,
                    'growth': rss_after - rss_before},
        'exit_code': code, 'traceback': 'Traceback' in output,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=500.0, help='stream rate_hz')
    parser.add_argument('--requests', type=float, default=1000.0, help='goals per second')
    parser.add_argument('--seconds', type=float, default=10.0, help='flood length')
    parser.add_argument('--json', action='store_true', help='print JSON only')
    parser.add_argument('--flooder', metavar='TAG', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.flooder:
        print(json.dumps(flooder(args.flooder, args.requests, args.seconds)))
        return
    figures = run(args.rate, args.requests, args.seconds)
    if args.json:
        print(json.dumps(figures, indent=2))
        return
    period = figures['period_ms']
    print(f"flood: {figures['requests_sent']} goals in {args.seconds:g} s "
          f"({figures['request_hz_achieved']} /s) while streaming at {args.rate:g} Hz")
    print(f"  statuses: {figures['accepted']} accepted, {figures['superseded']} superseded, "
          f"{figures['refused']} refused, {figures['unanswered']} unanswered "
          f"({figures['lost_before_the_node']} never reached the node), in "
          f"{figures['status_messages']} status messages")
    print(f"  period ms: nominal {period['nominal']}, mean {period['mean']}, p50 "
          f"{period['p50']}, p99 {period['p99']}, max {period['max']} (idle before: p50 "
          f"{period['idle_p50']}, p99 {period['idle_p99']}, max {period['idle_max']}; while "
          f"the flooder started: max {period['flooder_joining_max']})")
    print(f"  stream during the flood: {figures['rate_during_flood_hz']} Hz, "
          f"{figures['samples_lost_in_transport']} samples published but not received")
    print(f"  RSS KiB: before {figures['rss_kib']['before']}, after "
          f"{figures['rss_kib']['after']} (growth {figures['rss_kib']['growth']})")
    print(f"  largest step / limit: position {figures['max_position_step_vs_limit']}, "
          f"velocity {figures['max_velocity_step_vs_limit']}; final is the newest goal: "
          f"{figures['final_is_newest_goal']}")


if __name__ == '__main__':
    main()
