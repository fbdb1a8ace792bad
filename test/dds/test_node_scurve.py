"""
Integration: profile ``scurve`` over DDS (issue 12): goals, via points, preemption, ``~/stop``.

A real generator subprocess streams ``joint_states``; this process reads them. The stream
carries position and velocity only, so acceleration is estimated as the mean over each
interval between consecutive stamps, ``(v[k+1] - v[k]) / (t[k+1] - t[k])``. For any motion
whose jerk stays within ``j_max`` the difference of two consecutive mean accelerations is
at most ``j_max`` times the distance between the two intervals' centres (whatever the
intervals' lengths: a late tick only widens the bound), so the estimate needs no timing
assumption; an acceleration step of ``d`` shows as a difference of about ``d``.
Stamps are the exact times at which the node sampled its plan, so late ticks on a busy
machine change nothing but the spacing.

Units: rad, rad/s, rad/s², rad/s³, s.
"""

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import (
    generator_session,
    JOINTS,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    stamp_ns,
    trajectory_arrays,
    via_message,
)
import numpy as np
import pytest
from traj_gen_ros import min_time, scurve_brake

RATE = 100.0
MAX_JERK = np.array([20.0, 20.0, 20.0, 30.0, 30.0, 30.0])
#: Factor on the jerk bound of consecutive mean accelerations (rounding, not timing).
SAMPLING = 1.05
#: Absolute slack on an acceleration difference (rad/s²): the plan's end is its exact
#: target, Ruckig's end state is within ~1e-9 of it.
ACCELERATION_SLACK = 1e-5


@pytest.fixture(scope='module')
def probe():
    with generator_session() as probe:
        yield probe


@pytest.fixture
def rest(probe):
    """Start every test at rest with profile scurve and known limits."""
    probe.require_parameters(profile='scurve', max_jerk=MAX_JERK.tolist(), rate_hz=RATE)
    return probe.wait_at_rest()


def status_values(status):
    return {kv.key: kv.value for kv in status.values}


def mean_accelerations(times: np.ndarray, velocities: np.ndarray):
    """Centres (s) of the intervals between samples and the mean acceleration over each."""
    return 0.5 * (times[:-1] + times[1:]), np.diff(velocities, axis=0) / np.diff(times)[:, None]


def acceleration_steps(centres: np.ndarray, accelerations: np.ndarray) -> np.ndarray:
    """Return each change of mean acceleration minus what ``MAX_JERK`` allows (> 0: a step)."""
    allowed = MAX_JERK * np.diff(centres)[:, None] * SAMPLING + ACCELERATION_SLACK
    return np.abs(np.diff(accelerations, axis=0)) - allowed


def assert_jerk_limited(probe, start_ns: int):
    """Check the stream from ``start_ns``: within velocity/acceleration limits, jerk bounded."""
    times, positions, velocities = probe.states_between(start_ns, rate_hz=RATE)
    assert len(times) > 10
    assert np.all(np.diff(times) > 0)
    assert np.isfinite(positions).all() and np.isfinite(velocities).all()
    assert np.all(np.abs(velocities) <= MAX_VELOCITY * (1 + 1e-6))
    centres, accelerations = mean_accelerations(times, velocities)
    assert np.all(np.abs(accelerations) <= MAX_ACCELERATION * (1 + 1e-6) + ACCELERATION_SLACK)
    excess = acceleration_steps(centres, accelerations)
    worst = np.unravel_index(int(np.argmax(excess)), excess.shape)
    assert excess[worst] <= 0, (
        f'acceleration step of {JOINTS[worst[1]]} at {centres[worst[0] + 1]:.3f} s: '
        f'{accelerations[worst[0], worst[1]]:.4g} -> {accelerations[worst[0] + 1, worst[1]]:.4g}'
        ' rad/s^2')
    return times, velocities, centres, accelerations


def test_scurve_goal_streams_the_min_time_plan_within_every_limit(probe, rest):
    target = rest + np.array([0.8, -0.5, 0.2, 0.0, 0.6, -1.0])
    status, trajectory = probe.goal(dict(zip(JOINTS, target, strict=True)))
    assert status.level == DiagnosticStatus.OK, status.message
    assert status_values(status)['profile'] == 'scurve'
    plan = min_time(rest, target, MAX_VELOCITY, MAX_ACCELERATION, profile='scurve',
                    max_jerk=MAX_JERK)
    sample_t, positions, velocities, accelerations = trajectory_arrays(trajectory)
    assert sample_t[-1] == pytest.approx(plan.duration, rel=1e-9)
    exp_q, exp_v, exp_a = plan.sample(sample_t)
    assert np.allclose(positions, exp_q, atol=1e-9)
    assert np.allclose(velocities, exp_v, atol=1e-9)
    assert np.allclose(accelerations, exp_a, atol=1e-8)
    start_ns = stamp_ns(trajectory.header.stamp)

    final = probe.wait_at_rest(timeout=plan.duration + 10)
    assert np.allclose(final, target, atol=1e-12)
    before_t, before_q, before_v = probe.states_between(start_ns - int(0.2e9), start_ns - 1)
    assert len(before_t) and np.all(before_q == rest) and not np.any(before_v)
    stream_t, stream_q, stream_v = probe.states_between(start_ns, rate_hz=RATE)
    moving = stream_t < plan.duration
    assert moving.sum() >= 10
    stream_exp_q, stream_exp_v, _ = plan.sample(stream_t[moving])
    assert np.allclose(stream_q[moving], stream_exp_q, atol=1e-9)
    assert np.allclose(stream_v[moving], stream_exp_v, atol=1e-9)
    # From the plan's duration on (min_time's, to 1e-9 above) the stream holds the target:
    # no timing bound on when the samples came, only what they say.
    assert np.count_nonzero(~moving) >= 10
    assert np.all(stream_q[~moving] == target) and not np.any(stream_v[~moving])
    _, _, centres, estimated = assert_jerk_limited(probe, start_ns - int(0.1e9))
    jerk = np.abs(np.diff(estimated, axis=0)) / np.diff(centres)[:, None]
    assert np.max(jerk / MAX_JERK) > 0.5  # the estimate sees the jerk phases


def test_scurve_via_points_pass_at_their_times_and_short_times_are_refused(probe, rest):
    targets = [rest + 0.2, rest + np.array([0.4, 0.1, -0.2, 0.3, 0.0, 0.5])]
    message = via_message(JOINTS, [(targets[0], 1.5), (targets[1], 3.0)])
    status, trajectory = probe.request(message)
    assert status.level == DiagnosticStatus.OK, status.message
    assert status_values(status)['profile'] == 'scurve'
    sample_t, positions, _, _ = trajectory_arrays(trajectory)
    for target, t in zip(targets, (1.5, 3.0), strict=True):
        index = int(np.argmin(np.abs(sample_t - t)))
        assert sample_t[index] == pytest.approx(t, abs=1e-9)
        assert np.allclose(positions[index], target, atol=1e-9)
    start_ns = stamp_ns(trajectory.header.stamp)
    probe.wait_at_rest(timeout=10)
    assert np.allclose(probe.position(), targets[1], atol=1e-12)
    assert_jerk_limited(probe, start_ns - int(0.1e9))

    here = probe.position()
    status, _ = probe.request(via_message(JOINTS, [(here + 1.0, 0.2)]))
    assert status.level == DiagnosticStatus.ERROR
    assert 'smallest duration that works' in status.message, status.message
    assert np.all(probe.position() == here)  # a refused request changes nothing


def test_preemption_by_a_goal_has_no_acceleration_step(probe, rest):
    first_target = rest.copy()
    first_target[0] += 3.0
    first_target[3] -= 2.0
    status, first = probe.goal({'joint_1': first_target[0], 'joint_4': first_target[3]})
    assert status.level == DiagnosticStatus.OK, status.message
    first_start = stamp_ns(first.header.stamp)
    first_plan = min_time(rest, first_target, MAX_VELOCITY, MAX_ACCELERATION,
                          profile='scurve', max_jerk=MAX_JERK)
    # Accelerating (a near max_acceleration from 0.2 s on): a reversal from here needs the
    # largest change of acceleration; any step would show in the stream.
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > first_start + 0.3e9,
                     5.0, 'the first motion under way')
    status, second = probe.goal({'joint_1': rest[0] - 0.2})
    assert status.level == DiagnosticStatus.OK, status.message
    second_start = stamp_ns(second.header.stamp)
    switch = (probe.stream_ns(second_start, RATE) - probe.stream_ns(first_start, RATE)) * 1e-9
    assert switch < first_plan.duration  # it replaced a moving motion
    # The new plan starts at the old plan's state at the switch, acceleration included.
    old_q, old_v, old_a = (value[0] for value in first_plan.sample(switch))
    _, q2, v2, a2 = trajectory_arrays(second)
    assert np.allclose(q2[0], old_q, atol=1e-9)
    assert np.allclose(v2[0], old_v, atol=1e-9)
    assert np.allclose(a2[0], old_a, atol=1e-8), (a2[0], old_a)
    assert abs(v2[0][0]) > 0.3

    probe.wait_at_rest(timeout=15)
    assert probe.position()[0] == pytest.approx(rest[0] - 0.2, abs=1e-12)
    assert probe.position()[3] == pytest.approx(first_target[3], abs=1e-12)  # not named: kept
    _, _, centres, accelerations = assert_jerk_limited(probe, first_start - int(0.05e9))
    # Around the switch in particular (the whole stream is checked above): samples on both
    # sides, and each acceleration change within j_max x interval x SAMPLING.
    switch_rel = switch + 0.05
    around = np.flatnonzero(np.abs(centres[1:] - switch_rel) <= 0.1)
    assert around.size >= 4
    assert np.all(acceleration_steps(centres, accelerations)[around] <= 0)


def test_stop_brakes_with_bounded_jerk_and_holds(probe, rest):
    target = rest + np.array([2.5, 0.0, 0.0, 0.0, 0.0, -2.5])
    status, first = probe.goal({'joint_1': target[0], 'joint_6': target[5]})
    assert status.level == DiagnosticStatus.OK, status.message
    first_start = stamp_ns(first.header.stamp)
    first_plan = min_time(rest, target, MAX_VELOCITY, MAX_ACCELERATION, profile='scurve',
                          max_jerk=MAX_JERK)
    probe.spin_until(lambda: stamp_ns(probe.latest().header.stamp) > first_start + 0.35e9,
                     5.0, 'the motion under way')
    count = len(probe.trajectories)
    response = probe.stop()
    assert response.success, response.message
    probe.spin_until(lambda: len(probe.trajectories) > count, 5.0, 'the stop trajectory')
    stop_plan = probe.trajectories[-1]
    stop_start = stamp_ns(stop_plan.header.stamp)
    t, q, v, a = trajectory_arrays(stop_plan)
    offset = (probe.stream_ns(stop_start, RATE) - probe.stream_ns(first_start, RATE)) * 1e-9
    assert offset < first_plan.duration
    old_q, old_v, old_a = (value[0] for value in first_plan.sample(offset))
    assert np.allclose(q[0], old_q, atol=1e-9) and np.allclose(v[0], old_v, atol=1e-9)
    assert np.allclose(a[0], old_a, atol=1e-8)  # the brake starts from the acceleration
    assert abs(v[0][0]) > 0.3
    expected = scurve_brake(q[0], v[0], a[0], MAX_ACCELERATION, MAX_JERK)
    assert t[-1] == pytest.approx(expected.duration, rel=1e-9)
    assert np.allclose(q, expected.sample(t)[0], atol=1e-9)
    assert np.all(np.abs(a) <= MAX_ACCELERATION * (1 + 1e-9))
    assert np.allclose(v[-1], 0) and np.allclose(a[-1], 0)
    final = probe.wait_at_rest(timeout=10)
    assert final[0] < target[0] - 0.1  # stopped short of the goal
    assert np.allclose(final, q[-1], atol=1e-12)
    assert_jerk_limited(probe, first_start - int(0.05e9))
