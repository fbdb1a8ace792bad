"""Jerk-limited S-curve moves (core.jerk_limited.move) against Ruckig as the oracle."""

import math
import re

import core_helpers as helpers
from hypothesis import assume, given, settings
import hypothesis.strategies as st
import numpy as np
import pytest
import ruckig
from ruckig_oracle import resolution, ruckig_duration
from traj_gen_ros import (
    JerkLimitedTrajectory,
    limit_violation,
    min_time,
    plan_path,
)
from traj_gen_ros.core.jerk_limited import fallback as scurve_fallback
from traj_gen_ros.core.jerk_limited.move import scurve, scurve_min_time
from traj_gen_ros.core.jerk_limited.problem import Move
from traj_gen_ros.core.trajectory import Trajectory

FAST = settings(max_examples=80, deadline=None)
TOL = 1e-9


def assert_ruckigs_duration(plan, expected):
    """Ruckig's duration to 1e-9, or, where Ruckig refuses (-101), a long one."""
    if expected is None:
        assert plan.duration > 7.6e3
    elif not math.isnan(expected):
        assert plan.duration == pytest.approx(expected, rel=TOL, abs=0.0)


def decade_limits(draw, joints):
    """Per-joint limits across four decades, 1e-2 … 1e2."""
    return tuple(np.array(draw(st.lists(st.floats(-2.0, 2.0), min_size=joints,
                                        max_size=joints))) for _ in range(3))


@st.composite
def moves(draw, moving=True):
    """Draw ``(q0, qf, v0, a0, vmax, amax, jmax)`` with a start the limits can hold."""
    joints = draw(st.integers(1, 7))
    exponents = decade_limits(draw, joints)
    vmax, amax, jmax = (10.0 ** exponent for exponent in exponents)
    q0 = np.array(draw(st.lists(helpers.positions, min_size=joints, max_size=joints)))
    qf = np.array(draw(st.lists(helpers.positions, min_size=joints, max_size=joints)))
    if not moving:
        return q0, qf, np.zeros(joints), np.zeros(joints), vmax, amax, jmax
    fractions = st.lists(st.floats(-1.0, 1.0), min_size=joints, max_size=joints)
    a0 = np.array(draw(fractions)) * np.minimum(amax, np.sqrt(2.0 * vmax * jmax))
    # A start velocity whose acceleration will not carry it past the limit: v0 plus the
    # velocity gained while the jerk brings a0 to zero stays within ±vmax.
    carried = a0 * np.abs(a0) / (2.0 * jmax)
    low, high = np.maximum(-vmax, -vmax - carried), np.minimum(vmax, vmax - carried)
    v0 = low + (high - low) * (np.array(draw(fractions)) + 1.0) / 2.0
    return q0, qf, v0, a0, vmax, amax, jmax


def check_plan(plan, q0, qf, v0, a0, vmax, amax, jmax):
    """Limits, continuity, exact start, rest at the goal: all to 1e-9 relative."""
    assert plan.degree == 3
    assert plan.breakpoints.shape == (plan.piece_count + 1, len(q0))
    assert np.all(np.diff(plan.breakpoints, axis=0) >= 0.0)
    assert np.all(plan.breakpoints[-1] == plan.duration)
    peak_velocity, peak_acceleration = helpers.reference_peaks(plan)
    acceleration_slack, velocity_slack = resolution(plan, jmax, amax)
    assert np.all(peak_velocity <= vmax * (1 + TOL) + velocity_slack), (peak_velocity, vmax)
    assert np.all(peak_acceleration <= amax * (1 + TOL) + acceleration_slack), (
        peak_acceleration, amax)
    assert np.all(plan.peak_jerk() <= jmax * (1 + TOL)), (plan.peak_jerk(), jmax)
    jumps, scales = helpers.boundary_jumps(plan)
    scale = np.stack([np.maximum(np.abs(qf - q0), 1.0), vmax, amax])[:, None, :]
    slack = np.stack([np.zeros_like(vmax), velocity_slack, acceleration_slack])[:, None, :]
    assert np.all(np.abs(jumps) <= TOL * np.maximum(scales, scale) + slack), jumps
    position, velocity, acceleration = plan.sample(0.0)
    assert np.array_equal(position[0], q0) and np.array_equal(velocity[0], v0)
    # Exact: the piece stores a0/2, which is exact except for subnormal a0.
    assert np.all(np.abs(acceleration[0] - a0) <= 1e-300), (acceleration[0], a0)
    # The end state is Ruckig's: exact to its precision (1e-8 in position and velocity,
    # 1e-10 in acceleration, absolute), plus rounding.
    position, velocity, acceleration = plan.sample(plan.duration)
    reach = max(1.0, np.max(np.abs(qf)), np.max(np.abs(q0)))
    assert np.all(np.abs(position[0] - qf) <= 1e-8 + TOL * reach), (position, qf)
    assert np.all(np.abs(velocity[0]) <= 1e-8 + TOL * vmax + velocity_slack)
    assert np.all(np.abs(acceleration[0]) <= 1e-10 + TOL * amax + acceleration_slack)


@FAST
@given(moves(moving=False))
def test_rest_to_rest_duration_is_ruckigs_and_within_limits(move):
    plan = scurve_min_time(*move)
    expected, _ = ruckig_duration(*move)
    assert_ruckigs_duration(plan, expected)
    check_plan(plan, *move)


@FAST
@given(moves())
def test_moving_start_duration_is_ruckigs_and_within_limits(move):
    expected, _ = ruckig_duration(*move)
    try:
        plan = scurve_min_time(*move)
    except ValueError as error:  # only where Ruckig itself refuses, and named
        assert (expected is None or math.isnan(expected)), error
        assert 'no jerk-limited plan for' in str(error)
        return
    assert_ruckigs_duration(plan, expected)
    check_plan(plan, *move)


@settings(max_examples=30, deadline=None)
@given(moves())
def test_pieces_equal_ruckigs_own_evaluation(move):
    plan = scurve_min_time(*move)
    _, solution = ruckig_duration(*move)
    assume(solution is not None)
    times = np.linspace(0.0, plan.duration, 37)
    position, velocity, acceleration = plan.sample(times)
    reach = max(1.0, float(np.max(np.abs(move[:2]))))
    for row, time in enumerate(times):
        expected = solution.at_time(time)
        for ours, theirs, scale in zip((position, velocity, acceleration), expected,
                                       (reach, move[4], move[5]), strict=True):
            assert np.all(np.abs(ours[row] - np.array(theirs)) <= 1e-8 * np.maximum(scale, 1))


def test_seven_phases_of_a_long_move_reach_every_limit():
    plan = scurve_min_time(np.zeros(1), np.array([10.0]), np.zeros(1), np.zeros(1),
                           np.array([1.0]), np.array([2.0]), np.array([8.0]))
    lengths = np.diff(plan.breakpoints[:, 0])
    # jerk phase 1/4 s, constant acceleration 1/4 s, cruise 10 - 0.75 s: T = 10 + 1/2 + 1/4.
    assert lengths == pytest.approx([0.25, 0.25, 0.25, 9.25, 0.25, 0.25, 0.25])
    assert plan.duration == pytest.approx(10.75)
    assert 6.0 * plan.coefficients[:, 3, 0] == pytest.approx([8, 0, -8, 0, -8, 0, 8])
    assert plan.peaks()[0] == pytest.approx([1.0]) and plan.peaks()[1] == pytest.approx([2.0])


def test_every_joint_arrives_together_and_a_still_joint_stays_put():
    plan = scurve_min_time(np.array([0.0, 1.0, 0.0]), np.array([3.0, 1.0, -0.1]), np.zeros(3),
                           np.zeros(3), np.ones(3), np.ones(3), np.ones(3))
    assert plan.duration == pytest.approx(5.0)  # 3/1 + 1/1 + 1/1
    position, velocity, _ = plan.sample(np.linspace(0.0, plan.duration, 101))
    assert np.all(position[:, 1] == 1.0) and np.all(velocity[:, 1] == 0.0)
    assert np.all(plan.breakpoints[-1] == 5.0)


@pytest.mark.parametrize('v0, a0', [(3.0, 0.0), (-3.0, 0.0), (0.0, 4.0), (0.9, 1.0),
                                    (-2.0, -5.0)])
def test_start_beyond_the_limits_brakes_first(v0, a0):
    q0, qf = np.array([0.0, 0.0]), np.array([1.0, -1.0])
    v0s, a0s = np.array([v0, 0.0]), np.array([a0, 0.0])
    limits = np.ones(2), np.array([2.0, 2.0]), np.array([4.0, 4.0])
    plan = scurve_min_time(q0, qf, v0s, a0s, *limits)
    expected, _ = ruckig_duration(q0, qf, v0s, a0s, *limits)
    assert plan.duration == pytest.approx(expected, rel=TOL, abs=0.0)
    assert plan.piece_count == 9  # two braking phases, then seven
    assert np.all(plan.peak_jerk() <= 4.0 * (1 + TOL))
    helpers.assert_continuous(plan, orders=3)
    position, velocity, acceleration = plan.sample([0.0, plan.duration])
    assert position[0].tolist() == [0.0, 0.0] and velocity[0].tolist() == [v0, 0.0]
    assert acceleration[0].tolist() == [a0, 0.0]
    assert position[1] == pytest.approx(qf, abs=1e-9) and velocity[1] == pytest.approx(0, abs=1e-9)
    # Once braked, the move stays within its limits.
    after = plan.breakpoints[2, 0]
    _, velocity, acceleration = plan.sample(np.linspace(after, plan.duration, 2001))
    assert np.all(np.abs(velocity) <= 1.0 + TOL) and np.all(np.abs(acceleration) <= 2 + TOL)


@FAST
@given(moves(), st.floats(1.0, 3.0))
def test_fixed_duration_is_exact_and_within_limits(move, stretch):
    q0, qf, v0, a0, vmax, amax, jmax = move
    try:
        shortest = scurve_min_time(*move).duration
    except ValueError:  # only where Ruckig itself refuses
        expected = ruckig_duration(*move)[0]
        assert expected is None or math.isnan(expected)
        return
    duration = max(shortest * stretch, 1e-3)
    try:
        plan = scurve(q0, qf, duration, vmax, amax, jmax, v0=v0, a0=a0)
    except ValueError as error:  # only a blocked duration may be refused here
        assert 'blocked' in str(error)
        return
    assert plan.duration == duration
    check_plan(plan, *move)


def test_fixed_duration_below_the_minimum_names_the_minimum():
    with pytest.raises(ValueError, match='minimum duration is 2.9 s'):
        scurve([0.0, 0.0], [1.0, -2.0], 2.8, 1.0, 2.0, 5.0)
    shortest, _ = ruckig_duration([0.0], [1.0], [0.5], [0.2], [1.0], [2.0], [5.0])
    with pytest.raises(ValueError) as refusal:
        scurve(0.0, 1.0, 0.5 * shortest, 1.0, 2.0, 5.0, v0=0.5, a0=0.2)
    named = float(re.search(r'minimum duration is ([0-9.e+-]+) s', str(refusal.value))[1])
    assert shortest <= named <= shortest * (1 + 1e-8)
    assert scurve(0.0, 1.0, named, 1.0, 2.0, 5.0, v0=0.5, a0=0.2).duration == named


@pytest.mark.parametrize('bad, message', [
    ({'max_jerk': 0.0}, 'max_jerk must be finite and > 0'),
    ({'max_velocity': [1.0, -1.0]}, 'max_velocity must be finite and > 0; joint 1'),
    ({'duration': 0.0}, 'duration must be > 0'),
    ({'q0': [0.0, float('nan')]}, 'q0 must be finite'),
    ({'v0': [1.0, 2.0, 3.0]}, 'v0 has 3 values for 2 joints'),
])
def test_scurve_validates_its_input(bad, message):
    arguments = {'q0': [0.0, 0.0], 'qf': [1.0, 1.0], 'duration': 5.0, 'max_velocity': 1.0,
                 'max_acceleration': 1.0, 'max_jerk': 1.0}
    arguments.update(bad)
    with pytest.raises(ValueError, match=re.escape(message)):
        scurve(**arguments)


def test_far_target_beyond_ruckigs_duration_limit_is_planned():
    # Ruckig alone refuses this synchronised duration (~1e7 s > 7.6e3 s).
    q0, qf = np.zeros(2), np.array([1e6, 1.0])
    limits = np.full(2, 0.1), np.full(2, 0.1), np.full(2, 0.1)
    parameters = ruckig.InputParameter(2)
    parameters.current_position, parameters.target_position = q0.tolist(), qf.tolist()
    parameters.max_velocity, parameters.max_acceleration, parameters.max_jerk = (
        limit.tolist() for limit in limits)
    with pytest.raises(ValueError, match='-101'):
        ruckig.Ruckig(2).calculate(parameters, ruckig.Trajectory(2))
    plan = scurve_min_time(q0, qf, np.zeros(2), np.zeros(2), *limits)
    assert plan.duration == pytest.approx(1e7 + 2.0, rel=TOL)  # D/v + v/a + a/j
    check_plan(plan, q0, qf, np.zeros(2), np.zeros(2), *limits)
    fixed = scurve(q0, qf, 2e7, *limits)
    assert fixed.duration == 2e7
    check_plan(fixed, q0, qf, np.zeros(2), np.zeros(2), *limits)


def test_duration_ruckig_answers_longer_in_scaled_units_is_met():
    # 1 rad at unit limits, moving on at v0 = -T0/(2T) of the rest-to-rest speed: nothing
    # blocks T = 4096 T0 (T0 = 4 (1/2)^(1/3) s, the rest-to-rest minimum time), but Ruckig
    # refuses it unscaled (-101) and, time scaled by 2^14, answers 4 T as if T were
    # blocked; lower limits (still within these) meet it. Before: "blocked" refused.
    duration = 4096.0 * 4.0 * 0.5 ** (1.0 / 3.0)
    v0 = -0.5 / duration
    plan = scurve(0.0, -1.0, duration, 1.0, 1.0, 1.0, v0=v0)
    assert plan.duration == duration
    ones = np.ones(1)
    check_plan(plan, np.zeros(1), -ones, np.array([v0]), np.zeros(1), ones, ones, ones)


def test_extreme_start_acceleration_ruckig_rejects_is_planned():
    arguments = (np.zeros(1), np.ones(1), np.zeros(1), np.array([1e3]), np.ones(1),
                 np.ones(1), np.ones(1))
    assert math.isnan(ruckig_duration(*arguments)[0])  # Ruckig raises RuckigError
    plan = scurve_min_time(*arguments)
    assert np.isfinite(plan.coefficients).all() and plan.duration > 999.0
    position, velocity, acceleration = plan.sample([0.0, plan.duration])
    assert acceleration[0, 0] == 1e3 and position[1, 0] == pytest.approx(1.0, rel=1e-6)
    assert np.all(plan.peak_jerk() <= 1.0 + TOL)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-300.0, 300.0), min_size=7, max_size=7), st.booleans(),
       st.integers(1, 3))
def test_extreme_inputs_give_a_finite_plan_or_a_value_error(exponents, fixed, joints):
    # Numeric warnings are errors here (pytest.ini): none may escape either.
    q0, qf, v0, a0, vmax, amax, jmax = (np.full(joints, 10.0**e) for e in exponents)
    try:
        plan = (scurve(-q0, qf, float(vmax[0]), vmax, amax, jmax, v0=v0, a0=-a0) if fixed else
                scurve_min_time(-q0, qf, v0, -a0, vmax, amax, jmax))
    except ValueError as error:
        assert 'scurve' in str(error)
        return
    assert np.isfinite(plan.coefficients).all() and np.isfinite(plan.breakpoints).all()
    assert np.all(plan.peak_jerk() <= jmax * (1 + TOL))


def test_peaks_report_jerk_the_largest_cubic_coefficient_times_six():
    plan = scurve_min_time(np.zeros(2), np.array([1.0, 0.1]), np.zeros(2), np.zeros(2),
                           np.ones(2), np.ones(2), np.array([3.0, 2.0]))
    manual = [max(abs(6.0 * c) for c in plan.coefficients[:, 3, joint]) for joint in (0, 1)]
    assert plan.peak_jerk().tolist() == pytest.approx(manual, rel=1e-15)
    assert plan.peaks()[2].tolist() == pytest.approx(manual, rel=1e-15)
    # One pass for all three is the same as the separate ones (limit_violation uses it).
    velocity, acceleration = Trajectory.peaks(plan)
    assert [a.tolist() for a in plan.peaks_with_jerk()] == \
        [velocity.tolist(), acceleration.tolist(), plan.peak_jerk().tolist()]
    assert manual == pytest.approx([3.0, 2.0], rel=1e-12)
    ramp = scurve_min_time(np.zeros(1), np.ones(1), np.zeros(1), np.zeros(1), np.ones(1),
                           np.ones(1), np.ones(1))
    assert ramp.peak_jerk().tolist() == pytest.approx([1.0])


@FAST
@given(helpers.positions, helpers.positions, st.lists(st.floats(-2.0, 2.0), min_size=3,
                                                      max_size=3))
def test_closed_form_rest_to_rest_fallback_equals_ruckig(q0, qf, exponents):
    vmax, amax, jmax = (10.0**e for e in exponents)
    plan, duration = scurve_fallback.rest_to_rest(
        Move([q0], [qf], [0.0], [0.0], [0.0], ([vmax], [amax], [jmax]), None))
    expected, _ = ruckig_duration([q0], [qf], [0.0], [0.0], [vmax], [amax], [jmax])
    if abs(qf - q0) > 1e-8:  # Ruckig takes smaller moves as done (its precision)
        assert duration == pytest.approx(expected, rel=TOL)
    check_plan(plan, np.array([q0]), np.array([qf]), np.zeros(1), np.zeros(1),
               np.array([vmax]), np.array([amax]), np.array([jmax]))


def test_target_ruckig_cannot_reach_is_planned_in_closed_form():
    # 1e13 rad at 1 rad/s: Ruckig fails directly and in every rescaled unit.
    q0, qf = np.array([1.0, -1.0]), np.array([1e13, 0.0])
    limits = np.ones(2), np.ones(2), np.full(2, 10.0)
    plan = scurve_min_time(q0, qf, np.zeros(2), np.zeros(2), *limits)
    assert plan.duration == pytest.approx(1e13 - 1.0 + 1.0 + 0.1, rel=1e-12)  # D/v + v/a + a/j
    assert np.all(plan.peak_jerk() <= 10.0 * (1 + TOL))
    position, velocity, _ = plan.sample(plan.duration)
    assert position[0] == pytest.approx(qf, rel=1e-12, abs=1e-8)
    # Breakpoints near 1e13 s are 2e-3 s apart: velocity is exact to a_max times that.
    _, velocity_slack = resolution(plan, limits[2], limits[1])
    assert np.all(np.abs(velocity[0]) <= velocity_slack) and velocity_slack[0] < 1e-2


def test_min_time_entry_point_plans_the_scurve_like_ruckig():
    q0, qf = np.array([0.0, 1.0, -0.5]), np.array([2.0, -1.0, 0.5])
    v0, a0 = np.array([0.4, -0.2, 0.0]), np.array([0.5, 0.0, -1.0])
    limits = (np.array([1.0, 2.0, 1.5]), np.array([2.0, 3.0, 2.0]), np.array([10.0, 5.0, 8.0]))
    plan = min_time(q0, qf, limits[0], limits[1], 'scurve', v0=v0, a0=a0, max_jerk=limits[2])
    assert isinstance(plan, JerkLimitedTrajectory)
    assert plan.duration == pytest.approx(ruckig_duration(q0, qf, v0, a0, *limits)[0], rel=1e-9)
    velocity, acceleration, jerk = plan.peaks()
    assert np.all(velocity <= limits[0] * (1 + TOL)) and np.all(jerk <= limits[2] * (1 + TOL))
    with pytest.raises(ValueError, match='scurve needs max_jerk'):
        min_time(q0, qf, limits[0], limits[1], 'scurve')


def test_plan_path_scurve_from_a_moving_state_keeps_acceleration_continuous():
    points = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, 0.0]])
    v0, a0 = np.array([0.3, -0.1]), np.array([0.4, 0.2])
    plan = plan_path(points, None, 'scurve', max_velocity=1.0, max_acceleration=2.0,
                     max_jerk=10.0, v0=v0, a0=a0)
    position, velocity, acceleration = plan.sample([0.0])
    np.testing.assert_array_equal(position[0], points[0])
    np.testing.assert_allclose(velocity[0], v0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(acceleration[0], a0, rtol=0, atol=1e-12)
    end, end_velocity, _ = plan.sample([plan.duration])
    np.testing.assert_allclose(end[0], points[-1], atol=1e-8)
    np.testing.assert_allclose(end_velocity[0], 0.0, atol=1e-8)
    assert limit_violation(plan, np.ones(2), 2 * np.ones(2), 10 * np.ones(2)) is None
