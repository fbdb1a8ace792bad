"""ROS-free planning: goals, via points, stops and S-curves through the pipeline; the schedule."""


from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
from planning_rig import config, JOINTS, rest
import pytest
from traj_gen_ros import limit_violation, min_time, scurve_brake
from traj_gen_ros.node.messages.parsing import (
    GoalRequest,
    parse_via,
    RequestError,
)
from traj_gen_ros.node.planning.motion import held, State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop
from traj_gen_ros.node.planning.sampling import sample_grid, sample_motion
from traj_gen_ros.node.stream.schedule import Schedule


def test_goal_plan_matches_core_min_time_and_holds_unnamed_joints():
    cfg = config()
    request = GoalRequest(np.array([0]), np.array([1.0]))
    motion = plan_request(cfg, rest(), np.array([0.0, 0.5, 0.0]), request)
    expected = min_time([0, 0, 0], [1.0, 0.5, 0.0], cfg.max_velocity, cfg.max_acceleration,
                        profile='quintic')
    assert motion.plan.duration == pytest.approx(expected.duration)
    assert motion.end.tolist() == [1.0, 0.5, 0.0]
    times, q, v, a = sample_motion(motion, cfg.rate_hz)
    assert times[-1] == motion.plan.duration and q[-1].tolist() == [1.0, 0.5, 0.0]
    assert not v[-1].any() and not a[-1].any()


def test_explicit_times_too_short_report_a_feasible_minimum():
    cfg = config(profile='cubic')
    request = parse_via(JOINTS, ['a'], [([1.0], [], [], 0.5)])
    with pytest.raises(RequestError, match='minimum feasible duration is ([0-9.]+) s') as info:
        plan_request(cfg, rest(), np.zeros(3), request)
    minimum = float(str(info.value).split('duration is ')[1].split(' s')[0])
    # cubic rest to rest: peak velocity 1.5 h / T binds (1 rad/s): T = 1.5 s.
    assert minimum == pytest.approx(1.5, rel=1e-3)


def test_auto_timing_stretches_when_the_start_state_needs_it():
    cfg = config()
    moving = State(np.zeros(3), np.array([0.9, 0, 0]), np.zeros(3))
    request = parse_via(JOINTS, ['a'], [([-0.05], [], [], 0.0)])
    motion = plan_request(cfg, moving, np.zeros(3), request)
    _, v, a = motion.plan.sample(np.linspace(0, motion.plan.duration, 2001))
    assert np.all(np.abs(v) <= cfg.max_velocity * (1 + 1e-6))
    assert np.all(np.abs(a) <= cfg.max_acceleration * (1 + 1e-6))


def test_stop_brakes_at_the_limit_to_rest():
    cfg = config()
    state = State(np.array([0.0, 1.0, 2.0]), np.array([2.0, -1.0, 0.0]), np.ones(3))
    motion = plan_stop(cfg, state)
    assert motion.plan.duration == pytest.approx(0.5)
    assert motion.end == pytest.approx([0.0 + 2.0**2 / 8, 1.0 - 1.0 / 8, 2.0])
    q, v, a = motion.plan.sample(np.array([0.0, 0.25, 0.5, 1.0]))
    assert q[0].tolist() == [0.0, 1.0, 2.0] and v[0].tolist() == [2.0, -1.0, 0.0]
    assert np.all(np.abs(a) <= 4.0) and not v[-1].any()


def test_scurve_goal_starts_from_the_acceleration_within_every_limit():
    cfg = config(profile='scurve', max_jerk=[10.0, 20.0, 30.0])
    assert cfg.max_jerk.tolist() == [10.0, 20.0, 30.0] and cfg.jerk_limit is cfg.max_jerk
    assert config().jerk_limit is None  # the other profiles are not checked for jerk
    state = State(np.zeros(3), np.array([0.5, -1.0, 0.0]), np.array([2.0, 1.0, -3.0]))
    motion = plan_request(cfg, state, np.zeros(3), GoalRequest(np.arange(3),
                                                               np.array([1.0, -1.0, 0.5])))
    assert motion.profile == 'scurve'
    q, v, a = (value[0] for value in motion.plan.sample(0.0))
    assert q.tolist() == [0.0] * 3 and v.tolist() == state.velocity.tolist()
    assert a == pytest.approx(state.acceleration, abs=1e-9)  # no acceleration step
    expected = min_time(state.position, [1.0, -1.0, 0.5], cfg.max_velocity,
                        cfg.max_acceleration, 'scurve', v0=state.velocity,
                        a0=state.acceleration, max_jerk=cfg.max_jerk)
    assert motion.plan.duration == pytest.approx(expected.duration, rel=1e-12)
    assert limit_violation(motion.plan, cfg.max_velocity, cfg.max_acceleration,
                           cfg.max_jerk) is None


def test_scurve_goal_from_the_velocity_limit_while_accelerating_is_accepted():
    # Limits lowered mid-motion: at 1 rad/s (the limit) and +2 rad/s^2 the velocity must
    # go on to 1 + 2^2 / (2 * 10) = 1.2 rad/s while the acceleration returns to zero.
    cfg = config(profile='scurve', max_jerk=10.0)
    state = State(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0]))
    motion = plan_request(cfg, state, np.zeros(3), GoalRequest(np.array([0]),
                                                               np.array([3.0])))
    velocity, acceleration, jerk = motion.plan.peaks()
    assert velocity[0] == pytest.approx(1.2, rel=1e-6)
    assert acceleration[0] <= 4.0 * (1 + 1e-9) and jerk[0] <= 10.0 * (1 + 1e-9)


def test_scurve_via_points_refuse_accelerations_and_time_from_the_limits():
    cfg = config(profile='scurve', max_jerk=10.0)
    with pytest.raises(RequestError, match='profile scurve cannot honour accelerations'):
        plan_request(cfg, rest(), np.zeros(3), parse_via(
            JOINTS, ['a'], [([0.5], [0.0], [0.0], 1.0)]))
    moving = State(np.zeros(3), np.array([0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]))
    motion = plan_request(cfg, moving, np.zeros(3), parse_via(
        JOINTS, ['a', 'b'], [([0.5, 0.2], [], [], 0.0), ([1.0, -0.3], [], [], 0.0)]))
    assert motion.note == 'timed from the limits'
    a0 = motion.plan.sample(0.0)[2][0]
    assert a0 == pytest.approx(moving.acceleration, abs=1e-9)
    assert limit_violation(motion.plan, cfg.max_velocity, cfg.max_acceleration,
                           cfg.max_jerk) is None


def test_scurve_stop_brakes_with_bounded_jerk_from_the_acceleration():
    cfg = config(profile='scurve', max_jerk=[10.0, 20.0, 30.0])
    state = State(np.array([0.0, 1.0, 2.0]), np.array([1.0, -1.0, 0.0]),
                  np.array([3.0, 0.0, -1.0]))
    motion = plan_stop(cfg, state)
    expected = scurve_brake(state.position, state.velocity, state.acceleration,
                            cfg.max_acceleration, cfg.max_jerk)
    assert motion.profile == 'stop' and motion.plan.duration == expected.duration
    q, v, a = motion.plan.sample(np.array([0.0, motion.plan.duration]))
    assert a[0] == pytest.approx(state.acceleration) and not np.any(np.abs(v[-1]) > 1e-12)
    assert np.allclose(motion.end, q[-1])
    assert limit_violation(motion.plan, np.full(3, 10.0), cfg.max_acceleration,
                           cfg.max_jerk) is None


def test_sample_grid():
    times = sample_grid(held([0.0]).plan, 100.0)
    assert times.tolist() == [0.0]
    plan = min_time(0.0, 0.3, 1.0, 4.0, profile='quintic')
    times = sample_grid(plan, 100.0)
    assert times[-1] == plan.duration and np.allclose(np.diff(times)[:-1], 0.01)


def test_limit_refusals_name_joints_by_their_ros_names():
    cfg = config(profile='cubic')
    request = parse_via(JOINTS, ['b'], [([1.0], [], [], 0.1)])
    with pytest.raises(RequestError, match="joint 'b' would reach"):
        plan_request(cfg, rest(), np.zeros(3), request)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.05, 0.6), st.floats(-1.0, 1.0),
                          st.sampled_from(['cubic', 'quintic', 'lspb'])),
                min_size=1, max_size=4))
def test_preemption_keeps_position_and_velocity_continuous(requests):
    """Accepted replans start at the setpoint; a refusal is a RequestError, never a crash."""
    schedule = Schedule(held(np.zeros(3)))
    now = 0
    last = np.zeros(3)
    for number, (delay, target, profile) in enumerate(requests):
        now += int(delay * 1e9)
        before = schedule.setpoint(now - 1)
        cfg = config(profile=profile)
        state = schedule.setpoint(now)
        try:
            motion = plan_request(cfg, state, schedule.end_position(now),
                                  GoalRequest(np.array([0, 2]), np.array([target, -target])))
        except RequestError as error:
            assert number > 0, error  # from rest every goal is feasible
            assert 'from the current motion' in str(error)
            continue
        schedule.splice(now, motion, now)
        last = motion.end
        after = schedule.setpoint(now)
        assert np.allclose(after.position, before.position, atol=1e-6)
        assert np.allclose(after.velocity, before.velocity, atol=1e-5)
        if profile == 'quintic':
            assert np.allclose(after.acceleration, state.acceleration, atol=1e-6)
    end = schedule.setpoint(now + 10**11)
    assert end.position.tolist() == last.tolist()
    assert not end.velocity.any()
