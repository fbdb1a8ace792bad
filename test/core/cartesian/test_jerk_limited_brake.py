"""brake_along_jerk_limited and rest_of_piece: to rest on the path, the jerk bounded."""

import numpy as np
import pytest
from synthetic_paths import corner, line, linear_joint, seven_joints
from traj_gen_ros.core.cartesian.jerk_limited_brake import (
    brake_along_jerk_limited,
    brake_from_timing,
    rest_of_piece,
)
from traj_gen_ros.core.cartesian.jerk_limited_timing import time_path_jerk_limited
from traj_gen_ros.core.cartesian.path_timing import ToolLimits
from traj_gen_ros.core.kinematic_limits import limit_violation

NO_TOOL = ToolLimits()
TOOL = ToolLimits(0.25, 1.2, 1.5)
LIMITS = (np.full(7, 1.0), np.full(7, 3.0), np.full(7, 20.0))


def test_one_linear_joint_stops_as_the_closed_form_s_curve_brake():
    """From cruise at v: A/J + v/A with the acceleration held (v J >= A²), v T / 2 long."""
    path = line(1.0)
    joint_path = linear_joint().joint_path(path)
    v, a, j = 0.8, 2.0, 10.0
    plan, end = brake_along_jerk_limited(path, joint_path, np.array([1.0]), np.array([a]),
                                         np.array([j]), NO_TOOL, 0.3, v)
    duration = a / j + v / a
    assert plan.duration == pytest.approx(duration, rel=1e-5)
    assert end == pytest.approx(0.3 + 0.5 * v * duration, rel=1e-5)
    assert limit_violation(plan, [1.0], [a], [j]) is None
    peaks = np.array(plan.peaks_with_jerk())[:, 0]
    assert peaks[2] == pytest.approx(j, rel=1e-5) and peaks[1] == pytest.approx(a, rel=1e-5)
    position, velocity, _ = plan.sample(np.array([0.0, plan.duration]))
    assert position[0, 0] == pytest.approx(0.3) and position[1, 0] == pytest.approx(end)
    assert velocity[0, 0] == pytest.approx(v) and abs(velocity[1, 0]) < 1e-9


def states(timed, fractions):
    """Return (time, s, ṡ, s̈) of the timing at each fraction of its duration."""
    for fraction in fractions:
        time = fraction * timed.duration
        yield (time, *(float(value) for value in timed.path_state(time)))


@pytest.mark.parametrize('path', [line(0.3), corner(0.2, 0.15, 1.0)], ids=['line', 'corner'])
def test_from_the_states_of_a_timing_the_brake_keeps_every_limit_and_the_path(path):
    joint_path = seven_joints().joint_path(path)
    timed = time_path_jerk_limited(path, joint_path, *LIMITS, TOOL)
    direct = 0
    for time, s0, speed, accel in states(timed, np.linspace(0.03, 0.97, 17)):
        next_rest = timed.rest_times[np.searchsorted(timed.rest_times, time)]
        try:
            brake_along_jerk_limited(path, joint_path, *LIMITS, TOOL, s0, speed, accel,
                                     timed=timed)
            direct += 1
        except ValueError:
            pass
        plan, end = brake_from_timing(timed, path, joint_path, LIMITS, TOOL, time, speed,
                                      accel)
        assert plan.duration <= next_rest - time + 1e-9  # never later than the plan
        assert limit_violation(plan, *LIMITS) is None
        # It starts at the plan's state: position, velocity and acceleration.
        start = plan.sample(0.0)
        planned = timed.trajectory.sample(time)
        for ours, theirs, tolerance in zip(start, planned, (1e-9, 1e-6, 1e-5), strict=True):
            assert np.abs(ours - theirs).max() < tolerance
        final = plan.sample(plan.duration)
        assert np.abs(final[1]).max() < 1e-9 and np.abs(final[2]).max() < 1e-7
        assert s0 <= end <= path.knots[np.searchsorted(path.knots, s0 + 1e-12)] + 1e-12
        # On the joint path: every sample of the plan is q(s) for an s in [s0, end].
        on_path = joint_path.joints.sample(np.linspace(s0, end, 4001))[0]
        samples = plan.sample(np.linspace(0.0, plan.duration, 50))[0]
        nearest = np.linalg.norm(samples[:, None] - on_path[None], axis=2).min(axis=1)
        assert nearest.max() < 3.0 * (end - s0) / 4000 + 1e-8  # the grid of s, |dq/ds| < 3
    assert direct >= 12  # most states brake at once


def test_the_rest_of_a_piece_slowed_by_the_override_is_the_same_motion_slower():
    path = line(0.3)
    joint_path = seven_joints().joint_path(path)
    timed = time_path_jerk_limited(path, joint_path, *LIMITS, TOOL)
    time = 0.9 * timed.duration
    plan, end = rest_of_piece(timed, time, 2.0)
    assert plan.duration == pytest.approx(2.0 * (timed.duration - time), rel=1e-12)
    assert end == pytest.approx(0.3, abs=1e-12)
    ours = plan.sample(np.array([0.0, 0.2, plan.duration]))
    theirs = timed.trajectory.sample(time + np.array([0.0, 0.2, plan.duration]) / 2.0)
    assert np.allclose(ours[0], theirs[0], atol=1e-12)
    assert np.allclose(ours[1], theirs[1] / 2.0, atol=1e-12)
    assert np.allclose(ours[2], theirs[2] / 4.0, atol=1e-10)
    with pytest.raises(ValueError, match='slower 0.5 >= 1'):
        rest_of_piece(timed, time, 0.5)


def test_refuses_at_rest_and_at_the_end():
    path = line(0.3)
    joint_path = linear_joint().joint_path(path)
    with pytest.raises(ValueError, match='nothing to brake'):
        brake_along_jerk_limited(path, joint_path, [1.0], [1.0], [10.0], NO_TOOL, 0.1, 0.0)
    with pytest.raises(ValueError, match='nothing to brake'):
        brake_along_jerk_limited(path, joint_path, [1.0], [1.0], [10.0], NO_TOOL, 0.3, 0.2)
    with pytest.raises(ValueError, match='must be >= 0'):
        brake_along_jerk_limited(path, joint_path, [1.0], [1.0], [10.0], NO_TOOL, 0.1, -0.2)
