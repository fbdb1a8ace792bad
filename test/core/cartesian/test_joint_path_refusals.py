"""
Craig §7.5's geometric problems on the UR10: singularities, a flip, the reach, a limit.

The UR10's wrist is singular at ``wrist_2 = 0``, where the wrist_1 and wrist_3 axes are
parallel; its tool frame (wrist_3_link) lies on the wrist_2 axis, so turning that axis
alone is a rotation of the tool in place. Its reach ends where the elbow is straight: the
wrist_1 axis ``a₂ + a₃`` from the shoulder_lift axis, measured on the URDF here. Every
refusal's where and how much is checked with an oracle of its own: numpy's SVD, the
analytic reach, a bisection with the inverse kinematics.
"""

import math

from kinematics_robots import robot_urdf, ROBOTS
from line_stub import LineStub, rotations, tool_errors
import numpy as np
import pytest
from traj_gen_ros.core.cartesian.continuation import RATE_LIMIT
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_checks import PROBE
from traj_gen_ros.core.cartesian.path_refusal import PathRefusal
from traj_gen_ros.core.kinematics import Chain, UnreachablePoseError

WRIST_1, WRIST_2 = 3, 4
START = np.array([0.3, -1.2, 1.5, -1.8, -0.3, 0.5])  # wrist_2 = -0.3: near the singularity


@pytest.fixture(scope='module')
def ur10(pytestconfig):
    spec = ROBOTS['erd-ur10']
    return Chain.from_urdf(robot_urdf(pytestconfig, spec.source, spec.name), spec.joints)


def turned(pose: np.ndarray, rotation: np.ndarray, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    goal = pose.copy()
    goal[:3, :3] = rotations(np.array([rotation]))[0] @ pose[:3, :3]
    goal[:3, 3] += translation
    return goal


def wrist_line(chain: Chain, tilt: float) -> LineStub:
    """Turn 0.8 rad about the wrist_2 axis, tilted by ``tilt`` rad/rad about a horizontal."""
    axis = chain.frame_pose('wrist_2_link', START)[:3, 2]
    across = np.cross(axis, [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    return LineStub(chain.forward(START),
                    turned(chain.forward(START), 0.8 * axis + tilt * across))


def test_a_line_through_the_wrist_singularity_with_bounded_rates_is_followed(ur10):
    """Only wrist_2 turns, from -0.3 through 0 (singular) to 0.5: 1 rad per rad."""
    line = wrist_line(ur10, 0.0)
    joints = follow(ur10, line, START).joints
    q, rate, _ = joints.sample(np.linspace(0.0, line.length, 2001))
    assert np.abs(np.abs(rate).max() - 1.0) < 1e-6
    assert q[0, WRIST_2] == -0.3 and abs(q[-1, WRIST_2] - 0.5) < 1e-6
    middle = ur10.jacobian(np.where(np.arange(6) == WRIST_2, 0.0, START))
    assert np.linalg.svd(middle, compute_uv=False)[-1] < 1e-12  # it does pass a singularity
    distance, angle = tool_errors(ur10, joints, line)
    assert distance <= 2e-5 and angle <= 2e-4


def test_a_general_line_through_the_singularity_in_the_jacobians_range_is_followed(ur10):
    """A line through the pose at wrist_2 = 0 along x' = J v: passed, wrist_2 changes sign."""
    singular = START.copy()
    singular[WRIST_2] = 0.0
    jacobian = ur10.jacobian(singular)
    assert np.linalg.svd(jacobian, compute_uv=False)[-1] < 1e-12
    v = np.array([0.4, -0.7, 0.3, 0.9, 1.0, -0.5])
    tangent = jacobian @ v / np.linalg.norm(jacobian @ v)  # in J's range, one unit of path
    pose = ur10.forward(singular)

    def at(s: float) -> np.ndarray:
        return turned(pose, s * tangent[3:], s * tangent[:3])

    before, after = 0.13, 0.21
    q_start = ur10.inverse(at(-before), singular - before * v / np.linalg.norm(jacobian @ v),
                           position_tolerance=1e-9, orientation_tolerance=1e-8).q
    line = LineStub(at(-before), at(after))
    joints = follow(ur10, line, q_start).joints
    q, rate, _ = joints.sample(np.linspace(0.0, line.length, 2001))
    assert q[0, WRIST_2] < -0.02 and q[-1, WRIST_2] > 0.02
    assert np.abs(rate).max() < 2.0
    distance, angle = tool_errors(ur10, joints, line)
    assert distance <= 2e-5 and angle <= 2e-4


def test_a_line_near_the_singularity_is_followed_with_high_rates(ur10):
    line = wrist_line(ur10, 0.2)
    joints = follow(ur10, line, START).joints
    q, rate, _ = joints.sample(np.linspace(0.0, line.length, 20001))
    assert 30.0 < np.abs(rate).max() < RATE_LIMIT
    assert (q[:, WRIST_2] < 0.0).all()  # it keeps its wrist configuration
    distance, angle = tool_errors(ur10, joints, line)
    assert distance <= 2e-5 and angle <= 2e-4


def test_a_line_too_close_to_the_singularity_is_refused_as_singular(ur10):
    line = wrist_line(ur10, 0.005)
    with pytest.raises(PathRefusal) as caught:
        follow(ur10, line, START)
    refusal = caught.value
    assert refusal.kind == 'singular' and 'singular' in str(refusal)
    assert refusal.joint == WRIST_1 and "'wrist_1_joint'" in str(refusal)
    s = refusal.fraction * line.length
    assert f'{100 * refusal.fraction:.4g} %' in str(refusal)
    # Its q is on the path there, J's smallest singular value is the one reported, and the
    # least-norm rate of the named joint is the limit: where |dq/ds| reaches 100 first.
    pose = ur10.forward(refusal.q)
    assert np.linalg.norm(pose[:3, 3] - line.pose(s)[:3, 3]) < 2e-5
    jacobian = ur10.jacobian(refusal.q)
    smallest = np.linalg.svd(jacobian, compute_uv=False)[-1]
    assert refusal.value == pytest.approx(smallest, rel=1e-9)
    assert f'{smallest:.3g}' in str(refusal)
    tangent = np.concatenate([line.step, line.turn]) / line.length
    rate = np.linalg.pinv(jacobian) @ tangent
    assert int(np.argmax(np.abs(rate))) == WRIST_1
    assert abs(rate[WRIST_1]) == pytest.approx(RATE_LIMIT, rel=2e-3)
    # Before it the rates are below the limit (and rising fast): the line up to just short
    # of it is followed.
    short = LineStub(line.pose(0.0), line.pose(0.999 * s))
    rates = follow(ur10, short, START).joints.sample(np.linspace(0, short.length, 5001))[1]
    assert RATE_LIMIT / 2 < np.abs(rates).max() < RATE_LIMIT


def planar_reach(chain: Chain, q: np.ndarray) -> tuple[np.ndarray, float]:
    """
    Return an outward direction in the arm's plane, and the s where the elbow is straight.

    With the tool's orientation fixed and the motion in the plane normal to the
    shoulder_lift axis, the pan and wrist stay put and the wrist_1 axis moves with the
    tool: the reach ends where it is ``|a₂| + |a₃|`` (the distance at elbow 0) from the
    shoulder_lift axis, a quadratic in ``s``.
    """
    def in_plane(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        shoulder = chain.frame_pose('upper_arm_link', q)
        normal = shoulder[:3, :3] @ [0.0, 1.0, 0.0]
        apart = chain.frame_pose('wrist_1_link', q)[:3, 3] - shoulder[:3, 3]
        return apart - (apart @ normal) * normal, normal

    straight = q.copy()
    straight[2] = 0.0
    longest = np.linalg.norm(in_plane(straight)[0])
    apart, normal = in_plane(q)
    direction = np.cross(normal, [0.0, 0.0, 1.0])
    direction *= np.sign(direction @ apart) / np.linalg.norm(direction)
    half = apart @ direction
    return direction, -half + math.sqrt(half * half - (apart @ apart - longest**2))


def test_a_line_out_of_reach_is_refused_where_the_elbow_is_straight(ur10):
    q_start = np.array([0.3, -1.2, 1.5, -1.8, 1.4, 0.5])
    direction, edge = planar_reach(ur10, q_start)
    line = LineStub(ur10.forward(q_start), turned(ur10.forward(q_start), np.zeros(3),
                                                  2.0 * direction))
    with pytest.raises(PathRefusal) as caught:
        follow(ur10, line, q_start)
    refusal = caught.value
    assert refusal.kind == 'reach' and refusal.joint is None
    assert abs(refusal.fraction - edge / line.length) < 1e-6
    assert 'leaves the reach' in str(refusal)
    # 1 mm beyond the edge the closest attempt stays about 1 mm away (the arm is straight).
    assert 0.5 * PROBE < refusal.value < PROBE
    with pytest.raises(UnreachablePoseError):
        ur10.inverse(line.pose(edge + PROBE), refusal.q)


def test_a_line_the_wrist_must_flip_to_follow_is_refused_as_a_flip(ur10):
    """From wrist_2 < 0 the elbow straightens where the flipped wrist still reaches on."""
    q_start = np.array([0.3, -1.2, 1.5, -1.8, -1.4, 0.5])
    direction, edge = planar_reach(ur10, q_start)
    line = LineStub(ur10.forward(q_start), turned(ur10.forward(q_start), np.zeros(3),
                                                  2.0 * direction))
    with pytest.raises(PathRefusal) as caught:
        follow(ur10, line, q_start)
    refusal = caught.value
    assert refusal.kind == 'flip' and 'configuration flip' in str(refusal)
    assert abs(refusal.fraction - edge / line.length) < 1e-6
    assert refusal.joint == WRIST_2 and "'wrist_2_joint' jumping by" in str(refusal)
    assert 3.0 < refusal.value < 3.3 and f'{refusal.value:.4g} rad' in str(refusal)
    beyond = line.pose(edge + PROBE)
    # Beyond the edge no joint positions with the start's wrist (wrist_2 < 0) reach...
    lower, upper = ur10.lower.copy(), ur10.upper.copy()
    lower[WRIST_2], upper[WRIST_2] = -math.pi + 0.01, -0.01
    with pytest.raises(UnreachablePoseError):
        ur10.inverse(beyond, refusal.q, lower, upper)
    # ...but the flipped wrist does, wrist_2 jumping by the size reported.
    lower[WRIST_2], upper[WRIST_2] = 0.01, math.pi - 0.01
    flipped = ur10.inverse(beyond, refusal.q, lower, upper).q
    assert abs(flipped[WRIST_2] - refusal.q[WRIST_2]) == pytest.approx(refusal.value, abs=0.05)


def test_a_line_across_a_joint_limit_is_refused_where_it_crosses_it(ur10):
    q_start = np.array([0.3, -1.2, 1.5, -1.8, -1.4, 0.5])
    start = ur10.forward(q_start)
    line = LineStub(start, turned(start, np.array([0.4, 0.3, -0.6]), [0.2, -0.3, 0.25]))
    joint, bound = 0, 0.05  # shoulder_pan goes from 0.3 down past 0.05
    lower = ur10.lower.copy()
    lower[joint] = bound
    with pytest.raises(PathRefusal) as caught:
        follow(ur10, line, q_start, lower=lower)
    refusal = caught.value
    assert refusal.kind == 'limit' and refusal.joint == joint and refusal.value == bound
    assert "joint 'shoulder_pan_joint' would cross its lower limit 0.05 rad" in str(refusal)

    def pan(s: float, seed: np.ndarray) -> np.ndarray:  # the continuation, by IK steps
        return ur10.inverse(line.pose(s), seed, position_tolerance=1e-10,
                            orientation_tolerance=1e-9).q

    q, low = q_start, 0.0
    while True:  # march to a bracket
        ahead = pan(low + 0.02, q)
        if ahead[joint] < bound:
            break
        q, low = ahead, low + 0.02
    high = low + 0.02
    while high - low > 1e-9:
        middle = 0.5 * (low + high)
        trial = pan(middle, q)
        if trial[joint] < bound:
            high = middle
        else:
            low, q = middle, trial
    assert abs(refusal.fraction * line.length - low) < 1e-7


def test_a_line_starting_singular_in_the_direction_the_arm_cannot_move_is_refused(ur10):
    singular = START.copy()
    singular[WRIST_2] = 0.0
    u, sigma, vt = np.linalg.svd(ur10.jacobian(singular))
    lost = u[:, -1]  # the tool motion the Jacobian cannot make there (σ₆ = 0)
    start = ur10.forward(singular)
    line = LineStub(start, turned(start, 0.05 * lost[3:], 0.05 * lost[:3]))
    with pytest.raises(PathRefusal) as caught:
        follow(ur10, line, singular)
    refusal = caught.value
    assert (refusal.kind, refusal.fraction) == ('singular', 0.0)
    assert refusal.value == pytest.approx(sigma[-1], abs=1e-12) and refusal.value < 1e-12
    assert refusal.joint == int(np.argmax(np.abs(vt[-1])))
    assert 'an unbounded rate' in str(refusal)
