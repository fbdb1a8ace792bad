"""The S-curve's closed-form peaks (JerkLimitedTrajectory.peaks_with_jerk) vs the general ones."""

from hypothesis import given, settings
import hypothesis.strategies as st
import numpy as np
from traj_gen_ros import JerkLimitedTrajectory, min_time, plan_path
from traj_gen_ros.core.trajectory import Trajectory

LIMITS = (np.array([1.0, 2.0, 0.5]), np.array([2.0, 5.0, 1.0]), np.array([10.0, 40.0, 3.0]))
unit = st.floats(-1.0, 1.0)
joints3 = st.lists(unit, min_size=3, max_size=3).map(np.array)


def test_an_interior_velocity_peak_where_the_acceleration_crosses_zero():
    # v = 0.5 - 2t + t²/2 on [0, 3]: v(0) = 0.5, v(3) = -1, and a = t - 2 = 0 at t = 2,
    # where v = -1.5: the peak |v| is inside the piece. |a| peaks at t = 0 (2), jerk is 1.
    plan = JerkLimitedTrajectory(np.array([0.0, 3.0]),
                                 np.array([[[0.0], [0.5], [-1.0], [1.0 / 6.0]]]))
    velocity, acceleration, jerk = plan.peaks_with_jerk()
    np.testing.assert_allclose([velocity[0], acceleration[0], jerk[0]], [1.5, 2.0, 1.0],
                               rtol=1e-15)


@settings(max_examples=150, deadline=None)
@given(start=joints3, goal=joints3, velocity=joints3, acceleration=joints3)
def test_closed_form_peaks_equal_the_general_exact_peaks(start, goal, velocity, acceleration):
    max_velocity, max_acceleration, max_jerk = LIMITS
    plan = min_time(start, goal, max_velocity, max_acceleration, 'scurve',
                    v0=1.2 * velocity * max_velocity, a0=1.2 * acceleration * max_acceleration,
                    max_jerk=max_jerk)
    closed_form = plan.peaks_with_jerk()
    general = Trajectory.peaks_with_jerk(plan)
    for ours, oracle in zip(closed_form, general, strict=True):
        np.testing.assert_allclose(ours, oracle, rtol=1e-12, atol=1e-15)
    # And no sample exceeds them (the peaks are maxima, not estimates from below).
    sampled = plan.sample(np.linspace(0.0, plan.duration, 2001))
    for ours, samples in zip(closed_form, sampled[1:], strict=False):
        assert np.all(np.abs(samples).max(axis=0) <= ours * (1 + 1e-12) + 1e-15)


def test_via_point_scurve_peaks_equal_the_general_exact_peaks():
    points = np.array([[0.0, 0.0, 0.0], [0.5, -1.0, 0.2], [1.0, 0.5, -0.3], [0.2, 0.0, 0.0]])
    plan = plan_path(points, None, 'scurve', max_velocity=LIMITS[0],
                     max_acceleration=LIMITS[1], max_jerk=LIMITS[2])
    assert isinstance(plan, JerkLimitedTrajectory) and plan.degree == 3
    for ours, oracle in zip(plan.peaks_with_jerk(), Trajectory.peaks_with_jerk(plan),
                            strict=True):
        np.testing.assert_allclose(ours, oracle, rtol=1e-12, atol=1e-15)
