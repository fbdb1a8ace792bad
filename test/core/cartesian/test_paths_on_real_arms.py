"""
Lines and arcs end to end on real arms: tool path, joint path, timing (issue 30).

Example-robot-data's Panda and UR10 and pybullet's KUKA iiwa. For each line and arc: the
joint trajectory within every joint limit exactly; the tool, at every millisecond, within
0.1 mm and 1 mrad of the ideal path at ``s(t)`` (forward kinematics of the sampled
trajectory); the duration within 1 % of the independent phase-plane optimum on 10,000
points of the same joint path (test/support/topp_reference.py).
"""

import numpy as np
from real_arms import arm_fixture, moved, STARTS
from scipy.spatial.transform import Rotation
from topp_reference import reference_duration
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path
from traj_gen_ros.core.kinematic_limits import limit_violation

TOOL = ToolLimits(0.25, 1.2, np.pi / 2)
arm = arm_fixture(STARTS)


def _check(chain, q0, path, vmax=1.5, amax=3.0):
    joint_path = follow(chain, path, q0)
    timed = time_path(path, joint_path, vmax, amax, TOOL, joint_names=chain.joints)
    assert limit_violation(timed.trajectory, vmax, amax) is None
    times = np.arange(0.0, timed.duration, 1e-3)
    q = timed.trajectory.sample(times)[0]
    s, _ = timed.path_parameter(times)
    reached, ideal = chain.forward(q), path.poses(s)
    distance = np.linalg.norm(reached[:, :3, 3] - ideal[:, :3, 3], axis=1)
    angle = (Rotation.from_matrix(ideal[:, :3, :3]).inv()
             * Rotation.from_matrix(reached[:, :3, :3])).magnitude()
    assert distance.max() < 1e-4 and angle.max() < 1e-3, (distance.max(), angle.max())
    end = chain.forward(timed.trajectory.sample(timed.duration)[0][0])
    assert np.linalg.norm(end[:3, 3] - path.poses(path.length)[0, :3, 3]) < 1e-4
    reference = reference_duration(path, joint_path.joints.sample, vmax, amax, TOOL)
    assert reference * (1.0 - 1e-3) <= timed.duration <= reference * 1.01, \
        (timed.duration, reference)
    return timed


def test_a_line_with_a_turn(arm):
    chain, q0 = arm
    start = chain.forward(q0)
    path = straight_path(start, [moved(start, [0.08, 0.1, -0.06], [0.0, 0.0, 0.3])])
    timed = _check(chain, q0, path)
    travel = np.linalg.norm(path.poses(path.length)[0, :3, 3] - start[:3, 3])
    assert timed.duration > travel / TOOL.max_linear_velocity


def test_two_lines_blended(arm):
    chain, q0 = arm
    start = chain.forward(q0)
    corner, goal = moved(start, [0.1, 0.0, 0.0]), moved(start, [0.1, 0.1, 0.0])
    blended = _check(chain, q0, straight_path(start, [corner, goal], 0.03))
    stopped = _check(chain, q0, straight_path(start, [corner, goal], 0.0))
    assert blended.duration < stopped.duration  # the blend saves the stop at the corner


def test_an_arc(arm):
    chain, q0 = arm
    start = chain.forward(q0)
    _check(chain, q0, circular_path(start, moved(start, [0.06, 0.06, 0.0]),
                                    moved(start, [0.12, 0.0, 0.0])))
