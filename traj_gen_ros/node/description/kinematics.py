"""
The robot's kinematics in force: the chain from ``base_frame`` to ``tool_frame``, or why none.

Built from the URDF in force (:mod:`traj_gen_ros.node.description.robot_description`)
with the core's :class:`~traj_gen_ros.core.kinematics.Chain` (Pinocchio is imported when
the first chain is built: a node without a URDF starts as before). A URDF whose chain cannot
be built (an unknown link, a chain without every joint of ``joints``) leaves the node
without kinematics: its tool-frame requests are refused with :attr:`RobotKinematics.problem`.
The URDF's joints outside ``joints`` stand at their measured positions
(:mod:`traj_gen_ros.node.description.held_joints`; 0 until measured); mimic joints follow
their leaders. No ROS here.

Units: m, rad.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from traj_gen_ros.core.kinematics import Chain
from traj_gen_ros.node.description.held_joints import HeldChain, HeldJoints

#: The problem when no URDF is loaded.
NO_URDF = ('no robot description: set the robot_description parameter or publish it on '
           'the robot_description topic (a URDF) to use tool-frame requests')


@dataclass(frozen=True)
class RobotKinematics:
    """
    The chain in force (None: none) and why there is none ('' when there is one).

    One chain per thread (a Pinocchio ``Data`` each: a chain is not thread-safe), each held
    at the latest measured positions of the other joints when its thread takes it:
    :meth:`for_requests` on the request thread (pose goals, lines, arcs: once per plan),
    :meth:`for_stream` on the stream thread (``~/tool_pose``: once per tick),
    :meth:`describe` on the executor's.
    """

    requests: HeldChain | None = None
    stream: HeldChain | None = None
    executor: HeldChain | None = None
    problem: str = NO_URDF

    @property
    def chain(self) -> Any:
        """Return the request thread's chain as last taken (its frames, links), or None."""
        return self.requests.chain if self.requests is not None else None

    def for_requests(self) -> Any:
        """Return the request thread's chain at the latest measured positions, or None."""
        return self.requests.take() if self.requests is not None else None

    def for_stream(self) -> Any:
        """Return the stream thread's chain at the latest measured positions, or None."""
        return self.stream.take() if self.stream is not None else None

    def describe(self) -> str:
        """Return the chain's one line at the latest measured positions, or the problem."""
        if self.executor is None:
            return self.problem
        return self.executor.take().describe()


def build_kinematics(urdf: str, joints: Sequence[str], base_frame: str = '',
                     tool_frame: str = '', held: HeldJoints | None = None) -> RobotKinematics:
    """
    Build the chain of ``joints`` from ``base_frame`` to ``tool_frame`` ('' = the defaults).

    An empty ``urdf``: no kinematics (:data:`NO_URDF`). A chain that cannot be built:
    no kinematics, its reason in ``problem`` (``ValueError`` of the core, or Pinocchio
    missing). ``held``: the measured positions of the other joints (None: all at 0).
    """
    if not urdf:
        return RobotKinematics()
    held = HeldJoints() if held is None else held
    try:
        chain = Chain.from_urdf(urdf, joints, base_frame or None, tool_frame or None,
                                held.values)
    except (ValueError, ImportError) as error:
        return RobotKinematics(problem=f'no kinematic chain: {error}')
    return RobotKinematics(HeldChain(chain.copy(), held), HeldChain(chain.copy(), held),
                           HeldChain(chain, held), '')
