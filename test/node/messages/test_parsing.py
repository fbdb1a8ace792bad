"""Read and check names and values: message fields into GoalRequest / ViaRequest, refusals."""

from planning_rig import JOINTS
import pytest
from traj_gen_ros.node.messages.parsing import (
    parse_goal,
    parse_via,
    RequestError,
)


def test_parse_goal_and_via_errors():
    assert parse_goal(JOINTS, ['c', 'a'], [1.0, 2.0]).joints.tolist() == [2, 0]
    with pytest.raises(RequestError, match="unknown joint 'x'; known joints"):
        parse_goal(JOINTS, ['x'], [1.0])
    with pytest.raises(RequestError, match='strictly increasing: point 2'):
        parse_via(JOINTS, ['a'], [([0.1], [], [], 1.0), ([0.2], [], [], 2.0),
                                  ([0.3], [], [], 2.0)])
    with pytest.raises(RequestError, match='point 0 has time_from_start -1.0 s'):
        parse_via(JOINTS, ['a'], [([0.1], [], [], -1.0)])
    with pytest.raises(RequestError, match='accelerations are given without velocities'):
        parse_via(JOINTS, ['a'], [([0.1], [], [0.0], 1.0)])
    assert parse_via(JOINTS, ['a'], [([0.1], [], [], 0.0), ([0.2], [], [], 0.0)]).auto_timed
