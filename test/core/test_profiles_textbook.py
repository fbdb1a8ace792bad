"""
The lecture's worked examples (Craig, *Introduction to Robotics*, ch. 7), one test each.

Each printed (rounded) number stands beside its exact value, re-derived from the lecture's
formulas in the test itself, never from the core's own matrices.
"""

import math
import re

import core_helpers as helpers
import numpy as np
import pytest
from traj_gen_ros import cubic, cubic_via, lspb, lspb_via, quintic

# --- Cubic polynomials, eq. (6) and (9) -----------------------------------------------


def test_cubic_example_15_to_75_degrees_in_3_seconds():
    trajectory = cubic(15.0, 75.0, 3.0)
    a0, a1, a2, a3 = trajectory.coefficients[0, :, 0]
    # Eq. (6): a2 = 3Δ/tf², a3 = -2Δ/tf³ with Δ = 60, tf = 3.
    assert a0 == pytest.approx(15.0, abs=1e-12)
    assert a1 == pytest.approx(0.0, abs=1e-12)
    assert a2 == pytest.approx(3.0 * 60.0 / 3.0**2, abs=1e-12)
    assert a3 == pytest.approx(-2.0 * 60.0 / 3.0**3, abs=1e-12)
    assert round(a2, 2) == 20.0
    assert round(a3, 2) == -4.44
    # Velocity 40t - 13.33t², acceleration 40 - 26.67t.
    assert round(2.0 * a2, 2) == 40.0
    assert round(3.0 * a3, 2) == -13.33
    assert round(6.0 * a3, 2) == -26.67
    times = np.linspace(0.0, 3.0, 31)
    position, velocity, acceleration = trajectory.sample(times)
    np.testing.assert_allclose(position[:, 0], 15 + 20 * times**2 - 40 / 9 * times**3,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(velocity[:, 0], 40 * times - 40 / 3 * times**2,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(acceleration[:, 0], 40 - 80 / 3 * times, rtol=0, atol=1e-12)
    assert position[-1, 0] == pytest.approx(75.0, abs=1e-12)
    assert velocity[0, 0] == velocity[-1, 0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(('q0', 'qf', 'v0', 'vf', 'tf'), [
    (15.0, 75.0, 0.0, 0.0, 3.0),
    (0.0, 1.0, 2.0, -1.0, 0.5),
    (-3.0, 4.0, -1.5, 2.5, 7.0),
    (2.0, 2.0, 1.0, 1.0, 1.0),
])
def test_cubic_with_boundary_velocities_is_eq_9(q0, qf, v0, vf, tf):
    coefficients = cubic(q0, qf, tf, v0=v0, vf=vf).coefficients[0, :, 0]
    expected = [
        q0,
        v0,
        3.0 / tf**2 * (qf - q0) - 2.0 / tf * v0 - 1.0 / tf * vf,
        -2.0 / tf**3 * (qf - q0) + 1.0 / tf**2 * (vf + v0),
    ]
    np.testing.assert_allclose(coefficients, expected, rtol=1e-12, atol=1e-12)


# --- Two-segment spline with continuous acceleration, eq. (13) ------------------------

EQ13_CASES = [
    # (θ0, θv, θg, tf)
    (15.0, 75.0, 15.0, 3.0),
    (0.0, 10.0, 30.0, 1.0),
    (-5.0, 2.0, -1.0, 0.25),
    (1.0, 1.0, 1.0, 2.0),
    (10.0, -20.0, 40.0, 7.5),
]


def eq13(theta0, theta_v, theta_g, tf):
    """Return the lecture's eq. (13): ``(a10 … a13), (a20 … a23)`` for tf1 = tf2 = tf."""
    first = [
        theta0,
        0.0,
        (12 * theta_v - 3 * theta_g - 9 * theta0) / (4 * tf**2),
        (-8 * theta_v + 3 * theta_g + 5 * theta0) / (4 * tf**3),
    ]
    second = [
        theta_v,
        (3 * theta_g - 3 * theta0) / (4 * tf),
        (-12 * theta_v + 6 * theta_g + 6 * theta0) / (4 * tf**2),
        (8 * theta_v - 5 * theta_g - 3 * theta0) / (4 * tf**3),
    ]
    return np.array([first, second])


@pytest.mark.parametrize(('theta0', 'theta_v', 'theta_g', 'tf'), EQ13_CASES)
def test_two_segment_spline_is_eq_13(theta0, theta_v, theta_g, tf):
    trajectory = cubic_via([theta0, theta_v, theta_g], [tf, tf], velocities='continuous')
    assert trajectory.coefficients.shape == (2, 4, 1)
    np.testing.assert_allclose(trajectory.coefficients[:, :, 0],
                               eq13(theta0, theta_v, theta_g, tf), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(trajectory.breakpoints, [0.0, tf, 2 * tf], rtol=0, atol=0)
    helpers.assert_continuous(trajectory, orders=3)


def test_two_segment_spline_for_several_joints_at_once():
    points = np.array([case[:3] for case in EQ13_CASES]).T  # (3 points, joints)
    for tf in (0.5, 2.0):
        trajectory = cubic_via(points, [tf, tf], velocities='continuous')
        for joint, (theta0, theta_v, theta_g, _) in enumerate(EQ13_CASES):
            np.testing.assert_allclose(trajectory.coefficients[:, :, joint],
                                       eq13(theta0, theta_v, theta_g, tf),
                                       rtol=1e-12, atol=1e-12)


# --- Quintic, "higher-order polynomials" eq. (3) --------------------------------------


def eq3(q0, qf, v0, vf, acc0, accf, tf):
    """Return the lecture's quintic eq. (3), coefficients a0 … a5."""
    return np.array([
        q0,
        v0,
        acc0 / 2,
        (20 * qf - 20 * q0 - (8 * vf + 12 * v0) * tf - (3 * acc0 - accf) * tf**2) / (2 * tf**3),
        (30 * q0 - 30 * qf + (14 * vf + 16 * v0) * tf + (3 * acc0 - 2 * accf) * tf**2)
        / (2 * tf**4),
        (12 * qf - 12 * q0 - (6 * vf + 6 * v0) * tf - (acc0 - accf) * tf**2) / (2 * tf**5),
    ])


QUINTIC_CASES = [
    # (θ0, θf, θ̇0, θ̇f, θ̈0, θ̈f, tf)
    (15.0, 75.0, 0.0, 0.0, 0.0, 0.0, 3.0),
    (0.0, 1.0, 0.5, -0.5, 2.0, -1.0, 1.0),
    (-2.0, 3.0, -1.0, 4.0, 0.0, 10.0, 0.3),
    (5.0, 5.0, 1.0, 1.0, -3.0, 3.0, 6.0),
]


@pytest.mark.parametrize(('q0', 'qf', 'v0', 'vf', 'acc0', 'accf', 'tf'), QUINTIC_CASES)
def test_quintic_is_eq_3(q0, qf, v0, vf, acc0, accf, tf):
    trajectory = quintic(q0, qf, tf, v0=v0, vf=vf, a0=acc0, af=accf)
    expected = eq3(q0, qf, v0, vf, acc0, accf, tf)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(trajectory.coefficients[0, :, 0], expected,
                               rtol=1e-12, atol=1e-12 * scale)
    position, velocity, acceleration = trajectory.sample([0.0, tf])
    np.testing.assert_allclose(position[:, 0], [q0, qf], rtol=0, atol=1e-10)
    np.testing.assert_allclose(velocity[:, 0], [v0, vf], rtol=0, atol=1e-10)
    np.testing.assert_allclose(acceleration[:, 0], [acc0, accf], rtol=0, atol=1e-9)


def test_quintic_15_to_75_rest_to_rest():
    # Rest to rest: a3 = 10Δ/tf³, a4 = -15Δ/tf⁴, a5 = 6Δ/tf⁵.
    coefficients = quintic(15.0, 75.0, 3.0).coefficients[0, :, 0]
    expected = [15.0, 0.0, 0.0, 600 / 27, -900 / 81, 360 / 243]
    np.testing.assert_allclose(coefficients, expected, rtol=1e-12, atol=1e-12)
    assert [round(value, 2) for value in coefficients[3:]] == [22.22, -11.11, 1.48]


# --- LSPB, single segment: eq. (5) and (6) --------------------------------------------


def blend_time_eq5(q0, qf, t, acceleration):
    """Return eq. (5): t_b = t/2 - math.sqrt(θ̈²t² - 4θ̈|θf - θ0|) / (2θ̈)."""
    return t / 2 - math.sqrt(acceleration**2 * t**2 - 4 * acceleration * abs(qf - q0)) / (
        2 * acceleration)


@pytest.mark.parametrize(('q0', 'qf', 't', 'acceleration'), [
    (15.0, 75.0, 3.0, 50.0),
    (15.0, 75.0, 3.0, 80.0 / 3.0),  # eq. (6) with equality: two blends, no line
    (75.0, 15.0, 3.0, 100.0),
    (0.0, 1.0, 2.0, 1.0),
])
def test_lspb_blend_time_is_eq_5(q0, qf, t, acceleration):
    trajectory = lspb(q0, qf, t, acceleration)
    blend = blend_time_eq5(q0, qf, t, acceleration)
    # At the equality of eq. (6) the square root of a rounded zero costs ~1e-8 s.
    tolerance = 1e-7 if blend == pytest.approx(t / 2) else 1e-12
    np.testing.assert_allclose(trajectory.blend_times[:, 0], [blend, blend], rtol=0,
                               atol=tolerance)
    # Eq. (1): the blend ends at the velocity of the line.
    direction = np.sign(qf - q0)
    assert trajectory.linear_velocities[0, 0] == pytest.approx(
        direction * acceleration * blend, abs=acceleration * tolerance)
    assert trajectory.linear_durations[0, 0] == pytest.approx(t - 2 * blend, abs=3 * tolerance)
    position, velocity, _ = trajectory.sample([0.0, t / 2, t])
    np.testing.assert_allclose(position[:, 0], [q0, (q0 + qf) / 2, qf], rtol=0, atol=1e-9)
    np.testing.assert_allclose(velocity[[0, 2], 0], [0.0, 0.0], rtol=0, atol=1e-9)
    helpers.assert_continuous(trajectory)


def test_lspb_15_to_75_in_3_seconds_at_50():
    trajectory = lspb(15.0, 75.0, 3.0, 50.0)
    blend = 1.5 - math.sqrt(50**2 * 9 - 4 * 50 * 60) / 100  # eq. (5): 1.5 - math.sqrt(1.05)
    assert blend == pytest.approx(1.5 - math.sqrt(1.05), abs=1e-15)
    assert trajectory.blend_times[0, 0] == pytest.approx(blend, abs=1e-12)
    assert round(trajectory.blend_times[0, 0], 2) == 0.48
    assert trajectory.linear_velocities[0, 0] == pytest.approx(50 * blend, rel=1e-12)


def test_lspb_below_eq_6_names_the_joint_and_the_minimum():
    # Joint 1 needs 4·|10 - 0| / 1² = 40; joint 0 is fine with 39.
    with pytest.raises(ValueError, match='joint 1') as error:
        lspb([0.0, 0.0], [1.0, 10.0], 1.0, 39.0)
    message = str(error.value)
    assert '40' in message
    assert 'acceleration' in message
    lspb([0.0, 0.0], [1.0, 10.0], 1.0, 40.0)  # the minimum itself fits (eq. 6 equality)
    with pytest.raises(ValueError, match='joint 1'):
        lspb([0.0, 0.0], [1.0, 10.0], 1.0, 40.0 * (1 - 1e-6))


# --- LSPB through via points: the lecture's example -----------------------------------


def test_lspb_via_example_10_35_25_10_degrees():
    trajectory = lspb_via([10.0, 35.0, 25.0, 10.0], [2.0, 1.0, 3.0], 50.0)
    t1, t2, t3, t4 = trajectory.blend_times[:, 0]
    v12, v23, v34 = trajectory.linear_velocities[:, 0]
    t12, t23, t34 = trajectory.linear_durations[:, 0]

    # First segment, eq. (2)-(3): t1 = 2 - math.sqrt(4 - 2·25/50) = 2 - math.sqrt(3).
    exact_t1 = 2 - math.sqrt(3)
    assert t1 == pytest.approx(exact_t1, abs=1e-12)
    assert round(t1, 2) == 0.27
    exact_v12 = 25 / (2 - exact_t1 / 2)  # = 50 (2 - math.sqrt(3))
    assert v12 == pytest.approx(exact_v12, abs=1e-12)
    assert v12 == pytest.approx(50 * (2 - math.sqrt(3)), abs=1e-12)
    assert round(v12, 1) == 13.4  # the slides print 13.5 from the rounded t1
    # Interior, eq. (1).
    assert v23 == pytest.approx(-10.0, abs=1e-12)
    exact_t2 = abs(-10 - exact_v12) / 50
    assert t2 == pytest.approx(exact_t2, abs=1e-12)
    assert round(t2, 2) == 0.47
    exact_t12 = 2 - exact_t1 - exact_t2 / 2
    assert t12 == pytest.approx(exact_t12, abs=1e-12)
    assert round(t12, 2) == 1.50
    # Last segment, eq. (4)-(5): t4 = 3 - math.sqrt(9 - 2·15/50).
    exact_t4 = 3 - math.sqrt(9 - 2 * 15 / 50)
    assert t4 == pytest.approx(exact_t4, abs=1e-12)
    assert round(t4, 2) == 0.10
    exact_v34 = (10 - 25) / (3 - exact_t4 / 2)
    assert v34 == pytest.approx(exact_v34, abs=1e-12)
    assert round(v34, 2) == -5.09
    exact_t3 = abs(exact_v34 - (-10)) / 50
    assert t3 == pytest.approx(exact_t3, abs=1e-12)
    assert round(t3, 3) == 0.098
    exact_t23 = 1 - exact_t2 / 2 - exact_t3 / 2
    assert t23 == pytest.approx(exact_t23, abs=1e-12)
    assert round(t23, 2) == 0.72
    exact_t34 = 3 - exact_t3 / 2 - exact_t4
    assert t34 == pytest.approx(exact_t34, abs=1e-12)
    assert round(t34, 2) == 2.85

    # Total duration kept exactly; ends at the goal at rest.
    assert trajectory.duration == pytest.approx(6.0, abs=1e-12)
    position, velocity, _ = trajectory.sample([0.0, 6.0])
    np.testing.assert_allclose(position[:, 0], [10.0, 10.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(velocity[:, 0], [0.0, 0.0], rtol=0, atol=1e-12)
    # Blend accelerations: sgn(θ̇kl - θ̇jk)·50 = +50, -50, +50, +50.
    np.testing.assert_allclose(2 * trajectory.coefficients[0::2, 2, 0],
                               [50.0, -50.0, 50.0, 50.0], rtol=0, atol=1e-12)
    helpers.assert_continuous(trajectory)


def test_lspb_via_example_rounds_the_corners():
    # The book's method does not reach interior via points (FIELD-NOTES: ≈33.6, ≈25.1).
    trajectory = lspb_via([10.0, 35.0, 25.0, 10.0], [2.0, 1.0, 3.0], 50.0)
    t1 = 2 - math.sqrt(3)
    v12 = 50 * t1
    t2 = (v12 + 10) / 50
    # At t = 2 (middle of the blend at point 2): line 1 at the blend start, then
    # half the blend at ``(v12 + (v12 - 50·t2/2)) / 2``.
    blend_start = 35 - v12 * t2 / 2
    expected = blend_start + v12 * t2 / 2 - 50 / 2 * (t2 / 2) ** 2
    position, _, _ = trajectory.sample([2.0, 3.0])
    assert position[0, 0] == pytest.approx(expected, abs=1e-12)
    assert round(position[0, 0], 1) == 33.6
    assert round(position[1, 0], 1) == 25.1


# --- LSPB via points that cannot fit (FIELD-NOTES) ------------------------------------

INFEASIBLE_PATH = [0.0, 10.0, 0.0]


def linear_part_of_first_segment(acceleration):
    """For θ = [0, 10, 0], durations [1, 1]: t12 = 1 - t1 - t2/2 by eq. (1)-(3)."""
    t1 = 1 - math.sqrt(1 - 2 * 10 / acceleration)
    velocity = 10 / (1 - t1 / 2)
    t2 = 2 * velocity / acceleration
    return 1 - t1 - t2 / 2


def test_smallest_fitting_acceleration_of_the_infeasible_example():
    # At |θ̈| = 80/3: t1 = 1/2, θ̇12 = 40/3, t2 = 1 and the linear part is exactly zero.
    assert linear_part_of_first_segment(80 / 3) == pytest.approx(0.0, abs=1e-12)
    assert linear_part_of_first_segment(25.0) == pytest.approx(-0.106, abs=1e-3)
    assert 1 - 2 * 10 / 19 < 0  # with 19 the first square root is negative


@pytest.mark.parametrize('acceleration', [25.0, 19.0])
def test_lspb_via_refuses_blends_that_cannot_fit(acceleration):
    with pytest.raises(ValueError) as error:
        lspb_via(INFEASIBLE_PATH, [1.0, 1.0], acceleration)
    message = str(error.value)
    assert re.search(r'\bpoints? \d', message), message
    assert 'joint 0' in message
    numbers = re.findall(r'smallest acceleration[^0-9]*([0-9.]+(?:e[-+]?\d+)?)', message)
    assert numbers, message
    reported = float(numbers[0])
    minimum = 80 / 3
    assert minimum <= reported <= minimum * (1 + 1e-3)
    # The reported minimum fits, and slightly less does not.
    fitting = lspb_via(INFEASIBLE_PATH, [1.0, 1.0], reported)
    assert np.all(fitting.linear_durations >= 0.0)
    helpers.assert_continuous(fitting)
    with pytest.raises(ValueError):
        lspb_via(INFEASIBLE_PATH, [1.0, 1.0], minimum * (1 - 1e-6))
    with pytest.raises(ValueError):
        lspb_via(INFEASIBLE_PATH, [1.0, 1.0], reported * (1 - 1e-3))


def test_lspb_via_refusal_names_the_joint_that_does_not_fit():
    points = np.array([[0.0, 0.0], [1.0, 10.0], [2.0, 0.0]])
    with pytest.raises(ValueError, match='joint 1'):
        lspb_via(points, [1.0, 1.0], 25.0)


def test_lspb_via_zero_displacement_needs_no_blend():
    # sgn(0) = 0: no 0/0 where a segment or a velocity change is zero.
    trajectory = lspb_via([1.0, 1.0, 3.0, 3.0, 3.0], [1.0, 1.0, 1.0, 1.0], 20.0)
    assert np.all(np.isfinite(trajectory.coefficients))
    starts, lengths = helpers.piece_spans(trajectory)
    assert np.all(np.isfinite(starts)) and np.all(lengths >= -1e-12)
    position, velocity, _ = trajectory.sample(np.linspace(0.0, 4.0, 101))
    assert np.all(np.isfinite(position)) and np.all(np.isfinite(velocity))
    assert position[0, 0] == 1.0
    assert position[-1, 0] == pytest.approx(3.0, abs=1e-12)
    helpers.assert_continuous(trajectory)
