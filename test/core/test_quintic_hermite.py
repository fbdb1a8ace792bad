"""quintic_hermite: one quintic per interval, each end's state exactly, accelerations per side."""

import numpy as np
from traj_gen_ros.core.polynomial import quintic_hermite


def test_each_interval_meets_both_end_states_and_its_own_accelerations():
    rng = np.random.default_rng(3)
    breaks = np.array([0.2, 0.7, 1.0, 2.5])
    q, v = rng.normal(size=(4, 2)), rng.normal(size=(4, 2))
    a_start, a_end = rng.normal(size=(3, 2)), rng.normal(size=(3, 2))
    plan = quintic_hermite(breaks, q, v, a_start, a_end)
    assert plan.degree == 5 and plan.breakpoints[0] == 0.2 and plan.duration == 2.5
    for k in range(3):
        h = breaks[k + 1] - breaks[k]
        c = plan.coefficients[k]
        tau = np.array([h ** n for n in range(6)])
        np.testing.assert_allclose(c[0], q[k], atol=1e-14)
        np.testing.assert_allclose(c[1], v[k], atol=1e-14)
        np.testing.assert_allclose(2 * c[2], a_start[k], atol=1e-14)
        np.testing.assert_allclose(tau @ c, q[k + 1], atol=1e-12)
        np.testing.assert_allclose(np.arange(6)[1:] * tau[:-1] @ c[1:], v[k + 1], atol=1e-11)
        second = np.array([n * (n - 1) for n in range(2, 6)])
        np.testing.assert_allclose(second * tau[:-2] @ c[2:], a_end[k], atol=1e-10)


def test_a_straight_line_stays_a_straight_line():
    breaks = np.linspace(0.0, 1.0, 5)
    q = np.column_stack([3.0 * breaks - 1.0])
    plan = quintic_hermite(breaks, q, np.full_like(q, 3.0), np.zeros((4, 1)), np.zeros((4, 1)))
    np.testing.assert_allclose(plan.coefficients[:, 2:], 0.0, atol=1e-12)
    position, velocity, _ = plan.sample(np.linspace(0, 1, 33))
    np.testing.assert_allclose(position[:, 0], 3.0 * np.linspace(0, 1, 33) - 1.0, atol=1e-13)
    np.testing.assert_allclose(velocity, 3.0, atol=1e-12)
