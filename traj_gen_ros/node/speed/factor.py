"""
The speed override's two inputs and the factor they ask for (ROS-free).

The ``speed_scaling`` parameter (the operator's slider) and the last valid
``~/speed_scaling_input`` message (what the robot or a program asks), each in ``[0, 1]``;
the factor asked for is their product. :mod:`traj_gen_ros.node.speed.input` is the rclpy
glue, :mod:`traj_gen_ros.node.speed.time_map` the ramp toward it. :class:`ChangeReport`
paces the log lines of its changes.
"""

from __future__ import annotations

import math
from typing import Protocol

#: Changes of the factor asked for are logged at most once per this many seconds.
REPORT_PERIOD = 1.0


def check_factor(value: object, name: str = 'speed_scaling') -> float:
    """Return ``value`` as a float in ``[0, 1]``; ``ValueError`` saying why it is not."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f'{name} must be a number in [0, 1], got {value!r}')
    if not math.isfinite(value):
        raise ValueError(f'{name} must be finite (a number in [0, 1]), got {value!r}')
    if not 0.0 <= value <= 1.0:
        raise ValueError(f'{name} must be in [0, 1] (0 pauses, 1 is full speed), '
                         f'got {value!r}')
    return float(value)


class FactorSink(Protocol):
    """What the speed inputs drive: the stream's ramp toward a factor (``SpeedView``)."""

    def set_factor(self, factor: float) -> list[tuple[object, object]]:
        """Ramp toward ``factor``; return the delayed motions dropped, with their tags."""

    def factor_in_force(self) -> float:
        """Return the ramped factor at the last published setpoint."""


class FactorInputs:
    """The two inputs, their product (the factor asked for) and the messages ignored."""

    def __init__(self, parameter: float = 1.0) -> None:
        """Start with the parameter ``speed_scaling`` and the topic at 1."""
        self.parameter = check_factor(parameter)
        self.topic = 1.0
        self.ignored = 0  # topic messages outside [0, 1] or not finite
        self.last_ignored = ''

    @property
    def product(self) -> float:
        """Return the factor asked for: parameter × topic."""
        return self.parameter * self.topic

    def take_message(self, value: float) -> str | None:
        """Take a topic factor; None if taken, else why it is ignored (counted)."""
        try:
            self.topic = check_factor(value, '~/speed_scaling_input factor')
        except ValueError as error:
            self.ignored += 1
            self.last_ignored = str(error)
            return self.last_ignored
        return None

    def values(self, in_force: float) -> list[tuple[str, str]]:
        """Give the ``/diagnostics`` key/values: both inputs, the factor in force, the ignored."""
        values = [('speed_scaling (parameter)', f'{self.parameter:g}'),
                  ('speed_scaling_input (topic)', f'{self.topic:g}'),
                  ('speed scaling in force', f'{in_force:.4g}'),
                  ('speed_scaling_input ignored', str(self.ignored))]
        if self.last_ignored:
            values.append(('last speed_scaling_input ignored', self.last_ignored))
        return values


class ChangeReport:
    """
    Lines saying a changing value, at most one per ``period`` s, the last value always said.

    The first change after a quiet period is said at once; later ones are held, and the
    line held last is due ``period`` s after the line said last (:meth:`due`), unless it
    repeats that line. Times in s on one monotonic clock.
    """

    def __init__(self, period: float = REPORT_PERIOD) -> None:
        """Say nothing yet; then at most one line per ``period`` s."""
        self.period = period
        self._said = ''
        self._said_at = -math.inf
        #: The line held for :meth:`due`, or None.
        self.held: str | None = None
        self._held_changes = 0

    def change(self, now: float, line: str) -> str | None:
        """Take a change said by ``line`` at ``now``: the line to log now, or None (held)."""
        if now - self._said_at >= self.period:
            return self._say(now, line)
        self.held = line
        self._held_changes += 1
        return None

    def due(self, now: float) -> str | None:
        """Return the held line if a period has passed since the last one, else None."""
        if self.held is None or now - self._said_at < self.period:
            return None
        line, changes = self.held, self._held_changes
        if line == self._said:  # back where it was said last: nothing new to say
            self.held, self._held_changes = None, 0
            return None
        said = self._say(now, line)
        return said if changes == 1 else f'{said} (the last of {changes} changes since)'

    def _say(self, now: float, line: str) -> str:
        self._said, self._said_at = line, now
        self.held, self._held_changes = None, 0
        return line
