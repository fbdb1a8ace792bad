"""
Inverse kinematics of traj_gen_ros.core.kinematics: round trips, nearest solutions, refusals.

Every answer is checked with the independent numpy chain of the URDF (numpy_chain.py):
the pose it reaches, within 0.01 mm and 0.1 mrad, inside the limits.
"""

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from kinematics_robots import FLOATING_ARM, robot_urdf, ROBOTS, UR
import numpy as np
from numpy_chain import NumpyChain
import pytest
from traj_gen_ros.core.kinematics import (
    Chain,
    descent,
    inverse,
    pose_distance,
    UnreachablePoseError,
)

POSITION, ORIENTATION = 1e-5, 1e-4  # m, rad: the convergence the issue asks for
ARMS = ['pybullet-panda', 'pybullet-iiwa', 'pybullet-xarm6', 'erd-panda', 'erd-ur10']


def reached(oracle: NumpyChain, chain: Chain, q: np.ndarray, target: np.ndarray) -> None:
    """Assert that ``q`` is inside the limits and puts the tool on ``target`` (oracle)."""
    assert np.all(q >= chain.lower) and np.all(q <= chain.upper)
    pose = oracle.pose(chain.tool_frame, dict(zip(chain.joints, q, strict=True)),
                       chain.base_frame)
    distance, angle = pose_distance(target, pose)
    assert distance <= POSITION and angle <= ORIENTATION, (distance, angle)


def within_limits(chain: Chain, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    low = np.where(np.isfinite(chain.lower), chain.lower, -math.pi)
    high = np.where(np.isfinite(chain.upper), chain.upper, math.pi)
    return rng.uniform(low, high, size=(count, len(chain.joints)))


def load(config, name: str) -> tuple[Chain, NumpyChain, str]:
    spec = ROBOTS[name]
    urdf = robot_urdf(config, spec.source, spec.name)
    return Chain.from_urdf(urdf, spec.joints), NumpyChain(urdf), urdf


@pytest.mark.parametrize('name', ARMS)
def test_round_trips_from_a_seed_within_0_3_rad(pytestconfig, name):
    chain, oracle, _ = load(pytestconfig, name)
    rng = np.random.default_rng(10)
    for q in within_limits(chain, 30, seed=11):
        target = chain.forward(q)
        seed = np.clip(q + rng.uniform(-0.3, 0.3, q.size), chain.lower, chain.upper)
        solution = chain.inverse(target, seed)
        reached(oracle, chain, solution.q, target)
        assert solution.position_error <= POSITION
        assert solution.orientation_error <= ORIENTATION
        assert solution.iterations >= 1 and solution.start in (
            'seed', *(f'restart {k}' for k in range(1, inverse.RESTARTS + 1)))


@pytest.fixture(scope='module')
def panda(pytestconfig):
    return load(pytestconfig, 'erd-panda')


@settings(deadline=None, max_examples=25, derandomize=True)
@given(fractions=st.lists(st.floats(0.02, 0.98), min_size=7, max_size=7),
       nudge=st.lists(st.floats(-0.3, 0.3), min_size=7, max_size=7))
def test_round_trip_property_and_least_joint_motion_on_the_panda(panda, fractions, nudge):
    """Any reachable pose: converged, in limits, and no farther from the seed than q."""
    chain, oracle, _ = panda
    q = chain.lower + np.array(fractions) * (chain.upper - chain.lower)
    seed = np.clip(q + nudge, chain.lower, chain.upper)
    target = chain.forward(q)
    solution = chain.inverse(target, seed)
    reached(oracle, chain, solution.q, target)
    # q itself is one solution on the same self-motion: the answer moves no more.
    assert np.linalg.norm(solution.q - seed) <= np.linalg.norm(q - seed) + 1e-6


def test_a_7_joint_arm_resolves_its_spare_freedom_toward_the_seed(panda):
    chain, oracle, _ = panda
    rng = np.random.default_rng(12)
    for q in within_limits(chain, 10, seed=13):
        target = chain.forward(q)
        seed = np.clip(q + rng.uniform(-0.3, 0.3, 7), chain.lower, chain.upper)
        answer = chain.inverse(target, seed).q
        # Alternatives: other points of the solutions, from seeds elsewhere.
        alternatives = [q] + [chain.inverse(target, np.clip(
            q + rng.uniform(-0.4, 0.4, 7), chain.lower, chain.upper)).q for _ in range(4)]
        for alternative in alternatives:
            reached(oracle, chain, alternative, target)
            assert np.linalg.norm(answer - seed) <= np.linalg.norm(alternative - seed) + 1e-6
        # Stationary: the way back to the seed has no part that keeps the tool in place
        # (unless a joint limit holds it).
        if np.all((answer > chain.lower + 1e-6) & (answer < chain.upper - 1e-6)):
            null = np.linalg.svd(chain.jacobian(answer))[2][-1]
            assert abs(null @ (seed - answer)) < 1e-4


def ur10_pair(chain: Chain) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return a pose and its elbow-down and elbow-up solutions on the UR10."""
    a = np.array([0.4, -1.2, 1.5, -1.0, -1.3, 0.5])
    target = chain.forward(a)
    b = chain.inverse(target, [0.4, 0.2, -1.5, 0.5, -1.3, 0.5]).q  # the elbow flipped
    assert b[2] == pytest.approx(-1.5, abs=1e-3) and b[1] == pytest.approx(0.2376, abs=1e-3)
    return target, a, b


def test_of_two_elbow_solutions_the_one_nearer_the_seed_wins(pytestconfig):
    chain, oracle, _ = load(pytestconfig, 'erd-ur10')
    target, a, b = ur10_pair(chain)
    rng = np.random.default_rng(14)
    for _ in range(10):
        for near, other in ((a, b), (b, a)):
            seed = near + rng.uniform(-0.25, 0.25, 6)
            answer = chain.inverse(target, seed).q
            reached(oracle, chain, answer, target)
            assert np.abs(answer - near).max() < 1e-3
            assert np.abs(answer - seed).max() < np.abs(other - seed).max()


def test_after_a_failed_seed_the_restart_solution_nearest_the_seed_wins(
        pytestconfig, monkeypatch):
    chain, oracle, _ = load(pytestconfig, 'erd-ur10')
    target, a, _ = ur10_pair(chain)
    monkeypatch.setattr(inverse, 'SEED_ITERATIONS', 1)  # the seed's descent cannot converge
    seed = a + 0.05
    solution = chain.inverse(target, seed)
    assert solution.start.startswith('restart ')
    reached(oracle, chain, solution.q, target)
    # Every restart's own solution, as the solver found them, with whole turns nearest.
    found = []
    for start in inverse.restarts(chain, seed, chain.lower, chain.upper):
        attempt = descent.descend(chain, target, start, seed, chain.lower, chain.upper,
                                  (POSITION, ORIENTATION), inverse.RESTART_ITERATIONS)
        if attempt.converged:
            found.append(inverse._nearest_turns(attempt.q, seed, chain.lower, chain.upper,
                                                chain.periodic))
    assert len(found) >= 2
    largest = [np.abs(q - seed).max() for q in found]
    assert np.abs(solution.q - seed).max() == pytest.approx(min(largest), abs=1e-12)


def test_whole_turns_nearest_the_seed_for_continuous_and_wide_revolute_joints(pytestconfig):
    urdf = robot_urdf(pytestconfig, 'erd', 'ur10')
    continuous = Chain.from_urdf(urdf.replace('type="revolute"', 'type="continuous"'), UR)
    revolute = Chain.from_urdf(urdf, UR)  # limits ±2π (the elbow ±π)
    assert continuous.lower.tolist() == [-math.inf] * 6 and continuous.periodic.all()
    q = np.array([0.4, -1.2, 1.5, -1.0, -1.3, 0.5])
    target = revolute.forward(q)
    assert np.abs(continuous.forward(q) - target).max() < 1e-12  # cos/sin at the boundary
    turns = np.array([1, 0, -1, 2, 0, -3])
    seed = q + 2 * math.pi * turns + 0.05
    answer = continuous.inverse(target, seed).q
    assert answer == pytest.approx(q + 2 * math.pi * turns, abs=1e-4)
    # Within ±2π a revolute joint takes the turn nearest the seed as well.
    turns = np.array([-1, 1, 0, 1, 1, -1])
    answer = revolute.inverse(target, q + 2 * math.pi * turns + 0.05).q
    assert answer == pytest.approx(q + 2 * math.pi * turns, abs=1e-4)
    # The turn must stay inside the limits: 0.5 seen from 6.2 is 0.5 (6.78 is beyond 2π).
    turned = inverse._nearest_turns(np.array([0.5, 0.5]), np.array([6.2, 6.2]),
                                    np.array([-2 * math.pi, -math.inf]),
                                    np.array([2 * math.pi, math.inf]), np.array([True, True]))
    assert turned == pytest.approx([0.5, 0.5 + 2 * math.pi])


def test_prismatic_floating_base_and_mimic_chains_round_trip(pytestconfig):
    oracle = NumpyChain(FLOATING_ARM)
    chain = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'j3'], tool_frame='tool')
    r2d2_urdf = robot_urdf(pytestconfig, 'pybullet', 'r2d2')
    gripper = Chain.from_urdf(r2d2_urdf, ['gripper_extension', 'left_gripper_joint'])
    xarm_urdf = robot_urdf(pytestconfig, 'pybullet', 'xarm6_gripper')
    finger = Chain.from_urdf(xarm_urdf, [*ROBOTS['pybullet-xarm6'].joints, 'drive_joint'],
                             tool_frame='left_finger')  # left_finger_joint mimics drive
    rng = np.random.default_rng(15)
    for case, model in ((chain, oracle), (gripper, NumpyChain(r2d2_urdf)),
                        (finger, NumpyChain(xarm_urdf))):
        for q in within_limits(case, 10, seed=16):
            target = case.forward(q)
            seed = np.clip(q + rng.uniform(-0.2, 0.2, q.size), case.lower, case.upper)
            reached(model, case, case.inverse(target, seed).q, target)


def test_a_chain_read_backwards_solves_too(pytestconfig):
    """The base frame moves with every joint: the tool0's base seen from the tool."""
    urdf = robot_urdf(pytestconfig, 'erd', 'ur10')
    chain = Chain.from_urdf(urdf.encode(), UR, base_frame='tool0', tool_frame='base_link')
    oracle = NumpyChain(urdf)
    rng = np.random.default_rng(17)
    for q in within_limits(chain, 10, seed=18):
        target = chain.forward(q)
        seed = np.clip(q + rng.uniform(-0.3, 0.3, 6), chain.lower, chain.upper)
        reached(oracle, chain, chain.inverse(target, seed).q, target)


def test_out_of_reach_is_refused_saying_how_close_it_came(panda):
    chain, _, _ = panda
    target = chain.forward(np.zeros(7))
    target[:3, 3] = [2.0, 0.0, 0.5]  # the Panda reaches about 0.86 m
    with pytest.raises(UnreachablePoseError) as caught:
        chain.inverse(target, np.zeros(7))
    error = caught.value
    assert isinstance(error, ValueError)
    assert 0.9 < error.position_error < 2.0
    message = str(error)
    assert message.startswith("no joint positions within the limits put 'panda_hand_tcp' "
                              'at the target pose: the closest found (from the seed and 24 '
                              'restarts) is ')
    assert f'{error.position_error * 1e3:.3f} mm and ' \
           f'{error.orientation_error * 1e3:.3f} mrad from it' in message
    assert np.all(error.q >= chain.lower) and np.all(error.q <= chain.upper)


def test_a_joint_limit_that_forbids_the_pose_is_named(pytestconfig):
    chain, _, _ = load(pytestconfig, 'erd-ur10')
    target, a, _ = ur10_pair(chain)
    lower, upper = chain.lower.copy(), chain.upper.copy()
    lower[0], upper[0] = -0.2, 0.2  # every solution turns the base to 0.4 or 0.4 - π
    with pytest.raises(UnreachablePoseError) as caught:
        chain.inverse(target, np.zeros(6), lower, upper)
    assert caught.value.limited == ('shoulder_pan_joint',)
    assert "stopped by joint 'shoulder_pan_joint' at its upper limit 0.2 rad" \
        in str(caught.value)
    # With its own limits the same pose is reached.
    assert chain.inverse(target, np.zeros(6)).q is not None


def test_invalid_targets_seeds_and_limits_are_refused(panda):
    chain, _, _ = panda
    target = chain.forward(np.zeros(7))
    sheared = target.copy()
    sheared[0, 1] += 0.1
    cases = [
        ((sheared, np.zeros(7)), 'target pose: the upper-left 3x3 block is not a rotation'),
        ((target[:3], np.zeros(7)), 'target pose must be a 4x4 homogeneous transform'),
        ((target, np.zeros(6)), 'seed has shape (6,): expected (7,)'),
        ((target, [0, 0, 0, math.nan, 0, 0, 0]), "seed of joint 'panda_joint4' is nan"),
        ((target, np.zeros(7), np.zeros(6)), 'lower limits must be 7 numbers'),
        ((target, np.zeros(7), chain.upper, chain.lower),
         "joint 'panda_joint1': lower limit 2.8973 > upper limit -2.8973"),
    ]
    for arguments, expected in cases:
        with pytest.raises(ValueError) as caught:
            chain.inverse(*arguments)
        assert expected in str(caught.value), str(caught.value)
        assert not isinstance(caught.value, UnreachablePoseError)
    with pytest.raises(ValueError, match='tolerances must be > 0'):
        chain.inverse(target, np.zeros(7), position_tolerance=0.0)


def test_a_seed_outside_the_limits_starts_inside_them(panda):
    chain, oracle, _ = panda
    q = np.array([0.0, 0.3, 0.0, -1.5, 0.0, 1.8, 0.7])
    target = chain.forward(q)
    seed = q.copy()
    seed[3] = 0.2  # above joint 4's upper limit, -0.0698 rad
    answer = chain.inverse(target, seed).q
    reached(oracle, chain, answer, target)
