import re

import core_helpers as helpers
from hypothesis import example, given, settings
import hypothesis.strategies as st
import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from traj_gen_ros import (
    cubic,
    cubic_via,
    heuristic_velocities,
    lspb,
    lspb_via,
    quintic,
    quintic_via,
)

FAST = settings(max_examples=60, deadline=None)


def per_joint(strategy, joints):
    return st.lists(strategy, min_size=joints, max_size=joints).map(np.array)


@st.composite
def moves(draw, moving=True):
    """Draw ``(q0, qf, duration, v0, vf)`` for 1-4 joints; velocities zero unless moving."""
    joints = draw(helpers.joint_counts)
    q0 = draw(per_joint(helpers.positions, joints))
    qf = draw(per_joint(helpers.positions, joints))
    v0 = draw(per_joint(helpers.velocities, joints)) if moving else np.zeros(joints)
    vf = draw(per_joint(helpers.velocities, joints)) if moving else np.zeros(joints)
    return q0, qf, draw(helpers.durations), v0, vf


def fitting_lspb_via(points, durations, acceleration, v0=0.0):
    """
    Plan ``lspb_via``; when refused, check the message and plan with its minimum.

    A refusal must name a point and the smallest acceleration that fits, and that
    acceleration must then fit.
    """
    acceleration = np.broadcast_to(acceleration, (np.shape(points)[1],)).astype(float)
    try:
        return lspb_via(points, durations, acceleration, v0=v0), acceleration
    except ValueError as error:
        message = str(error)
    assert re.search(r'\bpoints? \d', message), message
    found = re.search(r'smallest acceleration that fits is ([0-9.]+(?:e[-+]?\d+)?)', message)
    assert found, message
    acceleration = np.maximum(acceleration, float(found[1]))
    try:
        return lspb_via(points, durations, acceleration, v0=v0), acceleration
    except ValueError as error:  # another joint may need more still
        found = re.search(r'smallest acceleration that fits is ([0-9.]+(?:e[-+]?\d+)?)',
                          str(error))
        assert found, str(error)
        joint = int(re.search(r'joint (\d+)', str(error))[1])
        assert acceleration[joint] < float(found[1]), 'the reported minimum did not fit'
        acceleration = np.maximum(acceleration, float(found[1]))
        return fitting_lspb_via(points, durations, acceleration, v0=v0)


# --- Single segments: boundary conditions and sampling ------------------------------


@FAST
@given(moves())
def test_cubic_meets_its_boundary_conditions(move):
    q0, qf, duration, v0, vf = move
    trajectory = cubic(q0, qf, duration, v0=v0, vf=vf)
    position, velocity, _ = trajectory.sample([0.0, duration])
    helpers.assert_state(position, [q0, qf])
    helpers.assert_state(velocity, [v0, vf])
    assert trajectory.duration == duration


@FAST
@given(moves(), per_joint(helpers.velocities, 4), per_joint(helpers.velocities, 4))
def test_quintic_meets_its_boundary_conditions(move, acc0, accf):
    q0, qf, duration, v0, vf = move
    acc0, accf = acc0[:q0.size], accf[:q0.size]
    trajectory = quintic(q0, qf, duration, v0=v0, vf=vf, a0=acc0, af=accf)
    position, velocity, acceleration = trajectory.sample([0.0, duration])
    helpers.assert_state(position, [q0, qf])
    helpers.assert_state(velocity, [v0, vf])
    helpers.assert_state(acceleration, [acc0, accf])


@FAST
@given(moves(moving=False), st.floats(1.0, 10.0))
def test_lspb_meets_its_boundary_conditions(move, factor):
    q0, qf, duration, _, _ = move
    minimum = 4.0 * np.abs(qf - q0) / duration**2  # eq. (6)
    acceleration = np.maximum(minimum * factor, 0.1)
    trajectory = lspb(q0, qf, duration, acceleration)
    position, velocity, _ = trajectory.sample([0.0, duration])
    helpers.assert_state(position, [q0, qf])
    helpers.assert_state(velocity, [0.0 * q0, 0.0 * q0])
    helpers.assert_continuous(trajectory)
    # Every blend accelerates at ±acceleration (or not at all, for a still joint; eq. (5)
    # cannot resolve a blend for a move below ~1e-16 of θ̈t², which moves nowhere).
    blends = 2.0 * trajectory.coefficients[0::2, 2]
    moving = np.abs(qf - q0) > 1e-9
    np.testing.assert_allclose(np.abs(blends[:, moving]),
                               np.broadcast_to(acceleration[moving], blends[:, moving].shape),
                               rtol=1e-12)
    cruise_limit = acceleration * duration / 2 * (1 + 1e-9)  # a blend lasts at most t/2
    assert np.all(np.abs(trajectory.linear_velocities) <= cruise_limit)


@FAST
@given(moves(), st.floats(1.0, 10.0))
def test_lspb_from_a_moving_start(move, factor):
    q0, qf, duration, v0, _ = move
    # Enough acceleration for any move of this size from v0 within the duration.
    acceleration = factor * (4.0 * np.abs(qf - q0) / duration**2
                             + 4.0 * np.abs(v0) / duration + 0.1)
    trajectory = lspb(q0, qf, duration, acceleration, v0=v0)
    position, velocity, acceleration_sampled = trajectory.sample([0.0, duration])
    helpers.assert_state(position, [q0, qf])
    helpers.assert_state(velocity, [v0, 0.0 * v0])
    helpers.assert_continuous(trajectory)
    _, peak_acceleration = helpers.reference_peaks(trajectory)
    assert np.all(peak_acceleration <= acceleration * (1 + 1e-9))


def test_short_quintic_of_a_still_joint_away_from_zero_stays_still():
    # Joint 1 holds at 3 for 1 ms: every coefficient but a0 should be 0 (Δ = 0).
    trajectory = quintic([0.0, 3.0], [0.0, 3.0], 1e-3)
    _, velocity, acceleration = trajectory.sample(1e-3)
    np.testing.assert_allclose(velocity, 0.0, atol=1e-9)
    np.testing.assert_allclose(acceleration, 0.0, atol=1e-9)  # got 8.0e-9
    np.testing.assert_allclose(trajectory.coefficients[0, 1:, 1], 0.0, atol=1e-6)


# --- Via points ------------------------------------------------------------------------

VELOCITY_RULES = ['heuristic', 'continuous']


@FAST
@pytest.mark.parametrize('rule', VELOCITY_RULES)
@given(path=helpers.via_paths(), v0=helpers.velocities)
def test_cubic_via_passes_every_point_continuously(rule, path, v0):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    trajectory = cubic_via(points, durations, velocities=rule, v0=v0)
    times = np.concatenate(([0.0], np.cumsum(durations)))
    np.testing.assert_allclose(trajectory.breakpoints, times, rtol=1e-15, atol=0)
    position, velocity, _ = trajectory.sample(times)
    helpers.assert_state(position, points)
    helpers.assert_state(velocity[0], np.full(points.shape[1], v0), scale=scales[1])
    helpers.assert_state(velocity[-1], np.zeros(points.shape[1]), scale=scales[1])
    helpers.assert_continuous(trajectory, orders=3 if rule == 'continuous' else 2)


@FAST
@given(path=helpers.via_paths(), v0=helpers.velocities)
def test_continuous_spline_equals_scipy_clamped_spline(path, v0):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    trajectory = cubic_via(points, durations, velocities='continuous', v0=v0)
    times = np.concatenate(([0.0], np.cumsum(durations)))
    reference = CubicSpline(times, points, bc_type=((1, np.full(points.shape[1], v0)),
                                                    (1, np.zeros(points.shape[1]))))
    samples = np.linspace(0.0, times[-1], 301)
    position, velocity, acceleration = trajectory.sample(samples)
    helpers.assert_state(position, reference(samples))
    helpers.assert_state(velocity, reference(samples, 1), scale=scales[1])
    helpers.assert_state(acceleration, reference(samples, 2), scale=scales[2])


@FAST
@pytest.mark.parametrize('rule', VELOCITY_RULES)
@given(path=helpers.via_paths(), v0=helpers.velocities, acc0=helpers.velocities)
def test_quintic_via_passes_every_point_with_continuous_acceleration(rule, path, v0, acc0):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    trajectory = quintic_via(points, durations, velocities=rule, v0=v0, a0=acc0)
    times = np.concatenate(([0.0], np.cumsum(durations)))
    position, velocity, acceleration = trajectory.sample(times)
    helpers.assert_state(position, points)
    helpers.assert_state(velocity[0], np.full(points.shape[1], v0), scale=scales[1])
    helpers.assert_state(acceleration[0], np.full(points.shape[1], acc0), scale=scales[2])
    helpers.assert_state(velocity[-1], np.zeros(points.shape[1]), scale=scales[1])
    helpers.assert_state(acceleration[-1], np.zeros(points.shape[1]), scale=scales[2])
    helpers.assert_continuous(trajectory, orders=3)


@FAST
@given(path=helpers.via_paths(), data=st.data())
def test_via_splines_with_given_velocities_and_accelerations(path, data):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    point_velocities = data.draw(per_joint(helpers.velocities, points.size)).reshape(
        points.shape)
    point_accelerations = data.draw(per_joint(helpers.velocities, points.size)).reshape(
        points.shape)
    times = np.concatenate(([0.0], np.cumsum(durations)))
    for trajectory, orders in (
        (cubic_via(points, durations, velocities=point_velocities), 2),
        (quintic_via(points, durations, velocities=point_velocities,
                     accelerations=point_accelerations), 3),
    ):
        position, velocity, acceleration = trajectory.sample(times)
        helpers.assert_state(position, points)
        helpers.assert_state(velocity, point_velocities, scale=scales[1])
        if orders == 3:
            helpers.assert_state(acceleration, point_accelerations, scale=scales[2])
        helpers.assert_continuous(trajectory, orders=orders)


@FAST
@given(path=helpers.via_paths())
def test_heuristic_via_velocity_is_zero_where_the_slope_changes_sign(path):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    trajectory = cubic_via(points, durations, velocities='heuristic')
    _, velocity, _ = trajectory.sample(np.concatenate(([0.0], np.cumsum(durations))))
    slopes = np.diff(points, axis=0) / durations[:, None]
    left, right = slopes[:-1], slopes[1:]
    turning = left * right <= 0.0
    assert np.all(velocity[1:-1][turning] == 0.0)
    # Elsewhere Craig's rule: the mean of the two slopes.
    helpers.assert_state(velocity[1:-1][~turning], ((left + right) / 2)[~turning],
                         scale=scales[1])
    np.testing.assert_array_equal(heuristic_velocities(points, durations)[1:-1][turning], 0.0)


def test_heuristic_via_velocity_concrete_example():
    # Slopes 10, -10, -5, 5: a peak, a monotone stretch, a valley.
    trajectory = cubic_via([0.0, 10.0, 0.0, -5.0, 0.0], [1.0, 1.0, 1.0, 1.0])
    _, velocity, _ = trajectory.sample([0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(velocity[:, 0], [0.0, 0.0, -7.5, 0.0, 0.0], atol=1e-12)


def test_heuristic_step_within_the_resolution_counts_as_none():
    # Slopes 1e-9, 1, 1: the mean 0.5 at point 1 (same sign), unless a step of 1e-9 is
    # no motion (resolution 1e-8, Ruckig's precision, as scurve_via uses it): a stop.
    points, durations = np.array([[0.0], [1e-9], [1.0 + 1e-9], [2.0 + 1e-9]]), np.ones(3)
    np.testing.assert_allclose(heuristic_velocities(points, durations)[:, 0],
                               [0.0, 0.5 * (1e-9 + 1.0), 1.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(heuristic_velocities(points, durations, resolution=1e-8)[:, 0],
                               [0.0, 0.0, 1.0, 0.0], rtol=1e-15)


# --- LSPB through via points ---------------------------------------------------------


@settings(max_examples=80, deadline=None)
@given(path=helpers.via_paths(), acceleration=st.floats(1.0, 200.0),
       v0=st.one_of(st.just(0.0), helpers.velocities))
def test_lspb_via_properties(path, acceleration, v0):
    points, durations = path
    scales = helpers.natural_scales(points, durations)
    joints = points.shape[1]
    trajectory, used = fitting_lspb_via(points, durations, acceleration, v0=v0)
    used = np.broadcast_to(used, (joints,))
    times = np.concatenate(([0.0], np.cumsum(durations)))
    # Total duration kept exactly, start at v0 at the first point, end at rest at the goal.
    assert trajectory.duration == pytest.approx(times[-1], rel=1e-15, abs=0)
    np.testing.assert_allclose(trajectory.breakpoints[-1], times[-1], rtol=1e-15)
    position, velocity, _ = trajectory.sample([0.0, times[-1]])
    helpers.assert_state(position, [points[0], points[-1]])
    helpers.assert_state(velocity, [np.full(joints, v0), np.zeros(joints)], scale=scales[1])
    helpers.assert_continuous(trajectory)
    starts, lengths = helpers.piece_spans(trajectory)
    assert np.all(lengths >= -1e-9)
    # Blend accelerations have magnitude |θ̈| (or zero where no velocity changes).
    blends = np.abs(2.0 * trajectory.coefficients[0::2, 2])
    changes = np.abs(np.diff(np.concatenate(
        [np.full((1, joints), v0), trajectory.linear_velocities, np.zeros((1, joints))]),
        axis=0))
    expected = np.where(changes > 0.0, used, 0.0)
    np.testing.assert_allclose(blends, expected, rtol=1e-12, atol=0)
    # Lines are linear, and each passes through its interior via points at their times.
    np.testing.assert_array_equal(trajectory.coefficients[1::2, 2], 0.0)
    segment_count = len(durations)
    for segment in range(segment_count):
        line = trajectory.coefficients[2 * segment + 1]
        start = starts[2 * segment + 1]
        for point in (segment, segment + 1):
            if 0 < point < segment_count:
                on_line = line[0] + line[1] * (times[point] - start)
                helpers.assert_state(on_line, points[point])


def test_lspb_via_two_points_is_single_segment_lspb():
    via = lspb_via([1.0, 4.0], [2.0], 5.0)
    single = lspb(1.0, 4.0, 2.0, 5.0)
    samples = np.linspace(0.0, 2.0, 41)
    for ours, theirs in zip(via.sample(samples), single.sample(samples), strict=True):
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


# --- Multi-joint calls equal single-joint calls joint by joint -----------------------


def assert_same_per_joint(together, alone, samples, time_scale):
    """
    Assert joint ``j`` of ``together`` samples as ``alone[j]`` does, to rounding.

    Matrix products may sum in another order (or fuse a multiply-add), so derivative
    ``k`` may differ by 1e-12 of the quantity's scale ``max|position| / time_scale**k``.
    """
    combined = together.sample(samples)
    for joint, single in enumerate(alone):
        state = single.sample(samples)
        reach = max(1.0, np.max(np.abs(state[0])))
        for order, (ours, theirs) in enumerate(zip(combined, state, strict=True)):
            scale = max(np.max(np.abs(theirs)), reach / time_scale**order)
            np.testing.assert_allclose(ours[:, joint], theirs[:, 0], rtol=0,
                                       atol=1e-12 * scale)


@FAST
@given(moves())
def test_multi_joint_single_segments_equal_single_joint_results(move):
    q0, qf, duration, v0, vf = move
    samples = np.linspace(-0.5, duration + 0.5, 53)
    joints = range(q0.size)
    assert_same_per_joint(cubic(q0, qf, duration, v0=v0, vf=vf),
                          [cubic(q0[j], qf[j], duration, v0=v0[j], vf=vf[j]) for j in joints],
                          samples, duration)
    assert_same_per_joint(quintic(q0, qf, duration, v0=v0, vf=vf, a0=vf),
                          [quintic(q0[j], qf[j], duration, v0=v0[j], vf=vf[j], a0=vf[j])
                           for j in joints], samples, duration)
    acceleration = 4.0 * np.abs(qf - q0) / duration**2 + np.arange(1, q0.size + 1)
    assert_same_per_joint(lspb(q0, qf, duration, acceleration),
                          [lspb(q0[j], qf[j], duration, acceleration[j]) for j in joints],
                          samples, duration)


@FAST
@given(path=helpers.via_paths(), v0=helpers.velocities)
def test_multi_joint_via_paths_equal_single_joint_results(path, v0):
    points, durations = path
    samples = np.linspace(0.0, durations.sum(), 61)
    joints = range(points.shape[1])
    for rule in VELOCITY_RULES:
        assert_same_per_joint(cubic_via(points, durations, rule, v0=v0),
                              [cubic_via(points[:, j], durations, rule, v0=v0)
                               for j in joints], samples, durations.min())
        assert_same_per_joint(quintic_via(points, durations, rule, v0=v0),
                              [quintic_via(points[:, j], durations, rule, v0=v0)
                               for j in joints], samples, durations.min())
    trajectory, acceleration = fitting_lspb_via(points, durations, 50.0, v0=v0)
    acceleration = np.broadcast_to(acceleration, (points.shape[1],))
    assert_same_per_joint(trajectory,
                          [lspb_via(points[:, j], durations, acceleration[j], v0=v0)
                           for j in joints], samples, durations.min())


# --- Sampling ---------------------------------------------------------------------------


PLANS = {
    'cubic': lambda: cubic([0.0, 1.0], [2.0, -1.0], 2.0, v0=[0.5, 0.0]),
    'quintic': lambda: quintic([0.0, 1.0], [2.0, -1.0], 2.0, a0=[1.0, 0.0]),
    'lspb': lambda: lspb([0.0, 1.0], [2.0, -1.0], 2.0, 4.0),
    'cubic_via': lambda: cubic_via([[0.0, 1.0], [1.0, 0.0], [2.0, -1.0]], [1.0, 1.0]),
    'quintic_via': lambda: quintic_via([[0.0, 1.0], [1.0, 0.0], [2.0, -1.0]], [1.0, 1.0]),
    'lspb_via': lambda: lspb_via([[0.0, 1.0], [1.0, 0.0], [2.0, -1.0]], [1.0, 1.0], 20.0),
}


@pytest.mark.parametrize('name', PLANS)
def test_sample_outside_the_motion_returns_the_boundary_state(name):
    trajectory = PLANS[name]()
    assert trajectory.duration == pytest.approx(2.0, abs=1e-15)
    before = trajectory.sample([-5.0, -1e-3, 0.0])
    after = trajectory.sample([trajectory.duration, 2.0 + 1e-3, 100.0])
    for state in (*before, *after):
        assert state.shape == (3, 2)
    for ours in before:
        np.testing.assert_array_equal(ours, np.broadcast_to(ours[2], ours.shape))
    for ours in after:
        np.testing.assert_array_equal(ours, np.broadcast_to(ours[0], ours.shape))
    position, velocity, _ = after
    np.testing.assert_allclose(position[0], [2.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(velocity[0], [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize('name', PLANS)
def test_sample_shapes(name):
    trajectory = PLANS[name]()
    assert trajectory.joint_count == 2
    for times in ([0.1], np.linspace(0.0, 2.0, 7), np.array([[0.1, 0.2], [0.3, 0.4]])):
        for state in trajectory.sample(times):
            assert state.shape == (np.size(times), 2)
    for state in trajectory.sample(0.3):
        assert state.shape == (1, 2)


def test_scalar_inputs_give_one_joint():
    for trajectory in (cubic(0.0, 1.0, 1.0), quintic(0.0, 1.0, 1.0), lspb(0.0, 1.0, 1.0, 8.0),
                       cubic_via([0.0, 1.0, 0.0], [1.0, 1.0]),
                       quintic_via([0.0, 1.0, 0.0], [1.0, 1.0]),
                       lspb_via([0.0, 1.0, 0.0], [1.0, 1.0], 40.0)):
        assert trajectory.joint_count == 1
        assert trajectory.coefficients.shape[2] == 1
        for state in trajectory.sample([0.0, 0.5]):
            assert state.shape == (2, 1)


# --- Peaks --------------------------------------------------------------------------


def assert_exact_peaks(trajectory):
    peak_velocity, peak_acceleration = trajectory.peaks()
    reference_velocity, reference_acceleration = helpers.reference_peaks(trajectory)
    np.testing.assert_allclose(peak_velocity, reference_velocity, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(peak_acceleration, reference_acceleration, rtol=1e-9,
                               atol=1e-12)


@FAST
@given(path=helpers.via_paths(), v0=helpers.velocities)
def test_peaks_are_the_exact_extrema_for_cubic_and_lspb(path, v0):
    points, durations = path
    assert_exact_peaks(cubic_via(points, durations, 'continuous', v0=v0))
    assert_exact_peaks(cubic_via(points, durations, 'heuristic', v0=v0))
    assert_exact_peaks(fitting_lspb_via(points, durations, 30.0, v0=v0)[0])


def test_peaks_finds_the_higher_of_two_acceleration_lobes():
    # |θ̈| has lobes ≈5.6195 near t = 0.125 (the best seed) and 5.63374616 at t ≈ 0.8437;
    # an earlier peaks() refined only the best seed and returned 5.6195.
    trajectory = quintic(1.0, 0.0, 1.0, v0=0.109375, af=3.109375)
    acceleration = helpers.dense_state(trajectory, 200001)[2]
    assert np.max(np.abs(acceleration)) == pytest.approx(5.63374616, abs=1e-8)
    assert trajectory.peaks()[1][0] == pytest.approx(5.633746159685988, rel=1e-9)


@FAST
@example(path=(np.array([[1.0], [0.0], [0.0]]), np.array([1.0, 1.0])), v0=0.109375)
@given(path=helpers.via_paths(), v0=helpers.velocities)
def test_peaks_are_the_exact_extrema_for_quintic(path, v0):
    points, durations = path
    assert_exact_peaks(quintic_via(points, durations, 'heuristic', v0=v0))
    assert_exact_peaks(quintic_via(points, durations, 'continuous', v0=v0))
