"""
ROS-free request handling for the generator node.

Everything the node does between "a message arrived" and "a plan to publish"
lives here, on plain Python/numpy values, so it can be tested without ROS:

* :func:`make_config` validates the node parameters (per-joint limits, profile, rate).
* :func:`parse_goal` and :func:`parse_via` turn message fields into checked requests
  (known joints, matching lengths, finite numbers, strictly increasing times).
* :func:`plan_goal`, :func:`plan_via` and :func:`plan_stop` plan from the current
  setpoint with the core solver and check every plan against the limits.
* :class:`Schedule` keeps the executing plan (and a delayed one, if any) on the node's
  clock in integer nanoseconds and answers "what is the setpoint at time t".

Units are SI (rad, rad/s, rad/s^2, s); arrays are ``(samples, joints)``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
import math
from typing import NamedTuple, Protocol

import numpy as np

PROFILES = ('cubic', 'quintic', 'lspb')
VIA_VELOCITIES = ('heuristic', 'continuous')
MIN_RATE_HZ = 1.0
MAX_RATE_HZ = 1000.0

#: A first via point at ``time_from_start`` 0 must match the setpoint this closely (rad).
START_TOLERANCE = 1e-6
#: Relative slack allowed on the limits when a plan is checked (sampling, rounding).
LIMIT_TOLERANCE = 1e-6
#: Auto-timed plans and the "minimum feasible duration" search never stretch further.
MAX_STRETCH = 1e4
#: Most via points one request may carry (planning time grows with the count).
MAX_VIA_POINTS = 1000
#: Longest plan (and largest ``time_from_start``) accepted, seconds.
MAX_DURATION = 3600.0
#: Most samples one plan may have on ``~/trajectory`` (duration x rate_hz + 2).
MAX_TRAJECTORY_POINTS = 200_000
#: Most samples :func:`limit_violation` takes to locate a violation.
MAX_CHECK_SAMPLES = 20_001


class RequestError(ValueError):
    """A request the generator refuses; ``str(error)`` says what is wrong and what is valid."""


class Plan(Protocol):
    """What the node needs from a plan: the core ``Trajectory`` and the plans below."""

    @property
    def duration(self) -> float:
        """Length of the plan in seconds."""

    @property
    def joint_count(self) -> int:
        """Return the number of joints."""

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities, accelerations at ``times``, each ``(len(times), joints)``."""


class State(NamedTuple):
    """A setpoint: position, velocity and acceleration per joint."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


@dataclass(frozen=True)
class Config:
    """Validated generator parameters; per-joint arrays have one entry per joint."""

    joints: tuple[str, ...]
    rate_hz: float
    profile: str
    via_velocities: str
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    lspb_acceleration: np.ndarray

    @property
    def profile_acceleration(self) -> np.ndarray:
        """Acceleration limit used for timing: the LSPB blend acceleration for ``lspb``."""
        return self.lspb_acceleration if self.profile == 'lspb' else self.max_acceleration


@dataclass(frozen=True)
class GoalRequest:
    """Move ``joints`` (indices into the joint set) to ``positions``."""

    joints: np.ndarray
    positions: np.ndarray


@dataclass(frozen=True)
class ViaRequest:
    """
    Pass ``joints`` through ``positions`` (points, len(joints)) at ``times``.

    ``times`` are seconds from the start of execution; ``auto_timed`` means they were all
    zero ("time it for me from the limits"). ``velocities``/``accelerations`` are given for
    every point or are ``None``.
    """

    joints: np.ndarray
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None
    accelerations: np.ndarray | None
    auto_timed: bool


@dataclass(frozen=True)
class PlannedMotion:
    """An accepted plan and the words the status message reports about it."""

    plan: Plan
    profile: str
    end: np.ndarray
    note: str = ''


# --------------------------------------------------------------------------- parameters


def per_joint(name: str, value: object, joint_count: int, allow_zero: bool = False) -> np.ndarray:
    """
    Broadcast a parameter given as one number or one number per joint; check it.

    Raises ``ValueError`` naming the parameter when the value is not a number or a list of
    ``joint_count`` numbers, or when a value is not finite and positive (or zero, if allowed).
    """
    if isinstance(value, bool) or isinstance(value, str):
        raise ValueError(f'{name} must be a number or a list of {joint_count} numbers, '
                         f'got {value!r}')
    try:
        array = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f'{name} must be a number or a list of {joint_count} numbers, '
                         f'got {value!r}') from None
    if array.size == 1:
        array = np.full(joint_count, array[0])
    elif array.size != joint_count:
        raise ValueError(f'{name} has {array.size} values but there are {joint_count} joints: '
                         f'give one value for all joints or one per joint')
    bound = 'non-negative' if allow_zero else 'positive'
    for index, item in enumerate(array):
        if not math.isfinite(item) or item < 0.0 or (item == 0.0 and not allow_zero):
            raise ValueError(f'{name}[{index}] = {float(item)!r}: every value must be finite '
                             f'and {bound}')
    return array


def check_joint_names(joints: Sequence[str]) -> tuple[str, ...]:
    """Check the ``joints`` parameter: non-empty, non-empty names, no duplicates."""
    names = tuple(joints)
    if not names:
        raise ValueError('joints is empty: list the joint names, e.g. [joint_1, joint_2]')
    for index, name in enumerate(names):
        if not name:
            raise ValueError(f'joints[{index}] is an empty name')
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise ValueError(f'joints lists {duplicates} more than once')
    return names


def initial_state(joints: Sequence[str], initial_positions: Sequence[float]) -> np.ndarray:
    """Check ``initial_positions`` (empty means zeros) and return one per joint."""
    values = list(initial_positions)
    if not values:
        return np.zeros(len(joints))
    if len(values) != len(joints):
        raise ValueError(f'initial_positions has {len(values)} values but joints has '
                         f'{len(joints)}: give one position per joint (or none for zeros)')
    array = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise ValueError(f'initial_positions[{bad[0]}] is {array[bad[0]]}: must be finite')
    return array


def make_config(joints: Sequence[str], rate_hz: float, profile: str, via_velocities: str,
                max_velocity: object, max_acceleration: object,
                lspb_acceleration: object) -> Config:
    """Validate the node parameters together; raise ``ValueError`` with the reason."""
    names = check_joint_names(joints)
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, (int, float)) \
            or not MIN_RATE_HZ <= rate_hz <= MAX_RATE_HZ:
        raise ValueError(f'rate_hz must be a number in [{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}] Hz, '
                         f'got {rate_hz!r}')
    if profile not in PROFILES:
        raise ValueError(f'profile must be one of {", ".join(PROFILES)}; got {profile!r}')
    if via_velocities not in VIA_VELOCITIES:
        raise ValueError(f'via_velocities must be one of {", ".join(VIA_VELOCITIES)}; '
                         f'got {via_velocities!r}')
    count = len(names)
    v_max = per_joint('max_velocity', max_velocity, count)
    a_max = per_joint('max_acceleration', max_acceleration, count)
    a_lspb = per_joint('lspb_acceleration', lspb_acceleration, count, allow_zero=True)
    too_high = np.flatnonzero(a_lspb > a_max)
    if too_high.size:
        index = too_high[0]
        raise ValueError(f'lspb_acceleration for {names[index]} is {a_lspb[index]:g} rad/s^2, '
                         f'above max_acceleration {a_max[index]:g}: use a value <= '
                         f'max_acceleration, or 0 to use max_acceleration')
    a_lspb = np.where(a_lspb == 0.0, a_max, a_lspb)
    return Config(names, float(rate_hz), profile, via_velocities, v_max, a_max, a_lspb)


# --------------------------------------------------------------------------- requests


def _joint_indices(joints: Sequence[str], names: Sequence[str], what: str) -> np.ndarray:
    if len(names) == 0:
        raise RequestError(f'{what} names no joint: give a subset of {list(joints)}')
    seen = set()
    indices = []
    for name in names:
        if name in seen:
            raise RequestError(f'{what} names joint {name!r} more than once')
        seen.add(name)
        if name not in joints:
            raise RequestError(f'{what} names unknown joint {name!r}; known joints: '
                               f'{list(joints)}')
        indices.append(joints.index(name))
    return np.asarray(indices, dtype=int)


def _finite_row(values: Sequence[float], names: Sequence[str], what: str) -> np.ndarray:
    row = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(row))
    if bad.size:
        index = bad[0]
        raise RequestError(f'{what} for joint {names[index]!r} is {row[index]}: '
                           f'every value must be finite')
    return row


def parse_goal(joints: Sequence[str], names: Sequence[str],
               positions: Sequence[float]) -> GoalRequest:
    """Check a goal (``JointState`` name/position fields) against the joint set."""
    joints = list(joints)
    indices = _joint_indices(joints, list(names), 'goal')
    if len(positions) != len(names):
        raise RequestError(f'goal has {len(names)} names but {len(positions)} positions: '
                           f'give exactly one position per name')
    return GoalRequest(indices, _finite_row(positions, list(names), 'goal position'))


def parse_via(joints: Sequence[str], names: Sequence[str],
              points: Sequence[tuple[Sequence[float], Sequence[float], Sequence[float], float]]
              ) -> ViaRequest:
    """
    Check via points given as ``(positions, velocities, accelerations, time_from_start)``.

    Velocities and accelerations are boundary conditions: each is given for every point
    (with one value per name) or for none, as ``joint_trajectory_controller`` requires.
    """
    joints = list(joints)
    names = list(names)
    indices = _joint_indices(joints, names, 'via_points')
    if len(points) == 0:
        raise RequestError('via_points has no points: give at least one point')
    if len(points) > MAX_VIA_POINTS:
        raise RequestError(f'via_points has {len(points)} points, above the limit of '
                           f'{MAX_VIA_POINTS}: split the path into several requests')
    count = len(names)
    positions, velocities, accelerations, times = [], [], [], []
    for number, (pos, vel, acc, time) in enumerate(points):
        where = f'point {number}'
        if len(pos) != count:
            raise RequestError(f'{where} has {len(pos)} positions but joint_names has '
                               f'{count}: give one position per joint name')
        for field, values, store in (('velocities', vel, velocities),
                                     ('accelerations', acc, accelerations)):
            if len(values) not in (0, count):
                raise RequestError(f'{where} has {len(values)} {field} but joint_names has '
                                   f'{count}: give one per joint name or leave it empty')
            if len(values):
                store.append(_finite_row(values, names, f'{where} {field[:-3]}y'))
        positions.append(_finite_row(pos, names, f'{where} position'))
        if not math.isfinite(time) or time < 0.0:
            raise RequestError(f'{where} has time_from_start {time} s: must be >= 0')
        if time > MAX_DURATION:
            raise RequestError(f'{where} has time_from_start {time:g} s, above the limit of '
                               f'{MAX_DURATION:g} s')
        times.append(time)
    for field, store in (('velocities', velocities), ('accelerations', accelerations)):
        if store and len(store) != len(points):
            raise RequestError(f'{field} are given for {len(store)} of {len(points)} points: '
                               f'give them for every point or for none')
    if accelerations and not velocities:
        raise RequestError('accelerations are given without velocities: give both or '
                           'velocities only')
    times_array = np.asarray(times, dtype=float)
    auto = bool(np.all(times_array == 0.0))
    if not auto:
        steps = np.diff(times_array)
        bad = np.flatnonzero(steps <= 0.0)
        if bad.size:
            index = bad[0] + 1
            raise RequestError(f'time_from_start must be strictly increasing: point {index} '
                               f'({times_array[index]:g} s) is not after point {index - 1} '
                               f'({times_array[index - 1]:g} s)')
    return ViaRequest(indices, times_array, np.asarray(positions),
                      np.asarray(velocities) if velocities else None,
                      np.asarray(accelerations) if accelerations else None, auto)


# --------------------------------------------------------------------------- plans


class Hold:
    """Stand still at ``position``: a plan of zero duration."""

    def __init__(self, position: Sequence[float]) -> None:
        """Hold at ``position`` (one value per joint)."""
        self.position = np.array(position, dtype=float)
        self.duration = 0.0
        self.joint_count = self.position.size

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return the hold position and zero velocity/acceleration at every time."""
        count = np.size(times)
        zeros = np.zeros((count, self.joint_count))
        return np.tile(self.position, (count, 1)), zeros, zeros.copy()


class Stop:
    """
    Brake every joint at its full ``max_acceleration`` until it rests, then hold.

    Each joint stops as early as its limit allows (no synchronisation); position and
    velocity are continuous, acceleration steps to ``-sign(v) * max_acceleration``.
    """

    def __init__(self, state: State, max_acceleration: np.ndarray) -> None:
        """Plan the stop from ``state`` with per-joint deceleration ``max_acceleration``."""
        self.q0 = np.array(state.position, dtype=float)
        self.v0 = np.array(state.velocity, dtype=float)
        self.deceleration = -np.sign(self.v0) * max_acceleration
        self.stop_times = np.abs(self.v0) / max_acceleration
        self.duration = float(self.stop_times.max(initial=0.0))
        self.joint_count = self.q0.size

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Sample the braking motion; past each joint's stop time it holds."""
        t = np.minimum(np.reshape(times, (-1, 1)), self.stop_times)
        t = np.maximum(t, 0.0)
        braking = np.reshape(times, (-1, 1)) < self.stop_times
        position = self.q0 + self.v0 * t + 0.5 * self.deceleration * t * t
        velocity = np.where(braking, self.v0 + self.deceleration * t, 0.0)
        acceleration = np.where(braking, self.deceleration, 0.0) * np.ones_like(t)
        return position, velocity, acceleration


def sample_grid(plan: Plan, rate_hz: float) -> np.ndarray:
    """Return ``0, 1/rate, 2/rate, ...`` up to the plan's end, ending exactly at its duration."""
    count = int(math.floor(plan.duration * rate_hz + 1e-9))
    times = np.arange(count + 1) / rate_hz
    if plan.duration - times[-1] > 1e-9:
        times = np.append(times, plan.duration)
    return times


def sample_grid_count(times: np.ndarray, rate_hz: float) -> int:
    """Return how many leading ``times`` are exactly the regular grid ``k / rate_hz``."""
    count = len(times)
    if count and times[-1] != (count - 1) / rate_hz:
        count -= 1
    return count


def sample_motion(motion: PlannedMotion, rate_hz: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sample a plan on :func:`sample_grid`; the last sample is exactly the end, at rest."""
    times = sample_grid(motion.plan, rate_hz)
    positions, velocities, accelerations = motion.plan.sample(times)
    positions[-1] = motion.end
    velocities[-1] = 0.0
    accelerations[-1] = 0.0
    return times, positions, velocities, accelerations


def split_nanoseconds(times: np.ndarray) -> tuple[list[int], list[int]]:
    """Split times in seconds into ``builtin_interfaces/Duration`` (sec, nanosec) lists."""
    nanoseconds = np.round(np.asarray(times) * 1e9).astype(np.int64)
    return (nanoseconds // 1_000_000_000).tolist(), (nanoseconds % 1_000_000_000).tolist()


def limit_violation(plan: Plan, config: Config, acceleration: np.ndarray | None = None
                    ) -> str | None:
    """
    Describe the first joint whose velocity/acceleration exceeds its limit, else None.

    Uses the exact polynomial peaks of core trajectories (``peaks()``) when available and
    dense sampling otherwise; a violation is located in time by sampling.
    """
    if plan.duration <= 0.0:
        return None
    a_limit = config.max_acceleration if acceleration is None else acceleration
    peaks = getattr(plan, 'peaks', None)
    if peaks is not None:
        peak_velocity, peak_acceleration = peaks()
        if np.all(peak_velocity <= config.max_velocity * (1.0 + LIMIT_TOLERANCE)) and \
                np.all(peak_acceleration <= a_limit * (1.0 + LIMIT_TOLERANCE)):
            return None
    count = min(max(2001, int(plan.duration * config.rate_hz * 8) + 1), MAX_CHECK_SAMPLES)
    times = np.linspace(0.0, plan.duration, count)
    _, velocity, accel = plan.sample(times)
    for what, values, limit, unit in (('velocity', velocity, config.max_velocity, 'rad/s'),
                                      ('acceleration', accel, a_limit, 'rad/s^2')):
        if not np.isfinite(values).all():
            return f'the plan has a non-finite {what}'
        excess = np.abs(values) - limit * (1.0 + LIMIT_TOLERANCE) - 1e-12
        if (excess > 0.0).any():
            row, joint = np.unravel_index(np.argmax(excess), excess.shape)
            return (f'joint {config.joints[joint]!r} would reach {what} '
                    f'{abs(values[row, joint]):.4g} {unit} at t={times[row]:.3f} s, above '
                    f'max_{what} {limit[joint]:.4g} {unit}')
    if peaks is not None:  # a peak between samples
        excess = np.concatenate([peak_velocity / config.max_velocity,
                                 peak_acceleration / a_limit])
        index = int(np.argmax(excess))
        what = 'velocity' if index < len(config.joints) else 'acceleration'
        joint = index % len(config.joints)
        return (f'joint {config.joints[joint]!r} would exceed max_{what} by '
                f'{(excess[index] - 1.0) * 100:.2g} %')
    return None


def _as_state(state: State) -> State:
    return State(*(np.asarray(part, dtype=float) for part in state))


def check_size(motion: PlannedMotion, config: Config) -> PlannedMotion:
    """
    Refuse a plan longer than ``MAX_DURATION`` or with too many ``~/trajectory`` samples.

    The bounds keep the published message and the time to build it finite; the reason
    names the limit. Returns ``motion`` unchanged when it fits.
    """
    duration = motion.plan.duration
    if not math.isfinite(duration) or duration > MAX_DURATION:
        raise RequestError(f'the plan would last {duration:.4g} s, above the limit of '
                           f'{MAX_DURATION:g} s: move a shorter distance or raise the limits')
    samples = int(duration * config.rate_hz) + 2
    if samples > MAX_TRAJECTORY_POINTS:
        raise RequestError(f'the plan would have {samples} samples on ~/trajectory '
                           f'({duration:.4g} s at {config.rate_hz:g} Hz), above the limit of '
                           f'{MAX_TRAJECTORY_POINTS}: lower rate_hz or split the motion')
    return motion


def plan_goal(config: Config, state: State, hold: np.ndarray,
              request: GoalRequest) -> PlannedMotion:
    """
    Plan the synchronised minimum-time move from ``state`` to the goal.

    Joints the goal does not name go to ``hold`` (the end of the motion being replaced).
    The plan is bounded by :func:`check_size`.
    """
    with np.errstate(all='ignore'):
        return check_size(_plan_goal(config, state, hold, request), config)


def _plan_goal(config: Config, state: State, hold: np.ndarray,
               request: GoalRequest) -> PlannedMotion:
    from traj_gen_ros.timing import min_time

    state = _as_state(state)
    target = np.array(hold, dtype=float)
    target[request.joints] = request.positions
    if _at_rest_at(state, target, config.profile):
        return PlannedMotion(Hold(target), config.profile, target, 'already there')
    velocity_0 = state.velocity
    acceleration_0 = state.acceleration if config.profile == 'quintic' else 0.0 * velocity_0
    try:
        plan = min_time(state.position, target, config.max_velocity,
                        config.profile_acceleration, profile=config.profile,
                        v0=velocity_0, a0=acceleration_0)
    except ValueError as error:
        moving = '' if not np.any(velocity_0) else (
            f' from the current motion (velocity {np.round(velocity_0, 4).tolist()} rad/s, '
            f'acceleration {np.round(acceleration_0, 4).tolist()} rad/s^2); resend it when '
            'the motion has slowed, or call ~/stop first')
        raise RequestError(f'cannot plan the goal with profile {config.profile}{moving}: '
                           f'{error}') from None
    violation = limit_violation(plan, config, config.profile_acceleration)
    if violation:
        raise RequestError(f'the minimum-time plan breaks a limit: {violation}')
    return PlannedMotion(plan, config.profile, target)


def _at_rest_at(state: State, target: np.ndarray, profile: str) -> bool:
    still = np.allclose(state.velocity, 0.0, atol=1e-12)
    if profile == 'quintic':
        still = still and np.allclose(state.acceleration, 0.0, atol=1e-12)
    return still and np.allclose(state.position, target, rtol=0.0, atol=1e-12)


def via_points(joints: Sequence[str], state: State, hold: np.ndarray, request: ViaRequest
               ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """
    Full-joint points starting at the current setpoint, and their times.

    Rule: the executed trajectory starts at the current setpoint. A first point at
    ``time_from_start`` 0 must equal the current position of the joints it names (within
    ``START_TOLERANCE``) and stands for the start; otherwise the current setpoint is
    prepended as point 0 at t=0. When all times are zero (auto-timing) a first point at the
    current position is dropped likewise. Joints not named stay at ``hold`` at every point
    (with zero velocity/acceleration there).
    Returns ``(points, times or None when auto-timed, velocities, accelerations)``.
    """
    state = _as_state(state)
    count = request.positions.shape[0]
    points = np.tile(np.asarray(hold, dtype=float), (count, 1))
    points[:, request.joints] = request.positions
    velocities = accelerations = None
    if request.velocities is not None:
        velocities = np.zeros_like(points)
        velocities[:, request.joints] = request.velocities
    if request.accelerations is not None:
        accelerations = np.zeros_like(points)
        accelerations[:, request.joints] = request.accelerations
    times = request.times.copy()
    first_is_start = False
    named = request.joints
    if request.auto_timed:
        first_is_start = np.allclose(points[0, named], state.position[named], rtol=0.0,
                                     atol=START_TOLERANCE)
    elif times[0] == 0.0:
        offset = np.zeros_like(state.position)
        offset[named] = np.abs(points[0, named] - state.position[named])
        joint = int(np.argmax(offset))
        if offset[joint] > START_TOLERANCE:
            raise RequestError(
                f'point 0 has time_from_start 0 but joint {joints[joint]!r} '
                f'is at {state.position[joint]:.6g} rad, not {points[0, joint]:.6g}: a point '
                f'at t=0 must equal the current position; give it a time > 0 or drop it')
        first_is_start = True
    if first_is_start:
        points, times = points[1:], times[1:]
        velocities = None if velocities is None else velocities[1:]
        accelerations = None if accelerations is None else accelerations[1:]
    points = np.vstack([state.position, points])
    times = np.concatenate([[0.0], times])
    if velocities is not None:
        velocities = np.vstack([state.velocity, velocities])
    if accelerations is not None:
        accelerations = np.vstack([state.acceleration, accelerations])
    return points, None if request.auto_timed else times, velocities, accelerations


def plan_via(config: Config, state: State, hold: np.ndarray,
             request: ViaRequest) -> PlannedMotion:
    """
    Plan through via points from ``state`` with the configured profile.

    Explicit times are kept; a plan that would break a limit is refused with the minimum
    feasible duration (all times scaled by one factor). Auto-timed requests take the
    per-segment durations from the limits, stretched uniformly if the start state needs it.
    The plan is bounded by :func:`check_size`.
    """
    with np.errstate(all='ignore'):
        return check_size(_plan_via(config, state, hold, request), config)


def _plan_via(config: Config, state: State, hold: np.ndarray,
              request: ViaRequest) -> PlannedMotion:
    from traj_gen_ros.timing import via_durations

    state = _as_state(state)
    points, times, velocities, accelerations = via_points(config.joints, state, hold,
                                                          request)
    profile = config.profile
    if profile == 'lspb' and (velocities is not None or accelerations is not None):
        raise RequestError('profile lspb takes the velocities at via points from the segment '
                           'slopes (Craig 7.3) and cannot honour given velocities/'
                           'accelerations: leave them empty or use profile cubic or quintic')
    if profile == 'cubic' and accelerations is not None:
        raise RequestError('profile cubic cannot honour accelerations at via points: leave '
                           'them empty or use profile quintic')
    # The request's own last point (a lone point at the start is dropped from ``points``).
    if request.velocities is not None and \
            not np.allclose(request.velocities[-1], 0.0, atol=1e-12):
        raise RequestError('the last point must have zero velocity: the generator holds '
                           'still at the end of every plan')
    if request.accelerations is not None and \
            not np.allclose(request.accelerations[-1], 0.0, atol=1e-12):
        raise RequestError('the last point must have zero acceleration: the generator holds '
                           'still at the end of every plan')
    if len(points) == 1:  # only the start is left: the named joints come to rest there,
        target = np.array(hold, dtype=float)  # the others keep the target they had
        target[request.joints] = request.positions[-1]
        return _plan_goal(config, state, target, GoalRequest(np.zeros(0, int), np.zeros(0)))
    build = _via_builder(config, state, points, velocities, accelerations)
    a_limit = config.profile_acceleration
    if times is None:
        try:
            durations = np.asarray(via_durations(points, config.max_velocity, a_limit,
                                                 profile), dtype=float)
        except ValueError as error:
            raise RequestError(f'cannot time the via points: {error}') from None
        durations = np.maximum(durations, 1.0 / config.rate_hz)
        plan, stretch = _fit(build, durations, config, a_limit, explicit=False)
        note = 'timed from the limits' + (f', stretched x{stretch:.3g}' if stretch > 1 else '')
        return PlannedMotion(plan, profile, points[-1], note)
    plan, _ = _fit(build, np.diff(times), config, a_limit, explicit=True)
    return PlannedMotion(plan, profile, points[-1])


def _via_builder(config: Config, state: State, points: np.ndarray,
                 velocities: np.ndarray | None,
                 accelerations: np.ndarray | None) -> Callable[[np.ndarray], Plan]:
    from traj_gen_ros.profiles import cubic_via, lspb_via, quintic_via

    rule = config.via_velocities if velocities is None else velocities
    if config.profile == 'cubic':
        return lambda durations: cubic_via(points, durations, velocities=rule,
                                           v0=state.velocity)
    if config.profile == 'quintic':
        return lambda durations: quintic_via(points, durations, velocities=rule,
                                             accelerations=accelerations,
                                             v0=state.velocity, a0=state.acceleration)
    return lambda durations: lspb_via(points, durations, config.lspb_acceleration,
                                      v0=state.velocity)


def _try(build: Callable[[np.ndarray], Plan], durations: np.ndarray, config: Config,
         a_limit: np.ndarray) -> tuple[Plan | None, str | None]:
    try:
        plan = build(durations)
    except ValueError as error:
        return None, str(error)
    return plan, limit_violation(plan, config, a_limit)


def _fit(build: Callable[[np.ndarray], Plan], durations: np.ndarray, config: Config,
         a_limit: np.ndarray, explicit: bool) -> tuple[Plan, float]:
    """Build with ``durations``; if a limit breaks, find the smallest uniform stretch."""
    plan, problem = _try(build, durations, config, a_limit)
    if problem is None:
        return plan, 1.0
    # Feasibility is not monotonic in the stretch when the start accelerates (a long plan
    # keeps a0 too long): scan in steps of 1.25 up to x16, then double, up to the ceiling.
    ceiling = min(MAX_STRETCH, MAX_DURATION / max(float(np.sum(durations)), 1e-300))
    low, high = 1.0, 1.25
    while _try(build, durations * high, config, a_limit)[1] is not None:
        low, high = high, high * (1.25 if high < 16.0 else 2.0)
        if high > ceiling:
            raise RequestError(f'{problem}; no uniform stretch of the times up to '
                               f'x{ceiling:.4g} (at most {MAX_DURATION:g} s in all) meets '
                               f'the limits')
    while high - low > 1e-4 * high:
        middle = 0.5 * (low + high)
        if _try(build, durations * middle, config, a_limit)[1] is None:
            high = middle
        else:
            low = middle
    if explicit:
        total = float(np.sum(durations))
        raise RequestError(f'{problem}; the requested {total:.4g} s is too short: the minimum '
                           f'feasible duration is {total * high:.4g} s (all time_from_start '
                           f'scaled by {high:.4g})')
    plan, _ = _try(build, durations * high, config, a_limit)
    return plan, high


def plan_request(config: Config, state: State, hold: np.ndarray,
                 request: GoalRequest | ViaRequest) -> PlannedMotion:
    """Plan a parsed goal or via-point request (the node's worker process runs this)."""
    if isinstance(request, GoalRequest):
        return plan_goal(config, state, hold, request)
    return plan_via(config, state, hold, request)


def worker_init() -> None:
    """
    Set up a planning worker process.

    Ctrl-C is for the node (which ends the worker); the worker runs at a lower priority
    (nice +10) than the node, so on a busy machine the stream is scheduled first.
    """
    import os
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if os.getpriority(os.PRIO_PROCESS, 0) < 10:
        os.nice(10 - os.getpriority(os.PRIO_PROCESS, 0))


def plan_stop(config: Config, state: State) -> PlannedMotion:
    """Brake from ``state`` to rest within ``max_acceleration``, then hold."""
    state = _as_state(state)
    plan = Stop(state, config.max_acceleration)
    return PlannedMotion(plan, 'stop', plan.sample(np.array([plan.duration]))[0][0])


# --------------------------------------------------------------------------- schedule


class Schedule:
    """
    The executing plan and any delayed one, on the node clock (integer nanoseconds).

    A plan spliced in at ``start_ns`` replaces everything from that time on; until then
    the previous plan keeps running, so a delayed request does not interrupt the motion.
    Once a plan's duration has passed, the setpoint is exactly its end, at rest.
    """

    def __init__(self, motion: PlannedMotion) -> None:
        """Start with ``motion`` (usually a :class:`Hold`) in effect since forever."""
        self._segments: list[tuple[int, PlannedMotion]] = [(-(2 ** 62), motion)]

    def _segment(self, time_ns: int) -> tuple[int, PlannedMotion]:
        for start, motion in reversed(self._segments):
            if start <= time_ns:
                return start, motion
        return self._segments[0]

    def state_at(self, time_ns: int) -> State:
        """Setpoint at ``time_ns``."""
        start, motion = self._segment(time_ns)
        elapsed = (time_ns - start) * 1e-9
        if elapsed >= motion.plan.duration:
            zeros = np.zeros_like(motion.end)
            return State(motion.end.copy(), zeros, zeros.copy())
        position, velocity, acceleration = motion.plan.sample(np.array([max(elapsed, 0.0)]))
        return State(position[0], velocity[0], acceleration[0])

    def end_position(self, before_ns: int) -> np.ndarray:
        """Where the schedule rests if nothing starting at or after ``before_ns`` runs."""
        kept = [segment for segment in self._segments if segment[0] < before_ns]
        return (kept or self._segments)[-1][1].end.copy()

    def splice(self, start_ns: int, motion: PlannedMotion, now_ns: int) -> None:
        """Run ``motion`` from ``start_ns``, dropping what would start at or after it."""
        kept = [segment for segment in self._segments if segment[0] < start_ns]
        current = [index for index, segment in enumerate(kept) if segment[0] <= now_ns]
        if current:
            kept = kept[current[-1]:]
        self._segments = kept + [(start_ns, motion)]

    @property
    def pending(self) -> int:
        """Return the number of plans kept (the running one and delayed ones)."""
        return len(self._segments)
