"""
Step 6's *sample*: an accepted plan every ``1/rate_hz`` s, for ``~/trajectory`` (no ROS).

Units: s, rad, rad/s, rad/s².
"""

from __future__ import annotations

import math

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.messages.parsing import RequestError
from traj_gen_ros.node.planning.motion import PlannedMotion


def sample_grid(plan: Trajectory, rate_hz: float) -> np.ndarray:
    """Return ``0, 1/rate, 2/rate, ...`` (s) up to the plan's end, ending at its duration."""
    count = int(math.floor(plan.duration * rate_hz + 1e-9))
    times = np.arange(count + 1) / rate_hz
    if plan.duration - times[-1] > 1e-9:
        times = np.append(times, plan.duration)
    return times


def sample_motion(motion: PlannedMotion, rate_hz: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Step 6, *sample*: the plan every ``1/rate_hz`` s from its start, for ``~/trajectory``.

    The last sample is exactly the end, at rest. Raises :class:`RequestError` if any
    sample is not finite (then nothing of the plan is published or executed).
    """
    times = sample_grid(motion.plan, rate_hz)
    positions, velocities, accelerations = motion.plan.sample(times)
    positions[-1] = motion.end
    velocities[-1] = 0.0
    accelerations[-1] = 0.0
    finite = np.isfinite
    if not (finite(positions).all() and finite(velocities).all()
            and finite(accelerations).all()):
        raise RequestError('the plan has a non-finite sample: not executed')
    return times, positions, velocities, accelerations
