"""
traj_gen_ros: smooth joint trajectories after Craig, *Introduction to Robotics*, ch. 7.

Three layers, a folder each: :mod:`traj_gen_ros.core` (numpy; no ROS import), whose public
API is re-exported here; :mod:`traj_gen_ros.node` (the ``generator`` node) and
:mod:`traj_gen_ros.cli` (``traj-gen``), both standing on the core.
"""

from traj_gen_ros import core
from traj_gen_ros.core import *  # noqa: F401,F403

__all__ = core.__all__
