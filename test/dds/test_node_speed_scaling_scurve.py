"""
The speed override under ``scurve`` over DDS: the commanded jerk stays within ``max_jerk``.

Profile ``scurve`` with ``max_velocity`` 1 rad/s, ``max_acceleration`` 2 rad/s² and
``max_jerk`` 10 rad/s³; a goal of ``joint_1`` 0 → 2 rad: 2.7 s, jerk phases of 0.2 s at
0–0.2, 0.5–0.7, 2.0–2.2 and 2.5–2.7 s of plan time. Factors change while the plan itself
jerks (its first phase, its braking). Every sample is stamped with the time it was
sampled at (less what late ticks held the schedule back, rebuilt from the stamps), so
divided differences of the published velocities bound the commanded acceleration and
jerk by the mean value theorem, whatever the jitter of the stamps:
``Δv/Δt = a(ξ)`` and ``2 v[t₀, t₁, t₂] = j(ξ)`` (the acceleration is continuous).
"""

from node_harness import held_back_ns, stamp_ns
import numpy as np
import pytest
from speed_probe import GOAL, speed_session

A_MAX, J_MAX = 2.0, 10.0
ARGS = ('-p', 'profile:=scurve', '-p', 'max_velocity:=[1.0]', '-p', 'max_acceleration:=[2.0]',
        '-p', 'max_jerk:=[10.0]', '-p', 'rate_hz:=100.0')
#: Rounding only: velocities are doubles, stamps whole nanoseconds.
TOLERANCE = 1e-6


@pytest.fixture(name='probe')
def session():
    with speed_session(*ARGS) as probe:
        yield probe


def divided_differences(probe, first):
    """
    Return the acceleration ``Δv/Δt``, jerk ``2 v[t₀, t₁, t₂]`` of joint_1 from ``first``.

    Times from whole nanoseconds since the first sample (seconds since 1970 as a double
    would blur a 10 ms step by 2e-5 of it).
    """
    stamps = np.array([stamp_ns(s.header.stamp) for s in probe.states], dtype=np.int64)
    clock = (stamps - held_back_ns(stamps, 100.0))[first:]  # the schedule's time (late ticks)
    states = probe.states[first:]
    times = (clock - clock[0]) * 1e-9
    velocities = np.array([s.velocity[0] for s in states])
    acceleration = np.diff(velocities) / np.diff(times)
    jerk = 2.0 * np.diff(acceleration) / (times[2:] - times[:-2])
    return acceleration, jerk


def test_factors_while_the_plan_jerks_keep_acceleration_and_jerk_within_the_limits(probe):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 0.02, 'the first jerk phase')
    first = probe.factor(0.0)  # while the plan jerks up to speed
    probe.spin_until(lambda: len(probe.states) > first + 40, 5.0, '0.4 s')
    probe.factor(1.0)
    probe.factor(0.3)
    probe.spin_until(lambda: len(probe.states) > first + 120, 5.0, '0.8 s more')
    probe.factor(0.0)
    probe.factor(1.0)
    at_rest = probe.wait_at_rest(20.0)
    times, positions, velocities = probe.samples(first - 1)
    assert at_rest[0] == pytest.approx(GOAL, abs=1e-9)
    assert positions[-1] == pytest.approx(GOAL, abs=1e-9)
    assert np.all(np.isfinite(velocities))
    acceleration, jerk = divided_differences(probe, first - 1)
    assert np.max(np.abs(acceleration)) <= A_MAX * (1.0 + TOLERANCE)
    assert np.max(np.abs(jerk)) <= J_MAX * (1.0 + TOLERANCE), np.max(np.abs(jerk))
    # The factor did act: the motion lasted longer than the plan's 2.7 s.
    assert times[int(np.argmax(velocities == 0.0))] - times[0] > 2.7


def test_a_pause_while_the_plan_jerks_waits_then_holds_still_then_resumes(probe):
    probe.start_goal()
    probe.wait_velocity(lambda v: v >= 0.02, 'the first jerk phase')
    first = probe.factor(0.0)
    paused = probe.wait_velocity(lambda v: v == 0.0, 'the pause', 10.0)
    probe.spin_until(lambda: len(probe.states) > paused + 30, 5.0, '0.3 s of pause')
    held = {tuple(s.position) for s in probe.states[paused:paused + 30]}
    assert len(held) == 1 and 0.0 < next(iter(held))[0] < GOAL
    probe.factor(1.0)
    assert probe.wait_at_rest(20.0)[0] == pytest.approx(GOAL, abs=1e-9)
    times, _, velocities = probe.samples(first - 1)
    acceleration, jerk = divided_differences(probe, first - 1)
    assert np.max(np.abs(acceleration)) <= A_MAX * (1.0 + TOLERANCE)
    assert np.max(np.abs(jerk)) <= J_MAX * (1.0 + TOLERANCE), np.max(np.abs(jerk))
