"""
The robot's kinematics in force: the chain from ``base_frame`` to ``tool_frame``, or why none.

Built from the URDF in force (:mod:`traj_gen_ros.node.description.robot_description`)
with the core's :class:`~traj_gen_ros.core.kinematics.Chain` (Pinocchio is imported when
the first chain is built: a node without a URDF starts as before). A URDF whose chain cannot
be built (an unknown link, a chain without every joint of ``joints``) leaves the node
without kinematics: its tool-frame requests are refused with :attr:`RobotKinematics.problem`.
No ROS here.

Units: m, rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from traj_gen_ros.core.kinematics import Chain

#: The problem when no URDF is loaded.
NO_URDF = ('no robot description: set the robot_description parameter or publish it on '
           'the robot_description topic (a URDF) to use tool-frame requests')


@dataclass(frozen=True)
class RobotKinematics:
    """
    The chain in force (None: none) and why there is none ('' when there is one).

    ``chain`` is for the request thread, ``stream_chain`` its copy for the stream thread
    (a Pinocchio ``Data`` each: a chain is not thread-safe).
    """

    chain: Any = None
    stream_chain: Any = None
    problem: str = NO_URDF

    def describe(self) -> str:
        """Return the chain's one line, or the problem."""
        return self.chain.describe() if self.chain is not None else self.problem


def build_kinematics(urdf: str, joints: Sequence[str], base_frame: str = '',
                     tool_frame: str = '') -> RobotKinematics:
    """
    Build the chain of ``joints`` from ``base_frame`` to ``tool_frame`` ('' = the defaults).

    An empty ``urdf``: no kinematics (:data:`NO_URDF`). A chain that cannot be built:
    no kinematics, its reason in ``problem`` (``ValueError`` of the core, or Pinocchio
    missing).
    """
    if not urdf:
        return RobotKinematics()
    try:
        chain = Chain.from_urdf(urdf, joints, base_frame or None, tool_frame or None)
    except (ValueError, ImportError) as error:
        return RobotKinematics(problem=f'no kinematic chain: {error}')
    return RobotKinematics(chain, chain.copy(), '')
