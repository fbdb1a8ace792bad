"""
Shared helpers for the core's tests: exact per-piece evaluation, peaks, strategies.

Everything here is computed independently of the core's own evaluator: pieces are read
from ``coefficients`` and ``breakpoints`` and evaluated with ``numpy.polynomial``.
"""

import math

import hypothesis.strategies as st
import numpy as np
import numpy.polynomial.polynomial as poly

TOLERANCE = 1e-9

positions = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)
durations = st.floats(0.1, 10.0, allow_nan=False, allow_infinity=False)
limits = st.floats(0.1, 10.0, allow_nan=False, allow_infinity=False)
velocities = st.floats(-5.0, 5.0, allow_nan=False, allow_infinity=False)
joint_counts = st.integers(1, 4)


@st.composite
def via_paths(draw, min_points=3, max_points=6, max_joints=3):
    """Draw ``(points (points, joints), durations (segments,))``."""
    count = draw(st.integers(min_points, max_points))
    joints = draw(st.integers(1, max_joints))
    flat = draw(st.lists(positions, min_size=count * joints, max_size=count * joints))
    times = draw(st.lists(durations, min_size=count - 1, max_size=count - 1))
    return np.array(flat).reshape(count, joints), np.array(times)


def piece_spans(trajectory):
    """Return piece start times and lengths, each ``(pieces, joints)``."""
    breakpoints = np.asarray(trajectory.breakpoints, dtype=float)
    if breakpoints.ndim == 1:
        breakpoints = np.repeat(breakpoints[:, None], trajectory.joint_count, axis=1)
    return breakpoints[:-1], np.diff(breakpoints, axis=0)


def piece_state(trajectory, piece, joint, local_time):
    """
    Position, velocity and acceleration of one piece at a local time, by numpy.

    ``trajectory`` is a Trajectory or its coefficients array ``(pieces, order, joints)``.
    """
    table = getattr(trajectory, 'coefficients', trajectory)
    coefficients = table[piece, :, joint]
    velocity = poly.polyder(coefficients)
    acceleration = poly.polyder(velocity)
    return (poly.polyval(local_time, coefficients), poly.polyval(local_time, velocity),
            poly.polyval(local_time, acceleration))


def boundary_jumps(trajectory):
    """
    Jumps of position, velocity and acceleration at every interior breakpoint.

    Each piece is evaluated at its own end and the next at its own start. Returns an
    array ``(3, pieces - 1, joints)`` of ``right - left``, plus a scale of the same shape
    for relative tolerances: the larger magnitude of the two sides, at least 1, and at
    least the sum of the magnitudes of the terms summed at the piece's end (what bounds
    the rounding of evaluating it: a 10 s quintic ending at rest sums terms of ~1e3 to 0).
    """
    _, lengths = piece_spans(trajectory)
    pieces, joints = trajectory.piece_count, trajectory.joint_count
    jumps = np.zeros((3, max(pieces - 1, 0), joints))
    scales = np.ones_like(jumps)
    for joint in range(joints):
        for piece in range(pieces - 1):
            left = piece_state(trajectory, piece, joint, lengths[piece, joint])
            right = piece_state(trajectory, piece + 1, joint, 0.0)
            terms = piece_state(np.abs(trajectory.coefficients), piece, joint,
                                lengths[piece, joint])
            for order in range(3):
                jumps[order, piece, joint] = right[order] - left[order]
                scales[order, piece, joint] = max(1.0, abs(left[order]), abs(right[order]),
                                                  terms[order])
    return jumps, scales


def assert_continuous(trajectory, orders=2, tolerance=TOLERANCE):
    """Assert position (and derivatives up to ``orders - 1``) continuous at every joint."""
    jumps, scales = boundary_jumps(trajectory)
    for order in range(orders):
        worst = np.abs(jumps[order]) / scales[order]
        assert np.all(worst <= tolerance), (
            f'derivative {order} jumps by {np.max(np.abs(jumps[order]), initial=0.0)}')


def reference_peaks(trajectory):
    """
    Largest ``|velocity|`` and ``|acceleration|`` per joint, from the roots of each piece.

    The extrema of a polynomial on an interval lie at its ends or where its derivative
    vanishes; the roots come from ``numpy.polynomial``, independent of ``peaks()``. Every
    root's real part, clipped into the piece, is a candidate (rounding may give a double
    root a small imaginary part). Every piece counts, however short: a blend of 1e-20 s
    still runs at its blend acceleration.
    """
    _, lengths = piece_spans(trajectory)
    result = np.zeros((2, trajectory.joint_count))
    for joint in range(trajectory.joint_count):
        for piece in range(trajectory.piece_count):
            length = lengths[piece, joint]
            velocity = poly.polyder(trajectory.coefficients[piece, :, joint])
            for order, series in enumerate((velocity, poly.polyder(velocity))):
                peak = _largest_magnitude(series, length)
                result[order, joint] = max(result[order, joint], peak)
    return result[0], result[1]


def _largest_magnitude(series, length):
    """
    Return max ``|p(t)|`` for ``t`` in ``[0, length]``, from the roots of ``p'``.

    In unit time ``s = t / length`` the coefficients are ``c_k length**k``; a negligible
    leading coefficient (a quintic that is really a cubic) is trimmed first, since a
    badly scaled companion matrix gives inaccurate small roots.
    """
    scaled = np.asarray(series, dtype=float) * length ** np.arange(len(series))
    size = np.max(np.abs(scaled), initial=0.0)
    while len(scaled) > 1 and abs(scaled[-1]) <= 1e-14 * size:
        scaled = scaled[:-1]
    candidates = [0.0, 1.0]
    if len(scaled) > 2:
        slope = poly.polyder(scaled)
        curvature = poly.polyder(slope)
        roots = np.clip(poly.polyroots(slope).real, 0.0, 1.0)
        for _ in range(3):  # polish each root by Newton's method on p'
            bend = poly.polyval(roots, curvature)
            safe = np.where(bend == 0.0, 1.0, bend)
            roots = np.clip(roots - np.where(bend == 0.0, 0.0,
                                             poly.polyval(roots, slope) / safe), 0.0, 1.0)
        candidates += list(roots)
    return float(np.max(np.abs(poly.polyval(np.array(candidates), scaled))))


def dense_state(trajectory, count=4001):
    """Sample the whole trajectory at ``count`` evenly spaced times."""
    return trajectory.sample(np.linspace(0.0, trajectory.duration, count))


def assert_within(trajectory, max_velocity, max_acceleration, tolerance=TOLERANCE):
    """Assert no joint exceeds its limits: by exact roots, and by dense sampling."""
    max_velocity = np.broadcast_to(max_velocity, (trajectory.joint_count,))
    max_acceleration = np.broadcast_to(max_acceleration, (trajectory.joint_count,))
    peak_velocity, peak_acceleration = reference_peaks(trajectory)
    assert np.all(peak_velocity <= max_velocity * (1.0 + tolerance)), (
        peak_velocity, max_velocity)
    assert np.all(peak_acceleration <= max_acceleration * (1.0 + tolerance)), (
        peak_acceleration, max_acceleration)
    _, velocity, acceleration = dense_state(trajectory)
    assert np.all(np.abs(velocity) <= max_velocity * (1.0 + tolerance))
    assert np.all(np.abs(acceleration) <= max_acceleration * (1.0 + tolerance))


def optimal_lspb_time(distance, max_velocity, max_acceleration):
    """Time-optimal rest-to-rest duration: trapezoid ``D/v + v/a``, or triangle ``2√(D/a)``."""
    if distance >= max_velocity**2 / max_acceleration:
        return distance / max_velocity + max_velocity / max_acceleration
    return 2.0 * math.sqrt(distance / max_acceleration)


def natural_scales(points, durations):
    """
    Return the scales of position, velocity and acceleration of a path: ``R / T**k``.

    ``R`` is the largest position magnitude (at least 1) and ``T`` the shortest
    duration. Sampling at a breakpoint ``t`` rounds the local time by ~1e-16 ``t``, which
    moves the acceleration of a short, steep segment by far more than 1e-9 absolute.
    """
    reach = max(1.0, float(np.max(np.abs(points))))
    shortest = float(np.min(durations))
    return reach, reach / shortest, reach / shortest**2


def assert_state(actual, expected, tolerance=TOLERANCE, scale=1.0):
    """Assert sampled rows equal ``expected`` to ``tolerance`` relative to max(scale, |x|)."""
    actual = np.asarray(actual, dtype=float)
    expected = np.broadcast_to(np.asarray(expected, dtype=float), actual.shape)
    scale = np.maximum(scale, np.abs(expected))
    assert np.all(np.abs(actual - expected) <= tolerance * scale), (actual, expected)
