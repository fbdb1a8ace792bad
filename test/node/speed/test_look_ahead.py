"""
The speed ramp's look-ahead (``node/speed/look_ahead.py``): exact plan ranges, sound envelopes.

The ranges of a plan's ``v``, ``a``, ``j`` over an interval are checked against dense
samples (never narrower, and attained); the one-range envelope of a step and its brake
against the chunked rows it stands for (it holds every one of them), and the one-row
check in floats against the array check it shortcuts.
"""

from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from traj_gen_ros import quintic_via
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.core.trajectory import state_at
from traj_gen_ros.node.speed.look_ahead import _rows, _within, envelope, keeps_limits
from traj_gen_ros.node.speed.plan_window import bernstein_range, jerk_at, PlanWindow

A_MAX = np.array([2.0, 2.0, 1.5])
J_MAX = np.array([10.0, 10.0, 8.0])
#: scurve from rest to (3, -1.5, 0.4) rad, synchronised: jerk phases, cruise, braking.
PLAN = min_time(np.zeros(3), np.array([3.0, -1.5, 0.4]), np.array([1.0, 1.0, 0.8]), A_MAX,
                'scurve', max_jerk=J_MAX)
WINDOW = PlanWindow(PLAN)
instant = st.floats(0.0, PLAN.duration + 0.3)  # plan time: never before its start


def sampled(start: float, end: float) -> np.ndarray:
    """
    Per joint, the min/max of v, a, j on 2001 samples of [start, end] (0 past the end).

    The jerk (a step at a breakpoint) is sampled between the samples, inside the interval.
    """
    times = np.linspace(start, end, 2001)
    between = (times[:-1] + times[1:]) / 2.0 if end > start else times[:-1]
    rows = []
    for t, t_jerk in zip(times, np.append(between, between[-1]), strict=True):
        _, v, a = state_at(PLAN, min(t, PLAN.duration))
        j = jerk_at(PLAN, t_jerk) if t_jerk < PLAN.duration else np.zeros(3)
        rows.append(np.concatenate([v, a, j]) if t <= PLAN.duration else np.zeros(9))
    rows = np.array(rows).reshape(len(times), 3, 3)  # (samples, quantity, joint)
    return np.stack([rows.min(axis=0), rows.max(axis=0)], axis=1)  # (quantity, lo/hi, joint)


def test_the_plan_has_jerk_phases_cruise_and_braking():
    velocity, acceleration = PLAN.peaks()[:2]
    assert velocity[0] == pytest.approx(1.0, rel=1e-9)  # the binding joint cruises
    assert np.all(velocity <= [1.0, 1.0, 0.8]) and np.all(velocity > 0.1)  # in sync
    assert np.all(acceleration <= A_MAX * (1 + 1e-9))
    assert PLAN.piece_count >= 7 and PLAN.degree == 3


@settings(max_examples=200, deadline=None)
@given(instant, st.floats(0.0, 1.5))
def test_joint_ranges_hold_every_sample_and_are_attained(start, length):
    end = start + length
    exact = np.array(WINDOW.joint_ranges(start, end))  # (joints, 6)
    arrays = np.array([r[0] for r in WINDOW.ranges(np.array([start]), np.array([end]))])
    # Floats and arrays agree on v and a; on j the arrays also take the piece that starts
    # at the interval's end (a step of j at one instant: wider, never narrower).
    assert np.allclose(exact.T[:4], arrays[:4], rtol=0, atol=1e-12)
    assert np.all(arrays[4] <= exact.T[4]) and np.all(arrays[5] >= exact.T[5])
    samples = sampled(start, end)
    for quantity in range(3):
        low, high = exact[:, 2 * quantity], exact[:, 2 * quantity + 1]
        seen_low, seen_high = samples[quantity]
        assert np.all(low <= seen_low + 1e-9) and np.all(high >= seen_high - 1e-9)
        if quantity < 2:  # v and a are continuous: the extremes are attained
            assert low == pytest.approx(seen_low, abs=2e-3 * (1 + length))
            assert high == pytest.approx(seen_high, abs=2e-3 * (1 + length))


@settings(max_examples=300, deadline=None)
@given(st.floats(0.0, 3.5), st.floats(0.0, 1.0), st.floats(-3.0, 3.0),
       st.floats(-400.0, 400.0, allow_subnormal=False), st.floats(1e-2, 400.0))
def test_the_envelope_holds_every_chunk_of_the_step_and_brake(tau, factor, rate, c, k):
    h = 1e-3
    rows, good = _rows(tau, factor, rate, np.array([c]), np.array([k]), h)
    row = envelope(tau, factor, rate, c, k, h)
    assert (row is not None) == bool(good[0])
    if row is None:
        return
    chunks = rows[0]
    if row[0] < -1e-9:  # f below 0 (τ would run back): refused both ways (SLACK)
        assert not keeps_limits(WINDOW, row, A_MAX.tolist(), J_MAX.tolist())
        assert not _within(WINDOW, chunks, A_MAX, J_MAX).all()
        return
    middle = np.arange(len(chunks)) % (len(chunks) - 1) != 0
    chunks = chunks[~(middle & (chunks[:, 2] == chunks[:, 3]))]  # no brake steps: no time
    scale = 1e-9 * (1.0 + np.abs(chunks).max())
    assert np.all(chunks[:, 0::2] >= np.array(row[0::2]) - scale)  # lows
    assert np.all(chunks[:, 1::2] <= np.array(row[1::2]) + scale)  # highs
    # The whole range passing means every chunk passes (so no feasible step is lost
    # by asking the envelope first: it only ever answers yes where the chunks do).
    if keeps_limits(WINDOW, row, A_MAX.tolist(), J_MAX.tolist()):
        assert _within(WINDOW, chunks, A_MAX, J_MAX).all()
    assert keeps_limits(WINDOW, row, A_MAX.tolist(), J_MAX.tolist()) == \
        bool(_within(WINDOW, np.array([row]), A_MAX, J_MAX)[0])


def test_a_brake_through_the_plans_jerk_phase_is_refused_and_one_in_its_cruise_kept():
    """Braking ḟ from -1/s while the plan's own jerk is at +max: the sum exceeds it."""
    h = 1e-3
    k = 0.95 * 10.0  # K = σ j_max / |v| at 1 rad/s
    in_jerk_phase = envelope(0.05, 1.0, -0.5, 0.0, k, h)
    assert not keeps_limits(WINDOW, in_jerk_phase, A_MAX.tolist(), J_MAX.tolist())
    in_cruise = envelope(1.5, 1.0, -0.5, 0.0, k, h)
    assert keeps_limits(WINDOW, in_cruise, A_MAX.tolist(), J_MAX.tolist())


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-50.0, 50.0), min_size=1, max_size=5), st.floats(0.0, 2.0),
       st.floats(0.0, 2.0))
def test_bernstein_range_holds_the_polynomial_and_its_ends(coefficients, start, width):
    low, high = bernstein_range(coefficients, start, width)
    u = np.linspace(start, start + width, 401)
    values = np.polynomial.polynomial.polyval(u, coefficients)
    scale = 1e-9 * (1.0 + np.abs(values).max())
    assert low <= values.min() + scale and high >= values.max() - scale
    assert low <= values[0] + scale and high >= values[-1] - scale


def test_quintic_ranges_are_bounds_that_hold_every_sample():
    """An action goal's quintics: joint_ranges bounds v, a, j over any interval."""
    plan = quintic_via(np.array([[0, 0], [0.3, -0.2], [0.9, -0.5], [1.6, -0.6]], dtype=float),
                       np.full(3, 0.6))
    window = PlanWindow(plan)
    assert not window.cubic
    for start, end in [(0.0, 0.05), (0.1, 0.7), (0.55, 0.65), (1.0, 1.9), (1.7, 2.0)]:
        bounds = np.array(window.joint_ranges(start, end))  # (joints, 6)
        times = np.linspace(start, min(end, plan.duration), 301)
        states = [state_at(plan, t) for t in times]
        v = np.array([s[1] for s in states])
        a = np.array([s[2] for s in states])
        j = np.array([jerk_at(plan, t) for t in times[:-1] + 1e-9])
        for column, samples in enumerate((v, a, j)):
            assert np.all(bounds[:, 2 * column] <= samples.min(axis=0) + 1e-9)
            assert np.all(bounds[:, 2 * column + 1] >= samples.max(axis=0) - 1e-9)
