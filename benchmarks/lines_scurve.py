"""
What bounding the jerk costs on lines and arcs (issue 30): `make bench` runs it.

On example-robot-data's Panda and UR10 (fetched once into .pytest_cache like the tests
do), with the node's default limits (1 rad/s, 2 rad/s², 20 rad/s³; the tool's 0.25 m/s,
1.2 m/s², π/2 rad/s): each path timed by ``time_path`` (acceleration-limited, TOPP-RA,
within 1 % of the optimum) and by ``time_path_jerk_limited`` (profile ``scurve``), their
durations, the ratio, and the time each takes to plan.
"""

from functools import partial
import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')  # as benchmarks/run.py: small products

from pathlib import Path  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'support'))  # the tests' fetcher of the URDFs

from example_robot_data import urdfs_in  # noqa: E402
import numpy as np  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402
from traj_gen_ros.core.cartesian.jerk_limited_timing import time_path_jerk_limited  # noqa: E402
from traj_gen_ros.core.cartesian.joint_path import follow  # noqa: E402
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits  # noqa: E402
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path  # noqa: E402
from traj_gen_ros.core.kinematics import Chain  # noqa: E402

VELOCITY, ACCELERATION, JERK = 1.0, 2.0, 20.0
TOOL = ToolLimits(0.25, 1.2, np.pi / 2)
ARMS = {
    'panda': ([f'panda_joint{k}' for k in range(1, 8)], 'panda_hand_tcp',
              [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]),
    'ur10': (['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
              'wrist_2_joint', 'wrist_3_joint'], 'wrist_3_link',
             [0.3, -1.2, 1.6, -1.9, -1.57, 0.4]),
}


def moved(pose: np.ndarray, offset, rotvec=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Return ``pose`` moved by ``offset`` (m) and turned by ``rotvec`` (rad, base axes)."""
    result = pose.copy()
    result[:3, 3] += offset
    result[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix() @ pose[:3, :3]
    return result


def paths(start: np.ndarray) -> dict:
    """Return the benchmark's paths from the tool pose ``start``."""
    return {
        'line 0.30 m': straight_path(start, [moved(start, [0.0, 0.3, 0.0])]),
        'line 0.15 m, 0.3 rad': straight_path(
            start, [moved(start, [0.08, 0.1, -0.06], [0.0, 0.0, 0.3])]),
        'line 0.05 m': straight_path(start, [moved(start, [0.05, 0.0, 0.0])]),
        'two lines, corner': straight_path(start, [moved(start, [0.1, 0.0, 0.0]),
                                                   moved(start, [0.1, 0.1, 0.0])]),
        'arc 0.12 m': circular_path(start, moved(start, [0.06, 0.06, 0.0]),
                                    moved(start, [0.12, 0.0, 0.0])),
    }


def milliseconds(function) -> tuple[object, float]:
    """Return ``function()`` and the best of five runs' time, ms."""
    best, result = float('inf'), None
    for _ in range(5):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return result, best * 1e3


def main() -> None:
    found = urdfs_in(REPO / '.pytest_cache' / 'd')
    if isinstance(found, str):
        print(f'== lines under scurve: skipped, {found}')
        return
    print(f'== lines and arcs under profile scurve (issue 30): {VELOCITY:g} rad/s, '
          f'{ACCELERATION:g} rad/s^2, {JERK:g} rad/s^3; tool 0.25 m/s, 1.2 m/s^2')
    ratios = []
    for arm, (joints, tool_frame, ready) in ARMS.items():
        chain = Chain.from_urdf(found[arm].read_text(), joints, tool_frame=tool_frame)
        q0 = np.array(ready)
        for name, path in paths(chain.forward(q0)).items():
            joint_path = follow(chain, path, q0)
            optimal, optimal_ms = milliseconds(partial(
                time_path, path, joint_path, VELOCITY, ACCELERATION, TOOL))
            limited, limited_ms = milliseconds(partial(
                time_path_jerk_limited, path, joint_path, VELOCITY, ACCELERATION, JERK, TOOL))
            ratio = limited.duration / optimal.duration
            ratios.append(ratio)
            print(f'{arm:5s} {name:22s} acceleration-limited {optimal.duration:6.3f} s '
                  f'({optimal_ms:5.1f} ms) | jerk-limited {limited.duration:6.3f} s '
                  f'({limited_ms:5.1f} ms) | x{ratio:.3f}')
    print(f'   jerk-limited / acceleration-limited: {min(ratios):.2f} to {max(ratios):.2f}')


if __name__ == '__main__':
    main()
