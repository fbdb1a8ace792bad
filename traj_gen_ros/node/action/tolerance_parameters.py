"""
The action's tolerance parameters on the node: read, checked when set, kept current.

``allowed_start_tolerance``, ``goal_tolerance``, ``path_tolerance``,
``goal_time_tolerance`` and ``stopped_velocity_tolerance`` (JTC's names, docs/node.md)
are parsed by :func:`traj_gen_ros.node.action.tolerances.read_defaults`; this is the
rclpy glue: a set that would make them invalid is refused with the reason, and the
defaults in force follow every accepted set.
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.node import Node
from traj_gen_ros.node.action.tolerances import (
    read_defaults,
    TOLERANCE_PARAMETERS,
    Tolerances,
)


class ToleranceParameters:
    """The tolerance defaults in force: ``(allowed_start_tolerance (rad), Tolerances)``."""

    def __init__(self, node: Node, joint_count: Callable[[], int]) -> None:
        """Read them from ``node`` now (``ValueError``), again in :meth:`apply`."""
        self._node = node
        self._joint_count = joint_count
        self.defaults = self._read({})

    def _read(self, changed: dict[str, object]) -> tuple[float, Tolerances]:
        return read_defaults(lambda name: self._node.get_parameter(name).value,
                             self._joint_count(), changed)

    def check(self, parameters: list) -> str | None:
        """Say why the tolerance parameters among ``parameters`` are refused, or None."""
        changed = {p.name: p.value for p in parameters if p.name in TOLERANCE_PARAMETERS}
        try:
            self._read(changed)
        except ValueError as error:
            return str(error)
        return None

    def apply(self, parameters: list) -> None:
        """Read the defaults again after an accepted change of one of them."""
        if any(p.name in TOLERANCE_PARAMETERS for p in parameters):
            self.defaults = self._read({})
