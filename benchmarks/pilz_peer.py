"""
The peer of benchmarks/cartesian.py: lines and arcs planned the way MoveIt's Pilz planner does.

pilz_industrial_motion_planner's LIN and CIRC (written here from its documentation: no
code of it) time the tool's path by one Cartesian trapezoid and turn it into joints
sample by sample:

* the path is the same geometry as ours (:mod:`traj_gen_ros.core.cartesian.tool_path`:
  position along the line or the circle, orientation by slerp, both by the fraction of
  the path), the trapezoid is over ``P = max(L, θ·v/ω)`` (``L`` the translation in m, ``θ``
  the rotation in rad: rotation and translation synchronised, the rotation's trapezoid
  has ``ω_max`` and the same acceleration ratio ``a/v``), with the tool's ``v = max_trans_vel``
  and ``a = max_trans_acc`` (decelerating as it accelerates);
* it is sampled every :data:`SAMPLING_TIME` s (the steps evened out so that the last
  sample is the end, not a sliver of a step after the one before), the inverse
  kinematics of each sample seeded with the previous sample's solution
  (:meth:`Chain.inverse`), the first from the start joints;
* joint velocities ``(q_k - q_{k-1}) / Δt`` and accelerations from those by the same
  finite difference (from rest) are checked against the joint limits: any above, the plan
  is refused (Pilz leaves it to the user to lower the Cartesian scaling factors).

:func:`slowed` finds the uniformly slowed plan that fits, as a user lowering both scaling
factors would: the trapezoid's speed times ``α`` and its acceleration times ``α²`` (the
same path in ``t/α``), the largest ``α`` (within about 1 %).

Units: m, rad, s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
import math
import time

import numpy as np
from traj_gen_ros.core.cartesian.path_timing import ToolLimits
from traj_gen_ros.core.cartesian.tool_path import ToolPath
from traj_gen_ros.core.kinematics.inverse import UnreachablePoseError

#: Pilz's default sampling time of LIN and CIRC (s): 100 Hz.
SAMPLING_TIME = 0.01
#: The inverse kinematics' tolerance (m, rad): tight enough that the finite differences
#: measure the motion, not the solver (at the default 1e-5 m and 1e-4 rad, a second
#: difference over 10 ms carries up to ~1 rad/s² of the solver's stopping point).
TOLERANCE = (1e-8, 1e-7)
#: The slowest plan :func:`slowed` looks for: ``α`` below this is "does not fit".
SLOWEST = 0.02
_ROUNDS = 8  # rounds of slowing by the measured overshoot
_MARGIN = 0.998  # each round aims this much below the ratio that would just fit


@dataclass(frozen=True)
class PeerPlan:
    """
    One sampled plan of the peer.

    :ivar alpha: the speed factor it was planned with (acceleration ``alpha²``).
    :ivar duration: s.
    :ivar refused: '' if it fits; else why (``reach``: a sample without inverse
        kinematics; ``velocity``/``acceleration``: a joint above its limit).
    :ivar velocity_ratio: the largest finite-difference ``|q̇| / max_velocity``.
    :ivar acceleration_ratio: the largest ``|q̈| / max_acceleration``.
    :ivar q: ``(samples, joints)`` the joints at the samples (to the last one solved).
    :ivar seconds: the planning time (s): the samples' inverse kinematics and the check.
    """

    alpha: float
    duration: float
    refused: str
    velocity_ratio: float
    acceleration_ratio: float
    q: np.ndarray
    seconds: float

    @property
    def overshoot(self) -> float:
        """Return the factor by which the plan is too fast: ``max(v ratio, √(a ratio))``."""
        return max(self.velocity_ratio, math.sqrt(self.acceleration_ratio))


def trapezoid(length: float, velocity: float, acceleration: float
              ) -> tuple[float, Callable[[np.ndarray], np.ndarray]]:
    """
    Return the duration and ``p(t)`` of the rest-to-rest trapezoid over ``length``.

    Accelerate at ``acceleration`` to ``velocity``, cruise, decelerate symmetrically
    (a triangle where ``length < velocity² / acceleration``: peak ``√(length·a)``).
    """
    ramp = velocity / acceleration
    if length < velocity * ramp:
        ramp = math.sqrt(length / acceleration)
        velocity = acceleration * ramp
    duration = length / velocity + ramp

    def position(t: np.ndarray) -> np.ndarray:
        t = np.clip(t, 0.0, duration)
        rising = 0.5 * acceleration * np.minimum(t, ramp) ** 2
        cruising = velocity * np.clip(t - ramp, 0.0, duration - 2.0 * ramp)
        falling = np.maximum(t - (duration - ramp), 0.0)
        return rising + cruising + velocity * falling - 0.5 * acceleration * falling ** 2

    return duration, position


def trapezoid_length(path: ToolPath, tool: ToolLimits) -> float:
    """
    Return ``P = max(L, θ·v/ω)``: the length the trapezoid runs over (m).

    The path is one line or one arc: ``|dp/ds|`` and ``|ω_s|`` are constant along it, so
    ``L = |dp/ds|·S`` and ``θ = |ω_s|·S``.
    """
    start = path.sample(0.0)
    translation = float(np.linalg.norm(start.velocity[0])) * path.length
    rotation = float(np.linalg.norm(start.angular[0])) * path.length
    radius = tool.max_linear_velocity / tool.max_angular_velocity  # m per rad
    return max(translation, radius * rotation)


def sample(chain, path: ToolPath, q_start: np.ndarray, max_velocity: np.ndarray,
           max_acceleration: np.ndarray, tool: ToolLimits, alpha: float = 1.0) -> PeerPlan:
    """Plan ``path`` from ``q_start``, the trapezoid's speed ``α·v`` and acceleration ``α²·a``."""
    began = time.perf_counter()
    length = trapezoid_length(path, tool)
    duration, position = trapezoid(length, alpha * tool.max_linear_velocity,
                                   alpha ** 2 * tool.max_linear_acceleration)
    times = np.linspace(0.0, duration, math.ceil(duration / SAMPLING_TIME - 1e-9) + 1)
    poses = path.poses(position(times) / length * path.length)
    solved = [np.asarray(q_start, dtype=float)]
    refused = ''
    for pose in poses[1:]:
        try:
            solved.append(chain.inverse(pose, solved[-1], position_tolerance=TOLERANCE[0],
                                        orientation_tolerance=TOLERANCE[1]).q)
        except UnreachablePoseError:
            refused = f'reach at {100.0 * len(solved) / len(times):.0f} %'
            break
    q = np.array(solved)
    steps = np.diff(times[:len(q)])[:, None]
    velocity = np.vstack([np.zeros((1, q.shape[1])), np.diff(q, axis=0) / steps])
    acceleration = np.diff(velocity, axis=0) / steps
    velocity_ratio = float((np.abs(velocity) / max_velocity).max())
    acceleration_ratio = float((np.abs(acceleration) / max_acceleration).max(initial=0.0))
    if not refused and velocity_ratio > 1.0:
        refused = 'velocity'
    elif not refused and acceleration_ratio > 1.0:
        refused = 'acceleration'
    return PeerPlan(alpha, duration, refused, velocity_ratio, acceleration_ratio, q,
                    time.perf_counter() - began)


def slowed(chain, path: ToolPath, q_start: np.ndarray, max_velocity: np.ndarray,
           max_acceleration: np.ndarray, tool: ToolLimits, first: PeerPlan
           ) -> PeerPlan | None:
    """
    Return the fastest uniformly slowed plan that fits (``first`` if it fits), or None.

    Each round divides ``α`` by the overshoot of the last try (the finite differences
    scale as ``α`` and ``α²``, up to where the samples fall) and samples again. None: a
    sample out of reach (no timing helps), or ``α`` below :data:`SLOWEST` (a jump between
    samples that slowing does not shrink: the inverse kinematics changed configuration).
    """
    plan = first
    for _ in range(_ROUNDS):
        if not plan.refused:
            return plan
        if plan.refused.startswith('reach'):
            return None
        alpha = plan.alpha / plan.overshoot * _MARGIN
        if alpha < SLOWEST:
            return None
        plan = sample(chain, path, q_start, max_velocity, max_acceleration, tool, alpha)
    return None if plan.refused else plan
