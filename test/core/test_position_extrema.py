"""Trajectory.position_extrema: exact lowest and highest positions of a plan, and their times."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from traj_gen_ros import (
    brake,
    cubic,
    hold,
    lspb,
    min_time,
    plan_path,
    quintic,
    scurve,
)


def random_plans(count=150, seed=3):
    rng = np.random.default_rng(seed)
    v_max, a_max, j_max = np.full(3, 2.0), np.full(3, 4.0), np.full(3, 10.0)
    for _ in range(count):
        profile = str(rng.choice(['cubic', 'quintic', 'lspb', 'scurve']))
        points = rng.normal(size=(int(rng.integers(2, 7)), 3))
        try:
            if rng.random() < 0.5:
                durations = None if profile == 'lspb' else rng.uniform(0.3, 2.0, len(points) - 1)
                yield plan_path(points, durations, profile, max_velocity=v_max,
                                max_acceleration=a_max, max_jerk=j_max,
                                blend_acceleration=a_max)
            else:
                yield min_time(points[0], points[1], v_max, a_max, profile,
                               v0=rng.normal(size=3), max_jerk=j_max,
                               a0=rng.normal(size=3) if profile in ('quintic', 'scurve')
                               else 0.0)
        except ValueError:
            continue


def test_cubic_15_to_75_degrees_in_3_s_has_its_extrema_at_the_ends():
    # Craig, example 7.1: rest to rest, monotonic; the extrema are the end points.
    extrema = cubic(15.0, 75.0, 3.0).position_extrema()
    assert extrema.minimum.tolist() == pytest.approx([15.0], abs=1e-12)
    assert extrema.maximum.tolist() == pytest.approx([75.0], abs=1e-12)
    assert extrema.time_of_minimum.tolist() == pytest.approx([0.0], abs=1e-6)
    assert extrema.time_of_maximum.tolist() == pytest.approx([3.0], abs=1e-6)


def test_a_quintic_from_a_moving_state_overshoots_where_its_velocity_vanishes():
    # 0 -> 1 rad in 1 s starting at 4 rad/s: it overshoots the goal and comes back.
    plan = quintic(0.0, 1.0, 1.0, v0=4.0)
    extrema = plan.position_extrema()
    c = plan.coefficients[0, :, 0]
    roots = np.roots((c[1:] * np.arange(1, 6))[::-1])
    real = roots.real[(np.abs(roots.imag) < 1e-12) & (roots.real > 0) & (roots.real < 1)]
    peak_time = float(real[np.argmax(np.polyval(c[::-1], real))])
    oracle = minimize_scalar(lambda t: -plan.sample(t)[0][0, 0], bounds=(0.0, 1.0),
                             method='bounded', options={'xatol': 1e-12})
    assert extrema.maximum[0] > 1.05  # a real overshoot
    assert extrema.maximum[0] == pytest.approx(-oracle.fun, abs=1e-12)
    assert extrema.time_of_maximum[0] == pytest.approx(peak_time, abs=1e-12)
    assert extrema.minimum[0] == 0.0 and extrema.time_of_minimum[0] == 0.0


def test_extrema_bound_every_sample_and_are_reached_at_their_times():
    for plan in random_plans():
        extrema = plan.position_extrema()
        lowest, highest = extrema.minimum, extrema.maximum
        q = plan.sample(np.linspace(0.0, plan.duration, 100_001))[0]
        step = plan.duration / 100_000
        # Exact: no sample beyond them; dense samples come within v_max * step of them.
        assert np.all(q.min(axis=0) >= lowest - 1e-12)
        assert np.all(q.max(axis=0) <= highest + 1e-12)
        assert np.all(q.min(axis=0) - lowest <= 2.0 * step + 1e-12)
        assert np.all(highest - q.max(axis=0) <= 2.0 * step + 1e-12)
        for joint in range(plan.joint_count):
            at_min = plan.sample(extrema.time_of_minimum[joint])[0][0, joint]
            at_max = plan.sample(extrema.time_of_maximum[joint])[0][0, joint]
            assert at_min == pytest.approx(lowest[joint], abs=1e-9)
            assert at_max == pytest.approx(highest[joint], abs=1e-9)


def test_extrema_of_holds_brakes_lspb_and_scurve():
    extrema = hold(np.array([0.5, -0.25])).position_extrema()
    assert extrema.minimum.tolist() == [0.5, -0.25] and extrema.maximum.tolist() == [0.5, -0.25]
    assert extrema.time_of_minimum.tolist() == [0.0, 0.0]
    # Braking from 1 and -2 rad/s at 2 rad/s²: stops after v²/2a = 0.25 and 1 rad.
    extrema = brake(np.zeros(2), np.array([1.0, -2.0]), np.full(2, 2.0)).position_extrema()
    assert extrema.minimum.tolist() == [0.0, -1.0] and extrema.maximum.tolist() == [0.25, 0.0]
    assert extrema.time_of_maximum[0] == pytest.approx(0.5)
    assert extrema.time_of_minimum[1] == pytest.approx(1.0)
    # LSPB per joint breakpoints, one joint moving down.
    extrema = lspb(np.array([0.0, 2.0]), np.array([1.0, -1.0]), 2.0, 4.0).position_extrema()
    assert extrema.minimum.tolist() == pytest.approx([0.0, -1.0], abs=1e-12)
    assert extrema.maximum.tolist() == pytest.approx([1.0, 2.0], abs=1e-12)
    assert extrema.time_of_minimum.tolist() == pytest.approx([0.0, 2.0], abs=1e-6)
    # An S-curve from 3 rad/s towards a goal 0.1 rad away must pass it and come back.
    plan = scurve(0.0, 0.1, 3.0, 4.0, 8.0, 40.0, v0=3.0)
    extrema = plan.position_extrema()
    q = plan.sample(np.linspace(0.0, plan.duration, 200_001))[0][:, 0]
    assert extrema.maximum[0] > 0.5
    assert extrema.maximum[0] == pytest.approx(q.max(), abs=1e-9)
    assert math.isclose(plan.sample(extrema.time_of_maximum[0])[0][0, 0], extrema.maximum[0],
                        abs_tol=1e-12)
