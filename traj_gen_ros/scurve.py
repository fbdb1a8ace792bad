"""
Jerk-limited (S-curve) joint motion: the seven-phase, third-order profile, synchronised.

Each joint's motion is the classic seven-phase S-curve (Biagiotti & Melchiorri,
*Trajectory Planning for Automatic Machines and Robots*, Springer 2008, §3.4): jerk
``±j_max`` or 0 in each phase, so acceleration is piecewise linear and velocity piecewise
quadratic; phases whose limit is not reached have zero length. A start beyond the limits
(``|v0| > v_max``, ``|a0| > a_max``, or a velocity that ``a0`` will carry past ``v_max``)
is first brought back by up to two braking phases. The time-optimal synchronised
solution comes from Ruckig (L. Berscheid and T. Kröger, "Jerk-limited Real-time
Trajectory Generation with Arbitrary Target States", RSS 2021; the ``ruckig`` package,
MIT), read phase by phase into the package's piecewise cubic :class:`Trajectory`.

Ruckig refuses some valid requests (synchronised durations above ~7.6e3 s, numerically
extreme start states). The motion problem is invariant under scaling time by ``k`` and a
joint's positions by ``s`` (velocity ``s/k``, acceleration ``s/k²``, jerk ``s/k³``), so
such a request is solved again in scaled units, with powers of two so that scaling back
is exact. A request that still fails raises ``ValueError`` naming its input.

Units: rad (or m), rad/s, rad/s², rad/s³, s. Only this module and
:mod:`traj_gen_ros.scurve_via` import ruckig.
"""

from __future__ import annotations

import math

import numpy as np
import ruckig
from traj_gen_ros import validation
from traj_gen_ros.trajectory import Trajectory
from traj_gen_ros.validation import ArrayLike

PHASES = 7  # jerk phases of one S-curve; braking adds two before them
_DURATION_TOLERANCE = 1e-9  # relative: a plan this close to the requested time meets it
_GOOD = (ruckig.Result.Working, ruckig.Result.Finished)
_LIMIT_NAMES = ('max_velocity', 'max_acceleration', 'max_jerk')

Floats = list[float]


class _Move:
    """One state-to-state problem as Python floats, one list entry per joint."""

    __slots__ = ('start', 'goal', 'v0', 'a0', 'vf', 'limits', 'duration')

    def __init__(self, start: Floats, goal: Floats, v0: Floats, a0: Floats, vf: Floats,
                 limits: tuple[Floats, Floats, Floats], duration: float | None) -> None:
        self.start, self.goal, self.v0, self.a0, self.vf = start, goal, v0, a0, vf
        self.limits = limits  # (v_max, a_max, j_max)
        self.duration = duration  # the exact duration asked for, or None for minimum time

    def joint(self, index: int) -> _Move:
        """Return the same problem for one joint alone."""
        pick = slice(index, index + 1)
        return _Move(self.start[pick], self.goal[pick], self.v0[pick], self.a0[pick],
                     self.vf[pick], tuple(limit[pick] for limit in self.limits),
                     self.duration)


def scurve_min_time(
    start: np.ndarray,
    goal: np.ndarray,
    start_velocity: np.ndarray,
    start_acceleration: np.ndarray,
    max_velocity: np.ndarray,
    max_acceleration: np.ndarray,
    max_jerk: np.ndarray,
) -> Trajectory:
    """
    Plan the time-optimal synchronised jerk-limited move from ``(q0, v0, a0)`` to rest.

    All arguments are validated float arrays shaped ``(joints,)``: positions (rad), start
    velocity (rad/s) and acceleration (rad/s²), limits (rad/s, rad/s², rad/s³, > 0). The
    slowest joint sets the duration (s); every other joint runs a seven-phase profile of
    exactly that duration (Ruckig's time synchronisation), so all arrive together. The
    result has per-joint breakpoints ``(pieces + 1, joints)`` and cubic pieces: 7, or 9
    with braking first when the start state is beyond (or will overshoot) the limits.
    Raises ``ValueError`` when no plan can be found, naming the joint and its input.
    """
    move = _Move(start.tolist(), goal.tolist(), start_velocity.tolist(),
                 start_acceleration.tolist(), [0.0] * start.size,
                 (max_velocity.tolist(), max_acceleration.tolist(), max_jerk.tolist()), None)
    return plan_move(move)[0]


def scurve(
    q0: ArrayLike,
    qf: ArrayLike,
    duration: float,
    max_velocity: ArrayLike,
    max_acceleration: ArrayLike,
    max_jerk: ArrayLike,
    v0: ArrayLike = 0.0,
    a0: ArrayLike = 0.0,
) -> Trajectory:
    """
    Plan a jerk-limited move from ``(q0, v0, a0)`` to rest at ``qf`` in exactly ``duration``.

    :param q0: start position (rad), scalar or one per joint.
    :param qf: goal position (rad), scalar or one per joint.
    :param duration: the move's duration (s).
    :param max_velocity: velocity limit (rad/s), scalar or one per joint.
    :param max_acceleration: acceleration limit (rad/s²), scalar or one per joint.
    :param max_jerk: jerk limit (rad/s³), scalar or one per joint.
    :param v0: start velocity (rad/s).
    :param a0: start acceleration (rad/s²).

    Every joint runs a seven-phase S-curve (Ruckig with ``minimum_duration``). Raises
    ``ValueError`` giving the minimum duration when ``duration`` is shorter; a joint that
    cannot arrive at exactly ``duration`` although longer and shorter times work (a
    blocked interval: from a moving start it would stop short or overshoot) is named, with
    the next duration that works.
    """
    rows = validation.per_joint_rows(q0=q0, qf=qf, v0=v0, a0=a0, max_velocity=max_velocity,
                                     max_acceleration=max_acceleration, max_jerk=max_jerk)
    validation.require_positive(rows[4:], _LIMIT_NAMES)
    duration = validation.duration_of(duration)
    start, goal, start_velocity, start_acceleration = (row.tolist() for row in rows[:4])
    limits = tuple(row.tolist() for row in rows[4:])
    move = _Move(start, goal, start_velocity, start_acceleration, [0.0] * len(start),
                 limits, duration)
    return fixed_duration(move, 'scurve', 'duration')


def fixed_duration(move: _Move, caller: str, what: str) -> Trajectory:
    """
    Plan ``move`` in exactly ``move.duration`` or raise ``ValueError`` saying why not.

    ``caller`` and ``what`` (e.g. ``'segment 2'``) start the message.
    """
    trajectory, reached = plan_move(move)
    if reached <= move.duration * (1.0 + _DURATION_TOLERANCE):
        return trajectory
    fastest = minimum_duration(move)
    if fastest > move.duration * (1.0 + _DURATION_TOLERANCE):
        raise ValueError(f'{caller}: {what} {move.duration:g} s is too short for the limits; '
                         f'the minimum duration is {round_up(fastest)} s')
    blocked = [joint for joint in range(len(move.start))
               if plan_move(move.joint(joint))[1] > move.duration * (1 + _DURATION_TOLERANCE)]
    names = ', '.join(str(joint) for joint in blocked) or 'every'
    raise ValueError(f'{caller}: {what} {move.duration:g} s is in a blocked duration interval '
                     f'of joint {names} (from its start state it would stop short or '
                     f'overshoot); the minimum duration is {round_up(fastest)} s and the '
                     f'next one that works is {round_up(reached)} s')


def minimum_duration(move: _Move) -> float:
    """Return the time-optimal synchronised duration (s) of ``move``, ignoring its own."""
    return plan_move(_Move(move.start, move.goal, move.v0, move.a0, move.vf, move.limits,
                           None))[1]


def peak_jerk(trajectory: Trajectory) -> np.ndarray:
    """Return each joint's largest ``|jerk|`` (rad/s³), ``max |6 c3|`` over the pieces."""
    if trajectory.degree < 3:
        return np.zeros(trajectory.joint_count)
    return 6.0 * np.abs(trajectory.coefficients[:, 3]).max(axis=0)


def round_up(value: float, digits: int = 9) -> str:
    """``value`` rounded up to ``digits`` significant digits, so the printed number works."""
    if not math.isfinite(value) or value <= 0.0:
        return f'{value:g}'
    scale = 10.0 ** (digits - 1 - math.floor(math.log10(value)))
    return f'{math.ceil(value * scale * (1.0 - 1e-15)) / scale:.{digits}g}'


def plan_move(move: _Move) -> tuple[Trajectory, float]:
    """
    Solve ``move`` with Ruckig, directly then in scaled units; return it and its duration.

    With ``move.duration`` set, the plan lasts at least that long (longer when that is
    too short, or blocked). Raises ``ValueError`` when no attempt succeeds.
    """
    reason = ''
    for time_scale, position_scales in _scalings(move):
        solved = _calculate(move, time_scale, position_scales)
        if isinstance(solved, str):
            reason = reason or solved
            continue
        return solved
    raise ValueError(_failure_message(move, reason))


def _failure_message(move: _Move, reason: str) -> str:
    """Name the joint (or the synchronisation) that no Ruckig attempt could plan."""
    subject = 'the synchronised move'
    if len(move.start) > 1:
        for joint in range(len(move.start)):
            single = move.joint(joint)
            if all(isinstance(_calculate(single, k, s), str) for k, s in _scalings(single)):
                subject = f'joint {joint}'
                move = single
                break
    named = zip(_LIMIT_NAMES, move.limits, strict=True)
    limits = ', '.join(f'{name} {values}' for name, values in named)
    timing = '' if move.duration is None else f' in {move.duration:g} s'
    return (f'scurve: no jerk-limited plan for {subject}{timing} from position {move.start}, '
            f'velocity {move.v0}, acceleration {move.a0} to position {move.goal}, velocity '
            f'{move.vf} with {limits} ({reason}); the limits or the start state are too '
            'extreme for each other')


def _scalings(move: _Move):
    """
    Yield ``(time scale k, per-joint position scales s)``: first none, then two fallbacks.

    ``k`` brings the (estimated) duration near 1 s, ``s`` each joint's excursion near 1;
    both are powers of two, so results scale back exactly.
    """
    yield 1.0, None
    v_max, a_max, j_max = move.limits
    if move.duration is not None:
        estimate = move.duration
    else:
        rows = zip(move.start, move.goal, move.v0, move.a0, v_max, a_max, j_max, strict=True)
        estimate = max(abs(goal - start) / v + v / a + a / j + abs(v0) / a + abs(a0) / j
                       for start, goal, v0, a0, v, a, j in rows)
    time_scale = _power_of_two(estimate)
    yield time_scale, [1.0] * len(move.start)
    extents = [abs(goal - start) + abs(v0) * time_scale + abs(a0) * time_scale**2
               + abs(vf) * time_scale
               for start, goal, v0, a0, vf in zip(move.start, move.goal, move.v0, move.a0,
                                                  move.vf, strict=True)]
    yield time_scale, [_power_of_two(extent) for extent in extents]


def _power_of_two(value: float) -> float:
    """Return the power of two nearest ``value`` (1 for 0 or non-finite values)."""
    if not (math.isfinite(value) and value > 0.0):
        return 1.0
    return math.ldexp(1.0, max(-900, min(900, round(math.log2(value)))))


def _calculate(move: _Move, time_scale: float,
               position_scales: Floats | None) -> tuple[Trajectory, float] | str:
    """
    Run Ruckig once in units scaled by ``time_scale`` and ``position_scales``.

    ``position_scales`` ``None`` passes positions unchanged (no shift); otherwise each
    joint is shifted to start at 0 and scaled. Returns the trajectory in the caller's
    units and its duration, or a string saying why Ruckig gave none.
    """
    joints = len(move.start)
    k = time_scale
    scales = position_scales or [1.0] * joints
    shifts = move.start if position_scales is not None else [0.0] * joints
    v_max, a_max, j_max = move.limits
    parameters = ruckig.InputParameter(joints)

    def scaled(values: Floats, power: int) -> Floats:
        """Convert rad/s**power to scaled units: times k**power, divided by s."""
        factor = k**power
        return [value * factor / scale for value, scale in zip(values, scales, strict=True)]

    try:
        start = [q - c for q, c in zip(move.start, shifts, strict=True)]
        goal = [q - c for q, c in zip(move.goal, shifts, strict=True)]
        parameters.current_position, parameters.target_position = (scaled(start, 0),
                                                                   scaled(goal, 0))
        parameters.current_velocity = scaled(move.v0, 1)
        parameters.current_acceleration = scaled(move.a0, 2)
        parameters.target_velocity = scaled(move.vf, 1)
        parameters.target_acceleration = [0.0] * joints
        parameters.max_velocity = scaled(v_max, 1)
        parameters.max_acceleration = scaled(a_max, 2)
        parameters.max_jerk = scaled(j_max, 3)
        if move.duration is not None:
            parameters.minimum_duration = move.duration / k
        solution = ruckig.Trajectory(joints)
        result = ruckig.Ruckig(joints).calculate(parameters, solution)
    except (ruckig.RuckigError, ValueError, OverflowError) as error:
        # Ruckig raises on some inputs; an unknown result code (-101: duration above
        # ~7.6e3 s) surfaces as the enum's ValueError.
        return f'Ruckig: {" ".join(str(error).split())[:120]}'
    if result not in _GOOD:
        return f'Ruckig: {result.name}'
    duration = solution.duration * k
    if not math.isfinite(duration):
        return 'Ruckig gave a non-finite duration'
    if move.duration is not None and duration <= move.duration * (1 + _DURATION_TOLERANCE):
        duration = move.duration  # met: the last breakpoint is exactly the duration asked
    built = _build(solution.profiles[0], duration, k, scales, shifts, move)
    if built is None:
        return 'the plan overflows in these units'
    return built, duration


def _build(profiles: list, duration: float, k: float, scales: Floats, shifts: Floats,
           move: _Move) -> Trajectory | None:
    """
    Rebuild each joint's phases as cubic pieces ``[p, v, a/2, j/6]`` in the caller's units.

    Braking phases (``profile.brake``) come first when any joint brakes; a joint that does
    not brake gets two zero-length pieces there. Returns ``None`` if anything is not finite.
    """
    braking = any(profile.brake.duration > 0.0 for profile in profiles)
    times: list[float] = []
    values: list[float] = []
    for joint, profile in enumerate(profiles):
        scale, shift = scales[joint], shifts[joint]
        factors = (scale, scale / k, 0.5 * scale / (k * k), scale / (6.0 * k * k * k))
        phases = []
        if braking:
            brake = profile.brake
            phases.append((brake.t, brake.j, brake.a, brake.v, brake.p, 2))
        phases.append((profile.t, profile.j, profile.a, profile.v, profile.p, PHASES))
        clock = 0.0
        times.append(clock)
        for lengths, jerks, accelerations, velocities, positions, count in phases:
            for phase in range(count):
                values += (positions[phase] * factors[0] + shift,
                           velocities[phase] * factors[1],
                           accelerations[phase] * factors[2], jerks[phase] * factors[3])
                clock = min(clock + lengths[phase] * k, duration)
                times.append(clock)
        times[-1] = duration
        # Every piece that starts at 0 (the first, and any zero-length ones after it) starts
        # exactly at the given state, not at Ruckig's rounded copy of it.
        pieces = PHASES + 2 * braking
        first, clock_index = len(values) - 4 * pieces, len(times) - pieces - 1
        for piece in range(pieces):
            if times[clock_index + piece] != 0.0:
                break
            values[first + 4 * piece:first + 4 * piece + 3] = (
                move.start[joint], move.v0[joint], 0.5 * move.a0[joint])
    joints = len(profiles)
    coefficients = np.array(values).reshape(joints, -1, 4).transpose(1, 2, 0)
    breakpoints = np.array(times).reshape(joints, -1).T
    if not (validation.every(np.isfinite(coefficients))
            and validation.every(np.isfinite(breakpoints))):
        return None
    return Trajectory(np.ascontiguousarray(breakpoints), np.ascontiguousarray(coefficients))
