"""ROS-free request handling: parameter checks, request parsing, plans, schedule."""

import math

from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros import limit_violation, min_time, scurve_brake
from traj_gen_ros.node.messages.parsing import (
    GoalRequest,
    parse_goal,
    parse_via,
    RequestError,
)
from traj_gen_ros.node.messages.wire import peek_via_points, read_goal, read_joint_state
from traj_gen_ros.node.planning.motion import held, State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop
from traj_gen_ros.node.planning.sampling import sample_grid, sample_motion
from traj_gen_ros.node.planning.via_path import via_points
from traj_gen_ros.node.settings.config import make_config
from traj_gen_ros.node.stream.schedule import Schedule
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

JOINTS = ['a', 'b', 'c']


def config(**changes):
    values = {'joints': JOINTS, 'rate_hz': 100.0, 'profile': 'quintic',
              'via_velocities': 'heuristic', 'max_velocity': [1.0, 2.0, 3.0],
              'max_acceleration': 4.0, 'lspb_acceleration': 0.0}
    values.update(changes)
    return make_config(**values)


def rest(position=(0.0, 0.0, 0.0)):
    position = np.array(position, dtype=float)
    return State(position, np.zeros(3), np.zeros(3))


def test_config_broadcasts_and_replaces_zero_lspb_acceleration():
    cfg = config(lspb_acceleration=[0.0, 1.0, 0.0])
    assert cfg.max_acceleration.tolist() == [4.0, 4.0, 4.0]
    assert cfg.lspb_acceleration.tolist() == [4.0, 1.0, 4.0]
    assert cfg.profile_acceleration.tolist() == [4.0, 4.0, 4.0]
    assert config(profile='lspb', lspb_acceleration=2).profile_acceleration.tolist() == [2.0] * 3


@pytest.mark.parametrize('changes, reason', [
    ({'joints': []}, 'joints is empty'),
    ({'joints': ['a', 'a']}, r"joints lists \['a'\] more than once"),
    ({'rate_hz': True}, 'rate_hz must be a number'),
    ({'max_velocity': [1.0, math.nan, 1.0]},
     "max_velocity must be finite and > 0; joint 'b' has nan"),
    ({'max_acceleration': [1.0, 2.0]}, 'has 2 values but there are 3 joints'),
    ({'lspb_acceleration': -1.0}, ('lspb_acceleration must be finite and >= 0; '
                                   "joint 'a' has -1.0")),
    ({'max_jerk': 0.0}, "max_jerk must be finite and > 0; joint 'a' has 0.0"),
    ({'max_jerk': [1.0, -2.0, 1.0]}, "max_jerk must be finite and > 0; joint 'b' has -2.0"),
    ({'profile': 'septic'}, 'profile must be one of lspb, cubic, quintic, scurve'),
])
def test_config_errors_name_the_parameter(changes, reason):
    with pytest.raises(ValueError, match=reason):
        config(**changes)


def test_parse_goal_and_via_errors():
    assert parse_goal(JOINTS, ['c', 'a'], [1.0, 2.0]).joints.tolist() == [2, 0]
    with pytest.raises(RequestError, match="unknown joint 'x'; known joints"):
        parse_goal(JOINTS, ['x'], [1.0])
    with pytest.raises(RequestError, match='strictly increasing: point 2'):
        parse_via(JOINTS, ['a'], [([0.1], [], [], 1.0), ([0.2], [], [], 2.0),
                                  ([0.3], [], [], 2.0)])
    with pytest.raises(RequestError, match='point 0 has time_from_start -1.0 s'):
        parse_via(JOINTS, ['a'], [([0.1], [], [], -1.0)])
    with pytest.raises(RequestError, match='accelerations are given without velocities'):
        parse_via(JOINTS, ['a'], [([0.1], [], [0.0], 1.0)])
    assert parse_via(JOINTS, ['a'], [([0.1], [], [], 0.0), ([0.2], [], [], 0.0)]).auto_timed


def test_via_points_rules():
    state = State(np.array([0.0, 1.0, 2.0]), np.array([0.5, 0, 0]), np.zeros(3))
    hold = np.array([9.0, 1.0, 2.0])
    # time > 0: the setpoint is prepended; unnamed joints go to ``hold``.
    request = parse_via(JOINTS, ['b'], [([1.5], [], [], 1.0)])
    points, times, _, _ = via_points(JOINTS, state, hold, request)
    assert points.tolist() == [[0.0, 1.0, 2.0], [9.0, 1.5, 2.0]] and times.tolist() == [0, 1]
    # time 0 at the current position: it is the start.
    request = parse_via(JOINTS, ['b'], [([1.0], [], [], 0.0), ([1.5], [], [], 1.0)])
    points, times, _, _ = via_points(JOINTS, state, hold, request)
    assert len(points) == 2 and times.tolist() == [0, 1]
    # time 0 elsewhere: refused, naming the joint.
    request = parse_via(JOINTS, ['b'], [([1.2], [], [], 0.0), ([1.5], [], [], 1.0)])
    with pytest.raises(RequestError, match="joint 'b' is at 1 rad, not 1.2"):
        via_points(JOINTS, state, hold, request)


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


def test_peek_via_points_reads_frame_id_and_count_off_the_wire():
    message = JointTrajectory(joint_names=['a', 'bb', 'ccc'],
                              points=[JointTrajectoryPoint(positions=[1.0])] * 7)
    message.header.frame_id = 'tag-17'
    data = serialize_message(message)
    assert peek_via_points(data) == ('tag-17', 7)
    assert peek_via_points(data[:12]) == ('', 0)  # truncated: deserialising refuses it


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=12), st.lists(st.text(max_size=9), max_size=7),
       st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=7),
       st.lists(st.floats(-10.0, 10.0), max_size=3), st.integers(0, 2 ** 31 - 1))
def test_read_goal_reads_what_rclpy_serialises(frame_id, names, positions, velocities, sec):
    message = JointState(name=names, position=positions, velocity=velocities)
    message.header.frame_id = frame_id
    message.header.stamp.sec = sec
    data = serialize_message(message)
    expected = deserialize_message(data, JointState)  # rclpy's own reading ('a\0b' is 'a')
    read_frame, read_names, read_positions = read_goal(data)
    assert (read_frame, read_names) == (expected.header.frame_id, list(expected.name))
    np.testing.assert_array_equal(read_positions, np.array(expected.position, dtype=float))
    assert read_positions.dtype == np.float64 and read_positions.flags.writeable
    *same, read_velocities = read_joint_state(data)  # the measured state's: and velocities
    assert same[:2] == [read_frame, read_names]
    np.testing.assert_array_equal(same[2], read_positions)
    np.testing.assert_array_equal(read_velocities, np.array(expected.velocity, dtype=float))


def test_read_goal_leaves_what_it_cannot_read_to_rclpy():
    message = JointState(name=['a', 'b'], position=[1.0, 2.0])
    data = serialize_message(message)
    assert read_goal(data[:-24]) is None  # cut inside the positions
    assert read_goal(data[:14]) is None  # cut inside a name
    moving = serialize_message(JointState(name=['a', 'b'], position=[1.0, 2.0],
                                          velocity=[3.0, 4.0]))
    assert read_joint_state(moving)[3].tolist() == [3.0, 4.0]
    assert read_joint_state(moving[:-16]) is None  # cut inside the velocities
    assert read_goal(b'\x00\x00' + data[2:]) is None  # big-endian CDR: rclpy reads it
    corrupt = bytearray(data)
    corrupt[20:22] = b'\xff\xfe'  # not UTF-8 inside the first name
    assert read_goal(bytes(corrupt)) is None


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
