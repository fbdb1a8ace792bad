"""
Exact minimum-time timing of a cubic or quintic move from a moving state to rest.

Ruckig's shape, for polynomials: each joint's set of feasible durations (Step 1), the
smallest duration in every joint's set (synchronisation), then the fit (the caller).

Step 1: the durations at which a joint's peak ``|v|`` or ``|a|`` can equal its limit are
found exactly (:mod:`traj_gen_ros.core.exact.peak_candidates`: ends, and interior extrema from
the roots of resultant polynomials). Between two consecutive candidates feasibility
cannot change, so checking candidates and one duration inside each gap with the exact
peaks (:mod:`traj_gen_ros.core.exact.move_peaks`) decides feasibility everywhere: nothing is
sampled. Up to 16 joints, every joint is checked at every candidate above the
second-order lower bound (and in each gap): the first where all are feasible is the
synchronised duration. Beyond that, each analysed joint's feasible durations come out as
closed intervals ("runs") and the synchronised duration is the smallest run start that
lies in a run of every joint.

Units: rad, rad/s, rad/s², s.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core.exact import second_order
from traj_gen_ros.core.exact.move_peaks import peaks
from traj_gen_ros.core.exact.peak_candidates import candidates, durations
from traj_gen_ros.core.kinematic_limits import LIMIT_TOLERANCE

#: Shortest polynomial plan (s): shorter ones' coefficients ~ D/T⁵ overflow.
SHORTEST_POLYNOMIAL = 1e-9
_FIRST_BATCH = 16  # joints analysed exactly at first (the largest lower bounds)
_FIRST_POINTS = 16  # candidates above the lower bound checked first
# Relative nudges tried when rounding leaves a boundary candidate just outside its run.
_NUDGES = 1e-15 * 3.0 ** np.arange(25)  # 1e-15 … 2.8e-4


def _feasible(profile: str, moves: tuple, who: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """
    Whether move ``who[k]`` stays within its limits in ``durations[k]`` (exact peaks).

    Within half of ``LIMIT_TOLERANCE``: the plan's own peaks, computed again from its
    coefficients in real time (the node checks every plan), round apart from these.
    """
    displacement, velocity, acceleration, max_velocity, max_acceleration = \
        np.array(moves)[:, who]
    peak_velocity, peak_acceleration = peaks(profile, displacement, velocity, acceleration,
                                             durations)
    slack = 1.0 + 0.5 * LIMIT_TOLERANCE
    return (peak_velocity <= max_velocity * slack) & \
        (peak_acceleration <= max_acceleration * slack)


def feasible_runs(profile: str, moves: tuple) -> np.ndarray:
    """
    Every joint's feasible durations as closed runs ``(3, count)``: start, end, joint.

    ``moves`` is ``(D, v0, a0, v_max, a_max)``, flat arrays. An end of ``inf`` is a run
    that never ends. A joint with no run can achieve no duration.
    """
    joints = moves[0].size
    durations, owners = candidates(profile, *moves, shortest=SHORTEST_POLYNOMIAL)
    durations = np.concatenate([durations, np.full(joints, SHORTEST_POLYNOMIAL)])
    owners = np.concatenate([owners, np.arange(joints)])
    order = np.lexsort((durations, owners))
    durations, owners = durations[order], owners[order]
    fresh = np.ones(durations.size, dtype=bool)
    fresh[1:] = (durations[1:] != durations[:-1]) | (owners[1:] != owners[:-1])
    durations, owners = durations[fresh], owners[fresh]
    last = np.ones(durations.size, dtype=bool)
    last[:-1] = owners[1:] != owners[:-1]
    # One duration inside each gap after a point: the midpoint, or twice the last point.
    gaps = 2.0 * durations
    gaps[:-1] = np.where(last[:-1], gaps[:-1], 0.5 * (durations[:-1] + durations[1:]))
    feasible = _feasible(profile, moves, np.concatenate([owners, owners]),
                         np.concatenate([durations, gaps]))
    at_point, after = feasible[:durations.size], feasible[durations.size:]
    first = np.ones(durations.size, dtype=bool)
    first[1:] = last[:-1]
    before = np.zeros(durations.size, dtype=bool)
    before[1:] = after[:-1] & ~first[1:]
    _polish(profile, moves, durations, owners, gaps, at_point, after, before)
    starts = at_point & ~before
    ends = at_point & ~after
    end_points = durations[ends]
    # A feasible last gap runs on: its run never ends (inf).
    runs = np.full((3, np.count_nonzero(starts)), np.inf)
    runs[0], runs[2] = durations[starts], owners[starts]
    runs[1, np.cumsum(starts)[ends] - 1] = end_points
    return runs


def _polish(profile: str, moves: tuple, durations: np.ndarray, owners: np.ndarray,
            gaps: np.ndarray, at_point: np.ndarray, after: np.ndarray,
            before: np.ndarray) -> None:
    """
    Move boundary candidates that rounding left just outside their feasible gap onto it.

    A candidate next to a feasible gap is, exactly, the gap's closed end; rounding can
    leave it a hair outside (the peak over by ~1e-12). Each such candidate is moved
    towards its gap by the smallest relative nudge in :data:`_NUDGES` that makes it
    feasible (all tried at once); where that nudge is coarse (above 1e-9) or none works,
    the boundary is bisected within the bracket (48 halvings). In place; the order is
    kept.
    """
    rising = ~at_point & after
    falling = ~at_point & before & ~rising
    index = np.flatnonzero(rising | falling)
    if not index.size:
        return
    who = owners[index]
    bad = durations[index]
    direction = np.where(rising[index], 1.0, -1.0)
    inside_gap = np.where(rising[index], gaps[index], gaps[index - 1])
    tries = bad[:, None] * (1.0 + direction[:, None] * _NUDGES)
    fits = _feasible(profile, moves, np.repeat(who, _NUDGES.size),
                     tries.reshape(-1)).reshape(tries.shape)
    # Only nudges that stay within the gap (short of its test duration) count.
    fits &= (tries - inside_gap[:, None]) * direction[:, None] <= 0.0
    nudged = fits.any(axis=1)
    first = np.argmax(fits, axis=1)
    good = np.where(nudged, tries[np.arange(index.size), first], inside_gap)
    # A nudge above 1e-9 (the candidate was off) or none at all: bisect from the last
    # nudge that failed (or the candidate) to the first that worked (or the gap's test
    # duration), 48 halvings. Rare: ill-conditioned roots, e.g. starts exactly at a limit.
    coarse = ~nudged | (_NUDGES[first] > 1e-9)
    hard = np.flatnonzero(coarse)
    low = np.where(nudged & (first > 0), tries[np.arange(index.size), first - 1], bad)[hard]
    high = good[hard]
    for _ in range(48 if hard.size else 0):
        middle = 0.5 * (low + high)
        fits = _feasible(profile, moves, who[hard], middle)
        high = np.where(fits, middle, high)
        low = np.where(fits, low, middle)
    good[hard] = high
    durations[index] = good
    at_point[index] = True


def synchronised_duration(runs: np.ndarray, joints: int) -> float | None:
    """
    Return the smallest duration in a run of every one of ``joints``, or ``None``.

    The answer, if any, is a run's start; a joint's runs are disjoint, so a start lies in
    a run of every joint exactly when ``joints`` runs contain it. ``O(runs log runs)``.
    """
    # Sweep: +1 at each run's start, -1 at its end; at equal times starts come first
    # (closed runs), so the count after a start is the number of runs containing it.
    times = np.concatenate([runs[0], runs[1]])
    steps = np.concatenate([np.ones(runs.shape[1]), -np.ones(runs.shape[1])])
    order = np.lexsort((-steps, times))
    inside = np.cumsum(steps[order])
    common = np.flatnonzero((inside == joints) & (steps[order] > 0.0))
    return float(times[order][common[0]]) if common.size else None


def polynomial_minimum_duration(profile: str, displacement: np.ndarray,
                                start_velocity: np.ndarray, start_acceleration: np.ndarray,
                                max_velocity: np.ndarray, max_acceleration: np.ndarray
                                ) -> tuple[float | None, int | None]:
    """
    Return the smallest common duration: ``(duration, None)``, or ``(None, joint)``.

    ``joint`` is one that can achieve no duration at all (``None`` if every joint can, but
    never together). The second-order time-optimal duration
    (:func:`second_order.minimum_times`, bang-bang with the same limits) is a lower bound
    for any profile, so only durations above the largest bound are looked at. Up to
    ``_FIRST_BATCH`` joints, every joint is checked at every candidate of every joint
    (:func:`_smallest_common_duration`). Beyond that, joints are analysed in the order of
    their bound until the next bound is below the duration found; every other joint is
    then checked at that duration, and one that fails is analysed too.
    """
    moves = (displacement, start_velocity, start_acceleration, max_velocity,
             max_acceleration)
    joints = displacement.size
    bounds = second_order.minimum_times(displacement, start_velocity, max_velocity,
                                        max_acceleration)
    if joints <= _FIRST_BATCH:
        duration = _smallest_common_duration(profile, moves, float(bounds.max()))
        # None: the per-joint analysis tells which joint, if any, can never move.
        return (duration, None) if duration is not None else \
            _common_duration(profile, moves, None)
    order = np.argsort(-bounds)
    analysed = order[:_FIRST_BATCH]
    while True:
        duration, hopeless = _common_duration(profile, moves, analysed)
        if duration is None:
            return None, hopeless
        unanalysed = np.ones(joints, dtype=bool)
        unanalysed[analysed] = False
        rest = order[unanalysed[order]]
        binding = rest[bounds[rest] > duration]
        if not binding.size:
            binding = rest[~_feasible(profile, moves, rest, np.full(rest.size, duration))]
            if not binding.size:
                return duration, None
        analysed = np.concatenate([analysed, binding])


def _smallest_common_duration(profile: str, moves: tuple, bound: float) -> float | None:
    """
    Return the smallest duration from ``bound`` on that suits every joint, or ``None``.

    Every joint's feasibility is constant between consecutive candidates of all joints, so
    the answer is the first candidate where every joint is feasible, at the candidate or
    (rounding can leave a run's exact start a hair outside) in the gap after it; there
    the start is moved onto the run (:func:`_onto_common_run`). Every joint is checked at
    :data:`_FIRST_POINTS` candidates and their gaps at a time (the first chunk usually
    holds the answer): ``joints × 2 × points`` exact peaks in one broadcast call.
    """
    # Plans may use half of LIMIT_TOLERANCE: a feasible start can lie that far below.
    bound = max(bound * (1.0 - 1e-9), SHORTEST_POLYNOMIAL)
    # Every root, sorted (NaN last): the points are bound, then the finite ones above it.
    points = np.sort(durations(profile, *moves)[0])
    above = int(points.searchsorted(bound, 'right'))
    finite = int(points.searchsorted(np.inf))
    if above:  # the slot before the first point above bound holds bound
        points = points[above - 1:finite]
        points[0] = bound
    else:
        points = np.concatenate([[bound], points[:finite]])
    distinct = np.empty(points.size, dtype=bool)  # joints alike share candidates
    distinct[0] = True
    np.not_equal(points[1:], points[:-1], out=distinct[1:])
    points = points[distinct]
    # The answer is usually among the first few points: those first, then the rest.
    for start in range(0, points.size, _FIRST_POINTS):
        chunk = points[start:start + _FIRST_POINTS]
        count = chunk.size
        # The points, then one duration inside each gap after a point: the midpoint, or
        # twice the last point.
        times = np.empty(2 * count)
        times[:count] = chunk
        if start + count < points.size:
            np.add(chunk, points[start + 1:start + count + 1], out=times[count:])
            times[count:] *= 0.5
        else:
            np.add(chunk[:-1], chunk[1:], out=times[count:-1])
            times[count:-1] *= 0.5
            times[-1] = 2.0 * chunk[-1]
        together = _all_feasible(profile, moves, times)
        either = together[:count] | together[count:]
        first = int(either.argmax())
        if either[first]:
            if together[first]:
                return float(chunk[first])
            return _onto_common_run(profile, moves, float(chunk[first]),
                                    float(times[count + first]))
    return None


def _all_feasible(profile: str, moves: tuple, times: np.ndarray) -> np.ndarray:
    """Whether every joint stays within its limits in each of ``times`` (exact peaks)."""
    displacement, velocity, acceleration, max_velocity, max_acceleration = moves
    peak_velocity, peak_acceleration = peaks(
        profile, displacement[:, None], velocity[:, None], acceleration[:, None], times)
    slack = 1.0 + 0.5 * LIMIT_TOLERANCE
    within = (peak_velocity <= max_velocity[:, None] * slack) & \
        (peak_acceleration <= max_acceleration[:, None] * slack)
    return np.logical_and.reduce(within)


def _onto_common_run(profile: str, moves: tuple, outside: float, inside: float) -> float:
    """
    Return the smallest duration in ``(outside, inside]`` where every joint is feasible.

    ``outside`` is a run's start that rounding left just outside it and ``inside`` a
    duration in the run: the smallest relative nudge in :data:`_NUDGES` that suits every
    joint, or where that is coarse (above 1e-9) or none is, 48 halvings of the bracket.
    """
    joints = moves[0].size
    tries = outside * (1.0 + _NUDGES)
    tries = tries[tries < inside]
    fits = np.logical_and.reduce(_feasible(
        profile, moves, np.arange(joints).repeat(tries.size),
        np.repeat(tries[None], joints, axis=0).reshape(-1)).reshape(joints, -1))
    if fits.any() and _NUDGES[np.argmax(fits)] <= 1e-9:
        return float(tries[np.argmax(fits)])
    low = float(tries[np.argmax(fits) - 1]) if fits.any() and fits.argmax() > 0 else outside
    high = float(tries[np.argmax(fits)]) if fits.any() else inside
    everyone = np.arange(joints)
    for _ in range(48):
        middle = 0.5 * (low + high)
        if _feasible(profile, moves, everyone, np.full(joints, middle)).all():
            high = middle
        else:
            low = middle
    return high


def _common_duration(profile: str, moves: tuple,
                     joints: np.ndarray | None) -> tuple[float | None, int | None]:
    """:func:`polynomial_minimum_duration` over the given joints (``None``: all), exactly."""
    subset = moves if joints is None else tuple(values[joints] for values in moves)
    count = subset[0].size
    runs = feasible_runs(profile, subset)
    counts = np.bincount(runs[2].astype(np.intp), minlength=count)
    if not counts.all():
        hopeless = int(np.argmin(counts))
        return None, hopeless if joints is None else int(joints[hopeless])
    return synchronised_duration(runs, count), None
