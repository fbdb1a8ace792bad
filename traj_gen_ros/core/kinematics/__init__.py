"""
Kinematics of a URDF chain: forward, Jacobian, inverse (Pinocchio, imported when used).

``from traj_gen_ros.core.kinematics import Chain``; ``import traj_gen_ros`` does not load
this room (nor lxml, nor Pinocchio). See docs/core.md, "Kinematics".
"""

from traj_gen_ros.core.kinematics.chain import Chain
from traj_gen_ros.core.kinematics.inverse import IkSolution, UnreachablePoseError
from traj_gen_ros.core.kinematics.poses import (
    check_pose,
    pose_distance,
    pose_matrix,
    pose_quaternion,
)
from traj_gen_ros.core.kinematics.urdf_tree import chain_joints

__all__ = ['Chain', 'IkSolution', 'UnreachablePoseError', 'chain_joints', 'check_pose',
           'pose_distance', 'pose_matrix', 'pose_quaternion']
