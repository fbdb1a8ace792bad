"""
``traj-gen line`` and ``arc``'s side of ROS: the ``nav_msgs/Path`` they send.

:mod:`traj_gen_ros.cli.ros` publishes it on ``<node>/cartesian_path`` or
``<node>/circular_goal`` and matches the answer as for ``pose`` (its ``frame_id`` value
echoes ``--frame``). The node's OK answer names no joint goal: ``--wait`` waits for the
end of the node's plan of the request (the last point of its ``~/trajectory``,
:func:`plan_end`), at rest on the joint states.
"""

from __future__ import annotations

import argparse

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from traj_gen_ros.cli.tool_path_poses import tool_poses


def path_message(args: argparse.Namespace) -> Path:
    """
    Return the ``Path`` of ``line POSE …`` or ``arc INTERIM GOAL`` (``[--frame F]``).

    ``header.frame_id`` is ``F`` (default '') and applies to every pose, whose own
    ``frame_id`` is left empty; positions in m, orientations unit quaternions
    (:func:`traj_gen_ros.cli.tool_path_poses.tool_pose`: a quaternion off norm 1 is a
    UsageError before anything is sent). Stamps are left 0 ("now").
    """
    message = Path()
    message.header.frame_id = args.frame
    for position, quaternion in tool_poses(args.poses, args.command, args.degrees):
        stamped = PoseStamped()
        point, orientation = stamped.pose.position, stamped.pose.orientation
        point.x, point.y, point.z = (float(value) for value in position)
        orientation.x, orientation.y, orientation.z, orientation.w = (
            float(value) for value in quaternion)
        message.poses.append(stamped)
    return message


def plan_end(plan: object) -> tuple[list[str], list[float]]:
    """Return the joint names and the last positions (rad or m) of a ``JointTrajectory``."""
    return list(plan.joint_names), [float(value) for value in plan.points[-1].positions]
