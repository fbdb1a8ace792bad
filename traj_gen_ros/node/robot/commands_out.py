"""
``command_out_topic``: what a ros2_control controller takes, built without ROS.

* ``std_msgs/Float64MultiArray`` (``forward_command_controller``,
  ``position_controllers/JointGroupPositionController`` on ``<controller>/commands``):
  the setpoint positions in ``joints`` order at every stream tick
  (:func:`traj_gen_ros.node.messages.wire.float64_multi_array_cdr`, from the stream thread);
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

Units: rad (or m), rad/s, rad/s², s; ns where named.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
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
