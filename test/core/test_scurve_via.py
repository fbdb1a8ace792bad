"""Jerk-limited paths through via points (core.jerk_limited.path), Ruckig as the oracle."""

import math
import re

import core_helpers as helpers
from hypothesis import example, given, settings
import hypothesis.strategies as st
import numpy as np
import pytest
from ruckig_oracle import resolution, ruckig_duration
from traj_gen_ros.core.jerk_limited.path import scurve_via, scurve_via_durations
from traj_gen_ros.core.polynomial import heuristic_velocities

FAST = settings(max_examples=40, deadline=None)
TOL = 1e-9
# Ruckig's own precision at a segment's end (profile.hpp: p_precision, v_precision 1e-8,
# a_precision 1e-10, absolute); each segment then starts exactly at its via point.
RUCKIG_PRECISION = np.array([1e-8, 1e-8, 1e-10])
TINY = 4.45572216e-262  # a step far below Ruckig's precision, which it takes for none
UNIT = np.ones(1)


@st.composite
def paths(draw):
    """Draw ``(points (points, joints), vmax, amax, jmax)``, limits across four decades."""
    count, joints = draw(st.integers(3, 5)), draw(st.integers(1, 3))
    flat = draw(st.lists(helpers.positions, min_size=count * joints, max_size=count * joints))
    exponents = [np.array(draw(st.lists(st.floats(-2.0, 2.0), min_size=joints,
                                        max_size=joints))) for _ in range(3)]
    return (np.array(flat).reshape(count, joints),) + tuple(10.0**e for e in exponents)


def check_path(plan, points, durations, vmax, amax, jmax):
    """Through every point at its time, within the limits, continuous to Ruckig's precision."""
    times = np.concatenate([[0.0], np.cumsum(durations)])
    assert plan.duration == pytest.approx(times[-1], rel=1e-15)
    assert plan.piece_count >= 7 * len(durations)  # more where a fallback composed one
    position, velocity, acceleration = plan.sample(times)
    reach = max(1.0, float(np.max(np.abs(points))))
    acceleration_slack, velocity_slack = resolution(plan, jmax, amax)  # see test_scurve
    assert np.all(np.abs(position[:-1] - points[:-1]) <= TOL * reach)
    assert np.all(np.abs(position[-1] - points[-1]) <= RUCKIG_PRECISION[0] + TOL * reach)
    assert np.all(np.abs(acceleration) <= RUCKIG_PRECISION[2] + TOL * amax + acceleration_slack)
    peak_velocity, peak_acceleration = helpers.reference_peaks(plan)
    assert np.all(peak_velocity <= vmax * (1 + TOL) + velocity_slack), (peak_velocity, vmax)
    assert np.all(peak_acceleration <= amax * (1 + TOL) + acceleration_slack), (
        peak_acceleration, amax)
    assert np.all(plan.peak_jerk() <= jmax * (1 + TOL))
    jumps, _ = helpers.boundary_jumps(plan)
    scale = np.stack([np.full_like(vmax, reach), vmax, amax])[:, None, :]
    slack = np.stack([np.zeros_like(vmax), velocity_slack, acceleration_slack])[:, None, :]
    assert np.all(np.abs(jumps) <= RUCKIG_PRECISION[:, None, None] + TOL * scale + slack), jumps


@FAST
@given(paths())
# A tiny step took the sign of its neighbour's slope: 52016 s for 1 rad, and not tight
# (the backend refused a duration that works). First, in the middle, at the end, in one
# of three joints:
@example((np.array([[TINY], [0.0], [-1.0]]), UNIT, UNIT, UNIT))
@example((np.array([[-1.0], [0.0], [TINY], [1.0]]), UNIT, UNIT, UNIT))
@example((np.array([[-2.0], [-1.0], [0.0], [TINY]]), UNIT, UNIT, UNIT))
@example((np.array([[0.0, -2.0, 0.0], [0.5, -1.0, 0.1], [1.0, 0.0, 0.2], [1.5, TINY, 0.3],
                    [2.0, 1.0, 0.4]]), np.array([1.0, 1.0, 2.0]), np.array([1.0, 1.0, 2.0]),
          np.array([1.0, 1.0, 2.0])))
def test_heuristic_path_from_its_durations_is_feasible_and_tight(path):
    points, vmax, amax, jmax = path
    try:
        durations = scurve_via_durations(points, vmax, amax, jmax)
    except ValueError as error:  # no step above Ruckig's precision (1e-8): nothing to move
        assert 'nothing to move' in str(error)
        assert np.max(np.abs(np.diff(points, axis=0))) < 1e-8
        return
    plan = scurve_via(points, durations, vmax, amax, jmax)
    check_path(plan, points, durations, vmax, amax, jmax)
    # Craig's rule, a step within Ruckig's precision counting as none (a stop).
    assert np.allclose(plan.sample(np.concatenate([[0.0], np.cumsum(durations)]))[1],
                       heuristic_velocities(points, durations, resolution=1e-8), rtol=0.0,
                       atol=1e-8 + TOL * vmax.max())
    # The common factor is the smallest that works: a little less fails.
    with pytest.raises(ValueError, match=r'segment \d'):
        scurve_via(points, durations * (1.0 - 1e-6), vmax, amax, jmax)
    # Feasible factors form one interval: longer ones all work.
    check_path(scurve_via(points, durations * 1.7, vmax, amax, jmax), points,
               durations * 1.7, vmax, amax, jmax)


@FAST
@given(paths(), st.data())
def test_given_velocities_give_ruckigs_exact_segment_times(path, data):
    points, vmax, amax, jmax = path
    fractions = data.draw(st.lists(st.floats(-1.0, 1.0), min_size=points.size,
                                   max_size=points.size))
    velocities = np.array(fractions).reshape(points.shape) * vmax
    try:
        durations = scurve_via_durations(points, vmax, amax, jmax, velocities)
    except ValueError as error:  # nothing above Ruckig's precision (1e-8) moves
        assert 'the path never moves' in str(error)
        assert np.max(np.abs(np.diff(points, axis=0))) < 1e-8
        assert np.max(np.abs(velocities)) < 1e-8
        return
    zero = np.zeros(points.shape[1])
    for segment, duration in enumerate(durations):
        expected, _ = ruckig_duration(points[segment], points[segment + 1], velocities[segment],
                                      zero, vmax, amax, jmax, vf=velocities[segment + 1])
        if expected is None:  # Ruckig alone refuses (-101): a long segment
            assert duration > 7.6e3
        elif not math.isnan(expected):
            assert duration == pytest.approx(expected or 1e-9 * durations.max(), rel=TOL)
    plan = scurve_via(points, durations, vmax, amax, jmax, velocities)
    check_path(plan, points, durations, vmax, amax, jmax)
    _, velocity, _ = plan.sample(np.concatenate([[0.0], np.cumsum(durations)]))
    assert np.all(np.abs(velocity[:-1] - velocities[:-1]) <= TOL * vmax)
    assert np.all(np.abs(velocity[-1] - velocities[-1]) <= 1e-8 + TOL * vmax)


@pytest.mark.parametrize('step', [0.0, 5e-324, TINY, 1e-12, 1e-9])
def test_a_step_within_ruckigs_precision_is_a_stop(step):
    # 1 rad rest to rest at unit limits takes T = 4 (1/2)^(1/3) s (jerk-limited only:
    # peak velocity (1/2)^(2/3), acceleration (1/2)^(1/3)); a step d that Ruckig resolves
    # 4 (d/2)^(1/3) s, one it takes for none 0 (floored to 1e-6 T). A step within Ruckig's
    # precision (1e-8) is no motion: point 1 is a stop, as for an exact repeat, and no
    # factor stretches the path. Before: 16384 T for 1e-262 rad, 298 T for 1e-12 rad.
    points = np.array([[step], [0.0], [-1.0]])
    durations = scurve_via_durations(points, 1.0, 1.0, 1.0)
    whole = 4.0 * 0.5 ** (1.0 / 3.0)
    first = 4.0 * (0.5 * step) ** (1.0 / 3.0) if step > 1e-15 else 1e-6 * whole
    np.testing.assert_allclose(durations, [first, whole], rtol=1e-9)
    plan = scurve_via(points, durations, 1.0, 1.0, 1.0)
    check_path(plan, points, durations, UNIT, UNIT, UNIT)
    _, velocity, _ = plan.sample(np.concatenate([[0.0], np.cumsum(durations)]))
    assert np.all(velocity[:2] == 0.0)
    with pytest.raises(ValueError, match=r'segment \d'):
        scurve_via(points, durations * (1.0 - 1e-6), 1.0, 1.0, 1.0)
    # Given velocities are kept as given: zero, the tiny segment takes any time (a short
    # one, 1e-9 of the longest); -0.3 rad/s at point 1 Ruckig's exact time to reach it.
    given = scurve_via_durations(points, 1.0, 1.0, 1.0, np.zeros((3, 1)))
    np.testing.assert_allclose(given, [1e-9 * whole if step < 1e-15 else first, whole],
                               rtol=1e-9)
    moving = np.array([[0.0], [-0.3], [0.0]])
    given = scurve_via_durations(points, 1.0, 1.0, 1.0, moving)
    zero = np.zeros(1)
    for segment in range(2):
        expected, _ = ruckig_duration(points[segment], points[segment + 1], moving[segment],
                                      zero, UNIT, UNIT, UNIT, vf=moving[segment + 1])
        assert given[segment] == pytest.approx(expected, rel=TOL)
    check_path(scurve_via(points, given, 1.0, 1.0, 1.0, moving), points, given, UNIT, UNIT,
               UNIT)


def test_too_short_segment_is_named_with_its_minimum():
    points = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, -1.0], [1.5, -1.0]])
    velocities = np.array([[0.0, 0.0], [0.5, 0.0], [0.2, -0.5], [0.0, 0.0]])
    durations = scurve_via_durations(points, 1.0, 2.0, 5.0, velocities)
    shortest, _ = ruckig_duration(points[1], points[2], velocities[1], [0, 0], [1, 1],
                                  [2, 2], [5, 5], vf=velocities[2])
    assert durations[1] == pytest.approx(shortest, rel=TOL)
    short = durations.copy()
    short[1] *= 0.9
    with pytest.raises(ValueError, match=r'segment 1 \(points 1 to 2\)') as refusal:
        scurve_via(points, short, 1.0, 2.0, 5.0, velocities)
    named = float(re.search(r'minimum duration is ([0-9.e+-]+) s', str(refusal.value))[1])
    assert shortest <= named <= shortest * (1 + 1e-8)
    short[1] = named
    check_path(scurve_via(points, short, 1.0, 2.0, 5.0, velocities), points, short,
               np.ones(2), np.full(2, 2.0), np.full(2, 5.0))


def test_heuristic_refusal_names_the_segment_and_a_duration_that_works():
    points = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, -1.0], [1.5, -1.0]])
    durations = scurve_via_durations(points, 1.0, 2.0, 5.0)
    for segment in range(3):
        short = durations.copy()
        short[segment] *= 0.6
        with pytest.raises(ValueError, match=rf'segment {segment} ') as refusal:
            scurve_via(points, short, 1.0, 2.0, 5.0)
        found = re.search(r'works for (?:it|segment \d) is ([0-9.e+-]+) s', str(refusal.value))
        short[segment] = float(found[1])
        plan = scurve_via(points, short, 1.0, 2.0, 5.0)
        check_path(plan, points, short, np.ones(2), np.full(2, 2.0), np.full(2, 5.0))
        assert short[segment] < durations[segment] * 1.5


def test_via_velocity_above_the_limit_is_refused_naming_point_and_joint():
    points = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    velocities = np.array([[0.0, 0.0], [0.5, 1.5], [0.0, 0.0]])
    with pytest.raises(ValueError, match='point 1, joint 1: via velocity 1.5'):
        scurve_via(points, [3.0, 3.0], 1.0, 1.0, 1.0, velocities)
    with pytest.raises(ValueError, match='point 1, joint 1'):
        scurve_via_durations(points, 1.0, 1.0, 1.0, velocities)
    # Heuristic: 2 rad in 1 s around point 1 asks for 2 rad/s there.
    with pytest.raises(ValueError, match=r'segment [01] .*point 1, joint 0 is 2'):
        scurve_via(2.0 * points, [1.0, 1.0], 1.0, 1.0, 1.0)


@pytest.mark.parametrize('bad, message', [
    ({'velocities': 'continuous'}, 'velocities must be "heuristic" or an array'),
    ({'velocities': np.zeros((2, 2))}, 'velocities is shaped (2, 2); expected (3, 2)'),
    ({'durations': [1.0]}, 'durations has 1 entries for 2 segments'),
    ({'max_jerk': -1.0}, 'max_jerk must be finite and > 0'),
    ({'points': [[0.0, 0.0]]}, 'points needs at least 2 points'),
])
def test_scurve_via_validates_its_input(bad, message):
    arguments = {'points': np.zeros((3, 2)), 'durations': [1.0, 1.0], 'max_velocity': 1.0,
                 'max_acceleration': 1.0, 'max_jerk': 1.0}
    arguments.update(bad)
    with pytest.raises(ValueError, match=re.escape(message)):
        scurve_via(**arguments)


def test_far_via_path_beyond_ruckigs_duration_limit():
    points = np.array([[0.0, 0.0], [1e6, 1.0], [2e6, 0.0]])
    durations = scurve_via_durations(points, 0.1, 0.1, 0.1)
    assert durations.sum() > 7.6e3
    plan = scurve_via(points, durations, 0.1, 0.1, 0.1)
    check_path(plan, points, durations, np.full(2, 0.1), np.full(2, 0.1), np.full(2, 0.1))


def test_blocked_segment_duration_is_named_with_the_next_that_works():
    # Moving on at both ends, this segment can take 0.6745 s, or 2.6713 s and more:
    # in between it would overshoot or stop short (a blocked interval of Ruckig's).
    points = np.array([0.0, -0.21405911208958206])
    velocities = np.array([[-0.30229684569688664], [-0.3039605292834877]])
    shortest, _ = ruckig_duration(points[:1], points[1:], velocities[0], [0.0], [1.0], [1.0],
                                  [1.0], vf=velocities[1])
    with pytest.raises(ValueError, match='blocked duration interval of joint 0') as refusal:
        scurve_via(points, [1.5], 1.0, 1.0, 1.0, velocities)
    message = str(refusal.value)
    minimum = float(re.search(r'minimum duration is ([0-9.]+) s', message)[1])
    following = float(re.search(r'next one that works is ([0-9.]+) s', message)[1])
    assert shortest <= minimum <= shortest * (1 + 1e-8)
    assert 2.6 < following < 2.7
    limits = np.ones(1), np.ones(1), np.ones(1)
    for duration in (minimum, following):
        plan = scurve_via(points, [duration], 1.0, 1.0, 1.0, velocities)
        check_path(plan, points[:, None], np.array([duration]), *limits)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-200.0, 200.0), min_size=6, max_size=6), st.booleans())
def test_extreme_via_requests_give_a_finite_plan_or_a_value_error(exponents, timed):
    scale, duration, vmax, amax, jmax, spread = (10.0**e for e in exponents)
    points = np.array([[0.0, scale], [scale, -scale], [scale * spread, 0.0]])
    try:
        durations = ([duration] * 2 if timed else
                     scurve_via_durations(points, vmax, amax, jmax))
        plan = scurve_via(points, durations, vmax, amax, jmax)
    except ValueError as error:
        # Named: a segment, or (scale * spread overflowing) a point that is not finite.
        assert 'scurve_via' in str(error) or 'points must be finite' in str(error), error
        return
    assert np.isfinite(plan.coefficients).all() and np.isfinite(plan.breakpoints).all()
    assert np.all(plan.peak_jerk() <= jmax * (1 + TOL))
