"""A line's brake along its path under profile scurve: from the commanded state, jerk held."""

import numpy as np
import pytest
from synthetic_paths import line, seven_joints
from traj_gen_ros.core.cartesian.jerk_limited_timing import time_path_jerk_limited
from traj_gen_ros.core.cartesian.path_timing import ToolLimits
from traj_gen_ros.core.kinematic_limits import limit_violation
from traj_gen_ros.node.planning.tool_motion import AlongPath

TOOL = ToolLimits(0.25, 1.2, 1.5)
V, A, J = np.full(7, 1.0), np.full(7, 3.0), np.full(7, 20.0)
OFFSET = 0.5  # the brake to rest before the path, s


@pytest.fixture(scope='module')
def along():
    path = line(0.3)
    joint_path = seven_joints().joint_path(path)
    timed = time_path_jerk_limited(path, joint_path, V, A, J, TOOL)
    return AlongPath(path, joint_path, timed, OFFSET, V, A, TOOL, J)


@pytest.mark.parametrize('fraction', [0.08, 0.12, 0.5, 0.85])
@pytest.mark.parametrize('override', [1.0, 0.5])
def test_the_brake_continues_the_commanded_state_within_every_limit(along, fraction,
                                                                    override):
    local = fraction * along.timed.duration
    _, velocity, acceleration = (value[0] for value in along.timed.trajectory.sample(local))
    # A constant override f runs the plan's own time at f: q̇ f, q̈ f².
    commanded = velocity * override, acceleration * override ** 2
    for given in (None, commanded[1]):
        plan = along.brake(OFFSET + local, commanded[0], given)
        assert plan is not None
        start = plan.sample(0.0)
        assert np.abs(start[1][0] - commanded[0]).max() < 1e-6
        assert np.abs(start[2][0] - commanded[1]).max() < 1e-4  # no step: the jerk holds
        assert limit_violation(plan, V, A, J) is None
        final = plan.sample(plan.duration)
        assert np.abs(final[1][0]).max() < 1e-9
        assert plan.duration < (1.0 - fraction) * along.timed.duration / override + 1e-9


def test_no_brake_along_the_path_before_it_or_at_rest(along):
    velocity = along.timed.trajectory.sample(0.3)[1][0]
    assert along.brake(OFFSET - 0.1, velocity) is None  # still in the brake before it
    assert along.brake(OFFSET + 0.3, np.zeros(7)) is None
    assert along.brake(OFFSET + along.timed.duration + 0.1, velocity) is None
