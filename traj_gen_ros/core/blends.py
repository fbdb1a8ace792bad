"""
Linear segments with parabolic blends (LSPB), single segment and through via points.

Equation numbers are those of the lecture (Craig, *Introduction to Robotics*, 3rd ed.,
§7.3, "linear function with parabolic blends"): the single segment's blend time eq. (5)
and its feasibility condition eq. (6); for via points the interior formulas (1), the
first segment (2)-(3) and the last segment (4)-(5).

Every result is a piecewise parabola (blends) and line (linear parts) per joint.

Craig's via-point method rounds the corners: the path does not pass through interior via
points (it reaches them only in the limit of infinite acceleration), but keeps the total
duration exactly. That is the book's method, not an error.
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.core import validation
from traj_gen_ros.core.exact import second_order
from traj_gen_ros.core.kinematic_limits import JointError
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.core.validation import ArrayLike

_FEASIBILITY_TOLERANCE = 1e-12  # relative slack for rounding in the feasibility checks
_BISECTION_STEPS = 80


class BlendedTrajectory(Trajectory):
    """
    An LSPB trajectory: pieces alternate blend, line, blend, …, blend per joint.

    Craig's timing table is read off the pieces: ``blend_times`` (s, ``(points, joints)``),
    ``linear_velocities`` (rad/s, ``(segments, joints)``) and ``linear_durations``
    (s, ``(segments, joints)``).
    """

    @property
    def blend_times(self) -> np.ndarray:
        """Blend duration at every point (s), ``(points, joints)``."""
        return np.diff(self.breakpoints, axis=0)[0::2]

    @property
    def linear_durations(self) -> np.ndarray:
        """Duration of every linear part (s), ``(segments, joints)``."""
        return np.diff(self.breakpoints, axis=0)[1::2]

    @property
    def linear_velocities(self) -> np.ndarray:
        """Velocity of every linear part (rad/s), ``(segments, joints)``."""
        return self.coefficients[1::2, 1]


@validation.refuses_overflow('lspb')
def lspb(
    q0: ArrayLike,
    qf: ArrayLike,
    duration: float,
    acceleration: ArrayLike,
    v0: ArrayLike = 0.0,
) -> BlendedTrajectory:
    """
    One linear segment with two parabolic blends, ``q0`` → ``qf`` (rad) in ``duration`` (s).

    From rest, both blends last ``t_b`` of eq. (5),
    ``t_b = t/2 - sqrt(θ̈² t² - 4 θ̈ |θf - θ0|) / (2 θ̈)``, which needs eq. (6),
    ``θ̈ ≥ 4 |θf - θ0| / t²``: a lower ``acceleration`` (rad/s², magnitude, scalar or per
    joint) raises ``ValueError`` naming the joint and that minimum.

    ``v0`` (rad/s, an extension for replanning a moving joint) starts the first blend at
    that velocity; both blends then use ``acceleration`` and the cruise velocity is the
    closed-form root of :func:`traj_gen_ros.core.exact.second_order.cruise_velocity`. A duration
    too
    short for the move raises ``ValueError`` with the shortest one that works.
    """
    rows = validation.per_joint_rows(q0=q0, qf=qf, v0=v0)
    duration = validation.duration_of(duration)
    acceleration = validation.per_joint('acceleration', acceleration, rows.shape[1])
    with np.errstate(over='ignore', under='ignore', divide='ignore', invalid='ignore'):
        plan = single_segment(rows[0], rows[1], np.float64(duration), acceleration, rows[2])
    if not (np.isfinite(plan.breakpoints).all() and np.isfinite(plan.coefficients).all()):
        raise ValueError(f'lspb: the plan overflows with duration {duration:g} s and '
                         f'acceleration {acceleration.tolist()}: no finite plan; use values '
                         'within about 1e-100..1e100 of each other')
    return plan


def single_segment(
    start: np.ndarray,
    goal: np.ndarray,
    duration: float,
    acceleration: np.ndarray,
    start_velocity: np.ndarray,
) -> BlendedTrajectory:
    """
    Plan :func:`lspb` on validated ``(joints,)`` arrays: blend, line, blend.

    The first blend takes ``v0`` to the cruise velocity ``vc``, the last takes ``vc`` to
    rest; the line between them ends at ``goal - vc t_b/2``, so the goal is met exactly.
    """
    displacement = goal - start
    if np.count_nonzero(start_velocity):
        second_order.check_reachable(displacement, start_velocity, duration, acceleration)
        durations = np.full(start.size, duration)
        low, high = 0.5 * (start_velocity - acceleration * durations), \
            0.5 * (start_velocity + acceleration * durations)
        cruise = np.clip(second_order.cruise_velocity(displacement, start_velocity, durations,
                                                      acceleration), low, high)
        first_blend = np.abs(cruise - start_velocity) / acceleration
        last_blend = np.minimum(np.abs(cruise) / acceleration, duration - first_blend)
    else:
        first_blend = last_blend = _rest_start_blend_time(displacement, duration, acceleration)
        cruise = np.sign(displacement) * acceleration * first_blend
    first_acceleration = np.sign(cruise - start_velocity) * acceleration
    last_acceleration = -np.sign(cruise) * acceleration
    moves = (0.5 * (start_velocity + cruise) * first_blend, 0.5 * cruise * last_blend)
    return three_pieces(start, goal, duration, (first_blend, last_blend), moves, cruise,
                        start_velocity, (first_acceleration, last_acceleration))


def three_pieces(
    start: np.ndarray,
    goal: np.ndarray,
    duration: float | np.ndarray,
    blend_times: tuple[np.ndarray, np.ndarray],
    blend_moves: tuple[np.ndarray, np.ndarray],
    cruise: np.ndarray,
    start_velocity: np.ndarray | float,
    blend_accelerations: tuple[np.ndarray, np.ndarray],
) -> BlendedTrajectory:
    """
    Assemble blend, line, blend from their timing, all ``(joints,)`` arrays.

    ``duration`` (s) is the end of the last blend: one for all joints, or one per joint.

    The first blend takes ``start_velocity`` to ``cruise`` in ``blend_times[0]`` covering
    ``blend_moves[0]``; the last takes ``cruise`` to rest in ``blend_times[1]`` covering
    ``blend_moves[1]``; both at the signed ``blend_accelerations``. The line runs from
    ``start + blend_moves[0]`` to ``goal - blend_moves[1]``, so the goal is met exactly.
    """
    breakpoints = np.empty((4, start.size))
    breakpoints[0], breakpoints[1], breakpoints[3] = 0.0, blend_times[0], duration
    np.subtract(duration, blend_times[1], out=breakpoints[2])
    coefficients = np.zeros((3, 3, start.size))
    coefficients[0, 0], coefficients[0, 1], coefficients[1:, 1] = start, start_velocity, cruise
    coefficients[0, 2], coefficients[2, 2] = blend_accelerations
    coefficients[:, 2] *= 0.5
    np.add(start, blend_moves[0], out=coefficients[1, 0])
    np.subtract(goal, blend_moves[1], out=coefficients[2, 0])
    return BlendedTrajectory(breakpoints, coefficients)


@validation.refuses_overflow('lspb_via')
def lspb_via(
    points: ArrayLike,
    durations: ArrayLike,
    acceleration: ArrayLike,
    v0: ArrayLike = 0.0,
) -> BlendedTrajectory:
    """
    Craig's linear segments with parabolic blends through via points.

    :param points: positions (rad), ``(points,)`` or ``(points, joints)``.
    :param durations: time between consecutive points (s), one per segment (``t_djk``).
    :param acceleration: blend acceleration magnitude ``|θ̈|`` (rad/s²), scalar or per joint.
    :param v0: start velocity (rad/s); an extension of the first-segment formula (2) for
        replanning a moving joint. Zero gives Craig's formula exactly.

    First segment (2)-(3): ``t1 = t_d12 - sqrt(t_d12² - 2|θ2 - θ1|/|θ̈|)``,
    ``θ̇12 = (θ2 - θ1)/(t_d12 - t1/2)``; last segment (4)-(5) likewise; interior (1):
    ``θ̇jk = (θk - θj)/t_djk``, ``tk = |θ̇kl - θ̇jk|/|θ̈|``, ``t_jk = t_djk - tj/2 - tk/2``
    (a whole blend time at the first and last point). With two points the two end
    formulas contradict each other, so the single-segment eq. (5) is used instead.

    Raises ``ValueError`` naming the joint and point when a blend cannot fit (the first
    or last square root is negative, or two blends overlap), with the smallest
    acceleration that fits.

    """
    path = validation.path_points(points)
    durations = validation.segment_durations(durations, len(path) - 1)
    acceleration = validation.per_joint('acceleration', acceleration, path.shape[1])
    start_velocity = validation.per_joint_rows(v0=v0, like=path[0])[0]
    if len(path) == 2:
        return single_segment(path[0], path[1], durations[0], acceleration, start_velocity)
    timing = _via_timing(path, durations, acceleration, start_velocity)
    problem = _first_problem(timing, durations)
    if problem is not None:
        joint, reason = problem
        minimum = _smallest_fitting_acceleration(path, durations, acceleration, start_velocity)
        raise JointError(f'lspb_via: {{joint}}: {reason} with acceleration '
                         f'{acceleration[joint]:g}; the smallest acceleration that fits is '
                         f'{validation.round_up(minimum[joint], 4)}', joint)
    blend_times, velocities, _, _ = timing
    return _assemble(path, durations, blend_times, velocities, start_velocity, acceleration)


def _rest_start_blend_time(
    displacement: np.ndarray, duration: float, acceleration: np.ndarray
) -> np.ndarray:
    """
    Blend time ``t_b`` of eq. (5), after checking eq. (6) joint by joint.

    ``t_b = t/2 - sqrt(θ̈² t² - 4 θ̈ |Δθ|)/(2 θ̈)``, evaluated as the equal
    ``2 |Δθ| / (θ̈ (t + sqrt(t² - 4 |Δθ|/θ̈)))``, which does not cancel for tiny moves.
    """
    # room = 1 - 4|Δθ|/(θ̈ t²), formed without t² so that long durations do not overflow.
    room = 1.0 - 4.0 * np.abs(displacement) / acceleration / duration / duration
    too_low = room < -_FEASIBILITY_TOLERANCE
    if np.count_nonzero(too_low):
        joint = int(np.argmax(too_low))
        minimum = 4.0 * abs(displacement[joint]) / duration / duration
        raise JointError(
            f'lspb: {{joint}}: acceleration {acceleration[joint]:g} is too low to move '
            f'{displacement[joint]:g} in {duration:g} s; eq. (6) needs at least '
            f'{validation.round_up(minimum, 4)}', joint)
    # (T (1 + √room) would overflow for T near the largest float: divide by T first.)
    return np.abs(displacement) / acceleration / duration * (
        2.0 / (1.0 + np.sqrt(np.maximum(room, 0.0))))


def _via_timing(
    path: np.ndarray,
    durations: np.ndarray,
    acceleration: np.ndarray,
    start_velocity: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Craig's blend times ``(points, joints)``, linear velocities and durations.

    Returns also the two end discriminants ``(2, joints)``; a negative one means the first
    or last blend cannot reach its segment's line. Nothing is checked here.
    """
    h = durations[:, None]
    slopes = np.diff(path, axis=0) / h
    # First segment, eq. (2)-(3), from velocity v0: the excess over coasting at v0.
    excess = (path[1] - path[0]) - durations[0] * start_velocity
    first_disc = durations[0] ** 2 - 2.0 * np.abs(excess) / acceleration
    first_blend = _end_blend_time(durations[0], first_disc, excess, acceleration)
    first_velocity = start_velocity + np.sign(excess) * acceleration * first_blend
    # Last segment, eq. (4)-(5).
    last_step = path[-1] - path[-2]
    last_disc = durations[-1] ** 2 - 2.0 * np.abs(last_step) / acceleration
    last_blend = _end_blend_time(durations[-1], last_disc, last_step, acceleration)
    last_velocity = last_step / (durations[-1] - 0.5 * last_blend)
    velocities = slopes.copy()
    velocities[0] = first_velocity
    velocities[-1] = last_velocity
    # Interior blends, eq. (1).
    blend_times = np.empty_like(path)
    blend_times[0] = first_blend
    blend_times[-1] = last_blend
    blend_times[1:-1] = np.abs(np.diff(velocities, axis=0)) / acceleration
    weights_start = np.full(len(durations), 0.5)
    weights_end = np.full(len(durations), 0.5)
    weights_start[0] = weights_end[-1] = 1.0
    linear_durations = (
        h - weights_start[:, None] * blend_times[:-1] - weights_end[:, None] * blend_times[1:])
    return blend_times, velocities, linear_durations, np.stack([first_disc, last_disc])


def _end_blend_time(
    duration: float, discriminant: np.ndarray, step: np.ndarray, acceleration: np.ndarray
) -> np.ndarray:
    """
    Blend time at the first or last point, eq. (3) and (5): ``t_d - sqrt(t_d² - 2|Δθ|/θ̈)``.

    Evaluated as the equal ``(2|Δθ|/θ̈) / (t_d + sqrt(…))``, which does not cancel for tiny
    steps. Where the blend cannot fit (negative discriminant) it is ``t_d``, the formula's
    limit, so that the timing stays finite for the error report.
    """
    root = np.sqrt(np.maximum(discriminant, 0.0))
    return np.where(discriminant >= 0.0,
                    2.0 * np.abs(step) / (acceleration * (duration + root)), duration)


def _first_problem(
    timing: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], durations: np.ndarray
) -> tuple[int, str] | None:
    """Find the first joint whose blends do not fit, with a sentence saying where."""
    blend_times, _, linear_durations, discriminants = timing
    slack = _FEASIBILITY_TOLERANCE * durations[:, None]
    end_durations = np.array([[durations[0]], [durations[-1]]])
    bad_ends = discriminants < -_FEASIBILITY_TOLERANCE * end_durations**2
    bad_linear = linear_durations < -slack
    for joint in range(blend_times.shape[1]):
        if bad_ends[0, joint]:
            return joint, ("the blend at point 0 cannot reach the first segment's line within "
                           f'its {durations[0]:g} s')
        if bad_ends[1, joint]:
            last = len(blend_times) - 1
            return joint, (f"the blend at point {last} cannot leave the last segment's line "
                           f'within its {durations[-1]:g} s')
        overlapping = np.flatnonzero(bad_linear[:, joint])
        if overlapping.size:
            segment = int(overlapping[0])
            return joint, (f'the blends at points {segment} and {segment + 1} overlap (the '
                           f'linear part of segment {segment} would last '
                           f'{linear_durations[segment, joint]:.3g} s)')
    return None


def _fits(
    path: np.ndarray, durations: np.ndarray, acceleration: np.ndarray, start_velocity: np.ndarray
) -> np.ndarray:
    """Tell per joint whether all blends fit with this acceleration."""
    _, _, linear_durations, discriminants = _via_timing(
        path, durations, acceleration, start_velocity)
    return (linear_durations >= 0.0).all(axis=0) & (discriminants >= 0.0).all(axis=0)


def _smallest_fitting_acceleration(
    path: np.ndarray, durations: np.ndarray, acceleration: np.ndarray, start_velocity: np.ndarray
) -> np.ndarray:
    """
    Per joint, the smallest acceleration with which every blend fits (bisection).

    Blends shrink as the acceleration grows, so feasibility is monotonic in it.
    """
    high = acceleration.copy()
    for _ in range(200):
        fitting = _fits(path, durations, high, start_velocity)
        if fitting.all():
            break
        high = np.where(fitting, high, 2.0 * high)
    low = acceleration.copy()
    for _ in range(_BISECTION_STEPS):
        middle = 0.5 * (low + high)
        fitting = _fits(path, durations, middle, start_velocity)
        high = np.where(fitting, middle, high)
        low = np.where(fitting, low, middle)
    return high


def _assemble(
    path: np.ndarray,
    durations: np.ndarray,
    blend_times: np.ndarray,
    velocities: np.ndarray,
    start_velocity: np.ndarray,
    acceleration: np.ndarray,
) -> BlendedTrajectory:
    """
    Assemble pieces blend 0, line 0, blend 1, …, line n-2, blend n-1 (three points or more).

    Interior blends are centred on their via time; the first starts at 0 and the last
    ends at the total duration. Each line passes through its segment's far point at that
    point's time (the last one through its near point), which is how Craig defines the
    linear velocities.
    """
    via_times = np.concatenate(([0.0], np.cumsum(durations)))
    total = via_times[-1]
    segment_count = len(durations)
    blend_starts = via_times[:, None] - 0.5 * blend_times
    blend_starts[0] = 0.0
    blend_starts[-1] = total - blend_times[-1]
    linear_starts = blend_starts[:-1] + blend_times[:-1]
    # A point each line passes through: (time, position).
    anchor = np.arange(1, segment_count + 1)
    anchor[-1] = segment_count - 1
    anchor_times, anchor_positions = via_times[anchor][:, None], path[anchor]

    def on_line(segment: np.ndarray, times: np.ndarray) -> np.ndarray:
        return anchor_positions[segment] + velocities[segment] * (times - anchor_times[segment])

    segments = np.arange(segment_count)
    blend_positions = np.empty_like(path)
    blend_positions[0] = path[0]
    blend_positions[1:] = on_line(segments, blend_starts[1:])
    incoming = np.concatenate([start_velocity[None], velocities])
    linear_positions = (
        blend_positions[:-1] + 0.5 * (incoming[:-1] + velocities) * blend_times[:-1])
    outgoing = np.concatenate([velocities, np.zeros_like(path[:1])])
    blend_accelerations = np.sign(outgoing - incoming) * acceleration

    piece_count = 2 * len(path) - 1
    joint_count = path.shape[1]
    starts = np.empty((piece_count + 1, joint_count))
    coefficients = np.zeros((piece_count, 3, joint_count))
    starts[0:-1:2], starts[1:-1:2], starts[-1] = blend_starts, linear_starts, total
    coefficients[0::2, 0], coefficients[1::2, 0] = blend_positions, linear_positions
    coefficients[0::2, 1], coefficients[1::2, 1] = incoming, velocities
    coefficients[0::2, 2] = 0.5 * blend_accelerations
    return BlendedTrajectory(starts, coefficients)
