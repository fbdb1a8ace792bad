"""Jerk-limited braking (scurve_brake): Ruckig's velocity interface is the oracle."""

import core_helpers as helpers
from hypothesis import given, settings
import hypothesis.strategies as st
import numpy as np
import pytest
import ruckig
from traj_gen_ros import JerkLimitedTrajectory, scurve_brake

TOL = 1e-9


def ruckig_stop_time(v0, a0, max_acceleration, max_jerk):
    """One joint's time-optimal stop (velocity 0, acceleration 0) by Ruckig."""
    parameters = ruckig.InputParameter(1)
    parameters.control_interface = ruckig.ControlInterface.Velocity
    parameters.current_position = [0.0]
    parameters.current_velocity = [v0]
    parameters.current_acceleration = [a0]
    parameters.target_velocity = [0.0]
    parameters.target_acceleration = [0.0]
    parameters.max_velocity = [1e9]
    parameters.max_acceleration = [max_acceleration]
    parameters.max_jerk = [max_jerk]
    trajectory = ruckig.Trajectory(1)
    result = ruckig.Ruckig(1).calculate(parameters, trajectory)
    assert result == ruckig.Result.Working
    return trajectory.duration


@st.composite
def moving_states(draw):
    joints = draw(st.integers(1, 5))

    def row(strategy):
        return np.array(draw(st.lists(strategy, min_size=joints, max_size=joints)))

    max_acceleration = row(st.floats(-1.0, 1.0).map(lambda e: 10.0**e))
    max_jerk = row(st.floats(-1.0, 2.0).map(lambda e: 10.0**e))
    fraction = st.one_of(st.just(0.0), st.floats(1e-6, 1.0), st.floats(-1.0, -1e-6))
    v0 = 2.0 * row(fraction)
    a0 = row(fraction) * max_acceleration
    return row(st.floats(-3.0, 3.0)), v0, a0, max_acceleration, max_jerk


@settings(max_examples=150, deadline=None)
@given(moving_states())
def test_each_joint_stops_as_fast_as_ruckig_with_bounded_jerk(state):
    q0, v0, a0, max_acceleration, max_jerk = state
    plan = scurve_brake(q0, v0, a0, max_acceleration, max_jerk)
    assert isinstance(plan, JerkLimitedTrajectory)
    stop_times = plan.breakpoints[3]
    for joint in range(q0.size):
        expected = ruckig_stop_time(v0[joint], a0[joint], max_acceleration[joint],
                                    max_jerk[joint])
        assert stop_times[joint] == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert plan.duration == pytest.approx(stop_times.max())
    position, velocity, acceleration = plan.sample([0.0])
    np.testing.assert_array_equal(position[0], q0)
    np.testing.assert_array_equal(velocity[0], v0)
    np.testing.assert_array_equal(acceleration[0], a0)
    _, velocity_end, acceleration_end = plan.sample([plan.duration])
    scale = np.abs(v0) + np.abs(a0) + 1.0
    assert np.all(np.abs(velocity_end[0]) <= 1e-9 * scale)
    assert np.all(np.abs(acceleration_end[0]) <= 1e-9 * scale)
    _, peak_acceleration, peak_jerk = plan.peaks()
    assert np.all(peak_acceleration <= max_acceleration * (1 + TOL))
    assert np.all(peak_jerk <= max_jerk * (1 + TOL))
    helpers.assert_continuous(plan, orders=3, tolerance=1e-9)


def test_stop_example_with_a_hold_at_the_acceleration_limit():
    # v0 = 2, a0 = 0, a_max = 1, j_max = 2: ramp 0.5 s to -1, hold, ramp 0.5 s back.
    # The ramps change the velocity by -0.5 in all, so the hold lasts 1.5 s: 2.5 s in all.
    plan = scurve_brake(0.0, 2.0, 0.0, 1.0, 2.0)
    np.testing.assert_allclose(plan.breakpoints[:4, 0], [0.0, 0.5, 2.0, 2.5])
    position, velocity, _ = plan.sample([2.5])
    assert velocity[0, 0] == pytest.approx(0.0, abs=1e-12)
    assert position[0, 0] == pytest.approx(2.5, rel=1e-12)  # the mean velocity is 1 rad/s


def test_a_still_joint_holds():
    plan = scurve_brake([1.0, 2.0], [0.0, 0.0], [0.0, 0.0], 1.0, 1.0)
    assert plan.duration == 0.0
    np.testing.assert_array_equal(plan.sample([0.0, 1.0])[0], [[1.0, 2.0], [1.0, 2.0]])
