"""Via points' plan: the start rule of via_points (setpoint first; a point at 0 is the start)."""

import numpy as np
from planning_rig import JOINTS
import pytest
from traj_gen_ros.node.messages.parsing import (
    parse_via,
    RequestError,
)
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.planning.via_path import via_points


def test_via_points_rules():
    state = State(np.array([0.0, 1.0, 2.0]), np.array([0.5, 0, 0]), np.zeros(3))
    hold = np.array([9.0, 1.0, 2.0])
    # time > 0: the setpoint is prepended; unnamed joints go to ``hold``.
    request = parse_via(JOINTS, ['b'], [([1.5], [], [], 1.0)])
    points, times, _, _ = via_points(JOINTS, state, hold, request)
    assert points.tolist() == [[0.0, 1.0, 2.0], [9.0, 1.5, 2.0]] and times.tolist() == [0, 1]
    # time 0 at the current position: it is the start.
    request = parse_via(JOINTS, ['b'], [([1.0], [], [], 0.0), ([1.5], [], [], 1.0)])
    points, times, _, _ = via_points(JOINTS, state, hold, request)
    assert len(points) == 2 and times.tolist() == [0, 1]
    # time 0 elsewhere: refused, naming the joint.
    request = parse_via(JOINTS, ['b'], [([1.2], [], [], 0.0), ([1.5], [], [], 1.0)])
    with pytest.raises(RequestError, match="joint 'b' is at 1 rad, not 1.2"):
        via_points(JOINTS, state, hold, request)
