"""
Ruckig as the backend of the S-curve profile: one state-to-state move, read into pieces.

Ruckig (L. Berscheid and T. Kröger, "Jerk-limited Real-time Trajectory Generation with
Arbitrary Target States", RSS 2021; the ``ruckig`` package, MIT) gives the time-optimal
synchronised seven-phase profiles (and a braking pre-profile) per joint; each phase is
rebuilt as a cubic ``[p, v, a/2, j/6]`` of the package's :class:`Trajectory`.

Where Ruckig refuses (synchronised durations above ~7.6e3 s, numerically extreme
ratios), the request is solved again: in scaled units (time by ``k``, a joint's positions
by ``s``: velocity ``s/k``, acceleration ``s/k²``, jerk ``s/k³``, powers of two so that
scaling back is exact), with lowered limits for joints far faster than the common
duration, and finally composed per joint (stop, then a time-stretched rest-to-rest
move). What still fails raises ``ValueError`` naming its input.

Units: rad (or m), rad/s, rad/s², rad/s³, s.
"""

from __future__ import annotations

from collections.abc import Iterator
import math

import numpy as np
import ruckig
from traj_gen_ros.core import validation
from traj_gen_ros.core.jerk_limited import fallback as scurve_fallback
from traj_gen_ros.core.jerk_limited.problem import (
    DURATION_TOLERANCE,
    Floats,
    LIMIT_NAMES,
    Move,
    PRECISION,
)
from traj_gen_ros.core.trajectory import JerkLimitedTrajectory, Trajectory

PHASES = 7  # jerk phases of one S-curve; braking adds two before them
_GOOD = (ruckig.Result.Working, ruckig.Result.Finished)
_LIMIT_TOLERANCE = 1e-10  # relative: a Ruckig phase beyond a limit by more is refused
_CHECKED_BELOW = 1e-2  # plans are checked against limits this small (in Ruckig's units)
_SMALLEST_RATIO = 2.0**-20  # lowered limits stay above this fraction (cubed for jerk)


def scurve_minimum_duration(move: Move) -> float:
    """Return the time-optimal synchronised duration (s) of ``move``, ignoring its own."""
    return plan_move(move.minimum_time())[1]


def plan_move(move: Move) -> tuple[Trajectory, float]:
    """
    Solve ``move`` with Ruckig, directly then in scaled units; return it and its duration.

    With ``move.duration`` set, the plan lasts at least that long (longer when that is
    too short, or blocked). Raises ``ValueError`` when no attempt succeeds.

    Ruckig's answer for a blocked duration is a longer plan. Given directly, it is
    trusted; from rescaled units, where Ruckig also answers so for durations that are
    not blocked (a 1 rad move with ``v0 = -0.5/T`` in ``T = 4096 · 32^(1/3)`` s at unit
    limits, refused directly (-101), time scaled: 4 T), it is kept, for a duration that
    is not too short, only if no later attempt meets the duration: such a false refusal
    would break the interval of feasible durations that
    :func:`traj_gen_ros.core.jerk_limited.path.scurve_via_durations` bisects.
    """
    reason = ''
    longer = None
    for variant, time_scale, position_scales, needed in _attempts(move):
        solved = _calculate(variant, time_scale, position_scales)
        if isinstance(solved, str):
            reason = reason or solved
            continue
        kept = move.duration if needed is None else needed
        if kept is None or solved[1] <= kept * (1.0 + DURATION_TOLERANCE):
            return solved
        if needed is None and longer is None:
            longer = solved
            if (time_scale == 1.0 and position_scales is None) or _too_short(move):
                return longer
    if longer is not None:
        return longer
    fallback = scurve_fallback.rest_to_rest(move) or scurve_fallback.composed(move, plan_move)
    if fallback is not None and _arrives(fallback[0], move):  # (a stretch may underflow)
        return fallback
    raise ValueError(_failure_message(move, reason))


def _too_short(move: Move) -> bool:
    """Tell whether ``move.duration`` is below the move's minimum time (unknown: no)."""
    try:
        return scurve_minimum_duration(move) > move.duration * (1.0 + DURATION_TOLERANCE)
    except ValueError:
        return False


def _attempts(move: Move) -> Iterator[tuple[Move, float, Floats | None, float | None]]:
    """
    Yield ``(move, time scale, position scales, duration it must keep or None)`` to try.

    In order: Ruckig directly; time scaled; lowered limits for fast joints (see
    :func:`_stretched`), time scaled; then the same with positions scaled too, last since
    Ruckig's absolute precision (1e-8) then grows with the position scale.
    """
    for time_scale, position_scales in _scalings(move, positions=False):
        yield move, time_scale, position_scales, None
    stretched = list(_stretched(move))
    for variant, duration in stretched:
        for time_scale, position_scales in _scalings(variant, positions=False):
            yield variant, time_scale, position_scales, duration
    for variant, duration in [(move, None)] + stretched:
        for time_scale, position_scales in _scalings(variant, positions=True):
            yield variant, time_scale, position_scales, duration


def _stretched(move: Move) -> Iterator[tuple[Move, float]]:
    """
    Yield ``move`` with lowered limits for joints far faster than the common duration.

    Ruckig fails for a joint whose own minimum time ``t`` is far below the common
    duration ``T`` (its jerk phases become vanishingly short in the synchronisation). Such
    a joint may run under lower limits ``(ρ v, ρ² a, ρ³ j)``, ``ρ = min(1, 2^m t/T)`` (at
    least 2^-20), never below its boundary velocities and start acceleration, and only if
    its start needs no braking under them: any plan then is within the original limits.
    For a joint at rest at both ends, ``m = 0`` is its own optimal profile slowed to
    exactly ``T``, so the duration stays optimal. Yields ``(move, T)``; a plan counts only
    if it keeps ``T``.
    """
    if move.duration is None and len(move.start) == 1:
        return  # nothing to stretch (what scurve_minimum_duration's own calls are)
    try:
        own = [scurve_minimum_duration(move.joint(joint))
               for joint in range(len(move.start))]
    except ValueError:
        return
    duration = move.duration or max(own)
    for doubling in (0, 1, 3, 6):
        limits = tuple(list(limit) for limit in move.limits)
        for joint, time in enumerate(own):
            ratio = min(1.0, max(2.0**doubling * time / duration, _SMALLEST_RATIO))
            floors = (max(abs(move.v0[joint]), abs(move.vf[joint])), abs(move.a0[joint]), 0.0)
            pairs = enumerate(zip(limits, floors, strict=True), start=1)
            lowered = [min(limit[joint], max(limit[joint] * ratio**power, floor))
                       for power, (limit, floor) in pairs]
            v0, a0 = move.v0[joint], move.a0[joint]
            if abs(v0 + a0 * abs(a0) / (2.0 * lowered[2])) <= lowered[0]:  # no braking
                for limit, value in zip(limits, lowered, strict=True):
                    limit[joint] = value
        yield Move(move.start, move.goal, move.v0, move.a0, move.vf, limits,
                   move.duration), duration


def _failure_message(move: Move, reason: str) -> str:
    """Name the joint (or the synchronisation) that no Ruckig attempt could plan."""
    subject = 'the synchronised move'
    if len(move.start) > 1:
        for joint in range(len(move.start)):
            single = move.joint(joint)
            if all(isinstance(_calculate(variant, k, s), str)
                   for variant, k, s, _ in _attempts(single)):
                subject = f'joint {joint}'
                move = single
                break
    named = zip(LIMIT_NAMES, move.limits, strict=True)
    limits = ', '.join(f'{name} {values}' for name, values in named)
    timing = '' if move.duration is None else f' in {move.duration:g} s'
    return (f'scurve: no jerk-limited plan for {subject}{timing} from position {move.start}, '
            f'velocity {move.v0}, acceleration {move.a0} to position {move.goal}, velocity '
            f'{move.vf} with {limits} ({reason}); the limits or the start state are too '
            'extreme for each other')


def _scalings(move: Move, positions: bool) -> Iterator[tuple[float, Floats | None]]:
    """
    Yield ``(time scale k, per-joint position scales s)`` for Ruckig to try.

    Without ``positions``: none, then ``k`` alone; with it: ``k`` and ``s``. ``k`` brings
    the (estimated) duration near 1 s, ``s`` each joint's excursion near 1; both are
    powers of two, so results scale back exactly.
    """
    if not positions:
        yield 1.0, None
    v_max, a_max, j_max = move.limits
    if move.duration is not None:
        estimate = move.duration
    else:
        rows = zip(move.start, move.goal, move.v0, move.a0, v_max, a_max, j_max, strict=True)
        estimate = max(abs(goal - start) / v + v / a + a / j + abs(v0) / a + abs(a0) / j
                       for start, goal, v0, a0, v, a, j in rows)
    time_scale = _power_of_two(estimate)
    if not positions:
        yield time_scale, [1.0] * len(move.start)
        return
    extents = [abs(goal - start) + abs(v0) * time_scale + abs(a0) * time_scale * time_scale
               + abs(vf) * time_scale
               for start, goal, v0, a0, vf in zip(move.start, move.goal, move.v0, move.a0,
                                                  move.vf, strict=True)]
    yield time_scale, [_power_of_two(extent) for extent in extents]


def _power_of_two(value: float) -> float:
    """Return the power of two nearest ``value`` (1 for 0 or non-finite values)."""
    if not (math.isfinite(value) and value > 0.0):
        return 1.0
    return math.ldexp(1.0, max(-900, min(900, round(math.log2(value)))))


def _calculate(move: Move, time_scale: float,
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
        factor = 1.0
        for _ in range(power):
            factor *= k
        return [value * factor / scale for value, scale in zip(values, scales, strict=True)]

    try:
        if k == 1.0 and position_scales is None:  # as given
            parameters.current_position, parameters.target_position = move.start, move.goal
            parameters.current_velocity, parameters.current_acceleration = move.v0, move.a0
            parameters.target_velocity = move.vf
            parameters.max_velocity, parameters.max_acceleration = v_max, a_max
            parameters.max_jerk = j_max
        else:
            start = [q - c for q, c in zip(move.start, shifts, strict=True)]
            goal = [q - c for q, c in zip(move.goal, shifts, strict=True)]
            parameters.current_position, parameters.target_position = (scaled(start, 0),
                                                                       scaled(goal, 0))
            parameters.current_velocity = scaled(move.v0, 1)
            parameters.current_acceleration = scaled(move.a0, 2)
            parameters.target_velocity = scaled(move.vf, 1)
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
    if move.duration is not None and duration <= move.duration * (1 + DURATION_TOLERANCE):
        # Met. A plan a rounding longer is compressed to the duration asked (time scale
        # k T/D: derivatives grow by (D/T)^n, ~1e-13), so that no piece is cut short.
        k *= move.duration / duration
        duration = move.duration
    limits = (parameters.max_velocity, parameters.max_acceleration, parameters.max_jerk)
    built = _build(solution.profiles[0], duration, k, scales, shifts, move, limits)
    if isinstance(built, str):
        return built
    if not _arrives(built, move):  # (in extreme units Ruckig may miss the goal)
        return 'Ruckig is not precise enough in these units'
    return built, duration


def _arrives(trajectory: Trajectory, move: Move) -> bool:
    """
    Tell whether a plan ends at the goal state as precisely as Ruckig does unscaled.

    Ruckig's precision is absolute (1e-8 in position and velocity); scaling positions by
    ``s`` widens it by ``s``, so a plan is kept only if it still arrives within ``1e-8``
    plus ``1e-9`` of the positions' or the limit's magnitude (for the velocity, plus what
    the resolution of its times allows: ``a_max · 4 ε · T``). Every plan is checked: in
    extreme units a plan can miss its goal (a time-stretch whose coefficients vanish).
    """
    c0, c1, c2, c3 = trajectory.coefficients[-1]  # each joint's last piece, at its end
    with np.errstate(over='ignore', invalid='ignore'):  # scaled back: inf or NaN fails
        length = trajectory.breakpoints[-1] - trajectory.breakpoints[-2]
        position = ((c3 * length + c2) * length + c1) * length + c0
        velocity = (3.0 * c3 * length + 2.0 * c2) * length + c1
        reach = np.maximum(np.maximum(np.abs(move.start), np.abs(move.goal)), 1.0)
        resolution = 4.0 * np.finfo(float).eps * trajectory.duration
        return (validation.every(np.abs(position - move.goal) <= PRECISION + 1e-9 * reach)
                and validation.every(np.abs(velocity - move.vf)
                                     <= PRECISION + 1e-9 * np.asarray(move.limits[0])
                                     + np.asarray(move.limits[1]) * resolution))


def _build(profiles: list, duration: float, k: float, scales: Floats, shifts: Floats,
           move: Move, limits: tuple[Floats, Floats, Floats]) -> Trajectory | str:
    """
    Rebuild each joint's phases as cubic pieces ``[p, v, a/2, j/6]`` in the caller's units.

    Braking phases (``profile.brake``) come first when any joint brakes; a joint that does
    not brake gets two zero-length pieces there. Piece ends are the running sums of the
    phase durations, clipped to ``duration``. Returns why not if a phase after braking
    exceeds ``limits`` (Ruckig's units) by more than rounding (Ruckig's tolerances are
    absolute, ~1e-12: far more than a tiny limit), or if anything is not finite.
    """
    braking = any(profile.brake.duration > 0.0 for profile in profiles)
    rows = []
    for profile in profiles:
        positions, velocities, accelerations = profile.p, profile.v, profile.a
        if braking:
            brake = profile.brake
            lengths, jerks = brake.t, brake.j
            start = (brake.p, brake.v, brake.a)
            if lengths[1] == 0.0:  # an unused second phase holds zeros: give it its state
                jerks = [jerks[0], 0.0]
                start = [[values[0], following[0]] for values, following in
                         zip(start, (positions, velocities, accelerations), strict=True)]
            rows.append((start[0] + positions[:PHASES], start[1] + velocities[:PHASES],
                         start[2] + accelerations[:PHASES], jerks + profile.j,
                         lengths + profile.t))
        else:
            rows.append((positions[:PHASES], velocities[:PHASES], accelerations[:PHASES],
                         profile.j, profile.t))
    table = np.array(rows).transpose(2, 1, 0)  # (pieces, p v a j t, joints)
    # Ruckig's tolerances (~1e-12, absolute) are below 1e-10 of limits of 1e-2 and more.
    if min(map(min, limits)) < _CHECKED_BELOW and not _within(table[2 * braking:], limits):
        return 'Ruckig exceeds a limit by more than rounding in these units'
    if k == 1.0 and not any(shifts) and scales.count(1.0) == len(scales):
        table[:, 2] *= 0.5
        table[:, 3] *= 1.0 / 6.0
        breakpoints = np.empty((len(table) + 1, len(profiles)))
        breakpoints[0] = 0.0
        np.minimum(np.cumsum(table[:, 4], axis=0), duration, out=breakpoints[1:])
    else:  # scaled units: the products may overflow (or k³ underflow to 0), then the
        # plan is refused below
        with np.errstate(over='ignore', divide='ignore', invalid='ignore'):
            divisors = np.array([[1.0], [k], [2.0 * k * k], [6.0 * k * k * k]])
            table[:, :4] *= np.array(scales) / divisors
            table[:, 0] += shifts
            table[:, 4] *= k
            breakpoints = np.empty((len(table) + 1, len(profiles)))
            breakpoints[0] = 0.0
            np.minimum(np.cumsum(table[:, 4], axis=0), duration, out=breakpoints[1:])
    breakpoints[-1] = duration
    coefficients = np.ascontiguousarray(table[:, :4])
    # Every piece that starts at 0 (the first, and any zero-length ones after it) starts
    # exactly at the given state, not at Ruckig's rounded copy of it.
    coefficients[0, :3] = move.start, move.v0, move.a0
    coefficients[0, 2] *= 0.5
    if not validation.every(breakpoints[1]):
        initial = (breakpoints[:-1] == 0.0)[:, None, :] & (np.arange(4) < 3)[None, :, None]
        coefficients = np.where(initial, coefficients[:1], coefficients)
    if not (validation.every(np.isfinite(coefficients))
            and validation.every(np.isfinite(breakpoints))):
        return 'the plan overflows in these units'
    return JerkLimitedTrajectory(breakpoints, coefficients)


def _within(phases: np.ndarray, limits: tuple[Floats, Floats, Floats]) -> bool:
    """
    Tell whether phases ``(count, p v a j t, joints)`` keep the limits to 1e-10 (relative).

    Acceleration peaks at phase ends, velocity there or where a jerk phase's acceleration
    crosses zero (rare: Ruckig's phases mostly end at zero acceleration). A first phase
    that starts beyond a limit (after braking from a start beyond it) may stay up to that
    level; jerk never exceeds its limit. Differences, not products, so nothing overflows.
    """
    magnitudes = np.abs(phases[:, 1:4])  # velocity, acceleration, jerk
    bounds = np.array(limits)
    bounds[:2] = np.maximum(bounds[:2], magnitudes[0, :2])
    if not validation.every(magnitudes - bounds <= _LIMIT_TOLERANCE * bounds):
        return False
    acceleration = phases[:, 2]
    crossing = acceleration[:-1] * np.sign(acceleration[1:]) < 0.0
    if not np.count_nonzero(crossing):
        return True
    pieces, joints = np.nonzero(crossing)
    before = phases[pieces, :, joints]  # (crossings, p v a j t)
    with np.errstate(over='ignore', divide='ignore', invalid='ignore'):  # zero jerk: inf, NaN
        peak = np.abs(before[:, 1] - before[:, 2] ** 2 / (2.0 * before[:, 3]))
    velocity_bound = bounds[0, joints]
    return validation.every(~(peak - velocity_bound > _LIMIT_TOLERANCE * velocity_bound))
