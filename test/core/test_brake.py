"""``brake``: every joint to rest at its own acceleration limit, then hold."""

import numpy as np
import pytest
from traj_gen_ros import brake


def test_each_joint_stops_where_and_when_its_limit_says():
    q0, v0, limit = np.array([1.0, -2.0, 0.5]), np.array([2.0, -1.0, 0.0]), np.array([4, 1, 3.0])
    trajectory = brake(q0, v0, limit)
    assert trajectory.duration == pytest.approx(1.0)  # joint 1: |-1| / 1
    stop_times = np.abs(v0) / limit
    positions, velocities, accelerations = trajectory.sample(stop_times)
    expected_stop = q0 + v0 * np.abs(v0) / (2 * limit)   # 1.5, -2.5, 0.5
    np.testing.assert_allclose(np.diag(positions), expected_stop, atol=1e-15)
    np.testing.assert_allclose(np.diag(velocities), 0.0, atol=1e-15)
    end = trajectory.sample([trajectory.duration, 5.0])
    np.testing.assert_allclose(end[0], [expected_stop] * 2, atol=1e-15)
    np.testing.assert_array_equal(end[1], 0.0)


def test_braking_stays_within_the_limit_and_is_continuous():
    trajectory = brake([0.0, 0.0], [3.0, -0.5], [2.0, 1.0])
    times = np.linspace(0.0, trajectory.duration, 20001)
    positions, velocities, accelerations = trajectory.sample(times)
    assert np.all(np.abs(accelerations) <= [2.0, 1.0])
    np.testing.assert_allclose(trajectory.peaks()[1], [2.0, 1.0])
    np.testing.assert_allclose(velocities[0], [3.0, -0.5])
    assert np.all(np.diff(np.abs(velocities), axis=0) <= 1e-15)  # never speeds up
    step = times[1]
    assert np.abs(np.diff(positions, axis=0)).max() <= 3.0 * step * (1 + 1e-9)


def test_a_joint_at_rest_holds_and_a_still_arm_gives_zero_duration():
    assert brake([1.0, 2.0], [0.0, 0.0], 1.0).duration == 0.0
    positions, velocities, _ = brake([1.0, 2.0], [0.0, 0.0], 1.0).sample([0.0, 1.0])
    np.testing.assert_array_equal(positions, [[1.0, 2.0]] * 2)
    np.testing.assert_array_equal(velocities, 0.0)
