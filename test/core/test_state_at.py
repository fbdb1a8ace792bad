"""trajectory.state_at (one time: the stream's setpoint) against Trajectory.sample."""

from hypothesis import given, settings
import hypothesis.strategies as st
import numpy as np
from traj_gen_ros import cubic_via, lspb_via, min_time, quintic
from traj_gen_ros.core.trajectory import state_at

LIMITS = (np.array([1.0, 2.0, 0.5]), np.array([2.0, 5.0, 1.0]), np.array([10.0, 40.0, 3.0]))
row = st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).map(np.array)


def test_textbook_quintic_midpoint_and_ends():
    # Craig's quintic rest to rest, 0 → 1 rad in 2 s: at t = 1 s the position is 0.5,
    # the velocity 15 D / (8 T) = 0.9375 rad/s and the acceleration 0.
    plan = quintic(np.zeros(1), np.ones(1), 2.0)
    position, velocity, acceleration = state_at(plan, 1.0)
    np.testing.assert_allclose([position[0], velocity[0], acceleration[0]], [0.5, 0.9375, 0.0],
                               atol=1e-15)
    assert state_at(plan, -1.0)[0][0] == 0.0 and state_at(plan, 5.0)[0][0] == 1.0


def _agrees(plan, times):
    for time in times:
        expected = plan.sample(time)
        for ours, theirs in zip(state_at(plan, time), expected, strict=True):
            np.testing.assert_allclose(ours, theirs[0], rtol=1e-12, atol=1e-13)


FRACTIONS = st.lists(st.floats(-0.1, 1.1), min_size=5, max_size=5)


@settings(max_examples=60, deadline=None)
@given(start=row, goal=row, velocity=row, fractions=FRACTIONS)
def test_state_at_equals_sample_for_every_profile(start, goal, velocity, fractions):
    max_velocity, max_acceleration, max_jerk = LIMITS
    towards = 0.3 * np.sign(goal - start) * np.abs(velocity) * max_velocity
    for profile in ('cubic', 'quintic', 'lspb', 'scurve'):
        plan = min_time(start, goal, max_velocity, max_acceleration, profile, v0=towards,
                        max_jerk=max_jerk)
        # Random times (some outside the plan), and every breakpoint: the piece starting
        # there is the one used, as in sample().
        _agrees(plan, [f * plan.duration for f in fractions] + list(plan.breakpoints.flat))


def test_state_at_equals_sample_through_via_points():
    rng = np.random.default_rng(4)
    points = np.cumsum(rng.normal(size=(6, 3)), axis=0)
    for plan in (cubic_via(points, rng.uniform(0.5, 1.5, 5), 'continuous'),
                 lspb_via(points, rng.uniform(2.0, 3.0, 5), 20.0)):
        _agrees(plan, list(rng.uniform(0.0, plan.duration, 50)) + list(plan.breakpoints.flat))
