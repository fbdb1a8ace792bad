"""
Core speed, measured against named peers in the same run (`make bench`).

Prints microseconds per plan against ruckig, plan + sample of a via-point spline against
scipy's CubicSpline, and sampling throughput, each with its target. Then the kinematics
(benchmarks/kinematics.py: inverse kinematics p50/p99, forward kinematics per call, beside
Pinocchio's own calls), what bounding the jerk costs on lines and arcs
(benchmarks/lines_scurve.py: durations against the acceleration-limited timing), the node
latency benchmark (benchmarks/node_latency.py) and the
graph-join benchmark (benchmarks/joins.py: 50 processes joining while the node streams at
500 Hz, against the node without its transport choice) when they are there; lines and arcs
of the tool (benchmarks/cartesian.py: planning time and a seeded set of 30, beside Pilz's
way, benchmarks/pilz_peer.py) and the node's stream on the Panda (benchmarks/panda_stream.py:
while lines are planned, and with ~/tool_pose against without).
"""

import os

# One BLAS thread: small products gain nothing from threads, and on a busy 2-core machine
# idle-spinning BLAS workers make them many times slower.
os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')

from pathlib import Path  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import timeit  # noqa: E402

import numpy as np  # noqa: E402
import ruckig  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402
import traj_gen_ros as tg  # noqa: E402

JOINTS = 6
START = np.zeros(JOINTS)
GOAL = np.array([1.0, -2.0, 0.5, 3.0, -0.7, 0.1])
MAX_VELOCITY = np.array([1.0, 1.5, 2.0, 1.0, 2.5, 3.0])
MAX_ACCELERATION = np.array([2.0, 3.0, 4.0, 2.0, 5.0, 6.0])


def seconds_per_call(function, budget: float = 0.3, rounds: int = 15) -> float:
    """
    Best of ``rounds`` rounds of the mean time per call, each round about ``budget/5`` s.

    The minimum is the cost without interference; on a shared machine, more rounds
    spread over a few seconds give it more chances to catch a quiet moment.
    """
    count, elapsed = 1, 0.0
    while elapsed < budget / 5:
        count *= 2
        elapsed = timeit.timeit(function, number=count)
    return min(timeit.repeat(function, number=count, repeat=rounds)) / count


def ruckig_planner():
    """Ruckig computing the same 6-DoF motion, acceleration-limited (infinite jerk)."""
    planner = ruckig.Ruckig(JOINTS)
    request = ruckig.InputParameter(JOINTS)
    request.current_position = START.tolist()
    request.target_position = GOAL.tolist()
    request.max_velocity = MAX_VELOCITY.tolist()
    request.max_acceleration = MAX_ACCELERATION.tolist()
    request.max_jerk = [float('inf')] * JOINTS
    trajectory = ruckig.Trajectory(JOINTS)
    return lambda: planner.calculate(request, trajectory), trajectory


def report(name: str, ours: float, peer_name: str, peer: float, unit: str, target: str) -> None:
    print(f'{name:44s} {ours:10.2f} {unit:4s} | {peer_name} {peer:10.2f} {unit:4s} '
          f'| ours/peer {ours / peer:6.2f} | target {target}')


def planning() -> None:
    print('== planning one 6-joint plan (µs per plan; ratio < 1 means faster than the peer)')
    ruckig_plan, ruckig_trajectory = ruckig_planner()
    ruckig_plan()
    ruckig_us = seconds_per_call(ruckig_plan) * 1e6
    ours = tg.min_time(START, GOAL, MAX_VELOCITY, MAX_ACCELERATION)
    assert abs(ours.duration - ruckig_trajectory.duration) < 1e-9, 'not the same motion'
    for name, plan in [
        ('quintic(q0, qf, 3 s)', lambda: tg.quintic(START, GOAL, 3.0)),
        ('min_time(..., "lspb")', lambda: tg.min_time(START, GOAL, MAX_VELOCITY,
                                                      MAX_ACCELERATION)),
    ]:
        us = seconds_per_call(plan) * 1e6
        verdict = 'met' if us < 30.0 else 'MISSED'
        report(name, us, 'ruckig', ruckig_us, 'µs', f'< 30 µs ({verdict})')
    print(f'   (both compute the same time-optimal motion: {ours.duration:.4f} s)')


def moving_state() -> None:
    print('== planning from a moving state (issue 10): 6 and 1000 joints, µs per plan')
    rng = np.random.default_rng(11)
    for joints, target_us in ((JOINTS, {'lspb': 100.0, 'cubic': 300.0, 'quintic': 300.0}),
                              (1000, {'lspb': 2000.0, 'cubic': 2000.0, 'quintic': 2000.0})):
        start = rng.uniform(-1.0, 1.0, joints)
        goal = rng.uniform(-1.0, 1.0, joints)
        max_velocity = rng.uniform(0.5, 2.0, joints)
        max_acceleration = rng.uniform(1.0, 4.0, joints)
        # Replanning on the way: moving towards the goal at up to half the velocity limit
        # (a quintic cannot turn a joint that speeds away from its goal at once).
        towards = np.sign(goal - start)
        velocity = towards * rng.uniform(0.0, 0.5, joints) * max_velocity
        acceleration = towards * rng.uniform(-0.2, 0.2, joints) * max_acceleration
        planner = ruckig.Ruckig(joints)
        request = ruckig.InputParameter(joints)
        request.current_position, request.target_position = start.tolist(), goal.tolist()
        request.current_velocity = velocity.tolist()
        request.max_velocity = max_velocity.tolist()
        request.max_acceleration = max_acceleration.tolist()
        request.max_jerk = [float('inf')] * joints
        trajectory = ruckig.Trajectory(joints)
        planner.calculate(request, trajectory)
        ruckig_us = seconds_per_call(lambda p=planner, r=request, t=trajectory:
                                     p.calculate(r, t)) * 1e6
        for profile, target in target_us.items():
            state = (start, goal, max_velocity, max_acceleration, profile)

            def plan(state=state, velocity=velocity, acceleration=acceleration):
                return tg.min_time(*state, v0=velocity, a0=acceleration)
            if profile == 'lspb':
                assert abs(plan().duration - trajectory.duration) <= 1e-9 * trajectory.duration
            us = seconds_per_call(plan, budget=0.5) * 1e6
            verdict = 'met' if us <= target else 'MISSED'
            report(f'{joints} joints min_time {profile} from v0, a0', us, 'ruckig', ruckig_us,
                   'µs', f'<= {target:g} µs ({verdict})')


def scurve_moving_state() -> None:
    print('== jerk-limited S-curve (issue 12): 6-joint min-time plan from a moving state, µs')
    rng = np.random.default_rng(12)
    start, goal = rng.uniform(-1.0, 1.0, JOINTS), rng.uniform(-1.0, 1.0, JOINTS)
    limits = (MAX_VELOCITY, MAX_ACCELERATION, 10.0 * MAX_ACCELERATION)
    velocity = rng.uniform(-0.5, 0.5, JOINTS) * MAX_VELOCITY
    acceleration = rng.uniform(-0.5, 0.5, JOINTS) * MAX_ACCELERATION
    planner, request = ruckig.Ruckig(JOINTS), ruckig.InputParameter(JOINTS)
    request.current_position, request.target_position = start.tolist(), goal.tolist()
    request.current_velocity = velocity.tolist()
    request.current_acceleration = acceleration.tolist()
    request.max_velocity, request.max_acceleration, request.max_jerk = (
        limit.tolist() for limit in limits)
    trajectory = ruckig.Trajectory(JOINTS)
    planner.calculate(request, trajectory)
    ruckig_us = seconds_per_call(lambda: planner.calculate(request, trajectory)) * 1e6

    def plan():
        return tg.min_time(start, goal, limits[0], limits[1], 'scurve', v0=velocity,
                           a0=acceleration, max_jerk=limits[2])

    assert abs(plan().duration - trajectory.duration) <= 1e-9 * trajectory.duration
    us = seconds_per_call(plan) * 1e6
    verdict = 'met' if us <= 100.0 else 'MISSED'
    report('min_time(..., "scurve") from v0, a0', us, 'ruckig', ruckig_us, 'µs',
           f'<= 100 µs ({verdict})')


def via_spline() -> None:
    print('== 6-joint, 20-via-point "continuous" cubic: plan + sample pos/vel/acc at 1 kHz')
    rng = np.random.default_rng(7)
    points = np.cumsum(rng.normal(size=(21, JOINTS)), axis=0)
    durations = rng.uniform(0.5, 1.5, size=20)
    knots = np.concatenate(([0.0], np.cumsum(durations)))
    times = np.arange(0.0, knots[-1], 1e-3)

    def ours():
        return tg.cubic_via(points, durations, 'continuous').sample(times)

    def scipy_spline():
        spline = CubicSpline(knots, points, bc_type='clamped')
        return spline(times), spline(times, 1), spline(times, 2)

    difference = max(np.abs(a - b).max() for a, b in zip(ours(), scipy_spline(), strict=True))
    ms, peer_ms = seconds_per_call(ours) * 1e3, seconds_per_call(scipy_spline) * 1e3
    verdict = 'met' if ms <= peer_ms else 'MISSED'
    report(f'cubic_via + sample ({times.size} samples)', ms, 'scipy', peer_ms, 'ms',
           f'<= scipy ({verdict})')
    print(f'   (largest difference from scipy: {difference:.1e})')


def sampling() -> None:
    print('== sampling throughput (million joint-samples per second, 100,000 sorted times)')
    rng = np.random.default_rng(7)
    points = np.cumsum(rng.normal(size=(21, JOINTS)), axis=0)
    durations = np.full(20, 2.0)
    knots = np.concatenate(([0.0], np.cumsum(durations)))
    spline = CubicSpline(knots, points, bc_type='clamped')

    scipy_times = np.linspace(0.0, knots[-1], 100_000)

    def scipy_sample():
        return spline(scipy_times), spline(scipy_times, 1), spline(scipy_times, 2)

    for name, trajectory in [
        ('quintic', tg.quintic(START, GOAL, 40.0)),
        ('cubic_via "continuous" (20 segments)', tg.cubic_via(points, durations, 'continuous')),
        ('lspb_via (20 segments)', tg.lspb_via(points, durations, 20.0)),
        ('min_time lspb', tg.min_time(START, GOAL, MAX_VELOCITY, MAX_ACCELERATION)),
    ]:
        times = np.linspace(0.0, trajectory.duration, 100_000)
        seconds = seconds_per_call(lambda t=trajectory, s=times: t.sample(s))
        rate = times.size * JOINTS / seconds / 1e6
        peer = times.size * JOINTS / seconds_per_call(scipy_sample) / 1e6
        verdict = 'met' if rate >= 50.0 else 'MISSED'
        report(name, rate, 'scipy CubicSpline', peer, 'M/s', f'>= 50 M/s ({verdict})')
    ruckig_plan, ruckig_trajectory = ruckig_planner()
    ruckig_plan()
    times = np.linspace(0.0, ruckig_trajectory.duration, 1000)
    ours = tg.min_time(START, GOAL, MAX_VELOCITY, MAX_ACCELERATION)
    ours_ms = seconds_per_call(lambda: ours.sample(times)) * 1e3
    ruckig_ms = seconds_per_call(lambda: [ruckig_trajectory.at_time(t) for t in times]) * 1e3
    report('1000 samples of the min-time plan', ours_ms, 'ruckig at_time', ruckig_ms, 'ms',
           'faster than ruckig')


def kinematics() -> None:
    """Run benchmarks/kinematics.py in its own process (Pinocchio loads only there)."""
    sys.stdout.flush()
    subprocess.run([sys.executable, str(Path(__file__).with_name('kinematics.py'))],
                   check=True)


def lines_and_arcs() -> None:
    """Run benchmarks/cartesian.py: lines and arcs beside Pilz's way (issue 30)."""
    script = Path(__file__).with_name('cartesian.py')
    if script.exists():
        sys.stdout.flush()
        subprocess.run([sys.executable, str(script)], check=True)


def panda_stream() -> None:
    """Run benchmarks/panda_stream.py: the stream while lines are planned, ~/tool_pose."""
    script = Path(__file__).with_name('panda_stream.py')
    if script.exists():
        sys.stdout.flush()
        subprocess.run([sys.executable, str(script)], check=True)


def lines_scurve() -> None:
    """Run benchmarks/lines_scurve.py in its own process (Pinocchio loads only there)."""
    sys.stdout.flush()
    subprocess.run([sys.executable, str(Path(__file__).with_name('lines_scurve.py'))],
                   check=True)


def node_latency() -> None:
    script = Path(__file__).with_name('node_latency.py')
    if script.exists():
        print('== node (across processes)', flush=True)
        subprocess.run([sys.executable, str(script)], check=True)


def graph_joins() -> None:
    script = Path(__file__).with_name('joins.py')
    if script.exists():
        print('== processes joining the ROS graph while the node streams (issue 28)', flush=True)
        subprocess.run([sys.executable, str(script)], check=True)


if __name__ == '__main__':
    planning()
    moving_state()
    scurve_moving_state()
    via_spline()
    sampling()
    kinematics()
    lines_and_arcs()
    lines_scurve()
    node_latency()
    graph_joins()
    panda_stream()
