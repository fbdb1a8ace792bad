"""
How a blend is parameterised: ``s`` runs at about the tool's combined speed across it.

The blend's ``s``-range is the combined length of its arc and of the rotation of the legs
it cuts; these tests hold it to that with oracles built here (the arc's length from the
corner's geometry, the legs' rotation from scipy), bound the tool point's speed
``|dp/ds|`` across sharp blends, and measure what that spares the timing's grid on a
zig-zag on pybullet's Panda (5,894 grid points when a blend kept the ``s`` of the corner
it cut away and the tool point nearly stopped in the middle of each).
"""

import math

from kinematics_robots import robot_urdf, ROBOTS
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from tool_path_oracles import assert_derivatives_match_differences, interior, pose
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.cartesian.tool_path import straight_path
from traj_gen_ros.core.kinematics import Chain


def corner(turn, radius, first, second, rotvecs):
    """Return a path along x that turns by ``turn`` (rad) in the xy plane, and its poses."""
    apex = np.array([first, 0.0, 0.0])
    end = apex + second * np.array([math.cos(turn), math.sin(turn), 0.0])
    poses = [pose([0, 0, 0], rotvecs[0]), pose(apex, rotvecs[1]), pose(end, rotvecs[2])]
    return straight_path(poses[0], poses[1:], radius), poses


def blend_speeds(path):
    """Return |dp/ds| and |ω_s| at 2001 points across the path's blend."""
    blend = next(piece for piece in path.pieces if piece.kind == 'blend')
    samples = path.sample(np.linspace(blend.start, blend.end, 2001), 'left')
    return (np.linalg.norm(samples.velocity, axis=1),
            np.linalg.norm(samples.angular, axis=1))


@pytest.mark.parametrize('turn_degrees', [160.0, 170.0, 178.0])
def test_without_rotation_the_tool_point_runs_through_a_sharp_blend_at_one_metre_per_unit(
        turn_degrees):
    path, _ = corner(math.radians(turn_degrees), 0.05, 0.3, 0.3, np.zeros((3, 3)))
    speed, angular = blend_speeds(path)
    assert speed.min() >= 0.5  # 0.024 at 160° when the blend kept the corner's s
    assert np.abs(speed - 1.0).max() < 1e-12 and not angular.any()


@pytest.mark.parametrize(('turn_degrees', 'rotation'), [(160.0, 0.05), (160.0, 0.1),
                                                        (170.0, 0.1)])
def test_with_rotation_the_combined_speed_stays_near_one_through_a_sharp_blend(
        turn_degrees, rotation):
    """The tool point slows where its arc is short and the orientation takes over."""
    rotvecs = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]) * rotation
    path, _ = corner(math.radians(turn_degrees), 0.05, 0.3, 0.3, rotvecs)
    speed, angular = blend_speeds(path)
    combined = np.hypot(speed, angular)
    assert 0.75 <= combined.min() and combined.max() <= 1.5, (combined.min(), combined.max())
    assert speed.min() >= 0.2
    # Shorter steps than elsewhere: the arc's radius is 9 mm (160°), 4 mm (170°).
    assert_derivatives_match_differences(path, interior(path, margin=1e-3), 1e-6,
                                         (1e-6, 5e-5))


def test_the_blend_spans_its_combined_length_and_bounds_the_tool_points_speed():
    """Random corners: span = √(Λ² + (θ1 d/L1 + θ2 d/L2)²), |dp/ds| between its bounds."""
    rng = np.random.default_rng(7)
    blended = 0
    for _ in range(300):
        turn, radius = rng.uniform(0.0, 3.1), rng.uniform(0.005, 0.2)
        first, second = rng.uniform(0.02, 0.5, 2)
        rotvecs = rng.normal(size=(3, 3)) * rng.choice([0.05, 0.3, 1.0])
        path, poses = corner(turn, radius, first, second, rotvecs)
        pieces = [piece for piece in path.pieces if piece.kind == 'blend']
        if not pieces:
            continue
        blended += 1
        d = min(radius, first / 2, second / 2)
        angles = [(Rotation.from_matrix(b[:3, :3]) * Rotation.from_matrix(a[:3, :3]).inv()
                   ).magnitude() for a, b in zip(poses[:-1], poses[1:], strict=True)]
        arc = turn * d / math.tan(turn / 2) if turn > 0 else 2 * d
        span = math.hypot(arc, angles[0] * d / first + angles[1] * d / second)
        assert pieces[0].end - pieces[0].start == pytest.approx(span, rel=1e-12)
        # On each leg |dp/ds| = L / S; across the blend it stays between the legs' speeds
        # and half (twice) the blend's mean Λ / span.
        legs = [length / math.hypot(length, angle)
                for length, angle in zip((first, second), angles, strict=True)]
        speed, _ = blend_speeds(path)
        assert speed.min() >= min(*legs, arc / span / 2) * (1 - 1e-9)
        assert speed.max() <= max(*legs, 2 * arc / span) * (1 + 1e-9)
    assert blended > 250


@pytest.fixture(scope='module')
def panda(request):
    robot = ROBOTS['pybullet-panda']
    return Chain.from_urdf(robot_urdf(request.config, robot.source, robot.name), robot.joints)


def test_a_zig_zag_of_sharp_blends_times_on_a_small_grid(panda):
    """Four 161° corners, 30 mm across and 5 mm along, blended by 5 mm (issue's review)."""
    q0 = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    start = panda.forward(q0)
    poses = []
    for k in range(5):
        goal = start.copy()
        goal[:3, 3] += [0.03 * ((k + 1) % 2), 0.005 * (k + 1), 0.0]
        poses.append(goal)
    path = straight_path(start, poses, 0.005)
    assert [piece.kind for piece in path.pieces].count('blend') == 4
    joint_path = follow(panda, path, q0)
    timed = time_path(path, joint_path, np.full(7, 1.5), np.full(7, 3.0),
                      ToolLimits(0.25, 1.2, 1.57))
    # The grid's rule asks at least β / 0.01 = 281 intervals of each blend for the tool's
    # bend alone (|d²p/ds²| / |dp/ds| = 1/ρ over the arc's length βρ), 477 for the joints'.
    assert len(timed.s) < 2500, len(timed.s)
    speed, _ = blend_speeds(path)
    assert np.abs(speed - 1.0).max() < 1e-12
