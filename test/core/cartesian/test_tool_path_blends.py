"""
Blended corners: the tangent arc's geometry, C¹ at the blend's ends, stops, degenerate corners.

Oracles: the tangent circle built here from the corner (centre on the bisector, radius
d / tan(β/2)), scipy's Slerp for the segments' orientations at the blend's ends, and
central differences of the path's own samples for every derivative.
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from tool_path_oracles import assert_derivatives_match_differences, interior, pose
from traj_gen_ros.core.cartesian.tool_path import straight_path


def corner_path(turn_degrees, radius, first=0.3, second=0.3, rotations=((0, 0, 0),) * 3):
    """Return a path along x, then turning by turn_degrees in the xy plane, and its corner."""
    turn = math.radians(turn_degrees)
    corner = np.array([first, 0.0, 0.0])
    end = corner + second * np.array([math.cos(turn), math.sin(turn), 0.0])
    poses = [pose([0, 0, 0], rotations[0]), pose(corner, rotations[1]), pose(end, rotations[2])]
    return straight_path(poses[0], poses[1:], radius), poses


def blend_ends(path):
    blend = next(piece for piece in path.pieces if piece.kind == 'blend')
    return blend.start, blend.end


@pytest.mark.parametrize('turn_degrees', [20.0, 90.0, 135.0, 160.0])
def test_blend_is_the_tangent_arc_within_the_radius_of_the_corner(turn_degrees):
    radius, turn = 0.05, math.radians(turn_degrees)
    path, poses = corner_path(turn_degrees, radius)
    corner = poses[1][:3, 3]
    u1, u2 = np.array([1.0, 0, 0]), np.array([math.cos(turn), math.sin(turn), 0.0])
    assert [p.kind for p in path.pieces] == ['line', 'blend', 'line']
    assert path.stops.tolist() == [0.0, path.length] and path.length == pytest.approx(0.6)
    start, end = blend_ends(path)
    # No rotation: s is metres on the lines, the blend keeps the 2r of the corner it cuts.
    assert (start, end) == pytest.approx((0.3 - radius, 0.3 + radius), abs=1e-15)
    ends = path.sample([start, end])
    assert ends.position == pytest.approx(np.array([corner - radius * u1,
                                                    corner + radius * u2]), abs=1e-15)
    assert ends.velocity == pytest.approx(np.array([u1, u2]), abs=1e-15)
    rho = radius / math.tan(turn / 2)
    centre = corner - radius * u1 + rho * np.array([0.0, 1.0, 0.0])
    s = np.linspace(start, end, 401)
    blend = path.sample(s, 'left')  # the blend's side at its end; its start is C¹ anyway
    offset = blend.position - centre
    assert np.abs(np.linalg.norm(offset, axis=1) - rho).max() < 1e-13
    assert np.abs(blend.position[:, 2]).max() == 0.0
    assert np.abs(np.sum(offset * blend.velocity, axis=1)).max() < 1e-14  # tangent
    distance = np.linalg.norm(blend.position - corner, axis=1)
    assert distance.max() <= radius + 1e-15
    assert distance.min() == pytest.approx(radius * math.tan(turn / 4), abs=1e-6)
    # Monotonic along the arc: the angle about the centre only grows, the speed stays > 0.
    angles = np.unwrap(np.arctan2(offset[:, 1], offset[:, 0]))
    assert np.all(np.diff(angles) > 0)
    speed = np.linalg.norm(blend.velocity, axis=1)
    assert speed.min() > 0
    # Centripetal: the acceleration towards the centre is |p'|² / ρ.
    inward = -offset / rho
    centripetal = np.sum(blend.acceleration * inward, axis=1)
    assert centripetal[1:] == pytest.approx(speed[1:] ** 2 / rho, rel=1e-12)
    assert_derivatives_match_differences(path, interior(path, margin=1e-3))


def test_blend_is_clipped_to_half_the_shorter_segment_and_may_eat_a_whole_segment():
    path, poses = corner_path(90.0, 0.5, first=0.3, second=0.1)
    start, end = blend_ends(path)
    assert (start, end) == pytest.approx((0.25, 0.35), abs=1e-15)
    assert path.sample(start).position[0] == pytest.approx([0.25, 0, 0], abs=1e-15)
    assert path.sample(end).position[0] == pytest.approx([0.3, 0.05, 0], abs=1e-15)
    # Three segments of 0.2 m, r = 0.1: the middle one is all blend, two blends meet.
    poses = [pose([0.2, 0, 0]), pose([0.2, 0.2, 0]), pose([0.4, 0.2, 0.0])]
    path = straight_path(pose([0, 0, 0]), poses, 0.1)
    assert [(p.kind, p.waypoint) for p in path.pieces] == [
        ('line', 1), ('blend', 1), ('blend', 2), ('line', 3)]
    assert path.knots == pytest.approx([0, 0.1, 0.3, 0.5, 0.6], abs=1e-15)
    assert path.stops.tolist() == [0.0, path.length]
    left, right = path.sample(0.3, 'left'), path.sample(0.3, 'right')
    assert left.position[0] == pytest.approx([0.2, 0.1, 0], abs=1e-15)
    assert right.position[0] == pytest.approx(left.position[0], abs=1e-15)
    assert right.velocity[0] == pytest.approx(left.velocity[0], abs=1e-15)
    assert right.velocity[0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)


def test_blend_with_rotation_is_c1_and_meets_each_segments_slerp():
    rotations = ((0.0, 0.0, 0.0), (0.0, 0.6, 0.3), (0.8, 0.2, -0.4))
    path, poses = corner_path(70.0, 0.08, first=0.4, second=0.25, rotations=rotations)
    lengths = np.diff(path.waypoint_s)
    start, end = blend_ends(path)
    segments = [Slerp([0, 1], Rotation.from_matrix([a[:3, :3], b[:3, :3]]))
                for a, b in zip(poses[:-1], poses[1:], strict=True)]
    # The blend leaves segment 1 at 0.08 m before the corner: s = s1 − 0.08 S1 / L1.
    assert start == pytest.approx(lengths[0] * (1 - 0.08 / 0.4), abs=1e-15)
    assert end == pytest.approx(lengths[0] + lengths[1] * 0.08 / 0.25, abs=1e-15)
    expected = [segments[0]([1 - 0.08 / 0.4]), segments[1]([0.08 / 0.25])]
    for s, rotation in zip((start, end), expected, strict=True):
        left, right = path.sample(s, 'left'), path.sample(s, 'right')
        assert right.rotation[0] == pytest.approx(rotation.as_matrix()[0], abs=1e-14)
        for name in ('position', 'rotation', 'velocity', 'angular', 'angular_acceleration'):
            assert getattr(left, name) == pytest.approx(getattr(right, name), abs=1e-13), name
        # The curvature steps there (line to arc): an acceleration step, allowed.
        assert np.abs(left.acceleration - right.acceleration).max() > 0.1
    # At the corner's s the blend turns through the corner's orientation.
    at_corner = path.sample(path.waypoint_s[1]).rotation[0]
    assert at_corner == pytest.approx(poses[1][:3, :3], abs=1e-15)
    # The blended rate mixes the two segments' rates: not parallel here.
    rates = path.sample([start, end]).angular
    assert np.linalg.norm(np.cross(*rates)) > 0.1
    assert_derivatives_match_differences(path, interior(path, count=11, margin=1e-3))


def test_straight_on_corner_blends_only_the_orientation():
    poses = [pose([0.2, 0, 0], [0, 0, 0.5]), pose([0.5, 0, 0], [0.4, 0, 0.5])]
    path = straight_path(pose([0, 0, 0]), poses, 0.05)
    assert [p.kind for p in path.pieces] == ['line', 'blend', 'line']
    s = np.linspace(0.0, path.length, 301)
    samples = path.sample(s)
    assert np.abs(samples.position[:, 1:]).max() == 0.0
    assert np.all(np.diff(samples.position[:, 0]) > 0)
    assert path.stops.tolist() == [0.0, path.length]
    assert_derivatives_match_differences(path, interior(path))


def test_reversals_rotations_in_place_and_too_sharp_corners_stop():
    poses = [pose([0.3, 0, 0]), pose([0.1, 0, 0]),                      # reversal at 0
             pose([0.1, 0, 0], [0, 0, 1]),                              # rotation in place
             pose([0.1, 0.2, 0], [0, 0, 1]),                            # after it
             pose([0.3, 0.2, 0], [0, 0, 1]),                            # a 90° corner
             pose([0.3 - 0.2 * math.cos(0.1), 0.2 + 0.2 * math.sin(0.1), 0], [0, 0, 1])]
    path = straight_path(pose([0, 0, 0]), poses, 0.05)
    knots = path.waypoint_s
    # Blended: the 90° corner (poses[3]) only; 174° (poses[4]) is too sharp for a blend.
    assert [(p.kind, p.waypoint) for p in path.pieces] == [
        ('line', 1), ('line', 2), ('line', 3), ('line', 4), ('blend', 4), ('line', 5),
        ('line', 6)]
    assert path.stops == pytest.approx([knots[0], knots[1], knots[2], knots[3], knots[5],
                                        knots[6]], abs=0)
    assert path.sample(knots[1]).position[0] == pytest.approx([0.3, 0, 0], abs=1e-15)
    unblended = straight_path(pose([0, 0, 0]), poses)
    assert unblended.stops.tolist() == unblended.knots.tolist() == knots.tolist()
