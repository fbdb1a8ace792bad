"""
The two Chain methods the joint path needs: pose_and_jacobian and jacobian_rate (J̇).

J̇ is checked against central differences of Chain.jacobian along ``q + t·q̇`` (its
definition), on real arms and on the written arm's awkward chains: a base_frame that is
not the root, one that the joints move, a continuous joint and an offset mimic joint.
"""

from kinematics_robots import FLOATING_ARM, robot_urdf, ROBOTS
import numpy as np
import pytest
from traj_gen_ros.core.kinematics import Chain


def chains(config) -> dict[str, Chain]:
    """Return the chains to check, by label."""
    found = {name: Chain.from_urdf(robot_urdf(config, ROBOTS[name].source, ROBOTS[name].name),
                                   ROBOTS[name].joints)
             for name in ('erd-panda', 'erd-ur10')}
    found['world base, continuous j2'] = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'j3'],
                                                         held={'side': 0.7})
    found['fixed base off the root, mimic j4'] = Chain.from_urdf(
        FLOATING_ARM, ['j1', 'j2', 'j3'], base_frame='arm_side', tool_frame='tool',
        held={'side': 0.7})
    found['moving base l2'] = Chain.from_urdf(FLOATING_ARM, ['j1', 'j2', 'side'],
                                              base_frame='l2', tool_frame='arm_side')
    found['moving base l4, mimic j4'] = Chain.from_urdf(
        FLOATING_ARM, ['j1', 'j2', 'j3'], base_frame='l4', tool_frame='arm_side',
        held={'side': 0.4})
    return found


@pytest.fixture(scope='module')
def every_chain(pytestconfig):
    return chains(pytestconfig)


def test_jacobian_rate_is_the_derivative_of_the_jacobian_along_the_motion(every_chain):
    rng = np.random.default_rng(7)
    for label, chain in every_chain.items():
        for _ in range(4):
            q = rng.uniform(-0.8, 0.8, len(chain.joints))
            rate = rng.uniform(-1.0, 1.0, len(chain.joints))
            step = 1e-6
            expected = (chain.jacobian(q + step * rate) - chain.jacobian(q - step * rate)) / (
                2 * step)
            turning = chain.jacobian_rate(q, rate)
            assert turning.shape == (6, len(chain.joints))
            assert np.abs(turning - expected).max() < 1e-8, label
            # J̇ is linear in the rate: twice the rate, twice J̇.
            assert np.allclose(chain.jacobian_rate(q, 2 * rate), 2 * turning, atol=1e-12)


def test_pose_and_jacobian_are_forward_and_jacobian_in_one_pass(every_chain):
    rng = np.random.default_rng(8)
    for chain in every_chain.values():
        q = rng.uniform(-0.8, 0.8, len(chain.joints))
        pose, jacobian = chain.pose_and_jacobian(q)
        assert np.array_equal(pose, chain.forward(q))
        assert np.array_equal(jacobian, chain.jacobian(q))


def test_one_configuration_only(every_chain):
    chain = every_chain['erd-ur10']
    with pytest.raises(ValueError, match=r'rate has shape \(2, 6\): jacobian_rate takes \(6,\)'):
        chain.jacobian_rate(np.zeros(6), np.zeros((2, 6)))
    with pytest.raises(ValueError, match=r'q has shape \(1, 6\): pose_and_jacobian takes \(6,\)'):
        chain.pose_and_jacobian(np.zeros((1, 6)))
