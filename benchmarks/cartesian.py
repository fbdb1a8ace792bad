"""
Lines and arcs of the tool (issue 30, "Speed"), beside Pilz's way in the same run: `make bench`.

On example-robot-data's Panda (7 joints, tool ``panda_hand_tcp``) and UR10 (tool
``wrist_3_link``), fetched once into .pytest_cache as the tests do; the tool's limits
0.25 m/s, 1.2 m/s², π/2 rad/s; the joints' velocity limits from the URDF (Panda 2.175 and
2.61 rad/s, UR10 2.16-3.2 rad/s), acceleration 2 rad/s² (the URDFs have none).

1. Planning one 0.3 m line on the Panda from its ready pose, p50 and p90 of single calls:
   the core (``straight_path`` + ``joint_path.follow`` + ``path_timing.time_path``; target
   <= 50 ms, aim 20 ms), the node's whole planning (``tool_motion.plan_tool_path`` with a
   Config built as the node builds it), and the peer (benchmarks/pilz_peer.py: a
   Cartesian trapezoid sampled at 100 Hz, inverse kinematics per sample, checked by
   finite differences).
2. The fixed, seeded set of benchmarks/cartesian_cases.py (20 lines, 10 arcs; away from
   and near singularities): ours refused or not (why, where), its duration and planning
   time; the peer's verdict, and where it must refuse, the duration of its uniformly
   slowed plan that fits (the largest ``α``: speed ``α·v``, acceleration ``α²·a``).

Usage: python benchmarks/cartesian.py [--repeats 30]
"""

import argparse
import dataclasses
import math
import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')  # as benchmarks/run.py: small products

from pathlib import Path  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'support'))  # the tests' fetcher of the URDFs

from cartesian_cases import Case, cases, PANDA_READY, SEED  # noqa: E402
from example_robot_data import benchmark_urdfs  # noqa: E402
import numpy as np  # noqa: E402
import pilz_peer  # noqa: E402
from traj_gen_ros.core.cartesian.joint_path import follow  # noqa: E402
from traj_gen_ros.core.cartesian.path_refusal import PathRefusal  # noqa: E402
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits  # noqa: E402
from traj_gen_ros.core.cartesian.tool_path import straight_path  # noqa: E402
from traj_gen_ros.core.kinematics import Chain  # noqa: E402
from traj_gen_ros.node.description.joint_limits import merge_limits, urdf_limits  # noqa: E402
from traj_gen_ros.node.description.kinematics import build_kinematics  # noqa: E402
from traj_gen_ros.node.planning.motion import State  # noqa: E402
from traj_gen_ros.node.planning.tool_motion import (  # noqa: E402
    CARTESIAN_PATH,
    plan_tool_path,
    ToolPathRequest,
)
from traj_gen_ros.node.settings.config import make_config  # noqa: E402

TOOL = ToolLimits(0.25, 1.2, math.pi / 2)
MAX_ACCELERATION = 2.0  # rad/s², every joint
JOINTS = {
    'panda': tuple(f'panda_joint{k}' for k in range(1, 8)),
    'ur10': ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
             'wrist_2_joint', 'wrist_3_joint'),
}
LINE = np.array([0.0, 0.3, 0.0])  # m: the line of part 1, from the Panda's ready pose


@dataclasses.dataclass(frozen=True)
class Robot:
    """A chain with its URDF, joint names and velocity limits (rad/s)."""

    urdf: str
    chain: Chain
    joints: tuple[str, ...]
    max_velocity: np.ndarray

    @property
    def max_acceleration(self) -> np.ndarray:
        return np.full(len(self.joints), MAX_ACCELERATION)


def ours(robot: Robot, case_path, q_start: np.ndarray):
    """Plan with the core: the joint path, then its timing (PathRefusal or ValueError)."""
    joint_path = follow(robot.chain, case_path, q_start)
    return time_path(case_path, joint_path, robot.max_velocity, robot.max_acceleration,
                     TOOL, joint_names=robot.joints)


def percentiles_ms(times: list[float]) -> tuple[float, float]:
    p50, p90 = np.percentile(times, [50, 90]) * 1e3
    return float(p50), float(p90)


def timed_calls(function, repeats: int) -> list[float]:
    """Return the wall time (s) of ``repeats`` calls, after three calls to warm up."""
    for _ in range(3):
        function()
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        function()
        times.append(time.perf_counter() - began)
    return times


def node_config(robot: Robot):
    """Return the node's Config for ``robot``, its limits and chain as the node builds them."""
    config = make_config(robot.joints, 500.0, 'quintic', 'heuristic',
                         robot.max_velocity.tolist(), [MAX_ACCELERATION], [0.0])
    limits = merge_limits(urdf_limits(robot.urdf, robot.joints),
                          max_velocity=config.max_velocity)
    return dataclasses.replace(config, max_velocity=np.array(limits.velocity), limits=limits,
                               kinematics=build_kinematics(robot.urdf, robot.joints))


def line_speed(panda: Robot, repeats: int) -> None:
    start = panda.chain.forward(PANDA_READY)
    goal = start.copy()
    goal[:3, 3] += LINE
    path = straight_path(start, [goal])
    timed = ours(panda, path, PANDA_READY)
    config = node_config(panda)
    rest = State(PANDA_READY, np.zeros(7), np.zeros(7))

    def node_plan():
        request = ToolPathRequest(CARTESIAN_PATH, '', (goal,))
        return plan_tool_path(config, rest, PANDA_READY, request)

    peer = pilz_peer.sample(panda.chain, path, PANDA_READY, panda.max_velocity,
                            panda.max_acceleration, TOOL)
    rows = [
        ('core: straight_path + follow + time_path',
         lambda: ours(panda, straight_path(start, [goal]), PANDA_READY)),
        ('node: tool_motion.plan_tool_path (Config)', node_plan),
        ('peer: trapezoid, IK per 10 ms sample, check',
         lambda: pilz_peer.sample(panda.chain, straight_path(start, [goal]), PANDA_READY,
                                  panda.max_velocity, panda.max_acceleration, TOOL)),
    ]
    print(f'== a 0.3 m line on the Panda (7 joints) from its ready pose: planning time, '
          f'{repeats} calls each, ms')
    results = {}
    for name, function in rows:
        results[name] = percentiles_ms(timed_calls(function, repeats))
    peer_p50 = results[rows[2][0]][0]
    for name, (p50, p90) in results.items():
        target = ''
        if name.startswith(('core', 'node')):
            verdict = 'met' if p90 <= 50.0 else 'MISSED'
            target = f' | target <= 50 ms ({verdict}), aim 20 ms ' \
                     f'({"met" if p50 <= 20.0 else "not yet"})'
        print(f'  {name:46s} p50 {p50:6.1f}  p90 {p90:6.1f}  | /peer p50 '
              f'{p50 / peer_p50:5.2f}{target}')
    print(f'   (ours: {timed.duration:.3f} s, {len(timed.s) - 1} grid intervals, '
          f'{len(follow(panda.chain, path, PANDA_READY).joints.breakpoints) - 1} joint '
          f'pieces; bounded by {timed.describe()}; the peer: {peer.duration:.3f} s, '
          f'{len(peer.q)} samples, {peer.refused or "fits"})')


def smallest_singular_value(chain: Chain, q: np.ndarray) -> float:
    """Return the smallest singular value of the Jacobian over the rows of ``q``."""
    return float(min(np.linalg.svd(chain.jacobian(row), compute_uv=False)[-1] for row in q))


def one_case(robot: Robot, case: Case) -> dict:
    """Plan ``case`` both ways: ours (3 times: the median time) and the peer's."""
    times, result = [], None
    for _ in range(3):
        began = time.perf_counter()
        try:
            result = ours(robot, case.path, case.q_start)
        except PathRefusal as refusal:
            result = refusal
        except ValueError as error:
            result = error
        times.append(time.perf_counter() - began)
    args = (robot.chain, case.path, case.q_start, robot.max_velocity, robot.max_acceleration,
            TOOL)
    peer = pilz_peer.sample(*args)
    fitted = pilz_peer.slowed(*args, peer)
    return {'ours': result, 'ours_ms': float(np.median(times)) * 1e3, 'peer': peer,
            'slowed': fitted, 'sigma': smallest_singular_value(robot.chain, peer.q)}


def verdict(result) -> str:
    if isinstance(result, PathRefusal):
        return f'refused: {result.kind} at {100 * result.fraction:.0f} %'
    if isinstance(result, ValueError):
        return f'refused: {str(result)[:40]}'
    return f'{result.duration:6.3f} s'


def the_set(robots: dict[str, Robot]) -> None:
    began = time.perf_counter()
    found = cases({name: robot.chain for name, robot in robots.items()})
    made = time.perf_counter() - began
    print(f'== {len(found)} lines and arcs (seed {SEED}; Panda and '
          'UR10): ours beside the peer (Pilz LIN/CIRC: trapezoid, 100 Hz, IK per sample, '
          'finite differences)')
    print(f'   tool 0.25 m/s, 1.2 m/s², π/2 rad/s; joints: URDF velocity, '
          f'{MAX_ACCELERATION:g} rad/s²; made in {made:.1f} s. σ: the smallest singular '
          "value of the Jacobian on the peer's samples. peer ×v/×a: its largest joint "
          'velocity / acceleration over the limit at full speed')
    print(f'  {"case":15s} {"kind":9s} {"m":>5s} {"σ":>6s} | {"ours":25s} {"ms":>5s} | '
          f'{"peer":12s} {"×v":>5s} {"×a":>6s} {"ms":>5s} | {"slowed peer":>16s} '
          f'{"/ours":>6s}')
    rows = []
    for case in found:
        row = one_case(robots[case.robot], case)
        rows.append((case, row))
        peer, fitted = row['peer'], row['slowed']
        slowed = '—' if fitted is None else f'{fitted.duration:6.3f} s α {fitted.alpha:.2f}'
        ratio = ''
        if fitted is not None and not isinstance(row['ours'], ValueError):
            ratio = f'{fitted.duration / row["ours"].duration:6.2f}'
        print(f'  {case.name:15s} {case.kind:9s} {case.translation:5.3f} '
              f'{row["sigma"]:6.3f} | {verdict(row["ours"]):25s} {row["ours_ms"]:5.0f} | '
              f'{peer.refused or "fits":12s} {peer.velocity_ratio:5.2f} '
              f'{peer.acceleration_ratio:6.2f} {peer.seconds * 1e3:5.0f} | '
              f'{slowed:>16s} {ratio:>6s}', flush=True)
    summary(rows)


def summary(rows: list) -> None:
    refused = [row for _, row in rows if row['peer'].refused]
    reasons = {}
    for row in refused:
        reason = row['peer'].refused.split()[0]
        reasons[reason] = reasons.get(reason, 0) + 1
    ratios = [row['slowed'].duration / row['ours'].duration for row in refused
              if row['slowed'] is not None and not isinstance(row['ours'], ValueError)]
    unfit = sum(row['slowed'] is None for row in refused)
    ours_refused = [(case.name, row['ours']) for case, row in rows
                    if isinstance(row['ours'], ValueError)]
    fits = [row['peer'].duration / row['ours'].duration for _, row in rows
            if not row['peer'].refused and not isinstance(row['ours'], ValueError)]
    ours_ms = [row['ours_ms'] for _, row in rows if not isinstance(row['ours'], ValueError)]
    print(f'refused by the peer: {len(refused)} of {len(rows)} ('
          + ', '.join(f'{name} {count}' for name, count in sorted(reasons.items()))
          + '); slowed peer duration / ours: median '
          + (f'{np.median(ratios):.2f}, max {max(ratios):.2f} ({len(ratios)} cases)'
             if ratios else '—')
          + (f'; {unfit} not fitted by slowing down to α {pilz_peer.SLOWEST:g}' if unfit
             else ''))
    if fits:
        print(f'   where the peer fits at full speed ({len(fits)}): its duration / ours median '
              f'{np.median(fits):.2f}, min {min(fits):.2f}, max {max(fits):.2f}')
    if ours_ms:
        print(f'   our planning time over the {len(ours_ms)} planned: p50 '
              f'{np.median(ours_ms):.0f} ms, p90 {np.percentile(ours_ms, 90):.0f} ms, max '
              f'{max(ours_ms):.0f} ms')
    print(f'   refused by ours: {len(ours_refused)} of {len(rows)}')
    for name, error in ours_refused:
        print(f'     {name}: {str(error)[:150]}')


def robots_from(found: dict[str, Path]) -> dict[str, Robot]:
    robots = {}
    for name, joints in JOINTS.items():
        urdf = found[name].read_text()
        chain = Chain.from_urdf(urdf, list(joints))
        robots[name] = Robot(urdf, chain, joints,
                             np.array(urdf_limits(urdf, joints).velocity, dtype=float))
    return robots


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    parser.add_argument('--repeats', type=int, default=30)
    args = parser.parse_args()
    found = benchmark_urdfs('lines and arcs')
    if found is None:
        return
    robots = robots_from(found)
    line_speed(robots['panda'], args.repeats)
    the_set(robots)


if __name__ == '__main__':
    main()
