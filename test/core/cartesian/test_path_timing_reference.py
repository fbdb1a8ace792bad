"""
time_path against an independent time-optimal timing: the phase plane on 10,000+ points.

The oracle is test/support/topp_reference.py (the classical phase-plane method, sharing
nothing with the package's timing), on the analytic ``q(s)`` of test/support/synthetic_paths.
"""

import pytest
from synthetic_paths import arc, blended_corner, corner, line, seven_joints
from topp_reference import reference_duration
from traj_gen_ros.core.cartesian.path_timing import time_path, ToolLimits

CASES = {
    'line, joint limits': (line(0.3), seven_joints(7), 1.0, 4.0, ToolLimits()),
    'line, joint and tool limits': (line(0.3), seven_joints(3), 2.0, 8.0,
                                    ToolLimits(0.5, 2.0, 1.0)),
    'arc, the tool acceleration': (arc(0.05, 2.0), seven_joints(1, scale=0.3), 3.0, 30.0,
                                   ToolLimits(1.0, 2.0)),
    'blended corner': (blended_corner(0.15, 0.02, 1.2, 0.15), seven_joints(5), 2.0, 10.0,
                       ToolLimits(0.5, 3.0)),
    'corner with a stop': (corner(0.15, 0.1, 1.0), seven_joints(2), 1.5, 6.0,
                           ToolLimits(0.4, 3.0)),
}


@pytest.mark.parametrize('case', CASES)
def test_duration_is_within_one_percent_of_the_phase_plane_optimum(case):
    path, joints, vmax, amax, tool = CASES[case]
    timed = time_path(path, joints.joint_path(path), vmax, amax, tool)
    reference = reference_duration(path, joints.states, vmax, amax, tool)
    # Never shorter than the optimum by more than the oracle's own Euler error (~1/POINTS);
    # the polygon of the tool's acceleration and the grid cost at most 1 % more.
    assert reference * (1.0 - 1e-3) <= timed.duration <= reference * 1.01
