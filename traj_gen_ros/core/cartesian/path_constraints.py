"""
The limits of a path's timing as linear constraints in ``(u, x) = (s̈, ṡ²)``, per interval.

Along a path ``q(s)``, ``p(s)`` the joint and tool rates are ``q̇ = q' ṡ``,
``q̈ = q' s̈ + q'' ṡ²``, ``ṗ = p' ṡ``, ``p̈ = p' s̈ + p'' ṡ²``, ``ω = ω_s ṡ`` (primes:
derivatives by ``s``). So every velocity limit bounds ``x = ṡ²`` at a grid point, and every
acceleration limit is linear in ``(u, x)``: ``|q'_j u + q''_j x| <= a_j`` (Pham & Pham,
"A new approach to time-optimal path parameterization based on reachability analysis",
IEEE T-RO 34(3), 2018, §III). On the interval ``[s_i, s_i + Δ_i]`` ``u`` is constant and
``x_{i+1} = x_i + 2 Δ_i u``; its constraints are put at both its ends, the start with the
right-side derivatives, the end with the left-side ones and ``x_{i+1}`` substituted, so
every grid point's accelerations on both sides are within the limits.

The tool's acceleration ``|p' u + p'' x| <= a`` is a norm. In the plane of ``p'`` and
``p''`` it has a component along the tangent, ``w_t = |p'| u + τ x`` (``τ = p̂'·p''``),
and one across it, ``w_n = κ x >= 0`` (``κ = |p'' - τ p̂'|``): the half disc
``w_t² + w_n² <= a²`` is replaced by the inscribed polygon of :data:`TOOL_EDGES` equal
edges. It is an inner approximation within ``1 - cos(π / (2·TOOL_EDGES))`` (0.21 %) of
the norm, exact on the tangent (``w_n = 0``: every straight line) and across it
(``w_t = 0``: a constant speed on an arc); edges whose span of ``w_n`` the interval cannot
reach are left out.

A jerk limit (the S-curve profile) is not linear in ``(u, x)``: it would enter here as a
third per-interval limit beside ``max_acceleration``, with a pass of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
import math

import numpy as np
from traj_gen_ros.core.cartesian import zero_inertia
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.trajectory import Trajectory

#: Intervals of the whole path's grid, shared among its pieces by length.
BASE_INTERVALS = 200
#: The fewest intervals of a piece between two knots.
PIECE_INTERVALS = 8
#: The largest change, relative, of the path's derivatives over one interval.
BEND_STEP = 0.01
#: Edges of the polygon inscribed in the half disc of the tool's acceleration (even: the
#: tangent and the normal directions are vertices).
TOOL_EDGES = 24
_VERTICES = np.pi * np.arange(TOOL_EDGES + 1) / TOOL_EDGES
_NORMALS = 0.5 * (_VERTICES[1:] + _VERTICES[:-1])  # each edge's outward direction φ_k
_EDGE_REACH = math.cos(np.pi / (2 * TOOL_EDGES))  # the edges' distance from the centre / a
# Each edge's lowest w_n / a (sin π is 1.2e-16: the last edge starts at w_n = 0 too).
_EDGE_LOW = np.minimum(np.sin(_VERTICES[1:]), np.sin(_VERTICES[:-1])).round(12)


@dataclass(frozen=True)
class ToolLimits:
    """
    Limits of the tool point: speed (m/s), acceleration (m/s²), angular speed (rad/s).

    ``inf`` (the default) is no limit. The acceleration is the whole vector of the tool
    point, tangential and centripetal.
    """

    max_linear_velocity: float = math.inf
    max_linear_acceleration: float = math.inf
    max_angular_velocity: float = math.inf

    def __post_init__(self) -> None:
        """Refuse a limit that is not a number > 0 (``inf`` is allowed: no limit)."""
        for field in fields(self):
            value = getattr(self, field.name)
            if isinstance(value, bool) or not isinstance(value, int | float) or \
                    not value > 0.0:
                raise ValueError(f'ToolLimits.{field.name} must be a number > 0 (inf: no '
                                 f'limit), got {value!r}')
            object.__setattr__(self, field.name, float(value))

    def as_array(self) -> np.ndarray:
        """Return the three limits in field order, ``(3,)``."""
        return np.array([self.max_linear_velocity, self.max_linear_acceleration,
                         self.max_angular_velocity])


@dataclass(frozen=True)
class PathGrid:
    """
    A path sampled at its grid ``s_0 … s_n``: what the constraints are made of.

    Arrays indexed ``[0]`` are at each interval's start (right-side derivatives at
    ``s_i``), ``[1]`` at its end (left-side ones at ``s_{i+1}``): ``(2, intervals, …)``.

    :ivar s: ``(n + 1,)`` the grid, every knot among it.
    :ivar stop: ``(n + 1,)`` where the tool must rest.
    :ivar q: ``(n + 1, joints)`` joint positions at the grid.
    :ivar dq: ``(2, n, joints)`` ``dq/ds`` (rad per unit of path).
    :ivar ddq: ``(2, n, joints)`` ``d²q/ds²``.
    :ivar tangent: ``(2, n)`` ``|p'|``.
    :ivar along: ``(2, n)`` ``τ``, the part of ``p''`` along ``p'``.
    :ivar across: ``(2, n)`` ``κ``, the part of ``p''`` across it.
    :ivar turn: ``(2, n)`` ``|ω_s|``.
    """

    s: np.ndarray
    stop: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tangent: np.ndarray
    along: np.ndarray
    across: np.ndarray
    turn: np.ndarray

    @property
    def delta(self) -> np.ndarray:
        """Each interval's length, ``(n,)``."""
        return np.diff(self.s)


@dataclass(frozen=True)
class Stages:
    """
    The constraints of every interval: ``a u + b x_i <= c`` and ``x_i <= x_max[i]``.

    :ivar x_max: ``(n + 1,)`` the bound of ``ṡ²`` at each grid point (velocities, stops).
    :ivar a: ``(n, k)`` the coefficients of ``u`` (both ends' constraints side by side,
        the end's with ``x_{i+1} = x_i + 2 Δ_i u`` substituted).
    :ivar b: ``(n, k)`` those of ``x_i``.
    :ivar c: ``(n, k)`` the limits, ``>= 0``; a column that does not apply has ``a = b =
        0``.
    :ivar delta: ``(n,)`` the intervals' lengths.
    """

    x_max: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    delta: np.ndarray


def joint_states(joints: Trajectory, s: np.ndarray, side: str
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Evaluate ``q``, ``dq/ds``, ``d²q/ds²`` at ``s`` on the ``side`` piece at a breakpoint.

    ``joints`` is a joint path's polynomial in ``s`` with breakpoints shared by every joint;
    ``(len(s), joints)`` each, by Horner's rule.
    """
    breakpoints, coefficients = joints.breakpoints, joints.coefficients
    if breakpoints.ndim != 1:
        raise ValueError('the joint path must have breakpoints shared by every joint')
    piece = np.searchsorted(breakpoints, s, side='right' if side == 'right' else 'left') - 1
    piece = np.clip(piece, 0, len(coefficients) - 1)
    local = (s - breakpoints[piece])[:, None]
    gathered = coefficients[piece]  # (samples, degree + 1, joints)
    states = [np.zeros((len(s), joints.joint_count)) for _ in range(3)]
    for power in range(coefficients.shape[1] - 1, -1, -1):
        states[2] = states[2] * local + 2.0 * states[1]
        states[1] = states[1] * local + states[0]
        states[0] = states[0] * local + gathered[:, power]
    return states[0], states[1], states[2]


def path_grid(path: IdealPath, joint_path: JointPath, tool_limited: bool, *,
              max_velocity: np.ndarray | None = None,
              max_acceleration: np.ndarray | None = None,
              tool_speed: np.ndarray | None = None) -> PathGrid:
    """
    Choose the grid (every knot and stop among it) and sample both paths there.

    Each piece between knots gets its share of :data:`BASE_INTERVALS` by length, at least
    :data:`PIECE_INTERVALS`, and one interval per :data:`BEND_STEP` of ``ℓ · bend``, the
    bend being ``max|d²/ds²| / max|d/ds|`` of the joints (and, where ``tool_limited``, of
    the tool point) at the piece's start, middle and end. A constraint held at both ends
    of an interval with ``s̈`` constant loses time in proportion to how much its
    coefficients change over it; these steps keep the duration within 1 % of the optimum
    (the tests compare it with a 10,000-point phase-plane integration). Given the joint
    limits (``(joints,)`` rad/s, rad/s²; ``tool_speed``: the tool's linear and angular
    speed limits, ``inf`` for none), the intervals near a zero-inertia point are cut
    finer (:func:`.zero_inertia.refine`) and both paths sampled again.
    """
    length = float(path.length)
    stops = merge_values(length, path.stops, joint_path.stops)
    knots = merge_values(length, path.knots, joint_path.knots, stops)
    s = _cut(path, joint_path, knots, tool_limited)
    grid = sample_grid(path, joint_path, s, nearest_points(s, knots), nearest_points(s, stops))
    if max_velocity is None or max_acceleration is None:
        return grid
    speeds = np.full(2, np.inf) if tool_speed is None else np.asarray(tool_speed, float)
    x_max = speed_bounds(grid, np.tile(max_velocity, (len(s), 1)), np.tile(speeds, (len(s), 1)))
    finer = zero_inertia.refine(s, grid.dq, grid.ddq, x_max, max_acceleration)
    if len(finer) == len(s):
        return grid
    return sample_grid(path, joint_path, finer, nearest_points(finer, knots),
                       nearest_points(finer, stops))


def merge_values(length: float, *sets: np.ndarray) -> np.ndarray:
    """Merge sorted ``s`` values (knots or stops) with 0 and ``length``, near ones as one."""
    merged = np.sort(np.concatenate([[0.0, length], *[np.asarray(v, float) for v in sets]]))
    merged = np.clip(merged, 0.0, length)
    merged = merged[np.concatenate([[True], np.diff(merged) > 1e-12 * length])]
    merged[-1] = length
    return merged


def nearest_points(s: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Return the index of the grid point nearest each of ``values``."""
    index = np.clip(np.searchsorted(s, values), 1, len(s) - 1)
    return np.where(values - s[index - 1] < s[index] - values, index - 1, index)


def _cut(path: IdealPath, joint_path: JointPath, knots: np.ndarray, tool_limited: bool
         ) -> np.ndarray:
    """Cut every piece between knots into equal intervals (:func:`path_grid`'s rule)."""
    starts, ends = knots[:-1], knots[1:]
    lengths = ends - starts
    probe = np.stack([starts, 0.5 * (starts + ends), ends], axis=1)
    bend = np.zeros(len(lengths))
    for column, side in enumerate(('right', 'right', 'left')):
        _, dq, ddq = joint_states(joint_path.joints, probe[:, column], side)
        rate = np.abs(dq).max(axis=1)
        bend = np.fmax(bend, np.abs(ddq).max(axis=1) / np.where(rate > 0.0, rate, np.inf))
        if tool_limited:
            samples = path.sample(probe[:, column], side)
            speed = np.linalg.norm(samples.velocity, axis=1)
            turn = np.linalg.norm(samples.acceleration, axis=1)
            bend = np.fmax(bend, turn / np.where(speed > 0.0, speed, np.inf))
    counts = np.maximum.reduce([
        np.full(len(lengths), PIECE_INTERVALS),
        np.ceil(BASE_INTERVALS * lengths / knots[-1]).astype(int),
        np.ceil(lengths * bend / BEND_STEP).astype(int)])
    pieces = [np.linspace(start, end, count + 1)[:-1]
              for start, end, count in zip(starts, ends, counts.tolist(), strict=True)]
    return np.concatenate(pieces + [knots[-1:]])


def sample_grid(path: IdealPath, joint_path: JointPath, s: np.ndarray, knots: np.ndarray,
                stops: np.ndarray) -> PathGrid:
    """Sample both paths at the grid ``s``; the left side differs only at the ``knots``."""
    q, dq_right, ddq_right = joint_states(joint_path.joints, s, 'right')
    _, dq_left, ddq_left = joint_states(joint_path.joints, s, 'left')
    right = _tool_terms(path.sample(s, 'right'))
    left = [terms.copy() for terms in right]
    for terms, at_knots in zip(left, _tool_terms(path.sample(s[knots], 'left')), strict=True):
        terms[knots] = at_knots
    stop = np.zeros(len(s), dtype=bool)
    stop[stops] = True
    return PathGrid(
        s=s, stop=stop, q=q,
        dq=np.stack([dq_right[:-1], dq_left[1:]]),
        ddq=np.stack([ddq_right[:-1], ddq_left[1:]]),
        **{name: np.stack([right[index][:-1], left[index][1:]])
           for index, name in enumerate(('tangent', 'along', 'across', 'turn'))})


def _tool_terms(samples: object) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return ``|p'|``, ``τ``, ``κ``, ``|ω_s|`` of :class:`PathSamples`, ``(n,)`` each."""
    velocity, acceleration = samples.velocity, samples.acceleration
    tangent = np.sqrt(np.einsum('ij,ij->i', velocity, velocity))
    unit = velocity / np.where(tangent > 0.0, tangent, 1.0)[:, None]
    along = np.einsum('ij,ij->i', unit, acceleration)
    normal = acceleration - along[:, None] * unit
    across = np.sqrt(np.einsum('ij,ij->i', normal, normal))
    turn = np.sqrt(np.einsum('ij,ij->i', samples.angular, samples.angular))
    return tangent, along, across, turn


def speed_bounds(grid: PathGrid, max_velocity: np.ndarray, tool_speed: np.ndarray
                 ) -> np.ndarray:
    """
    Bound ``ṡ²`` at every grid point by the velocity limits, ``(n + 1,)``; 0 at stops.

    ``max_velocity`` is ``(n + 1, joints)`` (per point: tightened ones may differ),
    ``tool_speed`` ``(n + 1, 2)``: the linear and the angular speed limits. Both sides'
    derivatives count at a knot.
    """
    rates = np.concatenate([np.abs(grid.dq), grid.tangent[..., None],
                            grid.turn[..., None]], axis=2)  # (2, n, joints + 2)
    limits = np.concatenate([max_velocity, tool_speed], axis=1)
    with np.errstate(divide='ignore', invalid='ignore'):
        start = np.min(np.where(rates[0] > 0.0, limits[:-1] / rates[0], np.inf), axis=1)
        end = np.min(np.where(rates[1] > 0.0, limits[1:] / rates[1], np.inf), axis=1)
    bound = np.full(len(grid.s), np.inf)
    bound[:-1] = start
    bound[1:] = np.minimum(bound[1:], end)
    bound = bound * bound
    bound[grid.stop] = 0.0
    return bound


def assemble(grid: PathGrid, max_velocity: np.ndarray, max_acceleration: np.ndarray,
             tool_speed: np.ndarray, tool_acceleration: np.ndarray) -> Stages:
    """
    Build every interval's constraints from the limits.

    :param max_velocity: ``(n + 1, joints)`` rad/s at each grid point.
    :param max_acceleration: ``(n, joints)`` rad/s² on each interval.
    :param tool_speed: ``(n + 1, 2)`` the tool's linear (m/s) and angular (rad/s) speed
        limits at each grid point.
    :param tool_acceleration: ``(n,)`` the tool's acceleration limit (m/s²) on each
        interval.
    """
    x_max = speed_bounds(grid, max_velocity, tool_speed)
    delta = grid.delta
    twice = (2.0 * delta)[:, None]
    # Joint accelerations, ±(q' u + q'' x): at the start on x_i, at the end on x_{i+1}.
    joint_a = np.concatenate([grid.dq[0], grid.dq[1] + twice * grid.ddq[1]], axis=1)
    joint_b = np.concatenate([grid.ddq[0], grid.ddq[1]], axis=1)
    joint_c = np.concatenate([max_acceleration, max_acceleration], axis=1)
    columns_a, columns_b, columns_c = [joint_a, -joint_a], [joint_b, -joint_b], \
        [joint_c, joint_c]
    if np.any(np.isfinite(tool_acceleration)):
        edge_a, edge_b, edge_c = _tool_edges(grid, x_max, tool_acceleration)
        columns_a.append(edge_a)
        columns_b.append(edge_b)
        columns_c.append(edge_c)
    return Stages(x_max, np.concatenate(columns_a, axis=1),
                  np.concatenate(columns_b, axis=1), np.concatenate(columns_c, axis=1),
                  delta)


def _tool_edges(grid: PathGrid, x_max: np.ndarray, limit: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Build the polygon's edges at both ends of every interval, ``(n, 2 · TOOL_EDGES)`` each.

    Edge ``k`` is ``cos φ_k w_t + sin φ_k w_n <= a cos(π / 2M)``; it is kept where its
    lowest ``w_n`` is within the ``κ x`` the interval can reach (else ``a = b = c = 0``).
    """
    cos, sin = np.cos(_NORMALS), np.sin(_NORMALS)
    finite = np.isfinite(limit)
    reach = np.where(finite, limit, 0.0)[:, None]
    delta = grid.delta[:, None]
    parts = []
    for end, x_reach in ((0, x_max[:-1]), (1, x_max[1:])):
        tangent, along, across = (grid.tangent[end][:, None], grid.along[end][:, None],
                                  grid.across[end][:, None])
        a = tangent * cos
        b = along * cos + across * sin
        if end:
            a = a + 2.0 * delta * b
        with np.errstate(invalid='ignore'):  # κ = 0 and x unbounded: w_n stays 0
            normal_reach = np.where(across > 0.0, across * x_reach[:, None], 0.0)
        used = finite[:, None] & (_EDGE_LOW * reach <= normal_reach * 1.000001)
        parts.append((np.where(used, a, 0.0), np.where(used, b, 0.0),
                      np.where(used, reach * _EDGE_REACH, 0.0)))
    return tuple(np.concatenate([part[index] for part in parts], axis=1) for index in range(3))
