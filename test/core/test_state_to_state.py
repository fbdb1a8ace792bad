"""
Exact state-to-state planning (issue 10): minimum time from any (q0, v0, a0).

Checked against Ruckig and against dense grids of shorter durations.
"""

import math

import core_helpers as helpers
from hypothesis import given, settings
import hypothesis.strategies as st
import numpy as np
import pytest
import ruckig
from traj_gen_ros import (
    cubic,
    hold,
    JointError,
    limit_violation,
    lspb,
    min_time,
    quintic,
    within_limits,
)
from traj_gen_ros.core.exact.polynomial_durations import SHORTEST_POLYNOMIAL

ORACLE = settings(max_examples=200, deadline=None)
GRID = settings(max_examples=12, deadline=None)


def ruckig_duration(q0, qf, v0, max_velocity, max_acceleration):
    """Ruckig's time-optimal duration with infinite jerk (second order), or None if it fails."""
    count = len(q0)
    parameters = ruckig.InputParameter(count)
    parameters.current_position = list(q0)
    parameters.current_velocity = list(v0)
    parameters.target_position = list(qf)
    parameters.max_velocity = list(max_velocity)
    parameters.max_acceleration = list(max_acceleration)
    parameters.max_jerk = [math.inf] * count
    trajectory = ruckig.Trajectory(count)
    try:
        result = ruckig.Ruckig(count).calculate(parameters, trajectory)
    except (ruckig.RuckigError, ValueError):  # ValueError: a code the binding cannot name
        return None
    return trajectory.duration if result == ruckig.Result.Working else None


def scaled_ruckig_duration(q0, qf, v0, max_velocity, max_acceleration):
    """
    Ruckig's duration, run in a faster time scale when it fails (its 7.6e3 s limit).

    Time scaled by ``k`` (velocities ``k``, accelerations ``k²``) divides the duration by
    ``k``: an exact identity of the problem, so the oracle stays independent of our code.
    """
    for scale in (1.0, 1e3, 1e6):
        duration = ruckig_duration(q0, qf, np.asarray(v0) * scale,
                                   np.asarray(max_velocity) * scale,
                                   np.asarray(max_acceleration) * scale**2)
        if duration is not None:
            return duration * scale
    return None


@st.composite
def moving_starts(draw, max_joints=7):
    """Draw q0, qf, v0, limits: moves 1e-9..1e3 (or none), limits 1e-2..1e2, v0 within."""
    joints = draw(st.integers(1, max_joints))

    def row(strategy):
        return np.array(draw(st.lists(strategy, min_size=joints, max_size=joints)))

    magnitude = st.one_of(st.just(0.0), st.floats(-9.0, 3.0).map(lambda e: 10.0**e))
    sign = st.sampled_from([-1.0, 1.0])
    q0 = row(st.floats(-10.0, 10.0))
    qf = q0 + row(magnitude) * row(sign)
    max_velocity = row(st.floats(-2.0, 2.0).map(lambda e: 10.0**e))
    max_acceleration = row(st.floats(-2.0, 2.0).map(lambda e: 10.0**e))
    # Towards, away from, or (with a large v0 near the target) past the target.
    fraction = st.one_of(st.just(0.0), st.floats(1e-6, 1.0), st.floats(-1.0, -1e-6))
    v0 = row(fraction) * max_velocity
    return q0, qf, v0, max_velocity, max_acceleration


@ORACLE
@given(moving_starts())
def test_lspb_minimum_time_equals_ruckig(move):
    q0, qf, v0, max_velocity, max_acceleration = move
    plan = min_time(q0, qf, max_velocity, max_acceleration, 'lspb', v0=v0)
    expected = scaled_ruckig_duration(q0, qf, v0, max_velocity, max_acceleration)
    if expected is None:  # Ruckig's own numerical failure: the slowest single joint
        # (second order has no blocked durations, so that is the synchronised duration).
        singles = [scaled_ruckig_duration(q0[j:j + 1], qf[j:j + 1], v0[j:j + 1],
                                          max_velocity[j:j + 1], max_acceleration[j:j + 1])
                   for j in range(q0.size)]
        assert None not in singles, 'Ruckig fails on a single joint too'
        expected = max(singles)
    assert plan.duration == pytest.approx(expected, rel=1e-12, abs=1e-300)
    assert_plan_is_sound(plan, q0, qf, v0, 0.0 * v0, max_velocity, max_acceleration)


def assert_plan_is_sound(plan, q0, qf, v0, a0, max_velocity, max_acceleration, orders=2):
    """Start state exact, end at rest at qf, within limits, continuous."""
    position, velocity, acceleration = plan.sample([0.0])
    np.testing.assert_array_equal(position[0], q0)
    np.testing.assert_array_equal(velocity[0], v0)
    if orders == 3:
        np.testing.assert_array_equal(acceleration[0], a0)
    end, end_velocity, _ = plan.sample([plan.duration])
    duration = plan.duration
    travel = (np.max(np.abs(np.concatenate([q0, qf]))) + np.max(v0 * v0 / max_acceleration)
              + np.max(np.abs(v0)) * duration + np.max(np.abs(a0)) * duration**2)
    helpers.assert_state(end, [qf], scale=travel + 1e-300)
    helpers.assert_state(end_velocity, [0.0 * qf], scale=np.max(max_velocity))
    assert limit_violation(plan, max_velocity, max_acceleration) is None
    helpers.assert_continuous(plan, orders=orders)


@st.composite
def polynomial_starts(draw, max_joints=4):
    """Draw a moving start for cubic/quintic: moves 1e-3..10, limits 0.1..10."""
    joints = draw(st.integers(1, max_joints))

    def row(strategy):
        return np.array(draw(st.lists(strategy, min_size=joints, max_size=joints)))

    q0, qf = row(helpers.positions), row(helpers.positions)
    max_velocity, max_acceleration = row(helpers.limits), row(helpers.limits)
    fraction = st.one_of(st.just(0.0), st.floats(1e-6, 1.0), st.floats(-1.0, -1e-6))
    v0 = row(fraction) * max_velocity
    a0 = row(fraction) * max_acceleration
    return q0, qf, v0, a0, max_velocity, max_acceleration


def feasible_on_grid(profile, q0, qf, v0, a0, max_velocity, max_acceleration, durations,
                     tolerance=1e-12):
    """
    Which durations keep the polynomial within the (start-raised) limits: by root peaks.

    Strict (1e-12): where a limit is touched tangentially, durations just below the
    minimum exceed it only to second order, within the 1e-9 the planner allows.
    """
    planner = {'cubic': lambda t: cubic(q0, qf, t, v0=v0),
               'quintic': lambda t: quintic(q0, qf, t, v0=v0, a0=a0)}[profile]
    result = []
    for duration in durations:
        velocity, acceleration = helpers.reference_peaks(planner(duration))
        result.append(bool(np.all(velocity <= max_velocity * (1 + tolerance))
                           and np.all(acceleration <= max_acceleration * (1 + tolerance))))
    return np.array(result)


@GRID
@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
@given(polynomial_starts())
def test_polynomial_minimum_time_is_feasible_and_minimal(profile, move):
    q0, qf, v0, a0, max_velocity, max_acceleration = move
    # The start may already sit at a limit: the polynomial may keep that level.
    velocity_limit = np.maximum(max_velocity, np.abs(v0))
    acceleration_limit = np.maximum(max_acceleration, np.abs(a0)) if profile == 'quintic' \
        else max_acceleration
    start_acceleration = a0 if profile == 'quintic' else 0.0 * a0
    try:
        plan = min_time(q0, qf, max_velocity, max_acceleration, profile, v0=v0, a0=a0)
    except ValueError:
        # Refused: then no duration on a wide grid works either.
        grid = np.geomspace(1e-3, 1e3, 300)
        assert not feasible_on_grid(profile, q0, qf, v0, start_acceleration, velocity_limit,
                                    acceleration_limit, grid).any()
        return
    assert_plan_is_sound(plan, q0, qf, v0, start_acceleration, velocity_limit,
                         acceleration_limit, orders=3 if profile == 'quintic' else 2)
    if plan.duration == 0.0:  # nothing to do: at rest at the goal already
        assert not (np.any(qf - q0) or np.any(v0) or np.any(start_acceleration))
        return
    # Polynomials last at least SHORTEST_POLYNOMIAL (1e-9 s): shorter ones overflow.
    shorter = np.linspace(max(plan.duration * 1e-3, SHORTEST_POLYNOMIAL),
                          plan.duration * (1 - 1e-4), 150)
    shorter = shorter[(shorter < plan.duration) & (shorter >= SHORTEST_POLYNOMIAL)]
    assert not feasible_on_grid(profile, q0, qf, v0, start_acceleration, velocity_limit,
                                acceleration_limit, shorter).any()


@GRID
@given(moving_starts(max_joints=4))
def test_lspb_minimum_time_is_minimal_on_a_grid(move):
    q0, qf, v0, max_velocity, max_acceleration = move
    plan = min_time(q0, qf, max_velocity, max_acceleration, 'lspb', v0=v0)
    # No shorter duration can move some joint within its acceleration: lspb() at full
    # acceleration reaches the most (and least) displacement, so it refuses each of them.
    for duration in np.linspace(plan.duration * 1e-3, plan.duration * (1 - 1e-6), 50):
        with pytest.raises(ValueError):
            plan_at = lspb(q0, qf, duration, max_acceleration, v0=v0)
            if limit_violation(plan_at, max_velocity, max_acceleration) is not None:
                raise ValueError('over the velocity limit')


# --- The reproducers of the issue ----------------------------------------------------


def test_quintic_window_from_a_moving_acceleration_is_found():
    # Feasible durations form a window (about 25.6-36.9 s); a doubling search jumped it.
    plan = min_time([0, 0], [0, 10], [0.01, 10], [1, 0.1], 'quintic', a0=[-0.004, -0.05])
    assert 25.5 < plan.duration < 25.7
    assert within_limits(plan, np.array([0.01, 10]), np.array([1, 0.1]))
    shorter = np.linspace(1.0, plan.duration * (1 - 1e-9), 300)
    assert not feasible_on_grid('quintic', np.zeros(2), np.array([0.0, 10.0]), np.zeros(2),
                                np.array([-0.004, -0.05]), np.array([0.01, 10]),
                                np.array([1, 0.1]), shorter).any()
    assert quintic([0, 0], [0, 10], 30.0, a0=[-0.004, -0.05]).duration == 30.0


def test_lspb_small_move_from_v0_takes_the_true_minimum():
    plan = min_time(0.0, 0.0, 1.0, 1.0, v0=1e-6)
    assert plan.duration == pytest.approx((1 + math.sqrt(2)) * 1e-6, rel=1e-12)
    assert plan.duration == pytest.approx(ruckig_duration([0.0], [0.0], [1e-6], [1.0], [1.0]),
                                          rel=1e-12)
    assert_plan_is_sound(plan, np.zeros(1), np.zeros(1), np.full(1, 1e-6), np.zeros(1),
                         np.ones(1), np.ones(1))


def test_lspb_too_short_from_v0_is_refused_with_the_shortest_duration():
    with pytest.raises(ValueError, match=r'shortest duration that works is 2\.41421356e-06'):
        lspb(0.0, 0.0, 1.5e-6, 1.0, v0=1e-6)


def test_peaks_of_a_still_plan_and_of_hold():
    peak_velocity, peak_acceleration = min_time([1.0], [1.0], 1, 1).peaks()
    np.testing.assert_array_equal(peak_velocity, [0.0])
    np.testing.assert_array_equal(peak_acceleration, [0.0])
    assert within_limits(hold([1.0]), np.ones(1), np.ones(1))


@pytest.mark.parametrize(('call', 'named'), [
    (lambda: min_time(0, 1, 1e-320, 1), 'max_velocity'),
    (lambda: min_time(0, 1, 1, 1e-320, 'quintic'), 'max_acceleration'),
])
def test_overflowing_plans_are_value_errors_naming_the_input(call, named):
    with pytest.raises(JointError, match=named):
        call()


def test_a_huge_lspb_duration_is_planned_without_overflow():
    plan = lspb(0, 1, 2e154, 1.0)
    position, velocity, _ = plan.sample([0.0, 1e154, 2e154])
    np.testing.assert_allclose(position[:, 0], [0.0, 0.5, 1.0], rtol=1e-12)
    assert velocity[1, 0] == pytest.approx(5e-155, rel=1e-9)


def test_a_joint_faster_than_its_limit_brakes_first():
    plan = min_time([0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [2.0, 2.0], 'lspb', v0=[3.0, 0.5])
    velocity, acceleration = plan.peaks()
    assert velocity[0] == pytest.approx(3.0)
    _, later_velocity, _ = plan.sample([1.0])
    assert abs(later_velocity[0, 0]) <= 1.0 + 1e-12  # braked to the limit after 1 s
    assert acceleration.max() <= 2.0 * (1 + 1e-12)


def test_error_names_the_joint_by_name_when_asked():
    with pytest.raises(JointError) as caught:
        lspb([0.0, 0.0], [0.0, 4.0], 1.0, [1.0, 1.0])
    assert caught.value.joint == 1
    assert "joint 'elbow'" in caught.value.named(['shoulder', 'elbow'])


def test_lspb_sampling_is_linear_in_joints():
    # Per-joint breakpoints are no longer merged: a 1000-joint LSPB samples 1000 times
    # without building a (joints x joints) union of pieces.
    rng = np.random.default_rng(3)
    count = 1000
    q0, qf = rng.uniform(-1, 1, count), rng.uniform(-1, 1, count)
    v0 = rng.uniform(-0.5, 0.5, count)
    plan = min_time(q0, qf, 1.0, 2.0, 'lspb', v0=v0)
    assert plan.breakpoints.shape == (4, count)
    position, velocity, _ = plan.sample(np.linspace(0.0, plan.duration, 1000))
    assert position.shape == (1000, count)
    np.testing.assert_array_equal(position[0], q0)
    np.testing.assert_allclose(position[-1], qf, atol=1e-12)
    np.testing.assert_allclose(velocity[-1], 0.0, atol=1e-12)


@pytest.mark.parametrize('joints', [3, 40])
def test_dense_and_sparse_sampling_of_per_joint_pieces_agree(joints):
    # Dense sampling of a few joints merges their breakpoints (one product per piece);
    # otherwise each sample's piece is gathered per joint. Both must give the same states.
    rng = np.random.default_rng(joints)
    q0, qf = rng.uniform(-1, 1, joints), rng.uniform(-1, 1, joints)
    plan = min_time(q0, qf, 1.0, 2.0, 'lspb', v0=rng.uniform(-0.5, 0.5, joints))
    times = np.linspace(0.0, plan.duration, 4001)
    dense = plan.sample(times)
    sparse = [plan.sample(times[index:index + 7]) for index in range(0, times.size, 7)]
    for order in range(3):
        np.testing.assert_allclose(dense[order], np.vstack([s[order] for s in sparse]),
                                   rtol=1e-12, atol=1e-12)
