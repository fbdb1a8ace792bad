"""
What the node's layers hand each other: a setpoint (:class:`State`) and an accepted plan.

A :class:`PlannedMotion` is a plan of the core (a ``Trajectory`` in local time from its
start) with where it ends at rest and the words its status reports: planning makes them,
the schedule runs them, the stream samples them into a :class:`State` per tick, and the
answers and diagnostics report them. No ROS here.

Units: rad (or m), rad/s, rad/s².
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
from traj_gen_ros.core.timing import hold
from traj_gen_ros.core.trajectory import Trajectory


class State(NamedTuple):
    """A setpoint: position (rad), velocity (rad/s) and acceleration (rad/s²) per joint."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


class BrakesAlong(Protocol):
    """A plan that brakes along its own path (a line, an arc): the tool stays on it."""

    def brake(self, elapsed: float, velocity: np.ndarray,
              acceleration: np.ndarray | None = None) -> Trajectory | None:
        """Brake from ``elapsed`` s into the plan at joint ``velocity``, ``acceleration``."""


@dataclass(frozen=True)
class PlannedMotion:
    """
    An accepted plan, where it ends (rad, at rest) and the words its status reports.

    ``unscaled``: the plan runs on the node clock whatever the speed scaling factor
    (``~/stop``, an action cancel: braking at full authority); every other plan's own
    time advances at the factor (:mod:`traj_gen_ros.node.speed.time_map`).
    ``tool_poses``: a line's or an arc's planned tool path, ``(knots, 4, 4)`` in
    ``base_frame`` (m), published on ``~/tool_path``; None for joint-space plans.
    ``along``: how a line or an arc brakes along its path (``~/stop``); None: each joint.
    """

    plan: Trajectory
    profile: str
    end: np.ndarray
    note: str = ''
    unscaled: bool = False
    tool_poses: np.ndarray | None = None
    along: BrakesAlong | None = None


def held(position: Sequence[float], profile: str = 'hold', note: str = '') -> PlannedMotion:
    """Stand still at ``position`` (rad): a zero-duration plan."""
    position = np.array(position, dtype=float)
    return PlannedMotion(hold(position), profile, position, note)
