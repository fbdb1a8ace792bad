"""Velocity commands (issue 28): v = v_ref + k_p (q_ref - q_measured), fresh, clipped, ramped."""

import math

import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message
from std_msgs.msg import Float64MultiArray
from traj_gen_ros.node.robot.commands_out import position_command, VelocityCommand
from traj_gen_ros.node.robot.measured_state import FRESH_AGE, MeasuredState
from traj_gen_ros.node.settings.config import (
    check_command_out_interface,
    check_position_gain,
    FLOAT64_MULTI_ARRAY,
    JOINT_TRAJECTORY,
)
from traj_gen_ros.node.settings.parameters import typed

JOINTS = ('a', 'b', 'c')
PERIOD = 0.01
V_MAX = np.array([1.0, 2.0, 3.0])
A_MAX = np.array([4.0, 4.0, 6.0])


def decoded(data: bytes) -> np.ndarray:
    return np.array(deserialize_message(data, Float64MultiArray).data)


class Measured:
    """What ``measured_position`` returns: the test sets it; counts the calls."""

    def __init__(self, position=None):
        self.position = None if position is None else np.array(position, dtype=float)
        self.calls = 0

    def __call__(self):
        self.calls += 1
        return self.position


def command(gain, measured, max_acceleration=A_MAX):
    return VelocityCommand(np.array(gain, dtype=float), lambda: V_MAX,
                           lambda: max_acceleration, lambda: PERIOD, measured)


def test_the_command_is_the_feed_forward_plus_the_gain_times_the_position_error():
    measured = Measured([0.10, -0.20, 0.30])
    velocity = command([2.0, 0.5, 0.0], measured, max_acceleration=np.full(3, 1e6))
    q_ref, v_ref = np.array([0.12, -0.25, 0.70]), np.array([0.3, -0.1, 0.2])
    out = decoded(velocity(q_ref, v_ref))
    expected = v_ref + np.array([2.0, 0.5, 0.0]) * (q_ref - measured.position)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-15)
    assert out[2] == 0.2  # k_p 0: the feed-forward alone, even far from the arm


def test_gain_zero_is_the_setpoint_velocity_exactly_and_reads_no_measured_state():
    measured = Measured([5.0, 5.0, 5.0])
    velocity = command(0.0 * V_MAX, measured)
    v_ref = np.array([0.3, -1.7, 2.9])
    assert decoded(velocity(np.zeros(3), v_ref)).tolist() == v_ref.tolist()
    assert measured.calls == 0


def test_the_command_is_clipped_to_max_velocity_per_joint():
    measured = Measured([0.0, 0.0, 0.0])
    velocity = command([10.0, 10.0, 10.0], measured, max_acceleration=np.full(3, 1e6))
    out = velocity.command(np.array([1.0, -1.0, 0.01]), np.array([0.9, -1.9, 2.5]))
    assert out.tolist() == [1.0, -2.0, 2.6]  # a, b at their limits; c within its 3.0
    out = velocity.command(np.zeros(3), np.array([1.5, -2.5, 3.5]))  # even feed-forward
    assert out.tolist() == [1.0, -2.0, 3.0]


def test_the_limits_in_force_are_read_every_tick():
    limits = [V_MAX]
    velocity = VelocityCommand(np.zeros(3), lambda: limits[0], lambda: A_MAX,
                               lambda: PERIOD, Measured())
    v_ref = np.array([0.9, 1.9, 2.9])
    assert velocity.command(np.zeros(3), v_ref).tolist() == v_ref.tolist()
    limits[0] = np.array([0.5, 0.5, 0.5])  # a URDF loaded, a parameter lowered
    assert velocity.command(np.zeros(3), v_ref).tolist() == [0.5, 0.5, 0.5]


def test_no_measured_state_no_correction():
    measured = Measured(None)  # stale, lost or not yet received: fresh_position is None
    velocity = command([3.0, 3.0, 3.0], measured)
    v_ref = np.array([0.1, 0.0, -0.1])
    assert velocity.command(np.ones(3), v_ref).tolist() == v_ref.tolist()
    assert measured.calls == 1


def test_the_correction_grows_by_at_most_max_acceleration_per_tick():
    # A measured state that becomes fresh with the arm 0.2 rad off: k_p * 0.2 = 0.8 rad/s
    # at once would be a jump; it ramps in at max_acceleration.
    measured = Measured([0.0, 0.0, 0.0])
    velocity = command([4.0, 4.0, 4.0], measured)
    q_ref = np.array([0.2, -0.2, 0.0])
    steps = [velocity.command(q_ref, np.zeros(3)) for _ in range(30)]
    first = steps[0]
    np.testing.assert_allclose(first, [0.04, -0.04, 0.0], rtol=1e-12)  # 4 rad/s^2 * 10 ms
    np.testing.assert_allclose(steps[9], [0.4, -0.4, 0.0], rtol=1e-12)
    assert steps[-1].tolist() == [0.8, -0.8, 0.0]  # reached: the formula holds again
    growth = np.diff(np.abs(np.array(steps)), axis=0)
    assert np.all(growth <= A_MAX * PERIOD * (1 + 1e-12))


def test_the_correction_falls_at_once_when_stale_lost_or_reseeded():
    measured = Measured([0.0, 0.0, 0.0])
    velocity = command([4.0, 4.0, 4.0], measured, max_acceleration=np.full(3, 1e6))
    q_ref = np.array([0.1, -0.1, 0.05])
    assert velocity.command(q_ref, np.zeros(3)).tolist() == pytest.approx([0.4, -0.4, 0.2])
    measured.position = None  # older than 0.1 s, or lost
    assert velocity.command(q_ref, np.zeros(3)).tolist() == [0.0, 0.0, 0.0]
    velocity = command([4.0, 4.0, 4.0], Measured([0.0, 0.0, 0.0]), A_MAX)
    for _ in range(50):
        velocity.command(q_ref, np.zeros(3))
    # Re-seeded where the arm is: the error is 0 and so is the command, in one tick.
    assert velocity.command(np.zeros(3), np.zeros(3)).tolist() == [0.0, 0.0, 0.0]


def test_a_correction_that_changes_sign_falls_to_zero_then_ramps():
    measured = Measured([0.0, 0.0, 0.0])
    velocity = command([4.0, 4.0, 4.0], measured)
    for _ in range(50):
        velocity.command(np.array([0.1, 0.0, 0.0]), np.zeros(3))
    assert velocity.correction[0] == pytest.approx(0.4)
    out = velocity.command(np.array([-0.1, 0.0, 0.0]), np.zeros(3))
    assert out[0] == pytest.approx(-0.04)  # through 0 at once, one step beyond


def test_zero_is_an_all_zero_command_and_forgets_the_correction():
    velocity = command([4.0, 4.0, 4.0], Measured([0.0, 0.0, 0.0]))
    velocity.command(np.ones(3), np.zeros(3))
    data = velocity.zero()
    assert decoded(data).tolist() == [0.0, 0.0, 0.0]
    assert not velocity.correction.any()


def test_position_command_carries_the_positions():
    data = position_command(np.array([0.1, -0.2]), np.array([5.0, 6.0]))
    assert decoded(data).tolist() == [0.1, -0.2]


def test_fresh_position_is_the_measured_one_for_a_tenth_of_a_second():
    measured = MeasuredState(JOINTS, '/robot/joint_states', 0.05, 0.5)
    assert measured.fresh_position(100.0) is None  # nothing received yet
    measured.read(['c', 'b', 'a'], np.array([3.0, 2.0, 1.0]), 100.0)
    assert FRESH_AGE == 0.1
    assert measured.fresh_position(100.0).tolist() == [1.0, 2.0, 3.0]
    assert measured.fresh_position(100.0 + FRESH_AGE).tolist() == [1.0, 2.0, 3.0]
    assert measured.fresh_position(100.0 + FRESH_AGE + 1e-6) is None  # stale
    measured.lost = True  # joint_topic_timeout passed
    assert measured.fresh_position(100.0) is None
    measured.read(['a', 'b', 'c'], np.array([1.5, 2.0, 3.0]), 101.0)  # back
    assert measured.fresh_position(101.05).tolist() == [1.5, 2.0, 3.0]


def test_command_out_interface_is_checked_with_command_out_type():
    assert check_command_out_interface('position', JOINT_TRAJECTORY) == 'position'
    assert check_command_out_interface('velocity', FLOAT64_MULTI_ARRAY) == 'velocity'
    with pytest.raises(ValueError, match=r"must be one of position, velocity; got 'effort'"):
        check_command_out_interface('effort', FLOAT64_MULTI_ARRAY)
    with pytest.raises(ValueError, match=r'velocity needs command_out_type '
                                         r'std_msgs/Float64MultiArray.*got trajectory_msgs'):
        check_command_out_interface('velocity', JOINT_TRAJECTORY)


@pytest.mark.parametrize('value,reason', [
    ([1.0, -0.5, 1.0], "position_gain must be finite and >= 0; joint 'b' has -0.5"),
    ([1.0, 1.0, math.inf], "position_gain must be finite and >= 0; joint 'c' has inf"),
    ([math.nan], "position_gain must be finite and >= 0; joint 'a' has nan"),
    ([1.0, 2.0], 'position_gain has 2 values but there are 3 joints'),
])
def test_position_gain_refusals_name_the_joint(value, reason):
    with pytest.raises(ValueError, match=reason.replace('(', r'\(')):
        check_position_gain(JOINTS, value)


def test_position_gain_is_per_joint():
    assert check_position_gain(JOINTS, [2.0]).tolist() == [2.0, 2.0, 2.0]
    assert check_position_gain(JOINTS, [0.0, 1.0, 2.0]).tolist() == [0.0, 1.0, 2.0]
    assert typed(Parameter('position_gain', value=3)).value == [3.0]  # a number: an array
