import math

import numpy as np
import pytest
from traj_gen_ros import (
    cubic,
    cubic_via,
    hold,
    lspb,
    lspb_via,
    min_time,
    quintic,
    quintic_via,
    via_durations,
)
from traj_gen_ros.core import validation

NAN, INF = float('nan'), float('inf')
PATH = [[0.0, 1.0], [1.0, 2.0], [2.0, 0.0]]


def refused(call, *fragments):
    """Assert ``call()`` raises ValueError whose message holds every fragment."""
    with pytest.raises(ValueError) as error:
        call()
    message = str(error.value)
    for fragment in fragments:
        assert fragment in message, f'{fragment!r} not in {message!r}'
    return message


# --- Shapes that disagree ----------------------------------------------------------------


@pytest.mark.parametrize(('call', 'fragments'), [
    (lambda: cubic([0.0, 1.0], [1.0, 2.0, 3.0], 1.0), ('q0', 'qf', '2', '3')),
    (lambda: quintic([0.0, 1.0], [1.0, 2.0], 1.0, a0=[1.0, 2.0, 3.0]), ('a0', '3')),
    (lambda: lspb([0.0, 1.0], [1.0, 2.0], 1.0, [8.0, 8.0, 8.0]),
     ('acceleration', '3', '2 joints')),
    (lambda: min_time([0.0, 1.0], [1.0, 2.0], 1.0, [1.0, 1.0, 1.0]),
     ('max_acceleration', '3', '2 joints')),
    (lambda: cubic_via(PATH, [1.0, 1.0, 1.0]), ('durations', '3', '2 segments')),
    (lambda: cubic_via(PATH, [1.0, 1.0], velocities=[0.0, 1.0]), ('velocities', '(2,)')),
    (lambda: quintic_via(PATH, [1.0, 1.0], accelerations=np.zeros((3, 3))),
     ('accelerations', '(3, 3)', '(3, 2)')),
    (lambda: lspb_via(PATH, [1.0, 1.0], 10.0, v0=[1.0, 2.0, 3.0]), ('v0', '3', '2')),
    (lambda: cubic_via([0.0], []), ('points', 'at least 2')),
    (lambda: cubic_via(np.zeros((2, 2, 2)), [1.0]), ('points', 'dimensions')),
    (lambda: cubic([[0.0, 1.0]], [1.0, 2.0], 1.0), ('q0', 'shape')),
])
def test_shapes_that_disagree_are_refused(call, fragments):
    refused(call, *fragments)


# --- Non-positive durations -----------------------------------------------------------


@pytest.mark.parametrize('duration', [0.0, -1.0])
def test_non_positive_duration_is_refused(duration):
    for call in (lambda: cubic(0.0, 1.0, duration), lambda: quintic(0.0, 1.0, duration),
                 lambda: lspb(0.0, 1.0, duration, 10.0)):
        refused(call, 'duration', '> 0')


@pytest.mark.parametrize('plan', [cubic_via, quintic_via,
                                  lambda p, d: lspb_via(p, d, 100.0)])
def test_non_positive_segment_duration_names_the_segment(plan):
    refused(lambda: plan([0.0, 1.0, 2.0, 3.0], [1.0, 1.0, 0.0]), 'durations', 'segment 2')
    refused(lambda: plan([0.0, 1.0, 2.0, 3.0], [1.0, -2.0, 1.0]), 'durations', 'segment 1')


# --- NaN and infinity -----------------------------------------------------------------


@pytest.mark.parametrize('bad', [NAN, INF, -INF])
def test_non_finite_per_joint_inputs_name_argument_and_joint(bad):
    refused(lambda: cubic([0.0, bad], [1.0, 2.0], 1.0), 'q0', 'finite', 'joint 1')
    refused(lambda: cubic([0.0, 1.0], [1.0, 2.0], 1.0, vf=[bad, 0.0]), 'vf', 'joint 0')
    refused(lambda: quintic(0.0, 1.0, 1.0, af=bad), 'af', 'finite')
    refused(lambda: lspb([0.0, 1.0], [1.0, 2.0], 1.0, 10.0, v0=[0.0, bad]), 'v0', 'joint 1')
    refused(lambda: min_time([0.0, 1.0], [bad, 2.0], 1.0, 1.0), 'qf', 'joint 0')
    refused(lambda: min_time([0.0, 1.0], [1.0, 2.0], [1.0, bad], 1.0),
            'max_velocity', 'joint 1')
    refused(lambda: hold([1.0, bad]), 'finite', 'joint 1')


@pytest.mark.parametrize('bad', [NAN, INF])
def test_non_finite_entry_of_numpy_array_inputs_names_argument_and_joint(bad):
    """All inputs numpy arrays of one shape (stacked in one step when finite)."""
    start, goal, limit = np.zeros(2), np.array([1.0, 2.0]), np.ones(2)
    refused(lambda: min_time(start, goal, limit, limit, 'quintic', v0=np.array([0.0, bad]),
                             a0=np.zeros(2)), 'v0', 'joint 1')
    refused(lambda: min_time(start, goal, np.array([bad, 1.0]), limit, 'cubic', v0=limit,
                             a0=start), 'max_velocity', 'joint 0')
    refused(lambda: min_time(start, goal, limit, limit, v0=np.zeros(3), a0=start),
            'v0', '3')
    plan = min_time(start, goal, limit, limit, 'quintic', v0=np.array([0.5, 0]),
                    a0=np.array([0, 1]))
    same = min_time(list(start), list(goal), 1.0, 1.0, 'quintic', v0=[0.5, 0.0], a0=[0.0, 1.0])
    assert plan.duration == same.duration


@pytest.mark.parametrize('bad', [NAN, INF])
def test_non_finite_duration_or_acceleration_is_refused(bad):
    refused(lambda: cubic(0.0, 1.0, bad), 'duration', 'finite')
    refused(lambda: lspb(0.0, 1.0, 1.0, bad), 'acceleration', 'finite')
    refused(lambda: lspb_via([0.0, 1.0, 2.0], [1.0, 1.0], bad), 'acceleration', 'finite')
    refused(lambda: min_time(0.0, 1.0, 1.0, bad), 'max_acceleration', 'finite')


@pytest.mark.parametrize('bad', [NAN, INF])
def test_non_finite_via_point_names_point_and_joint(bad):
    points = np.array(PATH)
    points[2, 1] = bad
    for plan in (cubic_via, quintic_via, lambda p, d: lspb_via(p, d, 100.0)):
        refused(lambda plan=plan: plan(points, [1.0, 1.0]), 'points', 'point 2', 'joint 1')
    refused(lambda: via_durations(points, 1.0, 1.0), 'points', 'point 2', 'joint 1')


def test_non_finite_point_velocities_are_refused():
    velocities = np.zeros((3, 2))
    velocities[1, 0] = NAN
    refused(lambda: cubic_via(PATH, [1.0, 1.0], velocities=velocities),
            'velocities', 'point 1', 'joint 0')


def test_non_finite_segment_duration_names_the_segment():
    refused(lambda: cubic_via([0.0, 1.0, 2.0], [1.0, NAN]), 'durations', 'segment 1')


def test_non_finite_point_acceleration_of_one_joint_names_the_point():
    message = refused(lambda: quintic_via([0.0, 1.0, 2.0], [1.0, 1.0],
                                          accelerations=[0.0, NAN, 1.0]),
                      'accelerations', 'point 1')
    assert 'joint 1' not in message


def test_sample_refuses_non_finite_times():
    refused(lambda: cubic(0.0, 1.0, 1.0).sample([0.5, NAN]), 'times', 'finite')


# --- Negative (and zero) limits --------------------------------------------------------


@pytest.mark.parametrize('bad', [0.0, -1.0])
def test_non_positive_limits_name_argument_and_joint(bad):
    refused(lambda: min_time([0.0, 1.0], [1.0, 2.0], [1.0, bad], 1.0), 'max_velocity',
            'joint 1', '> 0')
    refused(lambda: min_time([0.0, 1.0], [1.0, 2.0], 1.0, [bad, 1.0]), 'max_acceleration',
            'joint 0', '> 0')
    refused(lambda: min_time(0.0, 1.0, bad, 1.0), 'max_velocity', '> 0')
    refused(lambda: lspb([0.0, 1.0], [1.0, 2.0], 1.0, [8.0, bad]), 'acceleration',
            'joint 1', '> 0')
    refused(lambda: lspb_via(PATH, [1.0, 1.0], [bad, 100.0]), 'acceleration', 'joint 0')
    refused(lambda: via_durations(PATH, [1.0, bad], 1.0), 'max_velocity', 'joint 1')
    refused(lambda: via_durations(PATH, 1.0, bad), 'max_acceleration', '> 0')


def test_via_durations_refuses_a_negative_blend_acceleration():
    refused(lambda: via_durations(PATH, 1.0, 1.0, 'lspb', acceleration=-1.0),
            'acceleration', '> 0')


def test_via_durations_refuses_an_unknown_velocity_rule():
    refused(lambda: via_durations(PATH, 1.0, 1.0, 'cubic', velocities='bogus'),
            'velocities', 'bogus')


# --- Other refusals -------------------------------------------------------------------


def test_unknown_names_are_refused():
    refused(lambda: min_time(0.0, 1.0, 1.0, 1.0, 'septic'), 'profile', 'septic')
    refused(lambda: via_durations(PATH, 1.0, 1.0, 'septic'), 'profile', 'septic')
    refused(lambda: cubic_via(PATH, [1.0, 1.0], velocities='fast'), 'velocities', 'fast')


def test_non_numbers_are_refused():
    refused(lambda: cubic('a', 1.0, 1.0), 'q0', 'numbers')
    refused(lambda: cubic_via(['a', 'b'], [1.0]), 'points')


def test_via_durations_of_a_path_that_does_not_move():
    refused(lambda: via_durations([[1.0, 2.0]] * 3, 1.0, 1.0), 'nothing to move')


def test_valid_inputs_are_accepted_unchanged():
    # Integers, lists and numpy scalars are all numbers.
    trajectory = cubic(np.int64(0), [1, 2], np.float32(2.0))
    assert trajectory.joint_count == 2
    np.testing.assert_allclose(trajectory.sample(2.0)[0], [[1.0, 2.0]])


# ---------------------------------------------------------------- the one per-joint broadcaster


@pytest.mark.parametrize('value', [2.0, 2, [2.0], np.array([2.0]), np.float64(2.0)])
def test_per_joint_broadcasts_one_value_to_every_joint(value):
    assert validation.per_joint('max_velocity', value, 3).tolist() == [2.0, 2.0, 2.0]


def test_per_joint_keeps_one_value_per_joint():
    assert validation.per_joint('max_velocity', [1.0, 2.0, 3.0], 3).tolist() == [1.0, 2.0, 3.0]
    assert validation.per_joint('min_position', [-math.inf, 0.0], 2, 'any',
                                infinite=True).tolist() == [-math.inf, 0.0]
    assert validation.per_joint('lspb_acceleration', 0.0, 2, 'non-negative').tolist() == \
        [0.0, 0.0]


@pytest.mark.parametrize('value, sign, infinite, message', [
    ([1.0, 2.0], 'positive', False,
     '^max_velocity has 2 values but there are 3 joints: give one value for all joints or '
     'one per joint$'),
    ('fast', 'positive', False,
     "^max_velocity must be a number or one number per joint, got 'fast'$"),
    (True, 'positive', False, '^max_velocity must be a number or one number per joint'),
    ([[1.0, 2.0, 3.0]], 'positive', False, r'got shape \(1, 3\)$'),
    ([1.0, 0.0, 1.0], 'positive', False,
     r'^max_velocity must be finite and > 0; joint 1 has 0.0$'),
    ([1.0, 1.0, math.inf], 'positive', False,
     r'^max_velocity must be finite and > 0; joint 2 has inf$'),
    (-1.0, 'non-negative', False, r'^max_velocity must be finite and >= 0; joint 0 has -1.0$'),
    ([0.0, math.nan, 0.0], 'any', False, r'^max_velocity must be finite; joint 1 has nan$'),
    ([0.0, math.nan, 0.0], 'any', True,
     r'^max_velocity must be a number, not NaN \(\+-inf: no limit\); joint 1 has nan$'),
    (-math.inf, 'positive', True,
     r'^max_velocity must be > 0 \(inf: no limit\); joint 0 has -inf$'),
])
def test_per_joint_refusals_name_the_parameter_and_what_is_valid(value, sign, infinite, message):
    with pytest.raises(ValueError, match=message):
        validation.per_joint('max_velocity', value, 3, sign, infinite)


@pytest.mark.parametrize('value, digits, text', [
    (1.2345, 4, '1.235'), (1.7, 9, '1.7'), (1.23456789012, 9, '1.2345679'),
    (0.1 + 0.2, 4, '0.3'), (1.7976931348623157e308, 4, '1.798e+308'), (5e-324, 4, '4.941e-324'),
    (0.0, 4, '0'), (math.inf, 4, 'inf'),
])
def test_round_up_never_prints_a_smaller_number(value, digits, text):
    assert validation.round_up(value, digits) == text
    if math.isfinite(float(text)) and value > 0.0:
        assert float(text) >= value * (1.0 - 1e-15)  # a round number is not pushed up
