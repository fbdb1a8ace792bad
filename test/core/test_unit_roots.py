"""Real roots on [0, 1] of batched polynomials (traj_gen_ros.core.exact.unit_roots)."""

import numpy as np
import numpy.polynomial.polynomial as poly
import pytest
import traj_gen_ros as tg
from traj_gen_ros.core.exact import unit_roots
from traj_gen_ros.core.exact.unit_roots import (
    quadratic_roots_in_unit_interval,
    roots_in_unit_interval,
)
from traj_gen_ros.core.trajectory import state_at


def from_roots(roots, scale=1.0):
    """Ascending coefficients of ``scale · Π (τ - r)`` padded to degree 9."""
    coefficients = np.zeros(10)
    product = scale * poly.polyfromroots(roots).real
    coefficients[:product.size] = product
    return coefficients


def roots_of(rows, found):
    """Sorted roots of each row from ``(roots, rows)``."""
    roots, owners = found
    return [np.sort(roots[owners == row]) for row in range(rows)]


def test_known_roots_are_found_to_machine_precision():
    rng = np.random.default_rng(7)
    cases = []
    for _ in range(200):
        inside = rng.uniform(0.0, 1.0, rng.integers(0, 5))
        count = 9 - inside.size
        outside = rng.choice([-1.0, 1.0], count) * rng.uniform(1.05, 3.0, count)
        cases.append((np.sort(inside), from_roots(np.concatenate([inside, outside]),
                                                  rng.uniform(-1e3, 1e3))))
    found = roots_of(len(cases), roots_in_unit_interval(np.array([c for _, c in cases])))
    for (expected, _), roots in zip(cases, found, strict=True):
        assert roots.size == expected.size
        np.testing.assert_allclose(roots, expected, atol=1e-9)


@pytest.mark.parametrize('roots', [
    [0.3, 0.3 + 1e-3],             # close pair in one piece: split once
    [0.3, 0.3 + 1e-6],             # closer than the splits: eigenvalues
    [0.5, 0.5],                    # double root on a piece boundary
    [0.25],                        # simple root on a piece boundary
    [0.0, 1.0],                    # roots at the ends
    [0.7, 0.7, 0.7],               # triple root
])
def test_hard_roots_are_found(roots):
    coefficients = from_roots(roots + [2.0, -1.5, 3.0])
    found = roots_of(1, roots_in_unit_interval(coefficients[None]))[0]
    # Every root is found (multiple ones possibly more than once, or split by rounding).
    for root in roots:
        assert np.min(np.abs(found - root)) <= 1e-5
    assert np.all((found >= 0.0) & (found <= 1.0))


def _no_eigenvalues(polynomials):
    raise AssertionError(f'eigenvalues asked for {len(polynomials)} polynomials')


@pytest.mark.parametrize('gap', [1e-3, 1e-4, 2e-5])
def test_close_pairs_are_isolated_by_splitting_without_eigenvalues(gap, monkeypatch):
    # Parts down to 1/131072 (7.6e-6) of [0, 1]: pairs this close are separated by them.
    monkeypatch.setattr(unit_roots, '_eigenvalue_roots', _no_eigenvalues)
    expected = [0.2113, 0.2113 + gap, 0.7887 - gap, 0.7887]
    rows = np.array([from_roots(expected + [1.7]), from_roots(expected[:2] + [-2.0])])
    found = roots_of(2, roots_in_unit_interval(rows))
    np.testing.assert_allclose(found[0], expected, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(found[1], expected[:2], rtol=0.0, atol=1e-9)


def test_a_goal_soon_after_a_start_from_rest_needs_no_eigenvalues(monkeypatch):
    # 0.02-0.2 s into a 3.7 s quintic from rest the quintic's acceleration resultant has
    # near-double roots near (3 ± √3)/6, 1.3e-5 to 1.1e-3 apart.
    joints = 6
    limits = np.full(joints, 0.5), np.full(joints, 2.0)
    first = tg.min_time(np.zeros(joints), np.ones(joints), *limits, 'quintic')
    monkeypatch.setattr(unit_roots, '_eigenvalue_roots', _no_eigenvalues)
    for time in (0.02, 0.05, 0.1, 0.2):
        position, velocity, acceleration = state_at(first, time)
        plan = tg.min_time(position, -np.ones(joints), *limits, 'quintic', v0=velocity,
                           a0=acceleration)
        peak_velocity = np.abs(plan.sample(np.linspace(0.0, plan.duration, 4001))[1]).max()
        assert 0.5 * (1.0 - 1e-6) <= peak_velocity <= 0.5 * (1.0 + 1e-9)


def test_polynomials_without_roots_in_the_interval_give_none():
    rootless = np.array([from_roots([1.5, -0.5, 2.0]),
                         from_roots([1.0 + 1e-3]),
                         1.0 + np.arange(10) * 0.1,  # positive on [0, 1]
                         np.zeros(10)])
    roots, owners = roots_in_unit_interval(rootless)
    assert roots.size == 0 and owners.size == 0


def test_rows_keep_their_owner_and_are_independent_of_batch():
    rows = np.array([from_roots([0.2, 0.9]), np.zeros(10), from_roots([0.4])])
    together = roots_of(3, roots_in_unit_interval(rows))
    np.testing.assert_allclose(together[0], [0.2, 0.9], atol=1e-12)
    assert together[1].size == 0
    np.testing.assert_allclose(together[2], [0.4], atol=1e-12)


def test_quadratics_in_closed_form():
    rows = np.array([[0.06, -0.5, 1.0],     # (τ - 0.2)(τ - 0.3)
                     [-0.4, 1.0, 0.0],      # linear: 0.4
                     [1.0, 0.0, 1.0],       # complex pair
                     [0.25, -1.0, 1.0],     # double root 0.5
                     [2.0, -3.0, 1.0],      # roots 1 and 2: only 1 inside
                     [0.0, 0.0, 0.0]])
    roots = roots_of(6, quadratic_roots_in_unit_interval(rows))
    np.testing.assert_allclose(roots[0], [0.2, 0.3], atol=1e-15)
    np.testing.assert_allclose(roots[1], [0.4], atol=1e-15)
    assert roots[2].size == 0 and roots[5].size == 0
    np.testing.assert_allclose(roots[3], [0.5, 0.5], atol=1e-8)
    np.testing.assert_allclose(roots[4], [1.0], atol=1e-15)
