"""
The stream as the speed override sees it: the ramp's factor, its limits, the plan time left.

:class:`SpeedView` is the :class:`~traj_gen_ros.node.speed.factor.FactorSink` that the
speed inputs drive (:mod:`traj_gen_ros.node.speed.input`): a factor change ramps the
schedule's plan clock (:class:`~traj_gen_ros.node.speed.time_map.TimeMap`) from the next
tick not yet published, every published tick fixes the ramp up to it. The node sets the
ramp's limits when its parameters change, ``/diagnostics`` reads the plan time left.
Each call takes the stream's lock (:class:`~traj_gen_ros.node.stream.state.StreamState`).

Times in and out are node times (ns; the stream clock's hold-back applied inside), the
plan time s, limits rad/s² and rad/s³. No ROS here.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.node.planning.motion import PlannedMotion
from traj_gen_ros.node.stream.state import StreamState

#: A factor change waits for a motion spliced to start within this long (ns).
FACTOR_DEFER_NS = 500_000_000


class SpeedView:
    """The speed override's calls on the stream (see the module doc)."""

    def __init__(self, state: StreamState) -> None:
        """Act on the schedule and ramp of ``state``, under its lock."""
        self._state = state

    def set_factor(self, factor: float) -> list[tuple[PlannedMotion, object]]:
        """
        Ramp the speed scaling toward ``factor`` (in [0, 1]) from the last setpoint on.

        From the first 1 ms grid time after the last setpoint published: the next tick
        already shows it.

        Returns the delayed motions dropped because the change moved the state they were
        planned from, with the ``tag`` each was spliced with
        (:meth:`~traj_gen_ros.node.stream.schedule.Schedule.set_factor`).
        """
        state = self._state
        with state.lock:
            return state.schedule.set_factor(factor, state.published_at() + 1,
                                             FACTOR_DEFER_NS)

    def set_scaling_limits(self, max_acceleration: np.ndarray,
                           max_jerk: np.ndarray | None) -> None:
        """Ramp within ``max_acceleration`` (rad/s²) and ``max_jerk`` (rad/s³, or None)."""
        with self._state.lock:
            self._state.time_map.set_limits(max_acceleration, max_jerk)

    def factor_in_force(self) -> float:
        """Return the effective (ramped) factor at the last published setpoint."""
        state = self._state
        with state.lock:
            return state.schedule.factor_at(max(state.published_at(), 0))

    def time_left(self, time_ns: int) -> float:
        """
        Return the plan time (s) left at ``time_ns``, not before the last setpoint published.

        :meth:`~traj_gen_ros.node.stream.schedule.Schedule.time_left`.
        """
        state = self._state
        with state.lock:
            return state.schedule.time_left(
                state.clock.at(max(time_ns, state.last_published_ns)))
