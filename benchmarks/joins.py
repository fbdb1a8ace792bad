"""
Processes joining the ROS graph while the node streams (issue 28): the longest gap.

Two generator nodes stream at ``--rate`` Hz (default 500), one after the other (with
``--side-by-side`` at once, so that every join meets both at the same moment and under the
same load, but the two streams then compete for the 2 cores): ``defaults``, with the
node's defaults (no DDS setting: it takes UDPv4 only,
``traj_gen_ros.node.stream.transport``), and the peer, ``shm``, the same node with
``FASTDDS_BUILTIN_TRANSPORTS=DEFAULT`` (Fast DDS's default transports, shared memory and
UDPv4: the node as it was before issue 28). Each publishes its setpoint on
``/<name>/joint_states``.

``--joins`` short-lived processes (default 50, ``benchmarks/joiner.py``), one after the
other, join the graph as ``ros2 topic pub`` and ``ros2 topic echo`` do: for each node a
``~/goal`` publisher and a ``joint_states`` subscription; each waits until all are
matched (every subscription with a first message) and exits. Meanwhile this process
records both streams, and before each join sends both nodes a goal (every joint to +1 or
-1 rad in turn: a motion of about 1.5 s), so that most joins meet a moving stream. After
each join, as a control, the streams are recorded as long again with no process joining
(what the shared machine's load alone does to them). Reported per node: the largest gap
between setpoints published one after the other (their stamps; DDS publication sequence
numbers, as in ``benchmarks/flood.py``, so that a sample the recorder lost is not taken
for a late tick), in the joins and in the controls, the median of the joins' largest
gaps, how many joins (and controls) saw a gap over 3 periods and over 100 ms, the node's
own count of late ticks and how long they held its stream back (``/diagnostics``), and
the largest position step against what ``max_velocity`` allows in ``LATE_PERIODS``
periods (1 at most: no jump). Target: with the node's defaults, the largest gap in the
joins at most 3 periods. Beside each run, the machine's floor (``benchmarks/wake_floor.py``):
a real-time loop at the same rate with no ROS, whose largest gap no stream can beat.

The nodes run without ``ROS_AUTOMATIC_DISCOVERY_RANGE`` (ROS 2's default, ``SUBNET``);
this process and the joiners discover with ``LOCALHOST``, as the test harness does (with
it ``rmw_fastrtps`` gives them shared memory among themselves whatever else is set).

Usage: python benchmarks/joins.py [--joins 50] [--rate 500] [--side-by-side] [--json]
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

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from node_harness import (  # noqa: E402 - also isolates the DDS domain
    JOINTS,
    MAX_VELOCITY,
    node_env,
    NodeProcess,
    stamp_ns,
)
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from traj_gen_ros.node.stream.clock import LATE_PERIODS  # noqa: E402

JOINER = Path(__file__).with_name('joiner.py')
FLOOR = Path(__file__).with_name('wake_floor.py')
#: The nodes side by side: name → what is added to the environment.
NODES = {'defaults': {}, 'shm': {'FASTDDS_BUILTIN_TRANSPORTS': 'DEFAULT'}}
LABELS = {'defaults': "the node's defaults",
          'shm': 'peer: FASTDDS_BUILTIN_TRANSPORTS=DEFAULT (shared memory + UDPv4)'}
#: The target: the largest gap with the node's defaults, in periods.
TARGET_PERIODS = 3


class Recorder(Node):
    """Record each node's stream raw with its DDS sequence numbers, and /diagnostics."""

    def __init__(self, names: list[str]) -> None:
        super().__init__(f'join_recorder_{os.getpid()}')
        self.names = names
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self.raw = {name: [] for name in names}
        self.sequence = {name: [] for name in names}
        self.diagnostics: list[DiagnosticArray] = []
        for name in names:
            self.create_subscription(JointState, f'/{name}/joint_states',
                                     lambda data, info, n=name: self._record(n, data, info),
                                     reliable, raw=True)
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.goals = {name: self.create_publisher(JointState, f'/{name}/goal', 10)
                      for name in names}

    def _record(self, name: str, data: bytes, info: dict) -> None:
        self.raw[name].append(data)
        self.sequence[name].append(info['publication_sequence_number'])

    def count(self) -> int:
        """Return the fewest setpoints received from one node."""
        return min(len(raw) for raw in self.raw.values())

    def alone(self) -> bool:
        """Tell whether this process is the only one on the nodes' topics (no joiner)."""
        return all(self.count_subscribers(f'/{name}/joint_states') == 1
                   and self.count_publishers(f'/{name}/goal') == 1 for name in self.names)

    def spin_until(self, condition, timeout: float, what: str) -> None:
        """Spin until ``condition()``; raise after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise RuntimeError(f'timed out waiting for {what}')
            rclpy.spin_once(self, timeout_sec=0.005)

    def late_ticks(self, name: str) -> dict:
        """Return the node's last ``/diagnostics`` values (empty if none came)."""
        for message in reversed(self.diagnostics):
            for status in message.status:
                if status.name == f'{name}: Trajectory generator':
                    return {kv.key: kv.value for kv in status.values}
        return {}


def largest_gaps(stamps: np.ndarray, sequence: np.ndarray, windows: list) -> list[float]:
    """Return the largest gap (s) between setpoints published one after the other, per window."""
    largest = []
    for first, stop in windows:
        gaps = np.diff(stamps[first:stop]) * 1e-9
        consecutive = np.diff(sequence[first:stop]) == 1  # published one after the other
        if not consecutive.any():  # an RMW without publication sequence numbers
            consecutive[:] = True
        largest.append(float(gaps[consecutive].max()))
    return largest


def figures(recorder: Recorder, name: str, windows: list, controls: list,
            rate_hz: float) -> dict:
    """Return the figures of one node's stream over the joins' and the controls' samples."""
    messages = [deserialize_message(data, JointState) for data in recorder.raw[name]]
    stamps = np.array([stamp_ns(m.header.stamp) for m in messages], dtype=np.int64)
    positions = np.array([m.position for m in messages])
    sequence = np.array(recorder.sequence[name])
    period = 1.0 / rate_hz
    largest = largest_gaps(stamps, sequence, [window[name] for window in windows])
    control = largest_gaps(stamps, sequence, [window[name] for window in controls])
    moved = np.abs(np.diff(positions, axis=0))[np.diff(sequence) == 1]
    values = recorder.late_ticks(name)
    return {
        'largest_gap_ms': round(max(largest) * 1e3, 3),
        'largest_gap_periods': round(max(largest) / period, 2),
        'control_largest_gap_ms': round(max(control) * 1e3, 3),
        'controls_over_3_periods': sum(gap > TARGET_PERIODS * period for gap in control),
        'joins_over_100_ms': sum(gap > 0.1 for gap in largest),
        'controls_over_100_ms': sum(gap > 0.1 for gap in control),
        'median_join_gap_ms': round(float(np.median(largest)) * 1e3, 3),
        'joins_over_3_periods': sum(gap > TARGET_PERIODS * period for gap in largest),
        'late_ticks': values.get('late ticks', 'n/a'),
        'held_back_s': values.get('held back (s)', 'n/a'),
        'largest_step_vs_limit': round(float(
            (moved / (MAX_VELOCITY * LATE_PERIODS * period)).max()), 4),
    }


def node_environment(extra: dict) -> dict:
    """Return the harness's environment without the discovery range and Fast DDS's transports."""
    env = {name: value for name, value in node_env().items()
           if name not in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'FASTDDS_BUILTIN_TRANSPORTS')}
    return {**env, **extra}


def run(joins: int = 50, rate_hz: float = 500.0, names: list[str] | None = None) -> dict:
    """Start the nodes ``names`` (all), let ``joins`` processes join one by one; the figures."""
    names = list(NODES) if names is None else names
    rclpy.init()
    nodes = {name: NodeProcess('-r', f'__node:={name}', '-r',
                               f'joint_states:=/{name}/joint_states', '-p', f'rate_hz:={rate_hz}',
                               env=node_environment(NODES[name]))
             for name in names}
    joiner_env = dict(node_env())
    joiner_env.pop('FASTDDS_BUILTIN_TRANSPORTS', None)
    windows, controls, failed, results = [], [], 0, {}
    floor = subprocess.Popen([sys.executable, str(FLOOR), '--rate', str(rate_hz)],
                             env={**os.environ, 'PYTHONPATH': str(REPO)},
                             stdout=subprocess.PIPE, text=True)
    try:
        recorder = Recorder(names)
        recorder.spin_until(lambda: recorder.count() > rate_hz and all(
            goal.get_subscription_count() for goal in recorder.goals.values()), 30.0,
            'both streams')
        for index in range(joins):
            goal = JointState(name=JOINTS, position=[(-1.0) ** index] * len(JOINTS))
            for publisher in recorder.goals.values():
                publisher.publish(goal)
            first = {name: len(raw) for name, raw in recorder.raw.items()}
            process = subprocess.Popen([sys.executable, str(JOINER), *names], env=joiner_env)
            try:
                recorder.spin_until(lambda p=process: p.poll() is not None, 60.0, 'a joiner')
            finally:
                if process.poll() is None:
                    process.kill()
                process.wait()
            failed += process.returncode != 0
            # Its leaving belongs to the join: until the graph is without it, then 0.1 s.
            recorder.spin_until(recorder.alone, 30.0, 'the joiner gone from the graph')
            enough = recorder.count() + int(0.1 * rate_hz)
            recorder.spin_until(lambda n=enough: recorder.count() >= n, 30.0,
                                'the streams after a joiner')
            windows.append({name: (first[name], len(raw)) for name, raw in recorder.raw.items()})
            # The control: as many setpoints again, no process joining.
            first = {name: len(raw) for name, raw in recorder.raw.items()}
            enough = recorder.count() + max(stop - start for start, stop in windows[-1].values())
            recorder.spin_until(lambda n=enough: recorder.count() >= n, 60.0, 'a control')
            controls.append({name: (first[name], len(raw)) for name, raw in recorder.raw.items()})
        count = len(recorder.diagnostics)  # both nodes' reports after the last join
        recorder.spin_until(lambda: len(recorder.diagnostics) >= count + 2 * len(names), 10.0,
                            'the /diagnostics after the joins')
        transports = {name: next((line.split('DDS transport: ', 1)[1]
                                  for line in node.output().splitlines()
                                  if 'DDS transport: ' in line), 'not said')
                      for name, node in nodes.items()}
        results = {name: {'transport': transports[name],
                          **figures(recorder, name, windows, controls, rate_hz)}
                   for name in names}
        recorder.destroy_node()
    finally:
        floor.terminate()
        machine = json.loads(floor.communicate(timeout=30)[0] or '{}')
        rclpy.shutdown()
        for name, node in nodes.items():
            code = node.stop()
            output = node.output()
            node.close()
            if name in results:
                results[name].update(exit_code=code, traceback='Traceback' in output)
    for figures_of_node in results.values():
        figures_of_node['floor'] = machine
    return {'rate_hz': rate_hz, 'joins': joins, 'joins_failed': failed, 'nodes': results}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--joins', type=int, default=50, help='processes joining, one by one')
    parser.add_argument('--rate', type=float, default=500.0, help='stream rate_hz')
    parser.add_argument('--side-by-side', action='store_true',
                        help='both nodes at once (every join meets both), not one after the other')
    parser.add_argument('--json', action='store_true', help='print JSON only')
    args = parser.parse_args()
    if not args.side_by_side:
        parts = {name: run(args.joins, args.rate, [name]) for name in NODES}
        result = {'rate_hz': args.rate, 'joins': args.joins,
                  'joins_failed': sum(part['joins_failed'] for part in parts.values()),
                  'nodes': {name: part['nodes'][name] for name, part in parts.items()}}
    else:
        result = run(args.joins, args.rate)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    failed = result['joins_failed']
    streaming = ('two nodes stream side by side' if args.side_by_side
                 else 'each node in turn streams')
    print(f'{args.joins} processes join the graph one after the other (a ~/goal publisher '
          f'and a joint_states subscription per node) while {streaming} at {args.rate:g} Hz; '
          f'gaps between setpoints published one after the other'
          f'{f"; {failed} JOINERS FAILED" if failed else ""}')
    for name, f in result['nodes'].items():
        verdict = ''
        if name == 'defaults':
            met = f['largest_gap_periods'] <= TARGET_PERIODS
            verdict = f' | target <= {TARGET_PERIODS} periods ({"met" if met else "MISSED"})'
        print(f'  {LABELS[name]}: DDS transport {f["transport"]}')
        print(f'    largest gap {f["largest_gap_ms"]} ms ({f["largest_gap_periods"]} periods), '
              f'median of the joins {f["median_join_gap_ms"]} ms; joins with a gap over '
              f'{TARGET_PERIODS} periods: {f["joins_over_3_periods"]}/{args.joins}, over 100 ms: '
              f'{f["joins_over_100_ms"]}/{args.joins}{verdict}')
        print(f'    controls (no process joining): largest gap {f["control_largest_gap_ms"]} ms, '
              f'over {TARGET_PERIODS} periods: {f["controls_over_3_periods"]}/{args.joins}, over '
              f'100 ms: {f["controls_over_100_ms"]}/{args.joins}; '
              f'late ticks {f["late_ticks"]} (held back {f["held_back_s"]} s); largest step '
              f'{f["largest_step_vs_limit"]} of max_velocity x {LATE_PERIODS} periods')
        floor = f['floor']
        print(f"    the machine's floor in the same run (benchmarks/wake_floor.py: a "
              f'{floor.get("priority")} loop at the same rate, no ROS): largest gap '
              f'{floor.get("largest_gap_ms")} ms ({floor.get("largest_gap_periods")} periods), '
              f'{floor.get("gaps_over_3_periods")} of {floor.get("wakeups")} wake-ups over '
              f'{TARGET_PERIODS} periods')
        if f.get('exit_code') or f.get('traceback'):
            print(f'    PROBLEM: exit {f.get("exit_code")}, traceback {f.get("traceback")}')


if __name__ == '__main__':
    main()
