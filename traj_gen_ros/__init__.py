"""
traj_gen_ros: smooth joint trajectories after Craig, *Introduction to Robotics*, ch. 7.

The core (everything but the node and the command-line tool) imports no ROS. The public
API is that of :mod:`traj_gen_ros.profiles`, re-exported here.
"""

from traj_gen_ros import profiles
from traj_gen_ros.profiles import *  # noqa: F401,F403

__all__ = profiles.__all__
