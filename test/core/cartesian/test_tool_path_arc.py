"""
The circle through three points and the circular tool path along it.

Oracles: circles built here from a known centre, radius and plane (the points placed on
it at known angles), scipy's Slerp for the orientation, central differences of the
path's own samples for every derivative.
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from tool_path_oracles import assert_derivatives_match_differences, interior, pose
from traj_gen_ros.core.cartesian.circle import circle_through
from traj_gen_ros.core.cartesian.tool_path import circular_path

CENTRE = np.array([0.4, -0.1, 0.5])
RADIUS = 0.15
# A tilted plane: e1, e2 orthonormal, the normal e1 × e2.
TILT = Rotation.from_rotvec([0.4, -0.7, 0.2]).as_matrix()
E1, E2 = TILT[:, 0], TILT[:, 1]


def on_circle(angle):
    return CENTRE + RADIUS * (math.cos(angle) * E1 + math.sin(angle) * E2)


@pytest.mark.parametrize('interim_angle, goal_angle', [(0.5, 1.2), (2.5, 4.0), (0.1, 6.2)])
def test_circle_through_three_points_recovers_centre_radius_plane_and_angles(
        interim_angle, goal_angle):
    circle = circle_through(on_circle(0.0), on_circle(interim_angle), on_circle(goal_angle))
    assert circle.centre == pytest.approx(CENTRE, abs=1e-13)
    assert circle.radius == pytest.approx(RADIUS, abs=1e-13)
    assert circle.normal == pytest.approx(TILT[:, 2], abs=1e-13)
    assert circle.angle == pytest.approx(goal_angle, abs=1e-12)
    assert circle.interim_angle == pytest.approx(interim_angle, abs=1e-12)
    assert circle.length == pytest.approx(RADIUS * goal_angle, abs=1e-12)
    # Going the other way round (goal before interim on the way) flips the normal.
    back = circle_through(on_circle(goal_angle), on_circle(interim_angle), on_circle(0.0))
    assert back.normal == pytest.approx(-TILT[:, 2], abs=1e-13)
    assert back.angle == pytest.approx(goal_angle, abs=1e-12)


def test_circular_path_follows_the_circle_through_the_interim_with_slerp():
    start = pose(on_circle(0.0), [0.1, 0.2, 0.3])
    goal = pose(on_circle(2.0), [-0.4, 0.5, 0.9])
    interim = pose(on_circle(1.3), [3.0, 0.0, 0.0])  # its orientation is ignored
    path = circular_path(start, interim, goal)
    turn = Rotation.from_matrix(goal[:3, :3]) * Rotation.from_matrix(start[:3, :3]).inv()
    length = math.hypot(RADIUS * 2.0, turn.magnitude())
    assert path.length == pytest.approx(length, abs=1e-14)
    assert [(p.kind, p.start, p.waypoint) for p in path.pieces] == [('arc', 0.0, 2)]
    assert path.stops.tolist() == path.knots.tolist() == [0.0, path.length]
    assert path.waypoint_s == pytest.approx([0.0, length * 1.3 / 2.0, length], abs=1e-13)
    assert path.sample(path.waypoint_s[1]).position[0] == pytest.approx(on_circle(1.3),
                                                                        abs=1e-14)
    s = np.linspace(0.0, path.length, 201)
    samples = path.sample(s)
    fraction = s / path.length
    expected = np.array([on_circle(2.0 * f) for f in fraction])
    assert np.abs(samples.position - expected).max() < 1e-14
    offset = samples.position - CENTRE
    assert np.abs(np.linalg.norm(offset, axis=1) - RADIUS).max() < 1e-15
    assert np.abs(offset @ TILT[:, 2]).max() < 1e-15
    assert np.abs(np.sum(offset * samples.velocity, axis=1)).max() < 1e-15
    speed = np.linalg.norm(samples.velocity, axis=1)
    assert speed == pytest.approx(RADIUS * 2.0 / length, rel=1e-14)
    assert np.linalg.norm(samples.acceleration, axis=1) == pytest.approx(speed ** 2 / RADIUS,
                                                                         rel=1e-13)
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix([start[:3, :3], goal[:3, :3]]))
    assert np.abs(samples.rotation - slerp(fraction).as_matrix()).max() < 1e-14
    assert samples.angular == pytest.approx(np.tile(turn.as_rotvec() / length, (201, 1)),
                                            abs=1e-15)
    assert path.poses(path.length)[0] == pytest.approx(goal, abs=1e-14)
    assert_derivatives_match_differences(path, interior(path, count=21))
    # The interim as a bare position is the same path.
    same = circular_path(start, on_circle(1.3), goal).sample(s)
    assert np.abs(same.position - samples.position).max() == 0.0


def test_arc_past_half_a_turn_without_rotation_is_its_length_long():
    path = circular_path(pose(on_circle(0.0)), pose(on_circle(2.0)), pose(on_circle(5.0)))
    assert path.length == pytest.approx(RADIUS * 5.0, abs=1e-13)
    middle = path.sample(path.length * 0.7)
    assert middle.position[0] == pytest.approx(on_circle(3.5), abs=1e-14)
    assert not middle.angular.any()


def test_coincident_or_collinear_points_are_refused():
    a, b, c = np.zeros(3), np.array([0.1, 0.0, 0.0]), np.array([0.2, 0.03, 0.0])
    for points, names, gap in (((a, a + [0, 9e-4, 0], c), ('start', 'interim'), 0.9),
                               ((a, b, b + [0, 0, 5e-4]), ('interim', 'goal'), 0.5),
                               ((a, b, a + [2e-4, 0, 0]), ('start', 'goal'), 0.2)):
        with pytest.raises(ValueError) as caught:
            circular_path(*(pose(point) for point in points))
        assert str(caught.value) == (
            f'circular path: the {names[0]} and {names[1]} positions are {gap:.3g} mm apart; '
            f'a circle needs its three points at least 1 mm apart')
    # 0.05 mm off the line through the other two: collinear; 0.2 mm: a (large) circle.
    for offset, refused in ((5e-5, True), (2e-4, False)):
        points = [a, np.array([0.1, offset, 0.0]), np.array([0.2, 0.0, 0.0])]
        if refused:
            with pytest.raises(ValueError) as caught:
                circular_path(*(pose(point) for point in points))
            assert str(caught.value) == (
                'circular path: the start, interim and goal positions lie on one line within '
                '0.05 mm; a circle needs them at least 0.1 mm off a line')
        else:
            circle = circle_through(*points)
            assert circle.radius == pytest.approx((0.1 ** 2 + offset ** 2) / (2 * offset))
    with pytest.raises(ValueError, match='^circular path: goal: the upper-left'):
        circular_path(pose(a), pose(b), np.diag([1.0, 1.0, -1.0, 1.0]))
