"""tool_motion's brake along a line: at every instant, at full and at half speed, on the line."""

from kinematics_robots import robot_urdf, ROBOTS
import numpy as np
import pytest
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.cartesian.tool_path import straight_path
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.kinematics import Chain
from traj_gen_ros.node.planning.tool_motion import AlongPath

READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
VMAX, AMAX = np.full(7, 1.5), np.full(7, 3.0)
TOOL = ToolLimits(0.25, 1.2, np.pi / 2)


@pytest.fixture(scope='module')
def panda(request):
    robot = ROBOTS['erd-panda']
    return Chain.from_urdf(robot_urdf(request.config, robot.source, robot.name), robot.joints,
                           tool_frame=robot.default_tool)


def test_a_brake_along_a_line_stays_on_it_from_every_instant(panda):
    start = panda.forward(READY)
    goal = start.copy()
    goal[:3, 3] += [0.3, 0.0, 0.0]
    path = straight_path(start, [goal])
    joint_path = follow(panda, path, READY)
    timed = time_path(path, joint_path, VMAX, AMAX, TOOL)
    along = AlongPath(path, joint_path, timed, 0.0, VMAX, AMAX, TOOL)
    direction = np.array([1.0, 0.0, 0.0])
    # Early, mid-line and late, when the plan itself already brakes as hard as it may.
    for fraction in np.linspace(0.02, 0.98, 17):
        elapsed = fraction * timed.duration
        position, velocity, _ = timed.trajectory.sample(elapsed)
        for factor in (1.0, 0.5):  # the speed override: the commanded velocity is scaled
            plan = along.brake(elapsed, factor * velocity[0])
            assert plan is not None, (fraction, factor)
            first = plan.sample(0.0)
            np.testing.assert_allclose(first[0][0], position[0], atol=1e-8)
            np.testing.assert_allclose(first[1][0], factor * velocity[0], atol=1e-6)
            assert limit_violation(plan, VMAX, AMAX) is None
            assert np.abs(plan.sample(plan.duration)[1]).max() < 1e-9
            tool = panda.forward(plan.sample(np.linspace(0, plan.duration, 200))[0])[:, :3, 3]
            off = tool - start[:3, 3]
            across = off - (off @ direction)[:, None] * direction
            assert np.linalg.norm(across, axis=1).max() < 1e-5, (fraction, factor)
    assert along.brake(timed.duration + 0.1, np.zeros(7)) is None  # past the path


def test_a_brake_along_a_blended_corner_stays_on_the_path(panda):
    """Through the blend, where the plan itself slows for the arc: the brake never leaves it."""
    start = panda.forward(READY)
    corner, goal = start.copy(), start.copy()
    corner[:3, 3] = [0.407, 0.1, 0.487]
    goal[:3, 3] = [0.407, -0.1, 0.487]
    corner[:3, :3] = goal[:3, :3] = np.diag([1.0, -1.0, -1.0])
    path = straight_path(start, [corner, goal], 0.05)
    joint_path = follow(panda, path, READY)
    vmax, amax = np.full(7, 1.0), np.full(7, 2.0)
    timed = time_path(path, joint_path, vmax, amax, TOOL)
    along = AlongPath(path, joint_path, timed, 0.0, vmax, amax, TOOL)
    ideal = path.poses(np.linspace(0.0, path.length, 20001))[:, :3, 3]
    for elapsed in np.linspace(0.05, timed.duration - 0.05, 13):
        _, velocity, acceleration = timed.trajectory.sample(elapsed)
        for factor in (1.0, 0.5):
            plan = along.brake(elapsed, factor * velocity[0], factor ** 2 * acceleration[0])
            assert plan is not None, (elapsed, factor)
            assert limit_violation(plan, vmax, amax) is None
            tool = panda.forward(plan.sample(np.linspace(0, plan.duration, 60))[0])[:, :3, 3]
            nearest = np.min(np.linalg.norm(tool[:, None] - ideal[None], axis=2), axis=1)
            assert nearest.max() < 1e-4, (elapsed, factor, nearest.max())
