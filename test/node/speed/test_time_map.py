"""The speed override's ramp and plan clock (traj_gen_ros.node.speed.time_map), exact numbers."""

import math

import numpy as np
import pytest
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.planning.motion import held, PlannedMotion
from traj_gen_ros.node.planning.pipeline import plan_stop
from traj_gen_ros.node.speed.factor import check_factor, FactorInputs
from traj_gen_ros.node.speed.plan_window import jerk_at, PlanWindow
from traj_gen_ros.node.speed.ramp_bounds import MARGIN, rate_bounds
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.schedule import Schedule

MS = 1_000_000
T0 = 1_000_000 * MS  # 1000 s on the node clock


#: A plan cruising at 1 rad/s for 10⁶ s (one joint, one cubic piece: p = τ).
CRUISE = PlanWindow(Trajectory(np.array([0.0, 1e6]), np.array([[[0.0], [1.0], [0.0], [0.0]]])))


def cruising(time_ns, clock):
    """Give a plan's own state at 1 rad/s, no acceleration (one joint)."""
    del time_ns
    return CRUISE, clock + 1.0


@pytest.mark.parametrize('value', [-0.1, 1.5, math.nan, math.inf, 'half', True])
def test_invalid_factors_are_refused_with_a_reason(value):
    with pytest.raises(ValueError, match='speed_scaling'):
        check_factor(value)


def test_the_factor_asked_for_is_the_product_and_bad_messages_are_counted():
    inputs = FactorInputs(0.5)
    assert inputs.take_message(0.4) is None
    assert inputs.product == pytest.approx(0.2)
    assert 'finite' in inputs.take_message(math.nan)
    assert '[0, 1]' in inputs.take_message(1.5)
    assert inputs.topic == 0.4 and inputs.ignored == 2
    assert ('speed scaling in force', '0.2') in inputs.values(0.2)


def test_rate_bounds_are_the_closed_form_and_always_hold_zero():
    # |f² a + ḟ v| <= max(σ a_max, f² |a|): v = 1, a = 0, a_max = 2: ḟ in [-1.9, 1.9].
    assert rate_bounds(1.0, np.array([1.0]), np.array([0.0]), np.array([2.0])) == \
        pytest.approx((-2.0 * MARGIN, 2.0 * MARGIN))
    # The plan at its limit (a = a_max, v > 0): slowing only (ḟ v down to -2 a_max).
    low, high = rate_bounds(1.0, np.array([1.0]), np.array([2.0]), np.array([2.0]))
    assert (low, high) == pytest.approx((-4.0, 0.0))
    # Half speed, two joints: the tighter joint sets each end.
    low, high = rate_bounds(0.5, np.array([1.0, -2.0]), np.array([1.0, 0.0]),
                            np.array([2.0, 2.0]))
    assert low == pytest.approx(max((-1.9 - 0.25) / 1.0, -1.9 / 2.0))
    assert high == pytest.approx(min((1.9 - 0.25) / 1.0, 1.9 / 2.0))


def test_a_pause_from_cruise_ramps_at_sigma_a_max_over_v():
    time_map = TimeMap(np.array([2.0]))
    time_map.set_target(0.0, T0, cruising)
    # ḟ = -σ a_max / v = -1.9 /s: f reaches 0 after 1 / 1.9 s, P gains 1 / (2 · 1.9) s.
    clock0, factor, rate, _ = time_map.at(T0, cruising)
    assert (factor, rate) == (1.0, pytest.approx(-1.9))
    clock, factor, rate, _ = time_map.at(T0 + 100 * MS, cruising)
    assert factor == pytest.approx(1.0 - 0.19)
    assert clock - clock0 == pytest.approx(0.1 - 1.9 * 0.1 ** 2 / 2.0)
    clock, factor, rate, _ = time_map.at(T0 + 600 * MS, cruising)
    assert (factor, rate) == (0.0, 0.0)
    assert clock - clock0 == pytest.approx(1.0 / (2.0 * 1.9), abs=2e-6)


def test_a_change_applies_from_its_time_and_the_past_is_kept():
    time_map = TimeMap(np.array([2.0]))
    before = time_map.at(T0, cruising)
    time_map.commit(T0 + 5 * MS, cruising)
    time_map.set_target(0.5, T0 + 10 * MS, cruising)
    assert time_map.version == 1
    clock, factor, _, _ = time_map.at(T0 + 10 * MS, cruising)
    assert (factor, clock - before[0]) == (1.0, pytest.approx(0.010))
    assert time_map.at(T0 + 1000 * MS, cruising)[1] == 0.5


def test_without_moving_joints_the_factor_follows_in_one_step():
    time_map = TimeMap(np.array([2.0]))
    time_map.set_target(0.3, T0, lambda time_ns, clock: None)
    assert time_map.at(T0 + MS, lambda time_ns, clock: None)[1] == pytest.approx(0.3)


def test_jerk_at_is_the_third_derivative():
    plan = min_time(np.zeros(2), np.array([1.0, -0.5]), np.ones(2), 2.0 * np.ones(2),
                    'quintic')
    assert jerk_at(plan, 0.0) == pytest.approx(6.0 * plan.coefficients[0, 3])


def goal_motion():
    plan = min_time(np.zeros(1), np.array([1.0]), np.ones(1), 2.0 * np.ones(1), 'lspb')
    return PlannedMotion(plan, 'lspb', np.array([1.0]))


def test_half_speed_mid_motion_commands_half_the_velocity_and_no_jump():
    schedule = Schedule(held(np.zeros(1)), TimeMap(np.array([2.0])))
    motion = goal_motion()  # LSPB 0 -> 1 rad, 1 rad/s, 2 rad/s²: 1.5 s, cruise 0.5-1.0 s
    schedule.splice(T0, motion, T0)
    schedule.commit(T0 + 600 * MS)
    schedule.set_factor(0.5, T0 + 600 * MS, 0)
    previous = schedule.setpoint(T0 + 600 * MS)
    assert previous.velocity[0] == pytest.approx(1.0)
    for step in range(1, 4000):
        state = schedule.setpoint(T0 + 600 * MS + step * MS)
        assert abs(state.velocity[0] - previous.velocity[0]) <= 2.0 * MS * 1e-9 + 1e-12
        assert abs(state.acceleration[0]) <= 2.0 + 1e-9
        previous = state
    # The ramp 1 -> 0.5 at 1.9 /s takes 0.263 s; then 0.5 rad/s.
    assert schedule.setpoint(T0 + 900 * MS).velocity[0] == pytest.approx(0.5)
    assert schedule.plan_state(T0 + 900 * MS).velocity[0] == pytest.approx(1.0)
    # The remaining plan time 0.9 s - 0.6 s... runs at half speed: at rest at 1 rad.
    assert schedule.setpoint(T0 + 3000 * MS).position[0] == pytest.approx(1.0)


def test_a_new_plan_while_paused_starts_from_the_own_state_and_stays_paused():
    schedule = Schedule(held(np.zeros(1)), TimeMap(np.array([2.0])))
    schedule.splice(T0, goal_motion(), T0)
    schedule.set_factor(0.0, T0 + 700 * MS, 0)
    paused = schedule.setpoint(T0 + 2000 * MS)
    assert paused.velocity[0] == 0.0
    own = schedule.plan_state(T0 + 2000 * MS)
    assert own.velocity[0] == pytest.approx(1.0)  # still cruising in its own time
    plan = min_time(own.position, np.array([0.5]), np.ones(1), 2.0 * np.ones(1), 'lspb',
                    v0=own.velocity, a0=np.zeros(1))
    schedule.splice(T0 + 2000 * MS, PlannedMotion(plan, 'lspb', np.array([0.5])),
                    T0 + 2000 * MS)
    assert schedule.setpoint(T0 + 3000 * MS).position[0] == pytest.approx(paused.position[0])
    schedule.set_factor(1.0, T0 + 3000 * MS, 0)
    assert schedule.setpoint(T0 + 8000 * MS).position[0] == pytest.approx(0.5)


def test_a_brake_is_never_slowed():
    schedule = Schedule(held(np.zeros(1)), TimeMap(np.array([2.0])))
    schedule.splice(T0, goal_motion(), T0)
    schedule.set_factor(0.1, T0 + 600 * MS, 0)
    start = T0 + 2000 * MS
    commanded = schedule.setpoint(start)
    assert commanded.velocity[0] == pytest.approx(0.1)

    class Limits:
        profile = 'lspb'
        max_acceleration = np.array([2.0])
    stop = plan_stop(Limits(), commanded)
    assert stop.unscaled and stop.plan.duration == pytest.approx(0.1 / 2.0)
    schedule.splice(start, stop, start)
    assert schedule.setpoint(start + 25 * MS).velocity[0] == pytest.approx(0.05)
    # A goal asked while it brakes at a factor below 1 starts where it is at rest.
    assert schedule.scaled_start(start + 10 * MS) == start + 50 * MS


def test_a_delayed_motion_a_change_would_make_jump_is_dropped_with_its_tag():
    schedule = Schedule(held(np.zeros(1)), TimeMap(np.array([2.0])))
    schedule.splice(T0, goal_motion(), T0)  # cruising at 1 rad/s from 0.5 s to 1 s
    later = goal_motion()  # planned as if it started from the goal's state at 2 s: rest
    schedule.splice(T0 + 800 * MS, later, T0, tag='request 7')
    dropped = schedule.set_factor(0.5, T0 + 600 * MS, 0)  # moves the state at 0.8 s
    assert dropped == [(later, 'request 7')]
    assert schedule.pending == 1


def test_the_time_left_is_plan_time_still_while_paused():
    schedule = Schedule(held(np.zeros(1)), TimeMap(np.array([2.0])))
    schedule.splice(T0, goal_motion(), T0)  # 1.5 s
    assert schedule.time_left(T0 + 600 * MS) == pytest.approx(0.9)
    schedule.commit(T0 + 600 * MS)
    schedule.set_factor(0.0, T0 + 600 * MS, 0)  # at rest 1 / 1.9 s later (plan time 0.263)
    paused = schedule.time_left(T0 + 2000 * MS)
    assert paused == pytest.approx(0.9 - 1.0 / (2.0 * 1.9), abs=1e-5)
    assert schedule.time_left(T0 + 5000 * MS) == paused  # unscaled it would be 0
