"""
Straight tool paths without blends: lengths, slerp, derivatives, stops, refusals.

Oracles: scipy's Slerp for the orientation, the segment's closed-form numbers, and central
differences of the path's own samples for every derivative.
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from tool_path_oracles import assert_derivatives_match_differences, interior, pose
from traj_gen_ros.core.cartesian.tool_path import straight_path


def test_line_with_rotation_is_linear_in_position_and_slerps_by_the_fraction():
    start = pose([0.1, -0.2, 0.3], [0.2, -0.1, 0.4])
    goal = pose([0.4, 0.2, 0.3], [-0.5, 0.6, 0.1])
    path = straight_path(start, [goal])
    turn = (Rotation.from_matrix(goal[:3, :3]) * Rotation.from_matrix(start[:3, :3]).inv())
    angle = turn.magnitude()
    assert path.length == pytest.approx(math.hypot(0.5, angle), abs=1e-15)
    assert path.knots.tolist() == [0.0, path.length]
    assert path.stops.tolist() == [0.0, path.length]
    assert [(p.kind, p.waypoint) for p in path.pieces] == [('line', 1)]
    s = np.linspace(0.0, path.length, 11)
    samples = path.sample(s)
    fraction = s / path.length
    assert np.abs(samples.position - (start[:3, 3] + fraction[:, None] * [0.3, 0.4, 0.0])
                  ).max() < 1e-15
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix([start[:3, :3], goal[:3, :3]]))
    assert np.abs(samples.rotation - slerp(fraction).as_matrix()).max() < 1e-14
    assert np.abs(samples.velocity - np.array([0.3, 0.4, 0.0]) / path.length).max() < 1e-15
    assert np.abs(samples.angular - turn.as_rotvec() / path.length).max() < 1e-14
    assert not samples.acceleration.any() and not samples.angular_acceleration.any()
    # The combined speed is one per unit of path on a line: |p'|² + |ω_s|² = 1.
    combined = (samples.velocity ** 2).sum(1) + (samples.angular ** 2).sum(1)
    assert np.abs(combined - 1.0).max() < 1e-14
    assert_derivatives_match_differences(path, interior(path))
    assert np.abs(path.poses(s) - samples.poses()).max() == 0.0
    assert path.poses(path.length)[0] == pytest.approx(goal, abs=1e-14)


def test_pure_rotation_in_place_is_its_angle_long_and_turns_at_one_radian_per_unit():
    start = pose([0.5, 0.0, 0.2])
    goal = pose([0.5, 0.0, 0.2], [0.0, 0.0, 2.0])
    path = straight_path(start, [goal])
    assert path.length == pytest.approx(2.0, abs=1e-15)
    s = np.linspace(0.0, 2.0, 9)
    samples = path.sample(s)
    assert np.abs(samples.position - [0.5, 0.0, 0.2]).max() == 0.0
    assert not samples.velocity.any()
    assert np.abs(samples.angular - [0.0, 0.0, 1.0]).max() < 1e-15
    expected = Rotation.from_rotvec(np.outer(s, [0.0, 0.0, 1.0])).as_matrix()
    assert np.abs(samples.rotation - expected).max() < 1e-15
    assert_derivatives_match_differences(path, interior(path))


def test_half_turn_takes_one_axis_and_keeps_it():
    path = straight_path(pose([0, 0, 0]), [pose([0.2, 0, 0], [0.0, math.pi, 0.0])])
    assert path.length == pytest.approx(math.hypot(0.2, math.pi), abs=1e-14)
    end = path.sample(path.length).rotation[0]
    assert end == pytest.approx(Rotation.from_rotvec([0, math.pi, 0]).as_matrix(), abs=1e-14)
    half = path.sample(path.length / 2).rotation[0]
    assert Rotation.from_matrix(half).magnitude() == pytest.approx(math.pi / 2, abs=1e-14)


def test_corners_without_blend_are_stops_and_sides_pick_their_segment():
    poses = [pose([0.3, 0, 0], [0, 0, 0.3]), pose([0.3, 0.4, 0]), pose([0.3, 0.4, 0], [1, 0, 0])]
    path = straight_path(pose([0, 0, 0]), poses)
    lengths = [math.hypot(0.3, 0.3), math.hypot(0.4, 0.3), 1.0]
    assert path.knots == pytest.approx(np.cumsum([0.0] + lengths), abs=1e-15)
    assert path.stops.tolist() == path.knots.tolist()
    assert path.waypoint_s.tolist() == path.knots.tolist()
    assert [(p.kind, p.waypoint) for p in path.pieces] == [('line', 1), ('line', 2),
                                                           ('line', 3)]
    corner = path.knots[1]
    left, right = path.sample(corner, 'left'), path.sample(corner, 'right')
    assert left.position == pytest.approx(right.position, abs=1e-15)
    assert left.rotation == pytest.approx(right.rotation, abs=1e-15)
    assert left.velocity[0] == pytest.approx([0.3 / lengths[0], 0, 0], abs=1e-15)
    assert right.velocity[0] == pytest.approx([0, 0.4 / lengths[1], 0], abs=1e-15)
    assert left.angular[0] == pytest.approx([0, 0, 0.3 / lengths[0]], abs=1e-15)
    assert right.angular[0] == pytest.approx([0, 0, -0.3 / lengths[1]], abs=1e-15)
    # The ends: s outside [0, length] is clipped, 'left' at 0 and 'right' at the end are
    # the only pieces there.
    ends = path.sample([-1.0, 0.0, path.length, 99.0], 'left')
    assert ends.s.tolist() == [0.0, 0.0, path.length, path.length]
    assert path.sample(0.0, 'left').velocity == pytest.approx(left.velocity, abs=1e-15)
    assert path.fraction(path.knots[1]) == pytest.approx(lengths[0] / sum(lengths))
    assert_derivatives_match_differences(path, interior(path))


def test_repeated_pose_bad_rotation_and_bad_arguments_are_refused():
    start = pose([0, 0, 0])
    with pytest.raises(ValueError) as caught:
        straight_path(start, [pose([0.1, 0, 0]), pose([0.1, 0, 5e-7], [0, 0, 5e-7])])
    assert str(caught.value) == (
        'straight path: poses[1] repeats poses[0] (within 1e-06 m and 1e-06 rad), a segment '
        'of zero length; drop the repeated pose')
    with pytest.raises(ValueError, match=r'poses\[0\] repeats start '):
        straight_path(start, [start])
    # 1e-6 rad alone is a rotation in place, not a repeat.
    assert straight_path(start, [pose([0, 0, 0], [0, 0, 2e-6])]).length == pytest.approx(2e-6)
    sheared = pose([0.1, 0, 0])
    sheared[0, 1] = 1e-3
    with pytest.raises(ValueError, match=r'^straight path: poses\[0\]: the upper-left 3x3 '
                                         r'block is not a rotation'):
        straight_path(start, [sheared])
    with pytest.raises(ValueError, match='^straight path: start must be a 4x4'):
        straight_path(np.eye(3), [sheared])
    with pytest.raises(ValueError, match='at least one pose'):
        straight_path(start, [])
    for radius in (-0.01, math.nan, math.inf):
        with pytest.raises(ValueError, match='blend_radius must be a finite number'):
            straight_path(start, [pose([0.1, 0, 0])], radius)
    with pytest.raises(ValueError, match="side must be 'left' or 'right'"):
        straight_path(start, [pose([0.1, 0, 0])]).sample(0.0, 'middle')
