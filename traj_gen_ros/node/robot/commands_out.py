"""
``command_out_topic``: what a ros2_control controller takes, built without ROS.

* ``std_msgs/Float64MultiArray`` (``forward_command_controller``,
  ``position_controllers/JointGroupPositionController`` on ``<controller>/commands``):
  the setpoint positions in ``joints`` order at every stream tick
  (:func:`position_command`, from the stream thread); with ``command_out_interface``
  ``velocity`` (a ``forward_velocity_controller``) the setpoint velocities, corrected by
  the position error (:class:`VelocityCommand`);
* ``trajectory_msgs/JointTrajectory`` (a ``joint_trajectory_controller`` on
  ``~/joint_trajectory``): each accepted plan once, as :func:`controller_points` gives it.

A JTC interpolates between consecutive points itself: quintic Hermite when a point has
positions, velocities and accelerations, cubic Hermite with positions and velocities. A
quintic Hermite segment reproduces any polynomial of degree <= 5 exactly, a cubic one of
degree <= 3: so one point at every breakpoint of the plan's pieces (all joints' merged)
makes the JTC's trajectory the plan itself, not one point per stream tick.
Accelerations are given when the plan's acceleration is continuous at every breakpoint
(quintic, scurve, cubic from rest to rest); a plan whose acceleration jumps (LSPB's blends,
a cubic through via points, the second-order brake) has pieces of degree <= 3 and is
sent with positions and velocities, which a cubic Hermite reproduces exactly.

Velocity commands (issue 28): ``v = clip(v_ref + c, -max_velocity, max_velocity)`` per
joint, ``c = k_p·(q_ref − q_measured)`` with ``k_p`` the ``position_gain`` (1/s) while a
measured state at most 0.1 s old is present, else 0: the P case, with full feed-forward,
of ``joint_trajectory_controller``'s ``ff_velocity_scale·v_ref + PID`` on a velocity
interface; ``k_p = 0`` is the feed-forward alone, as MoveIt Servo's
``publish_joint_velocities``. The correction may fall to 0 at once (the measured state
lost or stale, a re-seed that puts the setpoint where the arm is), but grows by at most
``max_acceleration·period`` per tick: a measured state that becomes fresh again, after the
arm drifted, or a setpoint that steps away from the arm, never makes the command jump.

Units: rad (or m), rad/s, rad/s², s; ns where named.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.wire import float64_multi_array_cdr
from traj_gen_ros.node.planning.motion import PlannedMotion

#: A hold (a plan of no duration) is sent as two points this far apart (s), at rest.
HOLD_SPAN = 0.1
#: Relative tolerance of "continuous" acceleration at a breakpoint.
CONTINUITY = 1e-9


def _piece_ends(plan: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Acceleration at the end of each piece but the last, and at the start of the next."""
    lengths = np.diff(plan.breakpoints, axis=0)[:-1]  # (pieces - 1,) or (pieces - 1, joints)
    if lengths.ndim == 1:
        lengths = lengths[:, None]
    coefficients = plan.coefficients  # (pieces, degree + 1, joints)
    powers = np.arange(2, coefficients.shape[1])
    factors = powers * (powers - 1)
    end = np.einsum('k,pkj,pkj->pj', factors, coefficients[:-1, 2:],
                    lengths[:, None, :] ** (powers - 2)[None, :, None])
    start = 2.0 * coefficients[1:, 2] if coefficients.shape[1] > 2 else np.zeros_like(end)
    return end, start


def acceleration_continuous(plan: Trajectory) -> bool:
    """Tell whether the plan's acceleration is continuous at every breakpoint."""
    if plan.piece_count < 2 or plan.degree < 2:
        return plan.degree < 2 or plan.piece_count < 2
    end, start = _piece_ends(plan)
    return bool(np.all(np.abs(end - start) <= CONTINUITY * (1.0 + np.abs(end))))


def controller_points(motion: PlannedMotion
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """
    Return a plan's points for a JTC: ``time_from_start`` (ns), p, v, and a or ``None``.

    One point at every breakpoint of every joint (times strictly increasing, the first
    the plan's start state at 0, the last at rest); a hold is two points at rest
    :data:`HOLD_SPAN` apart. Positions ``(points, joints)`` in rad, velocities rad/s,
    accelerations rad/s² (``None`` when the plan's acceleration jumps: see the module).
    """
    plan = motion.plan
    if plan.duration <= 0.0:
        position = np.vstack([motion.end, motion.end])
        zeros = np.zeros_like(position)
        return np.array([0, int(HOLD_SPAN * 1e9)]), position, zeros, zeros.copy()
    times_ns = np.unique(np.round(np.clip(plan.breakpoints, 0.0, plan.duration)
                                  .ravel() * 1e9).astype(np.int64))
    positions, velocities, accelerations = plan.sample(times_ns * 1e-9)
    velocities[-1] = 0.0  # at rest (the plan ends there; exact zeros for the JTC)
    if not acceleration_continuous(plan):
        accelerations = None
    return times_ns, positions, velocities, accelerations


def position_command(position: np.ndarray, velocity: np.ndarray) -> bytes:
    """Write the ``Float64MultiArray`` of a position interface: the setpoint's positions."""
    del velocity
    return float64_multi_array_cdr(position)


class VelocityCommand:
    """A velocity interface's command each tick: feed-forward plus the position error."""

    def __init__(self, gain: np.ndarray, max_velocity: Callable[[], np.ndarray],
                 max_acceleration: Callable[[], np.ndarray], period: Callable[[], float],
                 measured_position: Callable[[], np.ndarray | None]) -> None:
        """
        Correct by ``gain`` (1/s, one per joint, each >= 0) toward ``measured_position()``.

        :param max_velocity: the velocity limits in force, rad/s (read every tick: they
            may change at run time): the command never exceeds them.
        :param max_acceleration: rad/s²: the correction grows by at most this times
            ``period()`` (s, the stream period) per tick.
        :param measured_position: the measured positions (rad) while fresh, else None
            (:meth:`MeasuredState.fresh_position`).
        """
        self.gain = np.array(gain, dtype=float)
        self._max_velocity = max_velocity
        self._max_acceleration = max_acceleration
        self._period = period
        self._measured = measured_position
        self._corrects = bool(np.any(self.gain > 0.0))
        #: The correction of the last command (rad/s).
        self.correction = np.zeros_like(self.gain)

    def __call__(self, position: np.ndarray, velocity: np.ndarray) -> bytes:
        """
        Write the ``Float64MultiArray`` of the setpoint (``position`` rad, ``velocity`` rad/s).

        Called from the stream thread each tick (a few microseconds: arrays of one value
        per joint).
        """
        return float64_multi_array_cdr(self.command(position, velocity))

    def command(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """Return the velocity (rad/s) to command for the setpoint (see the module)."""
        measured = self._measured() if self._corrects else None
        if measured is None:
            self.correction = np.zeros_like(self.gain)
            command = velocity
        else:
            wanted = self.gain * (position - measured)
            step = self._max_acceleration() * self._period()
            previous = self.correction
            # Anywhere between the last correction and 0 at once, beyond it by one step
            # (np.minimum/np.maximum: np.clip costs several times as much on a few values).
            self.correction = np.minimum(np.maximum(wanted, np.minimum(previous, 0.0) - step),
                                         np.maximum(previous, 0.0) + step)
            command = velocity + self.correction
        limit = self._max_velocity()
        return np.minimum(np.maximum(command, -limit), limit)

    def zero(self) -> bytes:
        """Write the all-zero command (the node's last, on SIGINT/SIGTERM)."""
        self.correction = np.zeros_like(self.gain)
        return float64_multi_array_cdr(np.zeros_like(self.gain))
