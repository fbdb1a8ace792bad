"""time_path_jerk_limited: the 1-D S-curve, every limit (jerk too) exactly, rests, s(t)."""

import math

import numpy as np
import pytest
from real_arms import arm_fixture, moved
from scipy.spatial.transform import Rotation
from synthetic_paths import arc, blended_corner, corner, line, linear_joint, seven_joints
from traj_gen_ros.core.cartesian import jerk_limited_timing
from traj_gen_ros.core.cartesian.bound_report import Bound
from traj_gen_ros.core.cartesian.jerk_bounds import piece_rows, scurve_duration
from traj_gen_ros.core.cartesian.jerk_limited_timing import time_path_jerk_limited
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path
from traj_gen_ros.core.kinematic_limits import limit_ratios, limit_violation
from traj_gen_ros.core.timing import min_time

NO_TOOL = ToolLimits()
TOOL = ToolLimits(0.25, 1.2, 1.5)
#: The node's defaults of the tool's limits.
TOOL_DEFAULTS = ToolLimits(0.25, 1.2, np.pi / 2)


def biagiotti_duration(length, v, a, j):
    """Rest-to-rest seven-phase S-curve time, Biagiotti & Melchiorri (3.30)-(3.31)."""
    if v * j >= a * a:
        accelerating = a / j + v / a
    else:
        accelerating = 2.0 * math.sqrt(v / j)
    if length >= v * accelerating:
        return length / v + accelerating
    if length >= 2.0 * a ** 3 / j ** 2:
        ramp = a / j
        return ramp + math.sqrt(ramp * ramp + 4.0 * length / a)
    return 4.0 * (length / (2.0 * j)) ** (1.0 / 3.0)


def accelerations_at_breakpoints(trajectory):
    """Each piece's acceleration at its end and the next one's at its start, (2, n, joints)."""
    lengths = np.diff(trajectory.breakpoints)[:-1, None]
    c = trajectory.coefficients
    powers = np.arange(2, c.shape[1])
    factors = powers * (powers - 1)
    ends = np.einsum('k,pkj,pk->pj', factors, c[:-1, 2:],
                     lengths ** (powers - 2)[None, :])
    return np.stack([ends, 2.0 * c[1:, 2]])


@pytest.mark.parametrize(('length', 'slope', 'v', 'a', 'j'), [
    (0.3, 1.0, 0.2, 1.0, 10.0),   # every phase: the cruise and the held accelerations
    (0.3, 2.0, 0.5, 3.0, 20.0),   # q = 2 s: the bounds of s are half the joint's
    (0.3, 1.0, 10.0, 2.0, 10.0),  # no cruise, the acceleration still reached
    (0.02, 1.0, 10.0, 2.0, 10.0),  # neither: four jerk phases
])
def test_one_linear_joint_is_the_time_optimal_s_curve(length, slope, v, a, j):
    """Q = slope · s: the bounds are exact, the motion is the joint's own 1-D S-curve."""
    path = line(length)
    timed = time_path_jerk_limited(path, linear_joint(slope).joint_path(path), v, a, j,
                                   NO_TOOL)
    closed = biagiotti_duration(slope * length, v, a, j)
    assert timed.duration == pytest.approx(closed, rel=1e-7)
    assert timed.duration == pytest.approx(
        min_time(0.0, slope * length, v, a, 'scurve', max_jerk=j).duration, rel=1e-7)
    piece = timed.pieces[0]
    assert piece.jerk == pytest.approx(j / slope, rel=1e-9)
    peaks = np.array(timed.trajectory.peaks_with_jerk())[:, 0]
    assert peaks[2] == pytest.approx(j, rel=1e-6)  # the jerk bound is touched
    assert np.all(peaks <= np.array([v, a, j]) * (1.0 + 1e-9))
    assert limit_violation(timed.trajectory, [v], [a], [j]) is None
    end = timed.trajectory.sample(timed.duration)
    assert end[0][0, 0] == pytest.approx(slope * length, abs=1e-12)
    assert abs(end[1][0, 0]) < 1e-12 and abs(end[2][0, 0]) < 1e-9


def test_the_closed_form_duration_is_the_core_s_curve():
    rng = np.random.default_rng(3)
    for _ in range(200):
        length, v, a, j = rng.uniform(0.01, 1.0), *rng.uniform(0.05, 3.0, 2), \
            rng.uniform(0.5, 50.0)
        ours = float(scurve_duration(length, np.array(v), np.array(a), np.array(j)))
        core = min_time(0.0, length, v, a, 'scurve', max_jerk=j).duration
        assert ours == pytest.approx(core, rel=1e-9)
        assert ours == pytest.approx(biagiotti_duration(length, v, a, j), rel=1e-12)


CASES = {
    'line': (line(0.3), None),
    'turning line': (line(0.35, direction=(1.0, 1.0, 0.0), turn=0.5), None),
    'arc': (arc(0.1, 2.0), None),
    'corner': (corner(0.2, 0.15, 1.0), 0.2),
    'blended corner': (blended_corner(0.15, 0.04, 1.2, 0.12), None),
}


@pytest.mark.parametrize('name', sorted(CASES))
def test_seven_joints_keep_every_limit_exactly_and_rest_at_every_knot(name):
    path, _ = CASES[name]
    joint_path = seven_joints().joint_path(path)
    v, a, j = np.full(7, 1.0), np.full(7, 3.0), np.full(7, 20.0)
    timed = time_path_jerk_limited(path, joint_path, v, a, j, TOOL)
    assert limit_violation(timed.trajectory, v, a, j) is None
    ratios = limit_ratios(timed.trajectory, v, a, j).max(axis=1)
    assert ratios[2] >= 0.9, ratios  # the jerk (or another limit) is close to tight
    steps = accelerations_at_breakpoints(timed.trajectory)
    assert np.abs(steps[0] - steps[1]).max() < 1e-7  # q̈ continuous: the jerk is bounded
    # Rests at every knot, blended or not (a blend's curvature steps at its ends).
    rests = timed.rest_times
    assert len(rests) == len(path.knots) and rests[0] == 0.0
    s, speed, accel = timed.path_state(rests)
    assert np.allclose(s, path.knots, atol=1e-12) and np.abs(speed).max() < 1e-12
    assert np.abs(accel).max() < 1e-9
    # The joints are q(s(t)) of the joint path; s(t) rises between the knots.
    times = np.linspace(0.0, timed.duration, 2001)
    s, speed = timed.path_parameter(times)
    assert np.all(np.diff(s) >= -1e-15) and np.all(speed >= -1e-12)
    q = timed.trajectory.sample(times)
    on_path = joint_path.joints.sample(s)
    assert np.abs(q[0] - on_path[0]).max() < 1e-9
    assert np.abs(q[1] - on_path[1] * speed[:, None]).max() < 1e-6  # rad/s
    # The tool's limits hold along the ideal path at s(t).
    tool = path.sample(s)
    accel = timed.path_state(times)[2]
    assert (np.linalg.norm(tool.velocity, axis=1) * speed).max() <= 0.25 * (1.0 + 1e-6)
    assert np.linalg.norm(tool.velocity * accel[:, None]
                          + tool.acceleration * speed[:, None] ** 2,
                          axis=1).max() <= 1.2 * (1.0 + 1e-6)


@pytest.mark.parametrize('name', sorted(CASES))
def test_never_faster_than_the_acceleration_limited_optimum(name):
    path, _ = CASES[name]
    joint_path = seven_joints().joint_path(path)
    jerk_limited = time_path_jerk_limited(path, joint_path, 1.0, 3.0, 20.0, TOOL)
    optimal = time_path(path, joint_path, 1.0, 3.0, TOOL)
    # time_path is within 1 % of the optimum, above it; a blend saves its stops there.
    assert jerk_limited.duration >= optimal.duration * 0.99
    assert jerk_limited.duration <= optimal.duration * 2.5


def test_the_conservative_bounds_alone_hold_every_limit_and_touch_one(monkeypatch):
    """Without refinement the chain-rule bound is never exceeded, and its row is tight."""
    monkeypatch.setattr(jerk_limited_timing, 'REFINEMENTS', 0)
    path = line(0.3)
    joint_path = seven_joints().joint_path(path)
    v, a, j = np.full(7, 1.0), np.full(7, 3.0), np.full(7, 20.0)
    timed = time_path_jerk_limited(path, joint_path, v, a, j, TOOL)
    assert timed.stretch == (1.0,)  # no joint above a limit: no slow-down
    bounds = timed.pieces[0]
    rows = piece_rows(path, joint_path, 0.0, 0.3, v, a, j, TOOL.as_array())
    values = rows.values(bounds)
    assert values[2].max() == pytest.approx(1.0, rel=1e-9)  # J is the jerk row's own
    assert all(value.max() <= 1.0 + 1e-9 for value in values)
    # The S-curve's jerk phase is at J: its cubic pieces' 6 c3.
    assert 6.0 * np.abs(timed.profile.coefficients[:, 3, 0]).max() == \
        pytest.approx(bounds.jerk, rel=1e-9)
    # The jerk's bound says which joint and where.
    assert bounds.jerk_bound == Bound('jerk', int(np.argmax(values[2])))
    assert 'jerk' in timed.describe()


def test_refuses_bad_limits_and_paths_that_disagree():
    path = line(0.3)
    joint_path = seven_joints().joint_path(path)
    with pytest.raises(ValueError, match="max_jerk must be .*joint 'j3' has -1"):
        time_path_jerk_limited(path, joint_path, 1.0, 3.0, [20.0] * 3 + [-1.0] + [20.0] * 3,
                               TOOL, joint_names=[f'j{k}' for k in range(7)])
    with pytest.raises(ValueError, match='joint_names has 2 names for 7 joints'):
        time_path_jerk_limited(path, joint_path, 1.0, 3.0, 20.0, TOOL, joint_names=['a', 'b'])
    with pytest.raises(ValueError, match='must be the same path'):
        time_path_jerk_limited(line(0.4), joint_path, 1.0, 3.0, 20.0, TOOL)
    with pytest.raises(ValueError, match='tool must be ToolLimits'):
        time_path_jerk_limited(path, joint_path, 1.0, 3.0, 20.0, (0.25, 1.2, 1.5))


arm = arm_fixture(['erd-panda', 'erd-ur10'])


@pytest.mark.parametrize('kind', ['line with a turn', 'two lines', 'arc'])
def test_real_arms_keep_the_tool_on_the_path_and_every_joint_within_its_jerk(arm, kind):
    chain, q0 = arm
    start = chain.forward(q0)
    if kind == 'arc':
        path = circular_path(start, moved(start, [0.06, 0.06, 0.0]),
                             moved(start, [0.12, 0.0, 0.0]))
    elif kind == 'two lines':
        path = straight_path(start, [moved(start, [0.1, 0.0, 0.0]),
                                     moved(start, [0.1, 0.1, 0.0])])
    else:
        path = straight_path(start, [moved(start, [0.08, 0.1, -0.06], [0.0, 0.0, 0.3])])
    joint_path = follow(chain, path, q0)
    v, a, j = 1.5, 3.0, 20.0
    timed = time_path_jerk_limited(path, joint_path, v, a, j, TOOL_DEFAULTS,
                                   joint_names=chain.joints)
    assert limit_violation(timed.trajectory, v, a, j) is None
    assert limit_ratios(timed.trajectory, v, a, j)[2].max() >= 0.95  # the jerk is touched
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
    optimal = time_path(path, joint_path, v, a, TOOL_DEFAULTS).duration
    # What the jerk bound costs (docs/node.md): 1.09-1.43 times the optimum here.
    assert optimal <= timed.duration <= 1.5 * optimal, (timed.duration, optimal)
