"""
Position limits applied to requests and plans: commanded positions and exact plan extrema.

No ROS here. The limits in force (:class:`traj_gen_ros.node.urdf_limits.JointLimits`, the
tighter of the URDF and the ``min_position``/``max_position`` parameters) ride on the
node's :class:`~traj_gen_ros.node.config.Config` (``Config.limits``). Two checks, each
raising :class:`~traj_gen_ros.node.parsing.RequestError` that names the joint by its ROS
name, the value and the range:

* :func:`check_request`: a goal position or via point outside the range, before planning;
* :func:`check_plan`: a plan that would leave the range between its points (a spline's
  overshoot, a moving start that must brake past the target). The plan's exact position
  extrema are found by :func:`position_extrema`: every piece of a
  :class:`~traj_gen_ros.core.trajectory.Trajectory` is a polynomial, so its extrema lie at the
  piece's ends or at real roots of its velocity, found as the eigenvalues of the velocity's
  companion matrix (all pieces and joints at once).

A joint may be outside its range already: ``initial_positions`` (or a measured state)
there, or limits narrowed while it was there. :func:`outside_ranges` says so (the node
logs it and reports WARN on ``/diagnostics``). Such a joint may hold where it is while
the others move, and move toward or into its range: for both checks the positions of a
joint that starts at ``s`` must stay within ``[min(s, lower), max(s, upper)]`` (its
range, widened to the start), so only a goal, via point or plan that takes it further
out is refused. ``~/stop`` is never checked.

Units: rad or m, s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.parsing import GoalRequest, RequestError, ViaRequest
from traj_gen_ros.node.urdf_limits import JointLimits, NONE, PARAMETER

#: Slack on a position bound (relative to ``max(1, |bound|)``): rounding, not an excess.
POSITION_TOLERANCE = 1e-9


def position_extrema(plan: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the exact lowest and highest position of every joint, ``(joints,)`` each.

    Candidates are each piece's ends and the real parts of the roots of its velocity in
    normalised time ``s = t / T`` (clipped to the piece): every candidate is a position the
    plan really takes, and every extremum is a candidate, so the result is exact to
    rounding, never an estimate that could miss an overshoot.
    """
    coefficients = np.asarray(plan.coefficients, dtype=float)
    pieces, order, joints = coefficients.shape
    lengths = np.diff(plan.breakpoints, axis=0)
    lengths = np.broadcast_to(lengths if lengths.ndim == 2 else lengths[:, None],
                              (pieces, joints))
    # Normalised pieces: p(s) = sum c_k T^k s^k on s in [0, 1], one row per piece and joint.
    powers = lengths[:, None, :] ** np.arange(order)[None, :, None]
    scaled = np.moveaxis(coefficients * powers, 1, 2).reshape(-1, order)
    values = [scaled[:, 0], scaled.sum(axis=1)]  # s = 0 and s = 1
    if order > 2:
        roots = _velocity_roots(scaled[:, 1:] * np.arange(1, order))
        candidates = np.clip(np.nan_to_num(roots, nan=0.0), 0.0, 1.0)
        values.append(_polyval(scaled, candidates))
    else:
        values.append(values[0][:, None])
    table = np.column_stack([values[0], values[1], values[2]]).reshape(pieces, joints, -1)
    return table.min(axis=(0, 2)), table.max(axis=(0, 2))


def _polyval(coefficients: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Evaluate each row's ascending ``coefficients`` at that row's ``points``."""
    value = np.zeros_like(points)
    for power in range(coefficients.shape[1] - 1, -1, -1):
        value = value * points + coefficients[:, power][:, None]
    return value


def _velocity_roots(velocity: np.ndarray) -> np.ndarray:
    """
    Real parts of the roots of each row's ascending polynomial, NaN where there are fewer.

    Rows are grouped by degree (the highest non-zero coefficient); each group's roots are
    the eigenvalues of its companion matrices, computed at once.
    """
    rows, size = velocity.shape
    roots = np.full((rows, max(size - 1, 1)), np.nan)
    nonzero = velocity != 0.0
    degree = np.where(nonzero.any(axis=1), size - 1 - np.argmax(nonzero[:, ::-1], axis=1), 0)
    for d in range(1, size):
        group = np.flatnonzero(degree == d)
        if group.size == 0:
            continue
        monic = velocity[group, :d] / velocity[group, d][:, None]
        if d == 1:
            roots[group, 0] = -monic[:, 0]
            continue
        companion = np.zeros((group.size, d, d))
        companion[:, 1:, :-1] = np.eye(d - 1)
        companion[:, :, -1] = -monic
        finite = np.isfinite(companion).all(axis=(1, 2))
        found = np.full((group.size, d), np.nan)
        if finite.any():
            try:
                found[finite] = np.linalg.eigvals(companion[finite]).real
            except np.linalg.LinAlgError:  # one at a time, so that one failure stays local
                for row in np.flatnonzero(finite):
                    found[row] = np.roots(np.append(1.0, monic[row, ::-1])).real
        roots[group, :d] = found
    return roots


def _bound_text(limits: JointLimits, index: int, bound: str) -> str:
    source = (limits.position.lower_source if bound == 'lower'
              else limits.position.upper_source)[index]
    if source == PARAMETER:
        origin = 'parameter min_position' if bound == 'lower' else 'parameter max_position'
    else:
        origin = 'URDF' if source != NONE else 'none'
    return f'{bound} from {origin}'


def _outside(limits: JointLimits, index: int, value: float) -> str | None:
    """Say which bound ``value`` breaks (``'lower'``/``'upper'``), or None."""
    lower = limits.position.lower[index]
    upper = limits.position.upper[index]
    if value < lower - POSITION_TOLERANCE * max(1.0, abs(lower)):
        return 'lower'
    if value > upper + POSITION_TOLERANCE * max(1.0, abs(upper)):
        return 'upper'
    return None


def _range(limits: JointLimits, index: int) -> str:
    unit = limits.units[index]
    return (f'[{limits.position.lower[index]:.6g}, {limits.position.upper[index]:.6g}] {unit} '
            f'({"; ".join(_bound_text(limits, index, b) for b in ("lower", "upper"))})')


def _envelope(limits: JointLimits, joints: np.ndarray, start: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Return the bounds a plan of ``joints`` must keep: the range widened to the start."""
    lower, upper = limits.position.lower[joints], limits.position.upper[joints]
    return np.minimum(lower, start[joints]), np.maximum(upper, start[joints])


def outside_ranges(limits: JointLimits | None, positions: Sequence[float]) -> str:
    """
    Say which joints are outside their position range at ``positions`` (rad or m).

    :return: '' when all are within (bounds included, with ``POSITION_TOLERANCE``);
        otherwise one clause per joint, joined by ``'; '``, e.g. ``joint 'joint_4' is at 0
        rad, outside its range [0.194395, 2.29440] rad (lower from URDF; upper from
        URDF)``.
    """
    if limits is None:
        return ''
    parts = []
    for index, value in enumerate(np.asarray(positions, dtype=float)):
        if _outside(limits, index, float(value)) is not None:
            parts.append(f'joint {limits.joints[index]!r} is at {value:.6g} '
                         f'{limits.units[index]}, outside its range {_range(limits, index)}')
    return '; '.join(parts)


def check_request(limits: JointLimits, request: GoalRequest | ViaRequest,
                  start: Sequence[float]) -> None:
    """
    Refuse a goal or via point outside its joint's position range.

    A joint whose ``start`` (rad or m) is outside its range may be sent anywhere between
    its start and its range, not further out (:func:`_envelope`).

    :raises RequestError: e.g. ``goal position 3.2 rad for joint 'joint_2' is outside its
        range [-2.9, 2.9] rad (lower from URDF; upper from URDF)``; for a joint outside
        already, ``…; it is at 0 rad, outside its range: only positions in [0, 2.29] rad
        (toward or into its range) are allowed``.
    """
    joints = np.asarray(request.joints, dtype=int)
    start = np.asarray(start, dtype=float)
    rows = np.atleast_2d(np.asarray(request.positions, dtype=float))  # (points, named)
    lower, upper = _envelope(limits, joints, start)
    slack = POSITION_TOLERANCE
    outside = (rows < lower - slack * np.maximum(1.0, np.abs(lower))) | \
        (rows > upper + slack * np.maximum(1.0, np.abs(upper)))
    if not outside.any():
        return
    point, column = np.argwhere(outside)[0]  # the first point, then the first joint named
    index, value = int(joints[column]), float(rows[point, column])
    label = 'goal position' if isinstance(request, GoalRequest) else \
        f'via point {point} position'
    unit = limits.units[index]
    message = (f'{label} {value:.6g} {unit} for joint {limits.joints[index]!r} is outside '
               f'its range {_range(limits, index)}')
    if _outside(limits, index, float(start[index])) is not None:
        message += (f'; it is at {start[index]:.6g} {unit}, outside its range: only '
                    f'positions in [{lower[column]:.6g}, {upper[column]:.6g}] {unit} (toward '
                    'or into its range) are allowed')
    raise RequestError(message)


def check_plan(limits: JointLimits, plan: Trajectory, start: Sequence[float]) -> None:
    """
    Refuse a plan whose exact positions leave a joint's range widened to its ``start``.

    :param start: where the plan starts, rad or m, ``(joints,)``.
    :raises RequestError: e.g. ``the plan would take joint 'joint_2' to 2.95 rad, outside
        its range [-2.9, 2.9] rad (…): …``.
    """
    if not (np.isfinite(limits.position.lower).any()
            or np.isfinite(limits.position.upper).any()):
        return  # no position limit at all: nothing to find
    lowest, highest = position_extrema(plan)
    start = np.asarray(start, dtype=float)
    for index in range(len(limits.joints)):
        for value, bound in ((lowest[index], 'lower'), (highest[index], 'upper')):
            broken = _outside(limits, index, float(value))
            if broken != bound:
                continue
            slack = POSITION_TOLERANCE * max(1.0, abs(start[index]))
            if (bound == 'lower' and value >= start[index] - slack) or \
                    (bound == 'upper' and value <= start[index] + slack):
                continue  # a start outside the range may stay there or come back
            raise RequestError(
                f'the plan would take joint {limits.joints[index]!r} to {value:.6g} '
                f'{limits.units[index]}, outside its range {_range(limits, index)}: the '
                'motion overshoots between its points or must brake past the target; '
                'choose other points or times, or send it when the joint moves slower')
