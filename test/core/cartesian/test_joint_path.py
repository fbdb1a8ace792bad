"""
The joint path of a straight tool line (test/support/line_stub.py) on real arms.

Every joint path is checked by what it must do, with oracles written here: the tool (the
chain's forward kinematics of ``joints.sample(s)``) within 0.02 mm and 0.2 mrad of the
ideal line at 10,000 values of ``s``; ``dq/ds`` and ``d²q/ds²`` against central
differences of ``q(s)`` and the tool's own velocity ``J q' = x'``; the joints inside their
limits; on the 7-joint arms the least joint motion, against scipy's integration of
``dq/ds = pinv(J) x'`` and the null space of ``J`` (numpy's SVD).
"""

from kinematics_robots import robot_urdf, ROBOTS
from line_stub import LineStub, PolylineStub, rotations, tool_errors
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from traj_gen_ros.core.cartesian.joint_path import follow
from traj_gen_ros.core.cartesian.path_refusal import PathRefusal
from traj_gen_ros.core.kinematics import Chain

POSITION, ORIENTATION = 2e-5, 2e-4  # m, rad: the bound between grid points
#: A start inside the limits of each arm, away from its singularities.
STARTS = {
    'erd-panda': [0.0, -0.4, 0.0, -2.2, 0.0, 1.8, 0.8],
    'erd-ur10': [0.3, -1.2, 1.5, -1.8, -1.4, 0.5],
    'pybullet-iiwa': [0.2, 0.6, -0.3, -1.2, 0.4, 0.9, 0.1],
}
MOVES = {  # (translation m, rotation vector rad) of the goal from the start
    'line': ([0.18, 0.12, -0.2], [0.0, 0.0, 0.0]),
    'line and rotation': ([0.18, 0.12, -0.2], [0.3, -0.4, 0.5]),
    'rotation in place': ([0.0, 0.0, 0.0], [0.3, -0.4, 0.5]),
}


def load(config, name: str) -> Chain:
    spec = ROBOTS[name]
    return Chain.from_urdf(robot_urdf(config, spec.source, spec.name), spec.joints)


def moved(pose: np.ndarray, translation, rotation) -> np.ndarray:
    goal = pose.copy()
    goal[:3, 3] += translation
    goal[:3, :3] = rotations(np.array([rotation], dtype=float))[0] @ pose[:3, :3]
    return goal


@pytest.fixture(scope='module', params=sorted(STARTS))
def arm(request, pytestconfig):
    return request.param, load(pytestconfig, request.param)


@pytest.mark.parametrize('move', sorted(MOVES))
def test_the_tool_follows_the_line_and_the_rates_are_the_derivatives(arm, move):
    name, chain = arm
    q_start = np.array(STARTS[name])
    line = LineStub(chain.forward(q_start), moved(chain.forward(q_start), *MOVES[move]))
    path = follow(chain, line, q_start)
    joints = path.joints
    assert path.length == line.length and joints.duration == line.length
    assert np.array_equal(path.knots, [0.0, line.length])
    assert np.array_equal(path.stops, [0.0, line.length])
    assert np.array_equal(joints.sample(0.0)[0][0], q_start)
    distance, angle = tool_errors(chain, joints, line)
    assert distance <= POSITION and angle <= ORIENTATION, (distance, angle)
    extrema = joints.position_extrema()
    assert (extrema.minimum >= chain.lower).all() and (extrema.maximum <= chain.upper).all()
    # The derivatives by s: central differences of q(s) away from the breakpoints.
    rng = np.random.default_rng(1)
    s = rng.uniform(0.01, 0.99, 40) * line.length
    step = 1e-5
    q, rate, curvature = joints.sample(s)
    ahead, behind = joints.sample(s + step)[0], joints.sample(s - step)[0]
    assert np.abs((ahead - behind) / (2 * step) - rate).max() < 1e-6
    assert np.abs((ahead - 2 * q + behind) / step**2 - curvature).max() < 1e-3
    # dq/ds moves the tool along the line at one unit of path per unit: J q' = x'.
    tangent = np.concatenate([line.step, line.turn]) / line.length
    for k in range(0, 40, 4):
        assert np.abs(chain.jacobian(q[k]) @ rate[k] - tangent).max() < 2e-3


@pytest.mark.parametrize('name', ['erd-panda', 'pybullet-iiwa'])
def test_a_seven_joint_arm_moves_its_joints_the_least(pytestconfig, name):
    """The continuation of dq/ds = J⁺ x': no motion in J's null space, as scipy integrates."""
    chain = load(pytestconfig, name)
    q_start = np.array(STARTS[name])
    line = LineStub(chain.forward(q_start),
                    moved(chain.forward(q_start), *MOVES['line and rotation']))
    joints = follow(chain, line, q_start).joints
    tangent = np.concatenate([line.step, line.turn]) / line.length
    oracle = solve_ivp(lambda s, q: np.linalg.pinv(chain.jacobian(q)) @ tangent,
                       (0.0, line.length), q_start, rtol=1e-10, atol=1e-12, dense_output=True)
    s = np.linspace(0.0, line.length, 60)
    assert np.abs(joints.sample(s)[0] - oracle.sol(s).T).max() < 1e-3
    for q, rate in zip(*joints.sample(s[1:])[:2], strict=True):
        _, _, vt = np.linalg.svd(chain.jacobian(q))
        null = vt[6:]  # (1, 7): the direction that leaves the tool where it is
        assert np.linalg.norm(null @ rate) < 2e-3 * np.linalg.norm(rate)
    # Any other joint path adds motion along the null space: the least-norm rate is unique.
    q, rate = joints.sample(0.5 * line.length)[:2]
    _, _, vt = np.linalg.svd(chain.jacobian(q[0]))
    other = rate[0] + 0.1 * vt[6]
    assert np.linalg.norm(other) > np.linalg.norm(rate[0])


def test_q_start_must_be_at_the_start_of_the_path(pytestconfig):
    chain = load(pytestconfig, 'erd-ur10')
    q_start = np.array(STARTS['erd-ur10'])
    start = chain.forward(q_start)
    line = LineStub(start, moved(start, [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]))
    off = q_start.copy()
    off[0] += 1e-4  # the tool moves by about 0.1 mm: more than the 0.01 mm allowed
    with pytest.raises(ValueError) as caught:
        follow(chain, line, off)
    distance = np.linalg.norm(chain.forward(off)[:3, 3] - start[:3, 3])
    assert f'{distance * 1e3:.4g} mm' in str(caught.value)
    assert 'within 0.01 mm and 0.1 mrad' in str(caught.value)
    with pytest.raises(ValueError, match='q_start must be 6 finite numbers'):
        follow(chain, line, [0.0] * 5)
    with pytest.raises(ValueError, match='upper limits must be 6 numbers'):
        follow(chain, line, q_start, upper=[1.0, 2.0])
    upper = chain.upper.copy()
    upper[2] = q_start[2] - 0.1
    with pytest.raises(PathRefusal, match="q_start puts joint 'elbow_joint' at 1.5 rad, "
                       'beyond its upper limit 1.4 rad') as caught:
        follow(chain, line, q_start, upper=upper)
    assert (caught.value.kind, caught.value.fraction, caught.value.joint) == ('limit', 0.0, 2)
    lower = chain.lower.copy()
    lower[2] = upper[2] + 0.1
    with pytest.raises(ValueError, match="joint 'elbow_joint': lower limit 1.5 > upper "):
        follow(chain, line, q_start, lower=lower, upper=upper)


def test_a_corner_is_a_breakpoint_where_the_rates_jump_to_the_next_line(pytestconfig):
    chain = load(pytestconfig, 'erd-panda')
    q_start = np.array(STARTS['erd-panda'])
    start = chain.forward(q_start)
    middle = moved(start, [0.15, 0.0, -0.1], [0.0, 0.2, 0.0])
    path = PolylineStub([start, middle, moved(middle, [0.0, 0.12, 0.05], [0.3, 0.0, 0.0])])
    joint_path = follow(chain, path, q_start)
    joints, corner = joint_path.joints, path.knots[1]
    assert np.array_equal(joint_path.knots, path.knots)
    assert np.array_equal(joint_path.stops, path.stops)
    assert corner in joints.breakpoints
    distance, angle = tool_errors(chain, joints, path)
    assert distance <= POSITION and angle <= ORIENTATION, (distance, angle)
    # q is continuous at the corner; each side's dq/ds is J⁺ x' of its own line.
    piece = int(np.flatnonzero(joints.breakpoints == corner)[0])
    before = joints.coefficients[piece - 1]
    length = corner - joints.breakpoints[piece - 1]
    end = before.T @ length ** np.arange(6)
    end_rate = before[1:].T @ (np.arange(1, 6) * length ** np.arange(5))
    q, rate, _ = joints.sample(corner)
    assert np.abs(end - q[0]).max() < 1e-12
    inverse = np.linalg.pinv(chain.jacobian(q[0]))
    for side, found in (('left', end_rate), ('right', rate[0])):
        sample = path.sample(corner, side)
        tangent = np.concatenate([sample.velocity[0], sample.angular[0]])
        assert np.abs(found - inverse @ tangent).max() < 1e-9, side
    assert np.abs(end_rate - rate[0]).max() > 0.1
