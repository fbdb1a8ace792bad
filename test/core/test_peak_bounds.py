"""The Bernstein bounds of a plan's peaks: never below the exact peaks, and close to them."""

from hypothesis import example, given, settings
from hypothesis import strategies as st
import numpy as np
from traj_gen_ros import cubic, limit_violation, quintic_via
from traj_gen_ros.core.exact.piece_extrema import peak_abs, peak_bounds, peaks_above
from traj_gen_ros.core.trajectory import Trajectory

coefficient = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.lists(coefficient, min_size=5, max_size=5), min_size=1, max_size=6),
       st.lists(st.floats(1e-3, 10.0), min_size=6, max_size=6), st.integers(1, 5))
def test_a_bound_is_never_below_the_exact_peak(rows, lengths, size):
    """Pieces of every degree up to 4, of any length: bound >= peak (to rounding)."""
    series = np.array(rows)[:, :size, None]  # (pieces, size, one joint)
    durations = np.array(lengths[:len(rows)])[:, None]
    (peak,), (bound,) = peak_abs(durations, series), peak_bounds(durations, series)
    assert bound >= peak * (1.0 - 1e-12) - 1e-12


SUBNORMAL_PR = [[0.0] * 5] * 6 + [[0.0, 0.0, 0.0, 0.0, 1.0],
                                  [0.0, 1.0, -3.86332644153686e-209, 0.0, 0.0]]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.lists(coefficient, min_size=5, max_size=5), min_size=2, max_size=12),
       st.lists(st.floats(1e-3, 10.0), min_size=12, max_size=12), st.integers(1, 5),
       st.floats(0.0, 1.5))
@example(rows=SUBNORMAL_PR, lengths=[1.0] * 12, size=5, share=0.0)  # a subnormal p·r
def test_peaks_above_a_limit_are_the_exact_peaks_and_within_it_bound_them(
        rows, lengths, size, share):
    """Roots only where a bound exceeds: above the limit exact, within it never below."""
    rows = rows[:len(rows) // 2 * 2]
    series = np.array(rows)[:, :size].reshape(-1, 2, size).transpose(0, 2, 1)  # two joints
    durations = np.array(lengths[:len(series)])[:, None].repeat(2, axis=1)
    (peak,) = peak_abs(durations, series)
    limit = share * peak.max() + np.array([0.0, 1e-3])
    (result,) = peaks_above(durations, [limit], series)
    for joint in range(2):
        if peak[joint] > limit[joint]:
            assert result[joint] == peak[joint]  # the same roots of the same pieces
        else:
            assert peak[joint] * (1 - 1e-12) - 1e-12 <= result[joint] <= limit[joint]


def test_craigs_cubic_velocity_bound_is_within_one_percent_of_its_peak():
    """Craig ex. 7.1: 15° to 75° in 3 s peaks at 30°/s (1.5 s) and 40°/s² (the ends)."""
    plan = cubic(np.radians([15.0]), np.radians([75.0]), 3.0)
    velocity, acceleration = plan.peak_bounds()
    assert np.radians(30.0) <= velocity[0] <= np.radians(30.0) * 1.01
    assert abs(acceleration[0] - np.radians(40.0)) <= 1e-15  # a line: its ends are the bound


def test_limit_violation_is_exact_near_the_limit_whichever_way_it_is_decided():
    """Within the bounds: no peaks asked; just over: the exact peak names the excess."""
    points = np.array([[0.0], [0.4], [1.0]])
    plan = quintic_via(points, np.array([1.0, 1.0]))
    velocity, acceleration = plan.peaks()
    bound_v, bound_a = plan.peak_bounds()
    assert bound_v[0] >= velocity[0] and bound_a[0] >= acceleration[0]
    assert limit_violation(plan, bound_v, bound_a) is None  # decided by the bounds
    assert limit_violation(plan, velocity, acceleration) is None  # by the exact peaks
    over = limit_violation(plan, velocity * (1.0 - 1e-6), acceleration * 2.0)
    assert (over.quantity, over.peak) == ('velocity', velocity[0])


def test_a_constant_plan_is_bounded_by_zero():
    plan = Trajectory(np.array([0.0, 1.0]), np.array([[[2.0]], [[0.0]]]))
    assert [b.tolist() for b in plan.peak_bounds(3)] == [[0.0], [0.0], [0.0]]
