"""
Candidate durations and exact peaks of cubic/quintic moves to rest from a moving state.

The resultant tables of ``polynomial_candidates`` are rebuilt here from their definition
(Sylvester resultant of ``P`` and ``∂P/∂τ`` in ``T``, from Craig's closed-form moves);
``move_peaks`` is compared with peaks from ``numpy.polynomial`` roots; and on a fine grid
of durations, feasibility only changes where a candidate lies.
"""

import core_helpers as helpers
import numpy as np
import numpy.polynomial.polynomial as poly
import pytest
from traj_gen_ros import cubic, quintic
from traj_gen_ros.core.exact.move_peaks import peaks
from traj_gen_ros.core.exact.peak_candidates import (
    _end_table,
    _END_TABLES,
    _interior_polynomials,
    _positive_roots,
    _SHAPES,
    candidates,
)
from traj_gen_ros.core.exact.polynomial_durations import (
    _common_duration,
    _onto_common_run,
    _smallest_common_duration,
    synchronised_duration,
)
from traj_gen_ros.core.exact.second_order import minimum_times

# Position in normalised time τ, per term (ascending in τ): Craig's quintic (eq. 7.3-7.5)
# and cubic (eq. 7.9) to rest, as D·m_D + v0 T·m_v + a0 T²·m_a.
SHAPES = {
    'quintic': {'D': [0, 0, 0, 10, -15, 6], 'v': [0, 1, 0, -6, 8, -3],
                'a': [0, 0, 0.5, -1.5, 1.5, -0.5]},
    'cubic': {'D': [0, 0, 3, -2], 'v': [0, 1, -2, 1], 'a': [0]},
}
# The known factor divided out of each resultant (see polynomial_candidates).
FACTORS = {
    ('quintic', 0, 'general'): lambda d, v, a: 60 * d * a * poly.polymul([0, 1], [1, -2, 1]),
    ('quintic', 0, 'no_a0'): lambda d, v, a: 60 * d * np.array([0, -1, 1]),
    ('quintic', 0, 'no_d'): lambda d, v, a: -a * np.array([-1, 1]),
    ('quintic', 1, 'general'): lambda d, v, a: np.array([720 * d]),
    ('quintic', 1, 'no_d'): lambda d, v, a: np.array([-12 * v]),
    ('cubic', 0, 'general'): lambda d, v, a: np.array([6 * d]),
}


def quadratic_in_t(profile, order, sign, d, v, a, limit):
    """Coefficients ``(p2, p1, p0)`` of ``P(τ, T)``, each ascending in τ."""
    shapes = SHAPES[profile]
    terms = [poly.polyder(shapes[key], order) * scale
             for key, scale in (('a', a), ('v', v), ('D', d))]
    limit_power = 1 if order == 1 else 0
    terms[limit_power] = poly.polysub(terms[limit_power], [sign * limit])
    return terms


def resultant(p, q):
    """Resultant in T of two quadratics (or lower) given as (p2, p1, p0) in τ."""
    m = poly.polymul
    p2, p1, p0 = p
    q2, q1, q0 = q
    if not np.any(p2) and not np.any(q2):
        return poly.polysub(m(p1, q0), m(q1, p0))
    first = poly.polysub(m(p2, q0), m(q2, p0))
    second = poly.polysub(m(p2, q1), m(q2, p1))
    third = poly.polysub(m(p1, q0), m(q1, p0))
    return poly.polysub(m(first, first), m(second, third))


@pytest.mark.parametrize('profile, order, kind', list(FACTORS))
def test_resultant_tables_equal_the_sylvester_resultant(profile, order, kind):
    rng = np.random.default_rng(3)
    for _ in range(20):
        d, v, a, limit = rng.uniform(0.3, 2.0, 4) * rng.choice([-1, 1], 4)
        limit = abs(limit)
        if kind == 'no_a0':
            a = 0.0
        if kind == 'no_d':
            d = 0.0
        if profile == 'cubic':
            a = 0.0
        moves = [np.array([x]) for x in (d, v, a, limit, limit)]
        table = _interior_polynomials(profile, *moves)[order, :, 0]
        for sign_index, sign in enumerate((1.0, -1.0)):
            p = quadratic_in_t(profile, order + 1, sign, d, v, a, limit)
            if kind == 'no_d':  # P has no constant term: divide by T
                p = [np.zeros(1), p[0], p[1]]
            q = [poly.polyder(term) if len(term) > 1 else np.zeros(1) for term in p]
            full = resultant(p, q)
            quotient, remainder = poly.polydiv(full, FACTORS[(profile, order, kind)](d, v, a))
            assert np.max(np.abs(remainder)) <= 1e-9 * np.max(np.abs(full))
            assert np.all(np.abs(quotient[10:]) <= 1e-9 * np.max(np.abs(quotient)))
            expected = np.zeros(10)
            expected[:min(quotient.size, 10)] = quotient[:10]
            np.testing.assert_allclose(table[sign_index], expected,
                                       atol=1e-9 * np.max(np.abs(expected)))


def plan(profile, d, v, a, duration):
    """Plan the move itself with the core's cubic/quintic."""
    if profile == 'cubic':
        return cubic([0.0], [d], duration, v0=[v])
    return quintic([0.0], [d], duration, v0=[v], a0=[a])


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_peaks_equal_peaks_from_numpy_roots(profile):
    rng = np.random.default_rng(11)
    count = 300
    d = rng.normal(size=count) * 10.0 ** rng.uniform(-3, 2, count)
    v, a = rng.normal(size=count), rng.normal(size=count) * 3.0
    duration = 10.0 ** rng.uniform(-2, 2, count)
    d[::7], v[::5], a[::3] = 0.0, 0.0, 0.0
    if profile == 'cubic':
        a[:] = 0.0
    velocity, acceleration = peaks(profile, d, v, a, duration)
    for k in range(count):
        expected = helpers.reference_peaks(plan(profile, d[k], v[k], a[k], duration[k]))
        np.testing.assert_allclose([velocity[k], acceleration[k]],
                                   [expected[0][0], expected[1][0]], rtol=1e-9, atol=1e-300)


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_feasibility_changes_only_at_candidates(profile):
    rng = np.random.default_rng(5)
    flips = 0
    for case in range(60):
        d = rng.normal()
        v, a = rng.normal() * 0.6, (rng.normal() if profile == 'quintic' else 0.0)
        max_velocity, max_acceleration = rng.uniform(0.5, 2.0), rng.uniform(1.0, 4.0)
        v = np.clip(v, -max_velocity, max_velocity)
        a = np.clip(a, -max_acceleration, max_acceleration)
        # The degenerate cases, each with its own resultant or a start at a limit.
        if case % 5 == 1:
            d = 0.0
        elif case % 5 == 2:
            a = 0.0
        elif case % 5 == 3:
            v = np.copysign(max_velocity, rng.normal())
        elif case % 5 == 4 and profile == 'quintic':
            a = np.copysign(max_acceleration, rng.normal())
        moves = [np.array([x]) for x in (d, v, a, max_velocity, max_acceleration)]
        found, _ = candidates(profile, *moves)
        grid = np.geomspace(1e-2, 1e2, 4000)
        velocity, acceleration = peaks(profile, np.full(grid.size, d), np.full(grid.size, v),
                                       np.full(grid.size, a), grid)
        # The planner's tolerance: a start at a limit stays there to rounding.
        feasible = (velocity <= max_velocity * (1 + 1e-9)) & \
            (acceleration <= max_acceleration * (1 + 1e-9))
        for change in np.flatnonzero(feasible[1:] != feasible[:-1]):
            flips += 1
            low, high = grid[change], grid[change + 1]
            assert np.any((found >= low * (1 - 1e-9)) & (found <= high * (1 + 1e-9))), \
                (d, v, a, max_velocity, max_acceleration, low, high, found)
    assert flips > 20  # the check did meet windows and boundaries


@pytest.mark.parametrize('runs, expected', [
    # joint 0: [1, 2] and [3, inf); joint 1: [2, 4] and the single duration 5
    ([[1.0, 3.0, 2.0, 5.0], [2.0, np.inf, 4.0, 5.0], [0, 0, 1, 1]], 2.0),
    ([[1.0, 2.5], [2.0, 3.0], [0, 1]], None),              # disjoint: none in common
    ([[1.0, 2.0], [2.0, 3.0], [0, 1]], 2.0),               # closed runs touching at 2
    ([[1.0, 7.0, 3.0], [2.0, 7.0, np.inf], [0, 0, 1]], 7.0),  # a single feasible duration
])
def test_synchronised_duration_is_the_smallest_common_one(runs, expected):
    assert synchronised_duration(np.array(runs), 2) == expected


def random_moves(rng, profile, joints):
    """Return moves ``(D, v0, a0, v_max, a_max)`` from random moving states, some still."""
    limits = 10.0 ** rng.uniform(-0.5, 0.5, (2, joints))
    start = rng.uniform(-1.0, 1.0, (2, joints)) * limits * rng.choice([0.0, 1.0], (2, joints))
    if profile == 'cubic':
        start[1] = 0.0
    displacement = rng.uniform(-3.0, 3.0, joints) * rng.choice([0.0, 1.0], joints, p=[0.1, 0.9])
    return displacement, start[0], start[1], limits[0], limits[1]


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_all_joints_check_agrees_with_the_runs_of_each_joint(profile):
    """Two syntheses of the same candidates: every joint at every candidate, and runs."""
    rng = np.random.default_rng(21)
    for _ in range(150):
        moves = random_moves(rng, profile, int(rng.integers(1, 7)))
        bound = float(minimum_times(moves[0], moves[1], moves[3], moves[4]).max())
        together = _smallest_common_duration(profile, moves, bound)
        by_runs, _ = _common_duration(profile, moves, None)
        if by_runs is None:
            assert together is None
        else:
            assert together == pytest.approx(by_runs, rel=1e-12)


def test_a_start_left_outside_by_rounding_is_moved_onto_the_common_run():
    rng = np.random.default_rng(22)
    for _ in range(20):
        moves = random_moves(rng, 'quintic', 3)
        bound = float(minimum_times(moves[0], moves[1], moves[3], moves[4]).max())
        exact = _smallest_common_duration('quintic', moves, bound)
        if exact is None or exact <= bound * (1.0 + 1e-6):
            continue  # no common duration, or the bound itself is the answer
        found = _onto_common_run('quintic', moves, exact * (1.0 - 1e-7), exact * (1.0 + 1e-3))
        # Feasibility allows half of LIMIT_TOLERANCE (1e-9): the bisection may stop that
        # much below the exact candidate.
        assert found == pytest.approx(exact, rel=1e-9)


def test_trajectory_peaks_with_a_tiny_cubic_term_in_the_slope():
    """A quintic whose velocity's quartic term is ~1e-8 of the rest (the review's case)."""
    plan = quintic([0.0], [1.0 + 1e-8 / 6.0], 1.0, v0=[0.0], a0=[12.0])
    velocity, acceleration = plan.peaks()
    expected = helpers.reference_peaks(plan)
    np.testing.assert_allclose([velocity[0], acceleration[0]],
                               [expected[0][0], expected[1][0]], rtol=1e-9)
    assert velocity[0] == pytest.approx(16.0 / 9.0, rel=1e-7)  # at t = 1/3
    for ratio in (1e-9, 1e-8, 1e-7, 1e-6, 1e-4):
        plan = quintic([0.0], [1.0 + ratio], 1.0, v0=[0.3], a0=[-5.0])
        expected = helpers.reference_peaks(plan)
        np.testing.assert_allclose(plan.peaks()[0], expected[0], rtol=1e-9)


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_end_quadratics_left_out_give_no_duration(profile):
    """Every end condition and sign gives the same positive durations as the kept ones."""
    rng = np.random.default_rng(31)
    full = _end_table(_SHAPES[profile])
    for case in range(200):
        moves = random_moves(rng, profile, 4)
        if case % 3 == 1:  # starts at a limit: the ends' T terms cancel
            moves = (moves[0], np.copysign(moves[3], moves[1]), moves[2], moves[3], moves[4])
        elif case % 3 == 2 and profile == 'quintic':
            moves = (moves[0], moves[1], np.copysign(moves[4], moves[2]), moves[3], moves[4])
        inputs = np.array([moves[2], moves[1], moves[0], moves[3], moves[4]])
        found = []
        for table in (full, _END_TABLES[profile]):
            roots = _positive_roots(*np.einsum('ri,ij->rj', table, inputs).reshape(3, -1))
            found.append(np.unique(roots[(roots > 0.0) & (roots < np.inf)]))
        np.testing.assert_array_equal(found[0], found[1])
    assert _END_TABLES[profile].shape[0] < full.shape[0]


@pytest.mark.parametrize('profile', ['cubic', 'quintic'])
def test_peaks_of_every_move_at_every_duration_by_broadcasting(profile):
    rng = np.random.default_rng(32)
    d, v, a = rng.normal(size=(3, 5))
    d[0], v[1], a[2] = 0.0, 0.0, 0.0
    durations = 10.0 ** rng.uniform(-1, 1, 7)
    grid = peaks(profile, d[:, None], v[:, None], a[:, None], durations)
    flat = peaks(profile, d.repeat(7), v.repeat(7), a.repeat(7), np.tile(durations, 5))
    for by_grid, by_move in zip(grid, flat, strict=True):
        assert by_grid.shape == (5, 7)
        np.testing.assert_array_equal(by_grid.reshape(-1), by_move)
