"""
The node's stream on the Panda: while lines are planned (issue 30), with ``~/tool_pose`` (29).

The generator runs as a subprocess with example-robot-data's Panda URDF (fetched once into
.pytest_cache as the tests do), measured from this process over DDS (an isolated domain,
localhost discovery: ``node_harness``); periods are those of the ``joint_states`` stamps,
i.e. when the node published them (benchmarks/node_latency.py's recorder).

1. At 500 Hz, ``--seconds`` s idle, then as long while a ``~/cartesian_path`` (one pose,
   0.1 m either side of the ready pose's tool in y, in turn) is sent every 0.3 s: each
   brakes the moving arm along its path and replans the line from there. p50/p99/max
   period of both; target: p99 while planning <= 1.1x the idle p99.
2. At 1000 Hz, ``publish_tool_pose`` true against false (idle, ``--seconds`` s each, the
   node started afresh for each): p99 period side by side (target: with <= 1.1x
   without), and the tool pose's cost per setpoint (forward kinematics, the quaternion,
   the message written to CDR: what the stream thread does) beside Pinocchio's own
   ``forwardKinematics`` + ``updateFramePlacement``.

Usage: python benchmarks/panda_stream.py [--seconds 8]
"""

import argparse
import contextlib
import json
import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')  # as benchmarks/run.py: small products

from pathlib import Path  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'support'))

from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402
from example_robot_data import benchmark_urdfs  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from kinematics import seconds_per_call  # noqa: E402 - benchmarks/kinematics.py
from nav_msgs.msg import Path as PathMessage  # noqa: E402
import node_latency  # noqa: E402 - benchmarks/node_latency.py: the recorder, the domain
import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from traj_gen_ros.core.kinematics import Chain, pose_quaternion  # noqa: E402
from traj_gen_ros.node.messages.wire import pose_stamped_cdr  # noqa: E402

JOINTS = [f'panda_joint{k}' for k in range(1, 8)]
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
GENERATOR = node_latency.GENERATOR
SEND_EVERY = 0.3  # s between ~/cartesian_path requests
SIDE = 0.1  # m: the two goals, either side of the ready pose's tool in y
LATE_WINDOW = 100.0  # ms after a request's arrival: a long period there is the planning's
RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


@contextlib.contextmanager
def panda_node(urdf: str, rate_hz: float, publish_tool_pose: bool = True):
    """Run the generator on the Panda; yield a ready recorder (node_latency.Recorder)."""
    values = {'joints': JOINTS, 'initial_positions': READY, 'rate_hz': rate_hz,
              'max_velocity': [2.61], 'max_acceleration': [2.0], 'robot_description': urdf,
              'publish_tool_pose': publish_tool_pose}
    with tempfile.TemporaryDirectory() as folder:
        parameters = Path(folder) / 'panda.yaml'
        parameters.write_text(json.dumps({'/**': {'ros__parameters': values}}))
        process = node_latency.start([sys.executable, '-m', 'traj_gen_ros.node.generator',
                                      '--ros-args', '--params-file', str(parameters)])
        recorder = node_latency.Recorder()
        try:
            recorder.wait_ready()
            yield recorder
        finally:
            node_latency.stop(process)
            recorder.destroy_node()


def stamped_periods(recorder, first: int, last: int) -> dict:
    """Return p50/p99/max (ms) of the stamps' periods of ``recorder.states[first:last]``."""
    stamps = np.array([row[1] for row in recorder.states[first:last]], dtype=np.int64)
    return node_latency.percentiles(np.diff(stamps) * 1e-6)


def path_message(pose: np.ndarray) -> PathMessage:
    message = PathMessage()
    stamped = PoseStamped()
    point, orientation = stamped.pose.position, stamped.pose.orientation
    point.x, point.y, point.z = (float(value) for value in pose[:3, 3])
    _, quaternion = pose_quaternion(pose)  # (x, y, z, w)
    orientation.x, orientation.y, orientation.z, orientation.w = (float(v) for v in quaternion)
    message.poses.append(stamped)
    return message


def while_planning(urdf: str, chain: Chain, seconds: float) -> dict:
    """Return the 500 Hz periods idle and while lines are sent every 0.3 s, and the answers."""
    ready = chain.forward(READY)
    goals = []
    for side in (SIDE, -SIDE):
        goal = ready.copy()
        goal[1, 3] += side
        goals.append(path_message(goal))
    answers = {'accepted': 0, 'refused': 0}
    reasons: list[str] = []

    def on_status(status: DiagnosticStatus) -> None:
        values = {value.key: value.value for value in status.values}
        if values.get('request') != 'cartesian_path':
            return
        ok = status.level == DiagnosticStatus.OK
        answers['accepted' if ok else 'refused'] += 1
        if not ok:
            reasons.append(status.message)

    with panda_node(urdf, 500.0) as recorder:
        recorder.create_subscription(DiagnosticStatus, f'{GENERATOR}/status', on_status,
                                     RELIABLE)
        lines = recorder.create_publisher(PathMessage, f'{GENERATOR}/cartesian_path', 10)
        recorder.spin_until(lambda: lines.get_subscription_count() > 0)
        idle = node_latency.periods(recorder, seconds)
        planned = len(recorder.planning)
        first = len(recorder.states)
        end = time.monotonic() + seconds
        sent = 0
        while time.monotonic() < end:
            lines.publish(goals[sent % 2])
            sent += 1
            recorder.spin_for(min(SEND_EVERY, max(end - time.monotonic(), 0.0)))
        planning = recorder.planning[planned:]
        last = len(recorder.states)
        busy = stamped_periods(recorder, first, last)
        recorder.spin_for(0.5)  # the last answers
        late = late_after_requests(recorder, first, last, idle['p99'], LATE_WINDOW)
    planning_ms = [row[0] for row in planning]
    return {'idle': idle, 'planning': busy, 'sent': sent, 'answers': answers, 'late': late,
            'reasons': reasons[:3],
            'planning_ms': node_latency.percentiles(planning_ms) if planning_ms else None}


def with_tool_pose(urdf: str, seconds: float, rounds: int = 2) -> dict:
    """
    Return the 1 kHz periods with ``publish_tool_pose`` false and true, pooled over rounds.

    The two alternate (false, true, false, ...), ``seconds / rounds`` each, so that a noisy
    spell of the shared machine falls on both; ``tool_poses`` counts the ``~/tool_pose``
    messages this process received (a subscriber, as RViz would be).
    """
    stamps: dict[bool, list[np.ndarray]] = {False: [], True: []}
    received = {False: 0, True: 0}
    for _ in range(rounds):
        for publish in (False, True):
            with panda_node(urdf, 1000.0, publish) as recorder:
                poses: list[bytes] = []
                recorder.create_subscription(PoseStamped, f'{GENERATOR}/tool_pose',
                                             poses.append, RELIABLE, raw=True)
                recorder.spin_until(lambda: len(recorder.states) > 50)
                first, begin = len(recorder.states), len(poses)
                recorder.spin_for(seconds / rounds)
                stamps[publish].append(np.diff(np.array(
                    [row[1] for row in recorder.states[first:]], dtype=np.int64)) * 1e-6)
                received[publish] += len(poses) - begin
    return {publish: node_latency.percentiles(np.concatenate(periods)) | {
        'tool_poses': received[publish]} for publish, periods in stamps.items()}


def setpoint_cost(chain: Chain) -> dict[str, float]:
    """
    Return µs per setpoint of the node's tool pose work, its parts, and Pinocchio's own.

    The node's work is :class:`traj_gen_ros.node.robot.tool_pose.ToolPoseOutput`'s, without
    the publish: ``chain.forward``, ``pose_quaternion`` (which checks the pose first),
    ``pose_stamped_cdr``.
    """
    import pinocchio as pin  # noqa: PLC0415 - loaded by the chain already

    q = np.array(READY)
    model, data = chain._model, chain._model.createData()
    config = chain._configuration.config(q)
    tool = model.getFrameId(chain.tool_frame, pin.FrameType.BODY)
    pose = chain.forward(q)
    point, quaternion = pose_quaternion(pose)

    def node_work():
        point, quaternion = pose_quaternion(chain.forward(q))
        return pose_stamped_cdr(time.time_ns(), chain.base_frame, point, quaternion)

    def pinocchio_forward():
        pin.forwardKinematics(model, data, config)
        return pin.updateFramePlacement(model, data, tool)

    calls = {'setpoint': node_work, 'forward': lambda: chain.forward(q),
             'quaternion': lambda: pose_quaternion(pose),
             'cdr': lambda: pose_stamped_cdr(time.time_ns(), chain.base_frame, point,
                                             quaternion),
             'pinocchio': pinocchio_forward}
    return {name: seconds_per_call(call) * 1e6 for name, call in calls.items()}


def late_after_requests(recorder, first: int, last: int, threshold_ms: float,
                        window_ms: float) -> tuple[int, int]:
    """
    Count the periods above ``threshold_ms`` in ``states[first:last]``, and the late ones.

    The late ones end within ``window_ms`` after a request arrived at the node (its
    ``received`` on ``~/status``).
    """
    stamps = np.array([row[1] for row in recorder.states[first:last]], dtype=np.int64)
    long = np.flatnonzero(np.diff(stamps) * 1e-6 > threshold_ms) + 1
    arrivals = np.array(sorted(recorder.received), dtype=np.int64)
    if arrivals.size == 0:
        return long.size, 0
    index = np.searchsorted(arrivals, stamps[long], side='right') - 1
    since = (stamps[long] - arrivals[np.maximum(index, 0)]) * 1e-6
    return long.size, int(np.sum((index >= 0) & (since <= window_ms)))


def report(planning: dict, tool_pose: dict, cost: tuple[float, float]) -> None:
    def cells(entry: dict) -> str:
        return f'{entry["p50"]:6.3f} / {entry["p99"]:6.3f} / {entry["max"]:7.3f}'

    idle, busy = planning['idle'], planning['planning']
    ratio = busy['p99'] / idle['p99']
    print('== the node on the Panda (URDF, 7 joints): joint_states period (stamps), ms '
          'p50 / p99 / max')
    print(f'  500 Hz idle                                {cells(idle)}')
    print(f'  500 Hz, a ~/cartesian_path every {SEND_EVERY:g} s      {cells(busy)} | '
          f'p99 / idle {ratio:4.2f} | target <= 1.1 ({"met" if ratio <= 1.1 else "MISSED"})')
    answers = planning['answers']
    note = (f'node planning time p50 {planning["planning_ms"]["p50"]:.1f} ms, p99 '
            f'{planning["planning_ms"]["p99"]:.1f} ms' if planning['planning_ms'] else
            'no planning times')
    long, near = planning['late']
    print(f'   ({planning["sent"]} lines sent, {answers["accepted"]} accepted, '
          f'{answers["refused"]} refused; {note}; {long} periods above the idle p99, '
          f'{near} of them within {LATE_WINDOW:g} ms after a request arrived)')
    for reason in planning['reasons']:
        print(f'     refused: {reason[:150]}')
    without, with_pose = tool_pose[False], tool_pose[True]
    ratio = with_pose['p99'] / without['p99']
    print(f'  1000 Hz, publish_tool_pose false           {cells(without)}')
    print(f'  1000 Hz, publish_tool_pose true            {cells(with_pose)} | '
          f'p99 with / without {ratio:4.2f} | target <= 1.1 '
          f'({"met" if ratio <= 1.1 else "MISSED"})')
    print(f'   (alternating, two rounds each; {with_pose["tool_poses"]} ~/tool_pose '
          f'messages received while measured, {without["tool_poses"]} without)')
    total, pinocchio = cost['setpoint'], cost['pinocchio']
    print(f'  tool pose per setpoint, publish aside {total:6.2f} µs | Pinocchio '
          f'forwardKinematics + updateFramePlacement {pinocchio:5.2f} µs | ours/peer '
          f'{total / pinocchio:4.1f} | {total / 10:.2f} % of a 1 ms tick')
    print(f'   (chain.forward {cost["forward"]:.2f} µs, pose_quaternion {cost["quaternion"]:.2f} '
          f'µs (with check_pose), pose_stamped_cdr {cost["cdr"]:.2f} µs)')


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--seconds', type=float, default=8.0)
    args = parser.parse_args()
    found = benchmark_urdfs('the node on the Panda')
    if found is None:
        return 0
    urdf = found['panda'].read_text()
    chain = Chain.from_urdf(urdf, JOINTS)
    cost = setpoint_cost(chain)
    rclpy.init()
    try:
        planning = while_planning(urdf, chain, args.seconds)
        tool_pose = with_tool_pose(urdf, args.seconds)
    finally:
        rclpy.try_shutdown()
    report(planning, tool_pose, cost)
    return 0


if __name__ == '__main__':
    sys.exit(main())
