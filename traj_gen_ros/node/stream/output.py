"""
What the stream sends with each setpoint: ``joint_states``, the command, the factor.

Called on the stream thread right after a setpoint is sampled, outside the stream's lock:
the ``JointState`` bytes first (written straight to CDR), then the command of the same
setpoint (``command_out_topic``, ``~/tool_pose``), then the effective speed factor when it
changed (``speed_scaling_output_topic``). No ROS here (bytes and callables).

Units: rad (or m), rad/s; ns.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from traj_gen_ros.node.messages.wire import joint_names_cdr, joint_state_cdr


class SetpointOutput:
    """The stream's outputs per setpoint (see the module doc)."""

    def __init__(self, joint_names: Sequence[str], publish: Callable[[bytes], None],
                 publish_command: Callable[[np.ndarray, np.ndarray], None] | None = None,
                 publish_factor: Callable[[float], None] | None = None) -> None:
        """
        Send through ``publish`` (serialised ``JointState``), then the optional outputs.

        :param publish_command: called with the setpoint's positions and velocities.
        :param publish_factor: called with the effective factor when it changed.
        """
        self._names_cdr = joint_names_cdr(list(joint_names))
        self._publish, self._publish_command = publish, publish_command
        self._publish_factor = publish_factor
        self._forwarded = -1.0  # the factor last forwarded

    @property
    def wants_factor(self) -> bool:
        """Whether the effective factor is forwarded (worth reading at each tick)."""
        return self._publish_factor is not None

    def joint_state(self, stamp_ns: int, position: np.ndarray, velocity: np.ndarray) -> None:
        """Publish the setpoint on ``joint_states``, stamped ``stamp_ns``."""
        self._publish(joint_state_cdr(stamp_ns, self._names_cdr, position, velocity))

    def command_and_factor(self, position: np.ndarray, velocity: np.ndarray,
                           factor: float) -> None:
        """Send the setpoint's command, then the factor if it changed."""
        if self._publish_command is not None:
            self._publish_command(position, velocity)
        if self._publish_factor is not None and factor != self._forwarded:
            self._forwarded = factor
            self._publish_factor(factor)
