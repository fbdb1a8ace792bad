"""
A request on its way through the node, and what planning and splicing need of the answers.

No ROS here: :class:`Request` is what every request (``~/goal``, ``~/via_points``,
``~/stop``, an action goal, the action's own brakes) carries from its parsing to its answer;
:class:`RequestListener` is what a party that follows them implements; :class:`Refusals`
the part of :class:`~traj_gen_ros.node.requests.answers.Answers` that the start tick uses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol


@dataclass
class Request:
    """
    A request: its kind, the values its answer carries, its start stamp (ns), its content.

    ``parsed`` is what its planner plans: a ``GoalRequest``, a ``ViaRequest``, an action's
    ``TrajectoryGoal``, or ``None`` for a brake.
    """

    kind: str
    values: dict[str, str]
    stamp_ns: int
    parsed: object
    #: Why it was refused, once answered so (:meth:`Refusals.refused`); '' until then.
    refusal: str = ''


class RequestListener(Protocol):
    """A party told of the requests spliced in and dropped (the action server is one)."""

    def accepted(self, request: Request, start_ns: int) -> None:
        """Take note: ``request`` was spliced in to start at ``start_ns`` (ns); answered next."""

    def dropped(self, request: Request, reason: str) -> None:
        """Take note: accepted ``request`` was dropped before its start, for ``reason``."""


class Refusals(Protocol):
    """Where a refused request is answered (ERROR on ``~/status``)."""

    def refused(self, request: Request, reason: str) -> None:
        """Answer ``request`` ERROR with ``reason``; sets ``request.refusal``."""
