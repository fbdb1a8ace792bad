"""
Seeded generator of malformed and valid requests, and the oracle that judges the answers.

Shared by ``test_reliability_fuzz.py`` (ROS-free ``planning`` layer and the live node over
DDS) and ``make fuzz``. A :class:`Case` is plain data: which topic, which names, the
positions or via points, and the refusal it must get (a regex) or ``None`` when it may be
accepted. The same case becomes ``planning`` arguments or a ROS message.

Commanded range (the envelope every published position must stay in), per joint:

* goal, or ``lspb`` via points, starting at rest: the hull of the start position and the
  commanded positions (rest-to-rest cubic/quintic/LSPB/S-curve are monotonic; Craig's LSPB
  blends round corners inside the hull of the via points). Exact.
* cubic/quintic/S-curve via points (splines may overshoot between points): on each segment
  ``[t_i, t_i+1]`` the hull of its two points widened by ``v_max * (t_i+1 - t_i) / 2``.
  Sound because the spline passes through both points and never exceeds ``v_max``.
* a start that is moving, or via points whose segment times are unknown: the hull of the
  start and all commanded positions widened by ``v_max * duration / 2`` (same argument).
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math

import numpy as np

JOINTS = [f'joint_{index}' for index in range(1, 7)]
MAX_VELOCITY = np.array([2.0, 2.0, 2.0, 3.0, 3.0, 3.0])
MAX_ACCELERATION = np.array([4.0, 4.0, 4.0, 6.0, 6.0, 6.0])
PROFILES = ('cubic', 'quintic', 'lspb', 'scurve')

NON_FINITE = r'is (nan|inf|-inf): every value must be finite'
LIMIT_REASON = (r'above max_|minimum feasible duration|no uniform stretch|breaks a limit|'
                r'cannot plan|cannot time|above the limit of|non-finite|samples on|'
                r'cannot leave|blend|too short|does not fit|profile lspb|profile cubic|'
                r'profile scurve|scurve_via')


@dataclass
class Case:
    """One request: ``kind`` is ``goal`` or ``via``; ``expect`` a refusal regex or None."""

    category: str
    kind: str
    names: list[str]
    positions: list[float] = field(default_factory=list)  # goal
    # via: (positions, velocities, accelerations, time_from_start seconds)
    points: list[tuple[list[float], list[float], list[float], float]] = field(
        default_factory=list)
    stamp_sec: int = 0
    expect: str | None = None

    @property
    def auto_timed(self) -> bool:
        return self.kind == 'via' and all(p[3] == 0.0 for p in self.points)


def _names(rng: np.random.Generator, low: int = 1) -> list[str]:
    count = int(rng.integers(low, len(JOINTS) + 1))
    return [JOINTS[i] for i in rng.permutation(len(JOINTS))[:count]]


def _targets(rng, count, around):
    return (np.asarray(around) + rng.uniform(-0.8, 0.8, count)).clip(-1.5, 1.5).tolist()


def _via(rng, names, current, count=None, timed=True, slack=3.0):
    count = count or int(rng.integers(1, 5))
    points, time, previous = [], 0.0, np.asarray(current, dtype=float)
    limit = np.array([MAX_VELOCITY[JOINTS.index(n)] for n in names])
    for _ in range(count):
        position = np.array(_targets(rng, len(names), previous))
        step = float(np.max(np.abs(position - previous) / limit)) * slack + 0.3
        time = time + step if timed else 0.0
        points.append((position.tolist(), [], [], round(time, 3)))
        previous = position
    return points


def make_case(rng: np.random.Generator, current: np.ndarray, dds: bool = False) -> Case:
    """
    Draw one case near ``current`` (the node's position, all joints).

    ``dds`` keeps huge messages rare (building 10,000 points in Python costs the sender
    tens of milliseconds) and plans short (the probe deserialises every ~/trajectory).
    """
    names = _names(rng)
    here = [float(current[JOINTS.index(n)]) for n in names]
    kind = 'goal' if rng.random() < 0.5 else 'via'
    weights = {'unknown': 1, 'duplicate': 1, 'empty': 1, 'lengths': 2, 'non_finite': 2,
               'huge_value': 2, 'negative_time': 1, 'non_increasing': 1, 'huge_time': 1,
               'many_points': 0.2 if dds else 1, 'zero_motion': 1, 'infeasible': 1,
               'partial_velocities': 1, 'moving_end': 1, 't0_elsewhere': 1,
               'long_plan': 0 if dds else 0.5, 'valid': 6}
    labels = list(weights)
    p = np.array([weights[k] for k in labels], dtype=float)
    category = labels[int(rng.choice(len(labels), p=p / p.sum()))]
    via_only = {'negative_time', 'non_increasing', 'huge_time', 'many_points', 'infeasible',
                'partial_velocities', 'moving_end', 't0_elsewhere', 'long_plan'}
    if category in via_only:
        kind = 'via'
    case = Case(category, kind, names)
    if kind == 'goal':
        case.positions = _targets(rng, len(names), here)
    else:
        case.points = _via(rng, names, here, timed=rng.random() < 0.7)
        if rng.random() < 0.1:
            case.stamp_sec = int(rng.choice([-5, -1, 1]))  # past or epoch stamps: "now"
    if category == 'unknown':
        bad = str(rng.choice(['joint_7', 'elbow', '', 'JOINT_1', 'joint_1 ', 'j\u00f6int']))
        names[int(rng.integers(len(names)))] = bad
        case.expect = rf'unknown joint {bad!r}'.replace('(', r'\(').replace(')', r'\)')
    elif category == 'duplicate':
        index = int(rng.integers(len(names)))
        names.append(names[index])
        if kind == 'goal':
            case.positions.append(case.positions[index])
        else:
            case.points = [([*p[0], p[0][index]], [], [], p[3]) for p in case.points]
        case.expect = 'more than once'
    elif category == 'empty':
        choice = int(rng.integers(3))
        if choice == 0 or kind == 'goal':
            case.names.clear()
            case.positions, case.points = [], [([], [], [], p[3]) for p in case.points]
            case.expect = 'names no joint'
        else:
            case.points = []
            case.expect = 'has no points'
    elif category == 'lengths':
        if kind == 'goal':
            case.positions = case.positions[:-1] if rng.random() < 0.5 else \
                case.positions + [0.0]
            case.expect = r'goal has \d+ names but \d+ positions'
        else:
            row = int(rng.integers(len(case.points)))
            pos, _, _, t = case.points[row]
            if rng.random() < 0.5:
                case.points[row] = (pos + [0.1], [], [], t)
                case.expect = r'positions but joint_names has'
            else:
                case.points = [(q, [0.0] * (len(q) + 1), [], s) for q, _, _, s in case.points]
                case.expect = r'velocities but joint_names has'
    elif category == 'non_finite':
        bad = float(rng.choice([math.nan, math.inf, -math.inf]))
        if kind == 'goal':
            case.positions[int(rng.integers(len(names)))] = bad
        else:
            row = int(rng.integers(len(case.points)))
            column = int(rng.integers(len(names)))
            pos, _, _, t = case.points[row]
            where = int(rng.integers(3))
            values = [list(pos), [0.0] * len(pos), [0.0] * len(pos)]
            values[where][column] = bad
            if where == 0:
                case.points[row] = (values[0], [], [], t)
            else:  # velocities (and accelerations) on every point, one of them bad
                case.points = [(q, [0.0] * len(q), [0.0] * len(q) if where == 2 else [], s)
                               for q, _, _, s in case.points]
                case.points[row] = (pos, values[1], values[2] if where == 2 else [], t)
        case.expect = NON_FINITE
    elif category == 'huge_value':
        bad = float(rng.choice([1e308, -1e308, 1e300, 1e15, -1e9]))
        if kind == 'goal':
            case.positions[int(rng.integers(len(names)))] = bad
        else:
            row = int(rng.integers(len(case.points)))
            pos, _, _, t = case.points[row]
            pos = list(pos)
            pos[int(rng.integers(len(names)))] = bad
            case.points[row] = (pos, [], [], t)
        case.expect = LIMIT_REASON
    elif category == 'negative_time':
        row = int(rng.integers(len(case.points)))
        pos, _, _, _ = case.points[row]
        case.points[row] = (pos, [], [], -float(rng.choice([1e-9, 0.5, 3.0, 2e9])))
        case.expect = r'time_from_start -[\d.e+-]+ s: must be >= 0'
    elif category == 'non_increasing':
        case.points = _via(rng, names, here, count=int(rng.integers(2, 5)))
        row = int(rng.integers(1, len(case.points)))
        pos, _, _, _ = case.points[row]
        earlier = case.points[row - 1][3] - float(rng.choice([0.0, 0.2]))
        case.points[row] = (pos, [], [], max(earlier, 0.001))
        case.expect = 'strictly increasing'
    elif category == 'huge_time':
        pos, _, _, _ = case.points[-1]
        case.points[-1] = (pos, [], [], float(rng.choice([3600.5, 1e5, 2.1e9])))
        case.expect = r'above the limit of 3600 s'
    elif category == 'many_points':
        count = int(rng.choice([1001, 5000, 10_000]))
        ramp = np.linspace(0.0, 0.5, count)
        case.points = [([float(here[0] + r)] + here[1:], [], [], 0.01 * (i + 1))
                       for i, r in enumerate(ramp)]
        case.expect = rf'via_points has {count} points, above the limit of 1000'
    elif category == 'zero_motion':
        if kind == 'goal':
            case.positions = list(here)
        else:
            case.points = [(list(here), [], [], 0.5)]
    elif category == 'infeasible':
        case.points = [(list(np.array(here) + 1.0), [], [], 0.01)]
        case.expect = r'minimum feasible duration|blend|no uniform stretch'
    elif category == 'partial_velocities':
        case.points = _via(rng, names, here, count=int(rng.integers(2, 5)))
        pos, _, _, t = case.points[0]
        case.points[0] = (pos, [0.0] * len(pos), [], t)
        case.expect = r'velocities are given for 1 of \d+ points'
    elif category == 'moving_end':
        case.points = [(q, [0.0] * len(q), [], t) for q, _, _, t in case.points]
        pos, vel, _, t = case.points[-1]
        case.points[-1] = (pos, [0.3] * len(pos), [], t)
        case.expect = r'last point must have zero velocity|profile lspb'
    elif category == 't0_elsewhere':
        case.points = [([h + 0.5 for h in here], [], [], 0.0), (list(here), [], [], 1.0)]
        case.expect = r'time_from_start 0 but joint'
    elif category == 'long_plan':
        case.points = [(list(np.array(here) + 0.1), [], [], float(rng.uniform(900, 3600)))]
    return case


def refusal_ok(case: Case, reason: str) -> bool:
    """Whether a refusal is acceptable: the expected reason, or a specific limit reason."""
    import re

    if 'internal error' in reason or not reason:
        return False
    if case.expect is not None:
        return re.search(case.expect, reason) is not None
    return re.search(LIMIT_REASON, reason) is not None


def full_rows(case: Case, hold: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Commanded positions of every joint (unnamed ones at ``hold``) and their times."""
    columns = [JOINTS.index(n) for n in case.names]
    if case.kind == 'goal':
        row = np.array(hold, dtype=float)
        row[columns] = case.positions
        return row[None, :], None
    rows = np.tile(np.asarray(hold, dtype=float), (len(case.points), 1))
    rows[:, columns] = [p[0] for p in case.points]
    times = np.array([p[3] for p in case.points])
    return rows, None if case.auto_timed else times


def envelope(times: np.ndarray, start: np.ndarray, moving: bool, rows: np.ndarray,
             row_times: np.ndarray | None, profile: str, kind: str, duration: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper commanded range at ``times`` (see the module docstring)."""
    times = np.asarray(times, dtype=float)
    if row_times is not None and len(row_times) and row_times[0] == 0.0:
        rows, row_times = rows[1:], row_times[1:]  # a t=0 point stands for the start
    points = np.vstack([start, rows])
    shape = (len(times), len(start))
    if not moving and (kind == 'goal' or profile == 'lspb'):
        return (np.broadcast_to(points.min(axis=0), shape),
                np.broadcast_to(points.max(axis=0), shape))
    if profile != 'lspb' and row_times is not None and kind == 'via':
        knots = np.concatenate([[0.0], row_times])
        index = np.clip(np.searchsorted(knots, times, side='right') - 1, 0, len(rows) - 1)
        first, second = points[index], points[index + 1]
        margin = MAX_VELOCITY * (knots[index + 1] - knots[index])[:, None] / 2
        return np.minimum(first, second) - margin, np.maximum(first, second) + margin
    margin = MAX_VELOCITY * duration / 2
    return (np.broadcast_to(points.min(axis=0) - margin, shape),
            np.broadcast_to(points.max(axis=0) + margin, shape))
