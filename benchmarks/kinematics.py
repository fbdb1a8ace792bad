"""
Kinematics speed (issue 29), beside Pinocchio's own calls: `make bench` runs it.

On example-robot-data's Panda (7 joints, tool ``panda_hand_tcp``; fetched once into
.pytest_cache like the tests do): inverse kinematics, warm, from a seed whose tool pose is
within 0.2 m of the goal (p50 and p99 of single calls; target p50 <= 2 ms), forward
kinematics and the Jacobian per call (the node's ``~/tool_pose`` runs forward kinematics
at the stream rate, up to 1 kHz), each beside the Pinocchio calls it is made of.
"""

import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')  # as benchmarks/run.py: small products

from pathlib import Path  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import timeit  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'support'))  # the tests' fetcher of the URDF

from example_robot_data import urdfs_in  # noqa: E402
import numpy as np  # noqa: E402
from traj_gen_ros.core.kinematics import Chain, pose_distance  # noqa: E402

POSES = 300
GOAL_DISTANCE = 0.2  # m: the seed's tool pose is at most this far from the goal


def seconds_per_call(function, budget: float = 0.3, rounds: int = 15) -> float:
    """Best of ``rounds`` rounds of the mean time per call (as benchmarks/run.py)."""
    count, elapsed = 1, 0.0
    while elapsed < budget / 5:
        count *= 2
        elapsed = timeit.timeit(function, number=count)
    return min(timeit.repeat(function, number=count, repeat=rounds)) / count


def cases(chain: Chain, rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    """Return ``(goal pose, seed)`` pairs: seeds within 0.2 m (tool position) of the goal."""
    found = []
    while len(found) < POSES:
        goal = rng.uniform(chain.lower, chain.upper)
        seed = np.clip(goal + rng.uniform(-0.2, 0.2, goal.size), chain.lower, chain.upper)
        target = chain.forward(goal)
        if np.linalg.norm(chain.forward(seed)[:3, 3] - target[:3, 3]) <= GOAL_DISTANCE:
            found.append((target, seed))
    return found


def inverse(chain: Chain) -> None:
    pairs = cases(chain, np.random.default_rng(29))
    for target, seed in pairs[:20]:
        chain.inverse(target, seed)  # warm
    times, iterations, from_seed = [], [], 0
    for target, seed in pairs:
        start = time.perf_counter()
        solution = chain.inverse(target, seed)
        times.append(time.perf_counter() - start)
        distance, angle = pose_distance(target, chain.forward(solution.q))
        assert distance <= 1e-5 and angle <= 1e-4, (distance, angle)
        iterations.append(solution.iterations)
        from_seed += solution.start == 'seed'
    p50, p99 = np.percentile(times, [50, 99]) * 1e3
    verdict = 'met' if p50 <= 2.0 else 'MISSED'
    print(f'inverse, seed within {GOAL_DISTANCE} m ({POSES} poses)   p50 {p50:6.3f} ms  '
          f'p99 {p99:6.3f} ms | target p50 <= 2 ms ({verdict})')
    print(f'   ({from_seed}/{POSES} converged from the seed; iterations p50 '
          f'{np.median(iterations):.0f}, max {max(iterations)})')


def per_call(chain: Chain) -> None:
    import pinocchio as pin  # noqa: PLC0415 - loaded by the chain already

    model = chain._model
    data = model.createData()
    q = chain.lower / 2 + chain.upper / 2
    config = chain._configuration.config(q)
    tool = model.getFrameId(chain.tool_frame, pin.FrameType.BODY)
    aligned = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def pinocchio_forward():
        pin.forwardKinematics(model, data, config)
        return pin.updateFramePlacement(model, data, tool).homogeneous

    def pinocchio_jacobian():
        pin.computeJointJacobians(model, data, config)
        return pin.getFrameJacobian(model, data, tool, aligned)

    samples = np.tile(q, (1000, 1))
    rows = [
        ('forward(q): the tool pose, one sample', lambda: chain.forward(q),
         'forwardKinematics + updateFramePlacement', pinocchio_forward),
        ('jacobian(q)', lambda: chain.jacobian(q),
         'computeJointJacobians + getFrameJacobian', pinocchio_jacobian),
        ('forward of 1000 samples, per sample', lambda: chain.forward(samples),
         'forwardKinematics only', lambda: pin.forwardKinematics(model, data, config)),
    ]
    for name, ours, peer_name, peer in rows:
        ours_us = seconds_per_call(ours) * 1e6
        if name.startswith('forward of'):
            ours_us /= samples.shape[0]
        peer_us = seconds_per_call(peer) * 1e6
        print(f'{name:44s} {ours_us:7.2f} µs | Pinocchio {peer_name} {peer_us:6.2f} µs '
              f'| ours/peer {ours_us / peer_us:5.1f}')
    share = seconds_per_call(lambda: chain.forward(q)) * 1e3 * 100
    print(f'   (forward kinematics at 1 kHz takes {share:.2f} % of each 1 ms tick)')


def main() -> None:
    found = urdfs_in(REPO / '.pytest_cache' / 'd')
    if isinstance(found, str):
        print(f'== kinematics: skipped, {found}')
        return
    chain = Chain.from_urdf(found['panda'].read_text(),
                            [f'panda_joint{k}' for k in range(1, 8)])
    import pinocchio  # noqa: PLC0415 - loaded by the chain already

    print(f'== kinematics (issue 29): {chain.describe()} (Pinocchio {pinocchio.__version__})')
    inverse(chain)
    per_call(chain)


if __name__ == '__main__':
    main()
