"""
A pose goal (PTP): the tool pose to reach, turned into a joint goal by inverse kinematics.

``~/pose_goal`` gives the tool pose in a frame (``header.frame_id``): empty or
``base_frame``, the base; any other link of the URDF, that link's frame at the start state
(the setpoint where the motion takes over); ``tool_frame`` itself, the tool's frame there
(a jog: ``{position: {z: 0.05}}`` moves the tool 5 cm along its own z). The pose is solved
from the start state (:meth:`Chain.inverse`: the seed first, then fixed restarts; the
answer nearest the start, inside every joint's position limits in force) and the joint goal
goes through the pipeline as a ``~/goal`` with those joint angles
(:data:`~traj_gen_ros.node.planning.pipeline.GOAL`: the profile in force, min-time timing,
continuous joints the short way). The URDF's joints outside ``joints`` stand where they were
last measured: the request thread's chain is held there once per plan
(:meth:`RobotKinematics.for_requests`, :func:`request_chain`). No ROS here.

Units: m, rad.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from traj_gen_ros.core.kinematics import UnreachablePoseError
from traj_gen_ros.node.messages.parsing import GoalRequest, RequestError
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.planning.pipeline import GOAL, plan_request
from traj_gen_ros.node.settings.config import Config

#: How many links a refusal of an unknown frame lists at most.
LISTED_LINKS = 12


@dataclass
class PoseRequest:
    """
    A tool pose in ``frame_id`` (``(4, 4)``, m), as read; ``answer`` gets the joint goal.

    ``answer`` is the request's answer values: the joint goal the inverse kinematics chose
    is added to it, by joint name, with its residual errors.
    """

    frame_id: str
    pose: np.ndarray
    answer: dict[str, str] = field(default_factory=dict)


def request_chain(config: Config) -> Any:
    """
    Return the request thread's chain, held at the latest measured positions of the others.

    Once per plan, on the request thread: the plan then sees one set of held values.

    :raises RequestError: no kinematics in force (saying why).
    """
    chain = config.kinematics.for_requests()
    if chain is None:
        raise RequestError(config.kinematics.problem)
    return chain


def target_in_base(chain: Any, request: PoseRequest, position: np.ndarray) -> np.ndarray:
    """
    Return the requested tool pose in ``base_frame`` (``(4, 4)``), from joint ``position``.

    ``chain``: :func:`request_chain`'s.

    :raises RequestError: an unknown frame (naming it and the valid ones).
    """
    frame = request.frame_id
    if frame in ('', chain.base_frame):
        return request.pose
    if frame == chain.tool_frame:
        return chain.forward(position) @ request.pose
    if frame in chain.links:
        return chain.frame_pose(frame, position) @ request.pose
    others = [link for link in chain.links if link not in (chain.base_frame, chain.tool_frame)]
    more = '' if len(others) <= LISTED_LINKS else f' and {len(others) - LISTED_LINKS} more'
    raise RequestError(f'pose frame_id {frame!r} is not a link of the robot description: '
                       f"give '' or {chain.base_frame!r} (the base), {chain.tool_frame!r} "
                       f'(relative to the tool), or another link: '
                       f'{", ".join(others[:LISTED_LINKS])}{more}')


def joint_goal(config: Config, request: PoseRequest, state: State) -> GoalRequest:
    """
    Solve the pose from ``state``'s positions: the joint goal nearest them (rad or m).

    Fills ``request.answer`` with the goal by joint name and the residual errors.
    :raises RequestError: the pose cannot be reached within the limits (how close it came,
        which joint limit stopped it), or no kinematics, or an unknown frame.
    """
    chain = request_chain(config)
    target = target_in_base(chain, request, state.position)
    limits = config.limits
    lower = None if limits is None else limits.position.lower
    upper = None if limits is None else limits.position.upper
    try:
        solution = chain.inverse(target, state.position, lower, upper)
    except UnreachablePoseError as error:
        raise RequestError(f'pose goal (frame {request.frame_id or chain.base_frame!r}): '
                           f'{error}') from None
    for name, value in zip(config.joints, solution.q, strict=True):
        request.answer[name] = f'{value:.9g}'
    request.answer['ik_position_error_mm'] = f'{solution.position_error * 1e3:.6f}'
    request.answer['ik_orientation_error_mrad'] = f'{solution.orientation_error * 1e3:.6f}'
    return GoalRequest(np.arange(len(config.joints)), np.asarray(solution.q, dtype=float))


def plan_pose(config: Config, state: State, hold_at: np.ndarray, request: PoseRequest
              ) -> PlannedMotion:
    """Plan a pose goal from ``state``: its joint goal through the pipeline (as ``~/goal``)."""
    return plan_request(config, state, hold_at, joint_goal(config, request, state), GOAL)
