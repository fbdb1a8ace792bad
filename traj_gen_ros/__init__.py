"""
traj_gen_ros: smooth joint trajectories after Craig, *Introduction to Robotics*, ch. 7.

The core (everything but the node and the command-line tool) imports no ROS.
"""

from traj_gen_ros.profiles import (
    BlendedTrajectory,
    brake,
    continuous_velocities,
    cubic,
    cubic_via,
    heuristic_velocities,
    hold,
    lspb,
    lspb_via,
    min_time,
    PROFILES,
    quintic,
    quintic_via,
    Trajectory,
    via_durations,
    within_limits,
)

__all__ = [
    'PROFILES',
    'BlendedTrajectory',
    'Trajectory',
    'brake',
    'continuous_velocities',
    'cubic',
    'cubic_via',
    'heuristic_velocities',
    'hold',
    'lspb',
    'lspb_via',
    'min_time',
    'quintic',
    'quintic_via',
    'via_durations',
    'within_limits',
]
