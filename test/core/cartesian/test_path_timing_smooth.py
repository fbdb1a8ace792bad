"""
time_path's s̈ has none of the grid's dents at zero-inertia points (a joint's dq/ds = 0).

There the constraints held at both ends of an interval with s̈ constant pinch the set of
speeds, and the timing had one interval of a lower s̈ and then a pair of equal ones
(traj_gen_ros/core/cartesian/zero_inertia.py): on the Panda's blend of docs/cli.md,
panda_joint2's acceleration jumped by 0.8 rad/s² for one interval and back. Measured
here as the largest *excursion*: how far one interval's acceleration (at its midpoint)
lies beyond both its neighbours', over the joint's limit, the largest over joints and
intervals. A genuine switch of s̈ moves a joint's acceleration monotonically, beyond its
neighbours only by the joint's own change per interval (≤ 0.06 of the limit on these
paths); before the fix the excursions were 0.33-0.41 on the Panda (on 7 of 13 grid
spacings) and 0.09-0.20 on the synthetic path. And the total variation of s̈ against the
same path timed on a grid twice as fine: dents add to it, a finer grid only resolves the
switches better.
"""

from kinematics_robots import PANDA, robot_urdf, ROBOTS
import numpy as np
import pytest
from synthetic_paths import AnalyticJoints, line
from traj_gen_ros.core.cartesian import path_constraints
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_constraints import Stages
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits
from traj_gen_ros.core.cartesian.reachability import time_optimal_squared_speed
from traj_gen_ros.core.cartesian.tool_path import straight_path
from traj_gen_ros.core.cartesian.zero_inertia import refine, SPLIT
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.core.kinematics import Chain
from traj_gen_ros.core.kinematics.poses import pose_matrix

READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
DOWN = (1.0, 0.0, 0.0, 0.0)  # (x, y, z, w): the tool pointing down, as docs/cli.md
#: Grids 3 % coarser to 3 % finer than the default: where a zero falls in its interval.
SPACINGS = [0.0097, 0.0099, 0.0101, 0.0103]
#: A genuine switch moves a joint's acceleration by its own change per interval only.
EXCURSION = 0.1


def largest_excursion(timed, max_acceleration) -> float:
    """How far one interval's joint acceleration lies beyond both neighbours', / limit."""
    middle = timed.times[:-1] + 0.5 * np.diff(timed.times)
    acceleration = timed.trajectory.sample(middle)[2]
    before, here, after = acceleration[:-2], acceleration[1:-1], acceleration[2:]
    beyond = np.maximum(here - np.maximum(before, after), np.minimum(before, after) - here)
    return float((beyond / max_acceleration).max())


def variation(timed) -> float:
    """Total variation of s̈ over the grid."""
    return float(np.abs(np.diff(timed.path_acceleration)).sum())


def spaced(monkeypatch, step: float) -> None:
    """Scale the default grid's spacing: ``BEND_STEP`` and ``BASE_INTERVALS`` alike."""
    monkeypatch.setattr(path_constraints, 'BEND_STEP', step)
    monkeypatch.setattr(path_constraints, 'BASE_INTERVALS', round(200 * step / 0.01))


@pytest.fixture(scope='module')
def panda_blend(pytestconfig):
    """docs/cli.md's plot: the line to a corner, a 5 cm blend, on to the second pose."""
    spec = ROBOTS['erd-panda']
    chain = Chain.from_urdf(robot_urdf(pytestconfig, spec.source, spec.name), PANDA,
                            'panda_link0', spec.default_tool)
    poses = [pose_matrix((0.407, 0.1, 0.487), DOWN), pose_matrix((0.407, -0.1, 0.487), DOWN)]
    path = straight_path(chain.forward(READY), poses, 0.05)
    return path, follow(chain, path, READY)


PANDA_LIMITS = (np.ones(7), np.full(7, 2.0), ToolLimits(0.25, 1.2, 1.5708))


@pytest.mark.parametrize('step', [0.01, *SPACINGS])
def test_the_panda_blend_has_no_dent_in_a_joint_acceleration(panda_blend, monkeypatch, step):
    spaced(monkeypatch, step)
    timed = time_path(*panda_blend, *PANDA_LIMITS)
    assert largest_excursion(timed, 2.0) <= EXCURSION
    assert limit_violation(timed.trajectory, *PANDA_LIMITS[:2]) is None


def test_the_panda_blend_varies_s_ddot_no_more_than_on_a_grid_twice_as_fine(
        panda_blend, monkeypatch):
    timed = time_path(*panda_blend, *PANDA_LIMITS)
    monkeypatch.setattr(path_constraints, 'BEND_STEP', 0.005)
    monkeypatch.setattr(path_constraints, 'BASE_INTERVALS', 400)
    fine = time_path(*panda_blend, *PANDA_LIMITS)
    # Before: 28.49 against 27.60 (+3.2 %); the fine grid resolves the switches a little
    # more (+0.4 % again at four times as fine).
    assert variation(timed) <= variation(fine) * 1.005
    # The zeros are refined, not the whole path, and the duration is the fine grid's.
    assert len(timed.s) < 0.7 * len(fine.s)
    assert timed.duration == pytest.approx(fine.duration, rel=1e-3)


#: A line whose joint 1 rides its limit through zeros of its rate (a search over such
#: paths found it; rounded to three digits), joint 2 bounds the deceleration after them.
ZERO_JOINTS = AnalyticJoints(
    offset=np.zeros(3), slope=np.array([0.8, 0.0, 1.98]),
    amplitude=np.array([[0.0], [0.00586], [0.0497]]),
    frequency=np.array([[0.0], [56.8], [14.5]]), phase=np.array([[0.0], [-7.0], [3.14]]))
ZERO_LIMITS = (5.0, np.array([10.0, 1.55, 3.14]), ToolLimits())


@pytest.mark.parametrize('step', [0.01, *SPACINGS])
def test_a_synthetic_joint_riding_its_limit_through_zeros_has_no_dent(monkeypatch, step):
    spaced(monkeypatch, step)
    path = line(0.3)
    timed = time_path(path, ZERO_JOINTS.joint_path(path), *ZERO_LIMITS)
    assert largest_excursion(timed, ZERO_LIMITS[1]) <= EXCURSION
    assert limit_violation(timed.trajectory, np.full(3, 5.0), ZERO_LIMITS[1]) is None


def test_only_the_intervals_near_a_zero_where_the_limit_can_bind_are_cut():
    # Joint 0: q' = s - 0.55 (a zero at 0.55, q'' = 1); joint 1 moves at q' = 1 and does
    # not bend; joint 2 has a zero at 0.2 but bends too little for its limit to bind.
    s = np.linspace(0.0, 1.0, 11)
    ends = np.stack([s[:-1], s[1:]])
    rates = np.stack([ends - 0.55, np.ones_like(ends), 1e-3 * (ends - 0.2)], axis=2)
    curvatures = np.stack([np.ones_like(ends), np.zeros_like(ends),
                           np.full_like(ends, 1e-3)], axis=2)
    squared_speed = np.ones(11)  # |q''| ṡ² can reach 1 for joint 0, 1e-3 for joint 2
    limits = np.ones(3)
    finer = refine(s, rates, curvatures, squared_speed, limits)
    # 2Δ|q''| >= |q'| / 2 where |s - 0.55| <= 0.4: the intervals with an end in
    # [0.15, 0.95], from [0.1, 0.2] to [0.9, 1.0], each cut in SPLIT.
    cut = [False] + [True] * 9
    expected = np.concatenate(
        [np.linspace(s[k], s[k + 1], SPLIT + 1)[:-1] if cut[k] else s[k:k + 1]
         for k in range(10)] + [s[-1:]])
    np.testing.assert_allclose(finer, expected, rtol=0.0, atol=1e-15)
    assert np.all(np.isin(s, finer))
    # A joint limit that cannot bind, or no joint that bends: the grid as it was.
    assert refine(s, rates, curvatures, squared_speed, np.array([5.0, 1.0, 1.0])) is s
    assert refine(s, rates[..., 1:2], curvatures[..., 1:2], squared_speed, limits[1:]) is s


def test_a_rate_of_rounding_size_bounds_the_speed_alone():
    # u <= 4 and u >= -4 on every interval; on interval 3 a joint at its zero of dq/ds:
    # 35 x <= 4 with s̈'s coefficient at 1e-17 (rounding) or exactly 0: the same profile.
    def timed(rate: float) -> np.ndarray:
        count = 6
        a, b, c = np.zeros((count, 3)), np.zeros((count, 3)), np.zeros((count, 3))
        a[:, 0], a[:, 1], c[:, :2] = 1.0, -1.0, 4.0
        a[3, 2], b[3, 2], c[3, 2] = rate, 35.0, 4.0
        x_max = np.ones(count + 1)
        x_max[[0, -1]] = 0.0
        return time_optimal_squared_speed(Stages(x_max, a, b, c, np.full(count, 0.01)))

    exact = timed(0.0)
    np.testing.assert_array_equal(timed(1e-17), exact)
    # At 4 up to the bound 4/35 at point 3 (with the line it stayed there: s̈ pinned to
    # 0), on at 4 and braking at -4 to rest at the end.
    np.testing.assert_allclose(exact, [0.0, 0.08, 0.16, 4.0 / 35.0, 0.16, 0.08, 0.0],
                               rtol=1e-12)
