"""brake_along: to rest along the path, as hard as the limits allow, never above them."""

import math

import numpy as np
import pytest
from synthetic_paths import line, linear_joint, seven_joints
from traj_gen_ros.core.cartesian.path_brake import brake_along
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.kinematic_limits import limit_violation

NO_TOOL = ToolLimits()


def test_one_linear_joint_brakes_at_its_acceleration_limit():
    """Brake q = s: from ṡ = v the brake lasts v / a and covers v² / 2a (Craig's LSPB blend)."""
    path = line(1.0)
    joint_path = linear_joint().joint_path(path)
    plan, end = brake_along(path, joint_path, np.array([1.0]), np.array([2.0]), NO_TOOL,
                            0.3, 0.8)
    assert plan.duration == pytest.approx(0.8 / 2.0, rel=1e-6)
    assert end == pytest.approx(0.3 + 0.8 ** 2 / 4.0, rel=1e-6)
    position, velocity, _ = plan.sample(np.array([0.0, plan.duration]))
    assert position[0, 0] == pytest.approx(0.3) and velocity[0, 0] == pytest.approx(0.8)
    assert position[1, 0] == pytest.approx(end) and abs(velocity[1, 0]) < 1e-9
    assert limit_violation(plan, 1.0, 2.0) is None


def test_seven_joints_mid_path_stay_on_the_joint_path_and_within_the_limits():
    path = line(0.3)
    joint_path = seven_joints().joint_path(path)
    vmax, amax = np.full(7, 1.0), np.full(7, 3.0)
    timed = time_path(path, joint_path, vmax, amax, ToolLimits(0.25, 1.2, 1.5))
    s0, speed = timed.path_parameter(0.4 * timed.duration)
    plan, end = brake_along(path, joint_path, vmax, amax, ToolLimits(0.25, 1.2, 1.5),
                            float(s0), float(speed))
    assert limit_violation(plan, vmax, amax) is None
    assert float(s0) < end < path.length
    # On the path: every breakpoint's joints are q(s) at some s in [s0, end].
    s = np.linspace(float(s0), end, 20001)
    on_path = joint_path.joints.sample(s)[0]
    positions = plan.sample(plan.breakpoints)[0]
    nearest = np.min(np.linalg.norm(positions[:, None] - on_path[None], axis=2), axis=1)
    assert nearest.max() < 1e-5
    final = plan.sample(plan.duration)
    assert np.abs(final[1]).max() < 1e-9
    # Harder than the timing's own slow-down from there: it stops sooner than the end.
    assert plan.duration < timed.duration - 0.4 * timed.duration
    assert math.isfinite(plan.duration)


def test_refuses_at_rest():
    path = line(0.3)
    with pytest.raises(ValueError, match='nothing to brake'):
        brake_along(path, linear_joint().joint_path(path), np.array([1.0]), np.array([1.0]),
                    NO_TOOL, 0.1, 0.0)
