"""
``traj-gen pose``'s side of ROS: the ``PoseStamped`` it sends, the joint goal it is answered.

:mod:`traj_gen_ros.cli.ros` publishes the message on ``<node>/pose_goal`` and matches the
answer as for ``goal`` (its ``frame_id`` value echoes ``--frame``); the node's OK answer
carries the joint goal its inverse kinematics chose, one value per joint name, which
``--wait`` waits for on the joint states.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Mapping

from geometry_msgs.msg import PoseStamped
from traj_gen_ros.cli.kinematics import pose_from_args


def pose_message(args: argparse.Namespace) -> PoseStamped:
    """
    Return the ``PoseStamped`` of ``X Y Z [--rpy | --quat] [--frame F]``.

    ``header.frame_id`` is ``F`` (default ''), the position in m and the orientation a
    unit quaternion: from ``--rpy`` (URDF roll, pitch, yaw), or ``--quat`` checked (norm 1
    within 1e-3, else a UsageError naming the norm, before anything is sent) and
    normalised, or the identity. The stamp is left 0.
    """
    position, quaternion = pose_from_args(args)
    message = PoseStamped()
    message.header.frame_id = args.frame
    point, orientation = message.pose.position, message.pose.orientation
    point.x, point.y, point.z = (float(value) for value in position)
    orientation.x, orientation.y, orientation.z, orientation.w = (
        float(value) for value in quaternion)
    return message


def answered_joints(values: Mapping[str, str], names: Iterable[str]) -> dict[str, float]:
    """Return the answer's value (rad or m) of each joint in ``names`` that it gives."""
    goal = {}
    for name in names:
        try:
            goal[name] = float(values[name])
        except (KeyError, ValueError):
            continue
    return goal
