"""
The goals the request thread and the executor both see: the active one, those replaced.

A :class:`GoalBook` is also what follows the requests for the action (a
:class:`~traj_gen_ros.node.requests.request.RequestListener`): any request spliced in
replaces the active goal (the monitor then ends it ABORTED, saying by what), one dropped
before its start aborts its goal. No ROS here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import threading

from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.requests.request import Request

KIND = 'follow_joint_trajectory'
#: The requests the action itself makes (braking on a cancel or a path violation).
OWN_KINDS = ('follow_joint_trajectory_cancel', 'follow_joint_trajectory_brake')
_REPLACED_BY = {'goal': 'a ~/goal request', 'via_points': 'a ~/via_points request',
                'stop': 'a ~/stop call', KIND: 'a newer follow_joint_trajectory goal'}
#: What happens to the arm when a goal is replaced: the new request's motion, or a brake.
_THEN = {'stop': 'the arm brakes to rest'}


@dataclass
class GoalBook:
    """
    The goals both threads see, under ``lock``: the active one, those replaced.

    ``starting`` is the goal being planned in the goal callback (it becomes the active one
    when its own request is spliced in).
    """

    lock: threading.Lock = field(default_factory=threading.Lock)
    active: ActiveGoal | None = None
    replaced: list[ActiveGoal] = field(default_factory=list)
    starting: ActiveGoal | None = None

    def accepted(self, request: Request, start_ns: int) -> None:
        """Take note of a request spliced in (any thread): the goal it replaces ends."""
        with self.lock:
            active, starting = self.active, self.starting
            if request.kind in OWN_KINDS:
                if active is not None and request is active.cancel:
                    active.brake_start_ns = start_ns
                return
            if starting is not None and request is starting.request:
                starting.start_ns = start_ns
                self.active = starting
            else:
                self.active = None
            if active is not None:
                then = _THEN.get(request.kind, 'its motion continues from the setpoint')
                active.replaced = (f'replaced by {_REPLACED_BY.get(request.kind, request.kind)} '
                                   f'(request_id {request.values.get("request_id", "?")}); '
                                   f'{then}')
                self.replaced.append(active)

    def dropped(self, request: Request, reason: str) -> None:
        """Take note of a request dropped before its start: its goal, if active, aborts."""
        with self.lock:
            active = self.active
            if active is not None and request is active.request:
                active.replaced = f'dropped: {reason}'
                self.replaced.append(active)
                self.active = None
