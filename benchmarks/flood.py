"""
Flood the generator node with goals while it streams, and report what it kept up with.

Default: 1,000 goals per second for 10 s at ``rate_hz`` 500, from a second process over
DDS (isolated domain, localhost discovery; the node is a subprocess). Reported: requests
sent and the achieved request rate; statuses by kind (accepted, superseded, refused);
JointState period p50/p99/max from the node's stamps during the flood; the node's RSS
(``VmRSS`` in ``/proc/<pid>/status``) before and after; the largest position/velocity
step against what the limits allow; whether the final setpoint is the newest goal.

Usage: python benchmarks/flood.py [--rate 500] [--requests 1000] [--seconds 10] [--json]
"""

import argparse
import json
from pathlib import Path
import sys
import time

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test'))

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402
from node_harness import (  # noqa: E402
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    NodeProcess,
    Probe,
    stamp_ns,
)
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
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


def goal(k: int, seconds: float) -> JointState:
    """The k-th goal: every joint somewhere new, within +-1 rad."""
    phase = np.arange(6) * 0.7 + k * 0.013
    message = JointState(name=JOINTS, position=np.round(np.sin(phase) * 0.9, 6).tolist())
    message.header.frame_id = f'flood-{k}'
    return message


def flood(probe: Probe, request_hz: float, seconds: float, tag: str) -> tuple[int, float]:
    """Publish goals on a fixed schedule, spinning in between; return (sent, elapsed)."""
    period = 1.0 / request_hz
    began = time.monotonic()
    sent = 0
    while True:
        elapsed = time.monotonic() - began
        if elapsed >= seconds:
            break
        due = int(elapsed / period) + 1
        while sent < due:
            message = goal(sent, seconds)
            message.header.frame_id = f'{tag}-{sent}'
            probe.goal_pub.publish(message)
            sent += 1
        rclpy.spin_once(probe, timeout_sec=max(0.0, due * period - elapsed))
    return sent, time.monotonic() - began


def run(rate_hz: float = 500.0, request_hz: float = 1000.0, seconds: float = 10.0) -> dict:
    """Start a node at ``rate_hz``, flood it, return the figures (see module docstring)."""
    rclpy.init()
    node = NodeProcess('-p', f'rate_hz:={rate_hz}')
    probe = None
    try:
        probe = Probe(name='flood')
        statuses = {}
        probe.create_subscription(
            DiagnosticStatus, '/trajectory_generator/status',
            lambda status: statuses.update(answered(status)),
            QoSProfile(depth=20000, reliability=ReliabilityPolicy.RELIABLE))
        probe.wait_ready()
        # Warm up (imports, first plans), then measure from rest.
        warm, _ = flood(probe, 200.0, 1.0, 'warm')
        probe.spin_until(lambda: f'warm-{warm - 1}' in statuses, 20.0, 'the warm-up')
        probe.wait_at_rest(timeout=30.0)
        idle_first = len(probe.states)
        probe.spin_until(lambda: len(probe.states) >= idle_first + int(2 * rate_hz), 10.0,
                         'two idle seconds')
        idle = np.diff([stamp_ns(s.header.stamp) * 1e-9 for s in probe.states[idle_first:]])
        rss_before = rss_kib(node.process.pid)
        first = len(probe.states)
        start_ns = probe.get_clock().now().nanoseconds
        sent, elapsed = flood(probe, request_hz, seconds, 'flood')
        end_ns = probe.get_clock().now().nanoseconds
        last = f'flood-{sent - 1}'
        probe.spin_until(lambda: last in statuses, 30.0, 'the last status')
        final = probe.wait_at_rest(timeout=30.0)
        rss_after = rss_kib(node.process.pid)
        alive = node.process.poll() is None
    finally:
        if probe is not None:
            probe.destroy_node()
        rclpy.shutdown()
        code = node.stop()
        output = node.output()
        node.close()
    states = [s for s in probe.states[first:]
              if start_ns <= stamp_ns(s.header.stamp) <= end_ns]
    stamps = np.array([stamp_ns(s.header.stamp) for s in probe.states[first:]]) * 1e-9
    q = np.array([s.position for s in probe.states[first:]])
    v = np.array([s.velocity for s in probe.states[first:]])
    steps = np.diff(stamps)
    during = np.diff(np.array([stamp_ns(s.header.stamp) for s in states]) * 1e-9)
    position_step = (np.abs(np.diff(q, axis=0)) / (MAX_VELOCITY * steps[:, None])).max()
    velocity_step = (np.abs(np.diff(v, axis=0)) / (MAX_ACCELERATION * steps[:, None])).max()
    answers = [statuses.get(f'flood-{k}', (None, None)) for k in range(sent)]
    ids = sorted(i for _, i in answers if i is not None)
    answers = [status for status, _ in answers]
    batches = len({id(a) for a in answers if a is not None})
    levels = {'accepted': DiagnosticStatus.OK, 'superseded': DiagnosticStatus.WARN,
              'refused': DiagnosticStatus.ERROR}
    counts = {name: sum(1 for a in answers if a is not None and a.level == level)
              for name, level in levels.items()}
    counts['unanswered'] = sum(1 for a in answers if a is None)
    counts['lost_before_the_node'] = counts['unanswered'] - (ids[-1] - ids[0] + 1 - len(ids))
    newest = np.array(goal(sent - 1, seconds).position)
    last_status = statuses[last][0]
    return {
        'rate_hz': rate_hz, 'request_hz_target': request_hz, 'seconds': seconds,
        'requests_sent': sent, 'request_hz_achieved': round(sent / elapsed, 1),
        **counts, 'status_messages': batches,
        'last_request': {'level': int.from_bytes(last_status.level, 'little'),
                         'message': last_status.message},
        'final_is_newest_goal': bool(np.allclose(final, newest, atol=1e-12)),
        'period_ms': {'nominal': round(1e3 / rate_hz, 3),
                      'p50': round(float(np.percentile(during, 50)) * 1e3, 3),
                      'p99': round(float(np.percentile(during, 99)) * 1e3, 3),
                      'max': round(float(during.max()) * 1e3, 3),
                      'idle_p50': round(float(np.percentile(idle, 50)) * 1e3, 3),
                      'idle_p99': round(float(np.percentile(idle, 99)) * 1e3, 3),
                      'idle_max': round(float(idle.max()) * 1e3, 3)},
        'samples_during_flood': len(states),
        'max_position_step_vs_limit': round(float(position_step), 4),
        'max_velocity_step_vs_limit': round(float(velocity_step), 4),
        'finite': bool(np.isfinite(q).all() and np.isfinite(v).all()),
        'rss_kib': {'before': rss_before, 'after': rss_after,
                    'growth': rss_after - rss_before},
        'node_alive_after': alive, 'exit_code': code,
        'traceback': 'Traceback' in output,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=500.0, help='stream rate_hz')
    parser.add_argument('--requests', type=float, default=1000.0, help='goals per second')
    parser.add_argument('--seconds', type=float, default=10.0, help='flood length')
    parser.add_argument('--json', action='store_true', help='print JSON only')
    args = parser.parse_args()
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
    print(f"  period ms: nominal {period['nominal']}, p50 {period['p50']}, "
          f"p99 {period['p99']}, max {period['max']} (idle before: p50 {period['idle_p50']}, "
          f"p99 {period['idle_p99']}, max {period['idle_max']})")
    print(f"  RSS KiB: before {figures['rss_kib']['before']}, after "
          f"{figures['rss_kib']['after']} (growth {figures['rss_kib']['growth']})")
    print(f"  largest step / limit: position {figures['max_position_step_vs_limit']}, "
          f"velocity {figures['max_velocity_step_vs_limit']}; final is the newest goal: "
          f"{figures['final_is_newest_goal']}")


if __name__ == '__main__':
    main()
