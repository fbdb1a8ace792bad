"""Integration: bad requests and parameters are refused with a reason; motion goes on."""

import math
import re

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    generator_session,
    JOINTS,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
from sensor_msgs.msg import JointState


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        yield probe


def goal(names, positions):
    return JointState(name=names, position=[float(p) for p in positions])


BAD_REQUESTS = {
    'unknown joint': (goal(['joint_1', 'elbow'], [0.1, 0.2]),
                      r"unknown joint 'elbow'; known joints: \['joint_1'"),
    'duplicate joint': (goal(['joint_1', 'joint_1'], [0.1, 0.2]),
                        "names joint 'joint_1' more than once"),
    'no joint': (goal([], []), 'goal names no joint'),
    'lengths disagree': (goal(['joint_1', 'joint_2'], [0.1]),
                         'goal has 2 names but 1 positions'),
    'nan goal': (goal(['joint_3'], [math.nan]),
                 "goal position for joint 'joint_3' is nan: every value must be finite"),
    'inf goal': (goal(['joint_3'], [math.inf]), "joint 'joint_3' is inf"),
    'via unknown joint': (via_message(['wrist'], [([0.1], 1.0)]), "unknown joint 'wrist'"),
    'via no points': (via_message(['joint_1'], []), 'via_points has no points'),
    'via point length': (via_message(['joint_1', 'joint_2'], [([0.1], 1.0)]),
                         'point 0 has 1 positions but joint_names has 2'),
    'via nan': (via_message(['joint_2'], [([0.1], 1.0), ([math.nan], 2.0)]),
                "point 1 position for joint 'joint_2' is nan"),
    'via inf velocity': (via_message(['joint_2'], [([0.1], 1.0, [math.inf])]),
                         "point 0 velocity for joint 'joint_2' is inf"),
    'times not increasing': (via_message(['joint_1'], [([0.1], 1.0), ([0.2], 1.0)]),
                             r'strictly increasing: point 1 \(1 s\) is not after point 0'),
    'times decreasing': (via_message(['joint_1'], [([0.1], 2.0), ([0.2], 1.5)]),
                         'strictly increasing'),
    'velocities on some points': (
        via_message(['joint_1'], [([0.1], 1.0, [0.1]), ([0.2], 2.0)]),
        'velocities are given for 1 of 2 points: give them for every point or for none'),
    'velocity length': (via_message(['joint_1', 'joint_2'], [([0.1, 0.1], 1.0, [0.0])]),
                        'point 0 has 1 velocities but joint_names has 2'),
    'moving at the end': (via_message(['joint_1'], [([0.1], 1.0, [0.5])]),
                          'the last point must have zero velocity'),
    'first point at t=0 elsewhere': (
        via_message(['joint_4'], [([1.0], 0.0), ([1.1], 1.0)]),
        "point 0 has time_from_start 0 but joint 'joint_4' is at"),
    # The largest excess is named: here acceleration (x4.3) before velocity (x2.25).
    'limit': (via_message(['joint_2'], [([3.0], 1.0)]),
              r"joint 'joint_2' would reach acceleration .* above max_acceleration 4 rad/s\^2"
              r'.*the minimum feasible duration is'),
}


def test_every_refusal_is_specific_and_leaves_the_motion_untouched(probe):
    probe.wait_at_rest()
    status, moving = probe.goal({'joint_1': probe.position()[0] + 1.5})
    assert status.level == DiagnosticStatus.OK
    start = stamp_ns(moving.header.stamp)
    trajectories = len(probe.trajectories)
    for label, (message, reason) in BAD_REQUESTS.items():
        status, trajectory = probe.request(message)
        assert status.level == DiagnosticStatus.ERROR, label
        assert status.name == '/trajectory_generator'
        assert re.search(reason, status.message), (label, status.message)
        assert not re.search(r'joint \d', status.message), status.message  # ROS names only
        assert trajectory is None
    assert len(probe.trajectories) == trajectories  # nothing new was planned
    # The stream followed the original plan all along, to the end.
    t, q, _, _ = trajectory_arrays(moving)
    probe.wait_at_rest(timeout=10)
    stream_t, stream_q, _ = probe.states_between(start, rate_hz=100.0)
    assert stream_t[-1] > t[-1]  # the refusals happened while it moved
    for joint in range(6):
        assert np.allclose(stream_q[:, joint], np.interp(stream_t, t, q[:, joint]), atol=2e-4)


def test_minimum_feasible_duration_is_feasible_and_tight(probe):
    start = probe.wait_at_rest()
    status, _ = probe.request(via_message(['joint_5'], [([start[4] + 0.3], 0.2)]))
    assert status.level == DiagnosticStatus.ERROR
    assert re.search(r"joint 'joint_5' would reach acceleration .* above max_acceleration "
                     r'6 rad/s\^2.*minimum feasible duration is', status.message), status.message
    target = start[1] + 1.0
    status, _ = probe.request(via_message(['joint_2'], [([target], 0.5)]))
    found = re.search(r'minimum feasible duration is ([0-9.]+) s', status.message)
    assert status.level == DiagnosticStatus.ERROR and found, status.message
    minimum = float(found.group(1))
    too_short, _ = probe.request(via_message(['joint_2'], [([target], minimum * 0.98)]))
    assert too_short.level == DiagnosticStatus.ERROR
    ok, trajectory = probe.request(via_message(['joint_2'], [([target], minimum * 1.01)]))
    assert ok.level == DiagnosticStatus.OK, ok.message
    assert trajectory_arrays(trajectory)[0][-1] == pytest.approx(minimum * 1.01, abs=1e-6)
    probe.wait_at_rest()


@pytest.mark.parametrize('profile, points, reason', [
    # The reproducer: the core says `lspb: joint 2: acceleration 4 is too low`.
    ('lspb', [(2.0, 0.5)], r"lspb: joint 'joint_3': acceleration 4 is too low to move"),
    ('lspb', [(1.0, 0.5), (-1.0, 0.7), (0.0, 5.0)],
     r"lspb_via: joint 'joint_3': .* with acceleration 4"),
    ('quintic', [(1.0, 0.1)], r"joint 'joint_3' would reach acceleration"),
])
def test_refusals_name_joints_by_their_ros_names(probe, profile, points, reason):
    probe.require_parameters(profile=profile)
    try:
        start = probe.wait_at_rest()[2]
        status, _ = probe.request(via_message(['joint_3'], [
            ([start + offset], time) for offset, time in points]))
    finally:
        probe.require_parameters(profile='quintic')
    assert status.level == DiagnosticStatus.ERROR
    assert re.search(reason, status.message), status.message
    assert not re.search(r'joint \d', status.message), status.message


@pytest.mark.parametrize('values, reason', [
    ({'profile': 'septic'}, "profile must be one of lspb, cubic, quintic, scurve; got 'septic'"),
    ({'via_velocities': 'smooth'}, 'via_velocities must be one of heuristic, continuous'),
    ({'max_velocity': -1.0}, "max_velocity must be finite and > 0; joint 'joint_1' has -1.0"),
    ({'max_velocity': [1.0, 2.0]}, 'max_velocity has 2 values but there are 6 joints'),
    ({'max_acceleration': 0.0},
     "max_acceleration must be finite and > 0; joint 'joint_1' has 0.0"),
    ({'max_acceleration': 'fast'}, "Wrong parameter type, expected 'Type.DOUBLE_ARRAY'"),
    ({'lspb_acceleration': 10.0}, 'lspb_acceleration for joint_1 is 10 rad/s.2, above '
                                  'max_acceleration 4'),
    ({'rate_hz': 0.0}, ''),
    ({'rate_hz': 5000}, r'rate_hz out of range Min: 1.0, Max: 1000.0'),
    ({'joints': ['a', 'b']}, 'read-only'),
])
def test_invalid_parameters_are_refused_with_a_reason(probe, values, reason):
    results = probe.set_parameters(**values)
    assert len(results) == 1 and not results[0].successful
    assert re.search(reason, results[0].reason), results[0].reason


def test_parameters_change_at_run_time(probe):
    probe.wait_at_rest()
    probe.require_parameters(rate_hz=50.0)
    try:
        first = len(probe.states)
        probe.spin_until(lambda: len(probe.states) > first + 25, 5, 'samples at 50 Hz')
        stamps = np.array([stamp_ns(s.header.stamp) for s in probe.states[first + 2:]]) * 1e-9
        assert np.median(np.diff(stamps)) == pytest.approx(0.02, rel=0.05)
        probe.require_parameters(profile='lspb', max_velocity=0.5, lspb_acceleration=1.0)
        status, trajectory = probe.goal({'joint_6': probe.position()[5] + 1.0})
        assert status.level == DiagnosticStatus.OK and 'profile=lspb' in status.message
        t, _, v, a = trajectory_arrays(trajectory)
        assert np.allclose(np.diff(t)[:-1], 0.02)  # sampled at the new rate
        assert np.abs(v).max() == pytest.approx(0.5, rel=1e-9)  # cruises at the new limit
        assert np.abs(a[:-1, 5]).max() == pytest.approx(1.0, rel=1e-9)  # blends at 1 rad/s^2
        probe.wait_at_rest(timeout=10)
    finally:
        probe.require_parameters(rate_hz=100.0, profile='quintic', max_velocity=[
            2.0, 2.0, 2.0, 3.0, 3.0, 3.0], lspb_acceleration=0.0)
    assert list(probe.latest().name) == JOINTS


def test_malformed_via_points_bytes_are_refused_and_the_node_goes_on(probe):
    start = probe.wait_at_rest()
    count = len(probe.statuses)
    probe.via_pub.publish(b'\x00\x01\x00\x00' + b'\xff' * 21)  # not a JointTrajectory
    probe.spin_until(lambda: len(probe.statuses) > count, 10.0, 'an answer')
    status = probe.statuses[count]
    assert status.level == DiagnosticStatus.ERROR and 'via_points refused' in status.message
    ok, _ = probe.goal({'joint_3': start[2] + 0.1})
    assert ok.level == DiagnosticStatus.OK, ok.message
    assert probe.wait_at_rest()[2] == pytest.approx(start[2] + 0.1, abs=1e-12)
