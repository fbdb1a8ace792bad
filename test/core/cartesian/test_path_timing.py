"""time_path: closed forms, the limits held exactly and touched, stops, s(t), refusals."""

import math
import re

import numpy as np
import pytest
from synthetic_paths import (
    AnalyticJoints,
    blended_corner,
    corner,
    line,
    linear_joint,
    seven_joints,
)
from traj_gen_ros.core.cartesian import path_timing
from traj_gen_ros.core.cartesian.path_timing import Bound, time_path, ToolLimits
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.timing import min_time

NO_TOOL = ToolLimits()


@pytest.mark.parametrize(('length', 'slope', 'vmax', 'amax'), [
    (0.3, 1.0, 0.2, 1.0),   # trapezoid: D/v + v/a
    (0.3, 2.0, 0.5, 3.0),   # q = 2 s: the joint moves 0.6 rad
    (0.3, 1.0, 10.0, 1.0),  # triangle: 2 sqrt(D/a)
])
def test_one_linear_joint_gives_the_time_optimal_lspb(length, slope, vmax, amax):
    path = line(length)
    timed = time_path(path, linear_joint(slope).joint_path(path), vmax, amax, NO_TOOL)
    optimum = min_time(0.0, slope * length, vmax, amax).duration
    # The grid point nearest the switch costs O(Δ²); never faster than the optimum.
    assert optimum * (1.0 - 1e-12) <= timed.duration <= optimum * (1.0 + 2e-4)
    distance = slope * length
    closed = distance / vmax + vmax / amax if distance >= vmax ** 2 / amax \
        else 2.0 * math.sqrt(distance / amax)
    assert timed.duration == pytest.approx(closed, rel=2e-4)


def test_the_tool_speed_alone_gives_l_over_v_plus_v_over_a():
    path = line(0.3, direction=(1.0, 2.0, -2.0))
    joints = seven_joints(4)
    timed = time_path(path, joints.joint_path(path), 1e3, 1e4, ToolLimits(0.5, 2.0))
    assert timed.duration == pytest.approx(0.3 / 0.5 + 0.5 / 2.0, rel=1e-4)
    assert timed.duration >= 0.85 * (1.0 - 1e-12)
    assert timed.describe() == ('max_linear_acceleration from 0 % to 21 % and from 79 % to '
                                '100 % of the path; max_linear_velocity elsewhere')


def test_the_angular_speed_bounds_a_line_that_turns():
    # |p'| = 0.8 m and |ω_s| = 0.6 rad per unit of path: ṡ <= 0.3 / 0.6, s̈ <= 4 / 0.8.
    path = line(0.4, turn=0.6)
    timed = time_path(path, seven_joints(2).joint_path(path), 1e3, 1e4,
                      ToolLimits(max_linear_acceleration=4.0, max_angular_velocity=0.3))
    speed, accel = 0.3 / 0.6, 4.0 / 0.8
    assert timed.duration == pytest.approx(0.4 / speed + speed / accel, rel=1e-4)
    assert timed.speed.max() == pytest.approx(speed, rel=1e-12)


@pytest.fixture(scope='module')
def timings():
    """Time a few paths; keep the analytic joints they follow."""
    cases = {
        'joints bind': (line(0.3), seven_joints(7), 1.0, 4.0, NO_TOOL),
        'tool binds': (line(0.3), seven_joints(3), 2.0, 8.0, ToolLimits(0.5, 2.0, 1.0)),
        'blend': (blended_corner(0.15, 0.02, 1.2, 0.15), seven_joints(5), 2.0, 10.0,
                  ToolLimits(0.5, 3.0)),
        'corner stop': (corner(0.15, 0.1, 1.0), seven_joints(2), 1.5, 6.0,
                        ToolLimits(0.4, 3.0)),
    }
    return {name: (path, joints, vmax, amax, tool,
                   time_path(path, joints.joint_path(path), vmax, amax, tool))
            for name, (path, joints, vmax, amax, tool) in cases.items()}


CASE_NAMES = ['joints bind', 'tool binds', 'blend', 'corner stop']


@pytest.mark.parametrize('name', CASE_NAMES)
def test_the_trajectory_is_within_the_joint_limits_exactly(timings, name):
    _, _, vmax, amax, _, timed = timings[name]
    assert timed.trajectory.degree <= 5
    assert limit_violation(timed.trajectory, np.full(7, vmax), np.full(7, amax)) is None
    assert timed.duration == timed.trajectory.duration == timed.times[-1]


@pytest.mark.parametrize('name', CASE_NAMES)
def test_the_tool_limits_hold_along_s_of_t(timings, name):
    path, _, _, _, tool, timed = timings[name]
    t = np.linspace(0.0, timed.duration, 20_001)
    s, speed = timed.path_parameter(t)
    piece = np.clip(np.searchsorted(timed.times, t, side='right') - 1, 0, len(timed.s) - 2)
    u = timed.path_acceleration[piece]
    sample = path.sample(s)
    linear = np.linalg.norm(sample.velocity, axis=1) * speed
    acceleration = np.linalg.norm(sample.velocity * u[:, None]
                                  + sample.acceleration * speed[:, None] ** 2, axis=1)
    angular = np.linalg.norm(sample.angular, axis=1) * speed
    # A sampled check, as time_path's own (3 points per interval, exact at the grid).
    assert linear.max() <= tool.max_linear_velocity * (1.0 + 1e-6)
    assert acceleration.max() <= tool.max_linear_acceleration * (1.0 + 1e-6)
    assert angular.max() <= tool.max_angular_velocity * (1.0 + 1e-6)


def _grid_ratios(path, joints, vmax, amax, tool, timed):
    """At every grid point, the largest rate / limit over joints and tool, both sides."""
    _, dq, ddq = joints.states(timed.s)
    x = timed.speed ** 2
    u = timed.path_acceleration
    ratios = [np.abs(dq).max(axis=1) * timed.speed / vmax]
    for side, accel in (('right', np.append(u, u[-1])), ('left', np.insert(u, 0, u[0]))):
        sample = path.sample(timed.s, side)
        ratios.append(np.abs(dq * accel[:, None] + ddq * x[:, None]).max(axis=1) / amax)
        ratios.append(np.linalg.norm(sample.velocity * accel[:, None] + sample.acceleration
                                     * x[:, None], axis=1) / tool.max_linear_acceleration)
        ratios.append(np.linalg.norm(sample.velocity, axis=1) * timed.speed
                      / tool.max_linear_velocity)
        ratios.append(np.linalg.norm(sample.angular, axis=1) * timed.speed
                      / tool.max_angular_velocity)
    return np.max(ratios, axis=0)


@pytest.mark.parametrize('name', CASE_NAMES)
def test_every_grid_point_touches_a_limit(timings, name):
    ratios = _grid_ratios(*timings[name])
    assert ratios.max() <= 1.0 + 1e-6  # the joint path is q(s) to ~1e-8: not exactly it
    # Time-optimality's fingerprint: a limit within ~1 % of tight everywhere (the interval
    # ending at a stop is held at one end, the other differs by its q' change: 1.2 %).
    assert ratios.min() >= 0.985


@pytest.mark.parametrize('name', CASE_NAMES)
def test_the_tool_rests_at_the_stops_only_and_passes_the_grid_on_the_joint_path(
        timings, name):
    path, joints, _, _, _, timed = timings[name]
    at_stop = np.isin(timed.s, path.stops)
    assert np.array_equal(timed.s[at_stop], path.stops)
    assert np.all(timed.speed[at_stop] == 0.0)
    assert np.all(timed.speed[~at_stop] > 0.0)
    assert np.all(np.isin(path.knots, timed.s))
    q, velocity, _ = timed.trajectory.sample(timed.times)
    np.testing.assert_allclose(q, joints.states(timed.s)[0], atol=1e-9)
    np.testing.assert_allclose(velocity[at_stop], 0.0, atol=1e-12)


def test_the_path_parameter_follows_the_grid(timings):
    *_, timed = timings['blend']
    s, speed = timed.path_parameter(timed.times)
    np.testing.assert_allclose(s, timed.s, atol=1e-12)
    np.testing.assert_allclose(speed, timed.speed, atol=1e-9)
    mid = 0.5 * (timed.times[:-1] + timed.times[1:])
    s_mid, speed_mid = timed.path_parameter(mid)
    dt = mid - timed.times[:-1]
    expected = timed.s[:-1] + timed.speed[:-1] * dt + 0.5 * timed.path_acceleration * dt ** 2
    np.testing.assert_allclose(s_mid, expected, atol=1e-12)
    assert np.all(np.diff(s_mid) > 0.0) and np.all(speed_mid > 0.0)
    assert timed.path_parameter(-1.0)[0] == 0.0
    assert timed.path_parameter(timed.duration + 1.0)[0] == pytest.approx(timed.s[-1])


def test_a_joint_velocity_that_binds_in_the_middle_is_described():
    # q1' = 2 (1 - cos 2πs/L) peaks mid-path; at 0.5 m/s the joint reaches 1.5 rad/s
    # where 1 - cos > 1.5: from L/3 to 2L/3.
    length = 0.3
    frequency = 2 * np.pi / length
    joints = AnalyticJoints(offset=np.zeros(2), slope=np.array([1.0, 2.0]),
                            amplitude=np.array([[0.0], [-2.0 / frequency]]),
                            frequency=np.array([[0.0], [frequency]]),
                            phase=np.array([[0.0], [0.0]]))
    path = line(length)
    timed = time_path(path, joints.joint_path(path), [10.0, 1.5], 100.0,
                      ToolLimits(0.5, 10.0), joint_names=['j0', 'j1'])
    # 1/3 and 2/3 fall inside grid intervals: the run starts and ends within one of them.
    text = ('max_linear_acceleration from 0 % to 4 % and from 96 % to 100 % of the path; '
            "joint 'j1' velocity from 3[34] % to 6[67] % of the path; max_linear_velocity "
            'elsewhere')
    assert re.fullmatch(text, timed.describe())
    assert timed.describe(['a', 'b']).count("joint 'b' velocity") == 1
    middle = timed.bounds[len(timed.bounds) // 2]
    assert middle == Bound('velocity', 1) and middle.name() == 'joint 1 velocity'


def test_when_tightening_runs_out_the_whole_plan_is_slowed_within_the_limits(monkeypatch):
    path = line(0.3)
    joints = seven_joints(7).joint_path(path)
    optimal = time_path(path, joints, 1.0, 4.0, NO_TOOL)
    monkeypatch.setattr(path_timing, 'TIGHTENING_ROUNDS', 1)
    slowed = time_path(path, joints, 1.0, 4.0, NO_TOOL)
    assert limit_violation(slowed.trajectory, np.ones(7), np.full(7, 4.0)) is None
    assert optimal.duration < slowed.duration < optimal.duration * (1.0 + 1e-3)


@pytest.mark.parametrize(('limit', 'bad', 'message'), [
    ('max_velocity', [1.0, 0.0], "max_velocity must be finite and > 0; joint 'b' has 0.0"),
    ('max_velocity', [1.0, -2.0], "max_velocity must be finite and > 0; joint 'b' has -2.0"),
    ('max_acceleration', [np.nan, 1.0],
     "max_acceleration must be finite and > 0; joint 'a' has nan"),
    ('max_acceleration', [1.0, np.inf],
     "max_acceleration must be finite and > 0; joint 'b' has inf"),
])
def test_bad_joint_limits_are_refused_naming_the_joint(limit, bad, message):
    path = line(0.3)
    joints = AnalyticJoints(np.zeros(2), np.ones(2)).joint_path(path)
    limits = {'max_velocity': 1.0, 'max_acceleration': 1.0, limit: bad}
    with pytest.raises(ValueError) as error:
        time_path(path, joints, tool=NO_TOOL, joint_names=['a', 'b'], **limits)
    assert str(error.value) == message


@pytest.mark.parametrize('field', ['max_linear_velocity', 'max_linear_acceleration',
                                   'max_angular_velocity'])
@pytest.mark.parametrize('bad', [0.0, -1.0, float('nan'), '1'])
def test_bad_tool_limits_are_refused_naming_the_limit(field, bad):
    with pytest.raises(ValueError, match=f'ToolLimits.{field} must be a number > 0'):
        ToolLimits(**{field: bad})
    assert getattr(ToolLimits(**{field: math.inf}), field) == math.inf


def test_paths_that_disagree_are_refused():
    path = line(0.3)
    with pytest.raises(ValueError, match='joint path is 0.2 long but the tool path 0.3'):
        time_path(path, linear_joint().joint_path(line(0.2)), 1.0, 1.0, NO_TOOL)
    with pytest.raises(ValueError, match='joint_names has 2 names for 1 joints'):
        time_path(path, linear_joint().joint_path(path), 1.0, 1.0, NO_TOOL,
                  joint_names=['a', 'b'])
    with pytest.raises(ValueError, match='tool must be ToolLimits'):
        time_path(path, linear_joint().joint_path(path), 1.0, 1.0, (1.0, 1.0, 1.0))
