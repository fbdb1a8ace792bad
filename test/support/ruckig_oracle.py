"""Ruckig as the oracle of the S-curve tests: its own durations for the same requests."""

import math

import numpy as np
import ruckig


def ruckig_duration(q0, qf, v0, a0, vmax, amax, jmax, minimum=None, vf=None):
    """Return Ruckig's own synchronised duration for the same request: the oracle."""
    joints = len(q0)
    parameters = ruckig.InputParameter(joints)
    parameters.current_position = list(q0)
    parameters.current_velocity = list(v0)
    parameters.current_acceleration = list(a0)
    parameters.target_position = list(qf)
    parameters.target_velocity = [0.0] * joints if vf is None else list(vf)
    parameters.target_acceleration = [0.0] * joints
    parameters.max_velocity = list(vmax)
    parameters.max_acceleration = list(amax)
    parameters.max_jerk = list(jmax)
    if minimum is not None:
        parameters.minimum_duration = minimum
    solution = ruckig.Trajectory(joints)
    try:
        result = ruckig.Ruckig(joints).calculate(parameters, solution)
    except ValueError as error:  # Ruckig's -101: a duration above its ~7.6e3 s
        assert '-101' in str(error)
        return None, None
    except ruckig.RuckigError:  # a numerically extreme request: no reference value
        return math.nan, None
    assert result == ruckig.Result.Working
    return solution.duration, solution


def resolution(plan, jmax, amax):
    """
    Return the slack in acceleration and velocity that the breakpoints' resolution allows.

    Breakpoints are absolute times, so a piece's length is known to ``ulp(duration)``:
    a jerk phase then ends up to ``j_max ulp`` off in acceleration (``a_max ulp`` in
    velocity). Negligible unless the duration is ~1e8 times ``a_max / j_max``.
    """
    step = 4.0 * np.spacing(plan.duration)
    return jmax * step, amax * step
