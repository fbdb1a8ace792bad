"""
Blended corners: the tangent arc's geometry and knots, C¹ at the blend's ends, stops.

Oracles: the tangent circle built here from the corner (centre on the bisector, radius
d / tan(β/2)) and its points by arc length, scipy's Slerp for the segments' orientations
at the blend's ends, and central differences of the path's own samples for every
derivative.
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp
from tool_path_oracles import assert_derivatives_match_differences, interior, pose
from traj_gen_ros.core.cartesian.tool_path import straight_path


def corner_path(turn_degrees, radius, first=0.3, second=0.3, rotations=((0, 0, 0),) * 3):
    """Return a path along x, then turning by turn_degrees in the xy plane, and its poses."""
    turn = math.radians(turn_degrees)
    corner = np.array([first, 0.0, 0.0])
    end = corner + second * np.array([math.cos(turn), math.sin(turn), 0.0])
    poses = [pose([0, 0, 0], rotations[0]), pose(corner, rotations[1]), pose(end, rotations[2])]
    return straight_path(poses[0], poses[1:], radius), poses


def blend_ends(path):
    blend = next(piece for piece in path.pieces if piece.kind == 'blend')
    return blend.start, blend.end


def arc_length(turn, distance):
    """Return Λ = β ρ of the tangent arc, ρ = d / tan(β/2) (2d on a straight corner)."""
    return 2.0 * distance if turn == 0.0 else turn * distance / math.tan(turn / 2.0)


@pytest.mark.parametrize('turn_degrees', [20.0, 90.0, 135.0, 160.0, 175.0])
def test_blend_is_the_tangent_arc_by_its_arc_length(turn_degrees):
    radius, turn = 0.05, math.radians(turn_degrees)
    path, poses = corner_path(turn_degrees, radius)
    corner = poses[1][:3, 3]
    u1, u2 = np.array([1.0, 0, 0]), np.array([math.cos(turn), math.sin(turn), 0.0])
    inward = np.array([0.0, 1.0, 0.0])
    rho = radius / math.tan(turn / 2)
    arc = turn * rho
    assert [p.kind for p in path.pieces] == ['line', 'blend', 'line']
    # No rotation: s is metres everywhere; the blend takes the arc's length, not the 2r
    # of the legs it cuts, and the line after it moves up by the difference.
    assert path.length == pytest.approx(0.6 - 2 * radius + arc, abs=1e-15)
    assert path.knots == pytest.approx([0.0, 0.3 - radius, 0.3 - radius + arc, path.length],
                                       abs=1e-15)
    assert path.stops.tolist() == [0.0, path.length]
    assert path.waypoint_s == pytest.approx([0.0, 0.3 - radius + arc / 2, path.length],
                                            abs=1e-15)
    start, end = blend_ends(path)
    ends = path.sample([start, end])
    assert ends.position == pytest.approx(np.array([corner - radius * u1,
                                                    corner + radius * u2]), abs=1e-15)
    assert ends.velocity == pytest.approx(np.array([u1, u2]), abs=1e-15)
    assert path.sample(path.length).position[0] == pytest.approx(poses[2][:3, 3], abs=1e-15)
    # By arc length x from the blend's start: the point ρ from the centre at angle x/ρ.
    centre = corner - radius * u1 + rho * inward
    x = np.linspace(0.0, arc, 401)
    phi = (x / rho)[:, None]
    blend = path.sample(start + x, 'left')  # the blend's side at its end (a line's at x = 0)
    assert np.abs(blend.position - (centre + rho * (np.sin(phi) * u1 - np.cos(phi) * inward))
                  ).max() < 1e-14
    assert np.abs(blend.velocity - (np.cos(phi) * u1 + np.sin(phi) * inward)).max() < 1e-12
    centripetal = (np.cos(phi) * inward - np.sin(phi) * u1) / rho
    assert np.abs(blend.acceleration - centripetal)[1:].max() < 1e-11 / rho
    assert np.abs(np.linalg.norm(blend.velocity, axis=1) - 1.0).max() < 1e-12
    distance = np.linalg.norm(blend.position - corner, axis=1)
    assert distance.max() <= radius + 1e-15
    assert distance.min() == pytest.approx(radius * math.tan(turn / 4), abs=1e-15)
    steps = (1e-6, 5e-5) if turn_degrees > 160.0 else (1e-5, 2e-4)  # a 2 mm circle at 175°
    assert_derivatives_match_differences(path, interior(path, margin=1e-3), 1e-6, steps)


def test_blend_is_clipped_to_half_the_shorter_segment_and_may_eat_a_whole_segment():
    path, poses = corner_path(90.0, 0.5, first=0.3, second=0.1)
    start, end = blend_ends(path)
    quarter = math.pi / 2 * 0.05  # ρ = d = 0.05 m at 90°
    assert (start, end) == pytest.approx((0.25, 0.25 + quarter), abs=1e-15)
    assert path.sample(start).position[0] == pytest.approx([0.25, 0, 0], abs=1e-15)
    assert path.sample(end).position[0] == pytest.approx([0.3, 0.05, 0], abs=1e-15)
    assert path.length == pytest.approx(0.25 + quarter + 0.05, abs=1e-15)
    # Three segments of 0.2 m, r = 0.1: the middle one is all blend, two blends meet.
    poses = [pose([0.2, 0, 0]), pose([0.2, 0.2, 0]), pose([0.4, 0.2, 0.0])]
    path = straight_path(pose([0, 0, 0]), poses, 0.1)
    quarter = math.pi / 2 * 0.1
    assert [(p.kind, p.waypoint) for p in path.pieces] == [
        ('line', 1), ('blend', 1), ('blend', 2), ('line', 3)]
    assert path.knots == pytest.approx([0, 0.1, 0.1 + quarter, 0.1 + 2 * quarter,
                                        0.2 + 2 * quarter], abs=1e-15)
    assert path.stops.tolist() == [0.0, path.length]
    meet = 0.1 + quarter
    left, right = path.sample(meet, 'left'), path.sample(meet, 'right')
    assert left.position[0] == pytest.approx([0.2, 0.1, 0], abs=1e-15)
    assert right.position[0] == pytest.approx(left.position[0], abs=1e-15)
    assert right.velocity[0] == pytest.approx(left.velocity[0], abs=1e-15)
    assert right.velocity[0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)
    assert path.sample(path.length).position[0] == pytest.approx([0.4, 0.2, 0], abs=1e-15)


def test_blend_with_rotation_is_c1_meets_each_segments_slerp_and_shifts_the_next_line():
    rotations = ((0.0, 0.0, 0.0), (0.0, 0.6, 0.3), (0.8, 0.2, -0.4))
    path, poses = corner_path(70.0, 0.08, first=0.4, second=0.25, rotations=rotations)
    turns = [Rotation.from_matrix(b[:3, :3] @ a[:3, :3].T).magnitude()
             for a, b in zip(poses[:-1], poses[1:], strict=True)]
    lengths = [math.hypot(0.4, turns[0]), math.hypot(0.25, turns[1])]  # S1, S2
    fractions = (0.08 / 0.4, 0.08 / 0.25)  # of each segment the blend cuts
    start, end = blend_ends(path)
    segments = [Slerp([0, 1], Rotation.from_matrix([a[:3, :3], b[:3, :3]]))
                for a, b in zip(poses[:-1], poses[1:], strict=True)]
    # The blend leaves segment 1 at 0.08 m before the corner: s = S1 (1 − 0.08 / L1). Its
    # span: the arc's length and the rotation of the two legs it cuts, combined.
    assert start == pytest.approx(lengths[0] * (1 - fractions[0]), abs=1e-15)
    span = math.hypot(arc_length(math.radians(70.0), 0.08),
                      fractions[0] * turns[0] + fractions[1] * turns[1])
    assert end - start == pytest.approx(span, abs=1e-15)
    cut = fractions[0] * lengths[0] + fractions[1] * lengths[1]
    assert path.length == pytest.approx(sum(lengths) - cut + span, abs=1e-15)
    assert path.waypoint_s[1] == pytest.approx(start + span / 2, abs=1e-15)
    expected = [segments[0]([1 - fractions[0]]), segments[1]([fractions[1]])]
    for s, rotation in zip((start, end), expected, strict=True):
        left, right = path.sample(s, 'left'), path.sample(s, 'right')
        assert right.rotation[0] == pytest.approx(rotation.as_matrix()[0], abs=1e-14)
        for name in ('position', 'rotation', 'velocity', 'angular', 'angular_acceleration'):
            assert getattr(left, name) == pytest.approx(getattr(right, name), abs=1e-13), name
        # The curvature steps there (line to arc): an acceleration step, allowed.
        assert np.abs(left.acceleration - right.acceleration).max() > 0.1
    # After the blend, segment 2's slerp and line resume where the blend leaves them.
    f = np.linspace(fractions[1], 1.0, 7)
    after = path.sample(end + (f - fractions[1]) * lengths[1])
    assert np.abs(after.rotation - segments[1](f).as_matrix()).max() < 1e-14
    assert np.abs(after.position - (poses[1][:3, 3] + np.outer(f, poses[2][:3, 3]
                                                               - poses[1][:3, 3]))).max() < 1e-15
    # The blended rate mixes the two segments' rates: not parallel here.
    rates = path.sample([start, end]).angular
    assert np.linalg.norm(np.cross(*rates)) > 0.1
    assert_derivatives_match_differences(path, interior(path, count=11, margin=1e-3))


def test_a_symmetric_corner_turns_through_its_orientation_in_the_middle_of_the_blend():
    rotations = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.4), (0.0, 0.0, 0.8))
    path, poses = corner_path(120.0, 0.05, rotations=rotations)
    middle = path.sample(path.waypoint_s[1])
    assert middle.rotation[0] == pytest.approx(poses[1][:3, :3], abs=1e-15)
    # There the tool is at the arc's midpoint, r tan(β/4) from the corner.
    distance = np.linalg.norm(middle.position[0] - poses[1][:3, 3])
    assert distance == pytest.approx(0.05 * math.tan(math.radians(30.0)), abs=1e-15)


def test_straight_on_corner_blends_only_the_orientation():
    poses = [pose([0.2, 0, 0], [0, 0, 0.5]), pose([0.5, 0, 0], [0.4, 0, 0.5])]
    path = straight_path(pose([0, 0, 0]), poses, 0.05)
    assert [p.kind for p in path.pieces] == ['line', 'blend', 'line']
    s = np.linspace(0.0, path.length, 301)
    samples = path.sample(s)
    assert np.abs(samples.position[:, 1:]).max() == 0.0
    assert np.all(np.diff(samples.position[:, 0]) > 0)
    assert path.stops.tolist() == [0.0, path.length]
    start, end = blend_ends(path)
    assert path.sample([start, end]).position[:, 0] == pytest.approx([0.15, 0.25], abs=1e-15)
    assert_derivatives_match_differences(path, interior(path))


def test_reversals_rotations_in_place_and_too_sharp_corners_stop():
    bent = math.radians(6.0)  # 174° corners
    poses = [pose([0.3, 0, 0]), pose([0.1, 0, 0]),                      # reversal at 0
             pose([0.1, 0, 0], [0, 0, 1]),                              # rotation in place
             pose([0.1, 0.2, 0], [0, 0, 1]),                            # after it
             pose([0.3, 0.2, 0], [0, 0, 1]),                            # a 90° corner
             pose([0.3 - 0.2 * math.cos(bent), 0.2 + 0.2 * math.sin(bent), 0], [0, 0, 1]),
             pose([0.3, 0.2 + 0.4 * math.sin(bent), 0], [0, 0, 1.3])]
    path = straight_path(pose([0, 0, 0]), poses, 0.05)
    # Blended: the 90° corner (poses[3]) and the 174° one without rotation (poses[4]);
    # the 174° corner into a segment turning 0.3 rad (poses[5]) is too sharp for a blend
    # (its arc is 8 mm, the rotation of its legs 75 mm of path).
    assert [(p.kind, p.waypoint) for p in path.pieces] == [
        ('line', 1), ('line', 2), ('line', 3), ('line', 4), ('blend', 4), ('line', 5),
        ('blend', 5), ('line', 6), ('line', 7)]
    knots = path.waypoint_s
    assert path.stops == pytest.approx([knots[0], knots[1], knots[2], knots[3], knots[6],
                                        knots[7]], abs=0)
    assert path.sample(knots[1]).position[0] == pytest.approx([0.3, 0, 0], abs=1e-15)
    assert path.sample(knots[6]).position[0] == pytest.approx(poses[5][:3, 3], abs=1e-15)
    unblended = straight_path(pose([0, 0, 0]), poses)
    assert unblended.stops.tolist() == unblended.knots.tolist() == unblended.waypoint_s.tolist()
