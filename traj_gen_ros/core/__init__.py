"""
The public trajectory API: every Craig ch. 7 profile, the jerk-limited S-curve, timing.

Positions are scalars (one joint) or 1-D arrays (one value per joint); via points are
``(points,)`` or ``(points, joints)``. Every result is a :class:`Trajectory`. Units are
SI: rad (or m), s.
"""

from traj_gen_ros.core.blends import BlendedTrajectory, lspb, lspb_via
from traj_gen_ros.core.jerk_limited.brake import scurve_brake
from traj_gen_ros.core.jerk_limited.move import scurve
from traj_gen_ros.core.jerk_limited.path import scurve_via
from traj_gen_ros.core.kinematic_limits import (
    JointError,
    LIMIT_TOLERANCE,
    limit_violation,
    Violation,
    within_limits,
)
from traj_gen_ros.core.paths import plan_path, via_durations
from traj_gen_ros.core.polynomial import (
    continuous_velocities,
    cubic,
    cubic_via,
    heuristic_velocities,
    quintic,
    quintic_via,
)
from traj_gen_ros.core.stops import brake
from traj_gen_ros.core.timing import hold, min_time, PROFILES
from traj_gen_ros.core.trajectory import JerkLimitedTrajectory, Trajectory

__all__ = [
    'PROFILES',
    'LIMIT_TOLERANCE',
    'BlendedTrajectory',
    'JerkLimitedTrajectory',
    'JointError',
    'Trajectory',
    'brake',
    'continuous_velocities',
    'cubic',
    'cubic_via',
    'heuristic_velocities',
    'hold',
    'limit_violation',
    'lspb',
    'lspb_via',
    'min_time',
    'plan_path',
    'quintic',
    'quintic_via',
    'scurve',
    'scurve_brake',
    'scurve_via',
    'Violation',
    'via_durations',
    'within_limits',
]
