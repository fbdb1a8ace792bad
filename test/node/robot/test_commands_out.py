"""The command outputs: their CDR bytes, and a JTC reproducing each plan from its points."""

from hypothesis import given, settings
from hypothesis import strategies as st
from jtc_interpolation import hermite
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Float64MultiArray
from traj_gen_ros.node.messages.parsing import parse_goal, parse_via
from traj_gen_ros.node.messages.wire import float64_multi_array_cdr, joint_trajectory_cdr
from traj_gen_ros.node.planning.motion import held, State
from traj_gen_ros.node.planning.pipeline import plan_request, plan_stop
from traj_gen_ros.node.robot.commands_out import controller_points, HOLD_SPAN
from traj_gen_ros.node.settings.config import check_command_out_type, make_config
from trajectory_msgs.msg import JointTrajectory

JOINTS = ['a', 'b', 'c']


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), max_size=12))
def test_float64_multi_array_bytes_are_rclpys(values):
    data = float64_multi_array_cdr(np.array(values, dtype=float))
    reference = serialize_message(Float64MultiArray(data=values))
    assert len(data) == len(reference)  # the same layout (rclpy's padding is not zeroed)
    assert data[:16] == reference[:16] and data[20:] == reference[20:]
    message = deserialize_message(data, Float64MultiArray)
    assert list(message.data) == values and not message.layout.dim


@pytest.mark.parametrize('names', [['a'], ['ab', 'c'], ['abc', 'de', 'f'], ['j'] * 4])
def test_trajectory_without_accelerations_reads_back(names):
    positions = np.arange(3.0 * len(names)).reshape(3, len(names))
    data = joint_trajectory_cdr(7, names, np.array([0, 5, 10**9 + 3]), positions,
                                positions + 0.5, None, 'f')
    message = deserialize_message(data, JointTrajectory)
    assert [list(p.positions) for p in message.points] == positions.tolist()
    assert [list(p.velocities) for p in message.points] == (positions + 0.5).tolist()
    assert all(len(p.accelerations) == 0 and len(p.effort) == 0 for p in message.points)
    assert message.points[2].time_from_start.sec == 1
    assert message.points[2].time_from_start.nanosec == 3


def test_command_out_type_refusal_names_the_valid_ones():
    assert check_command_out_type('trajectory_msgs/JointTrajectory')
    with pytest.raises(ValueError, match='std_msgs/Float64MultiArray, '
                                         'trajectory_msgs/JointTrajectory'):
        check_command_out_type('std_msgs/Float64')


def motions():
    """Plans of every kind the node makes: goals and via points per profile, brakes."""
    moving = State(np.array([0.1, -0.2, 0.3]), np.array([0.8, -0.5, 0.0]),
                   np.array([0.5, 1.0, -1.0]))
    rest = State(np.zeros(3), np.zeros(3), np.zeros(3))
    via = parse_via(JOINTS, JOINTS, [([0.5, 0.2, -0.3], [], [], 0.0),
                                     ([1.0, -0.4, 0.2], [], [], 0.0),
                                     ([0.2, 0.1, 0.0], [], [], 0.0)])
    goal = parse_goal(JOINTS, ['c', 'a'], [0.7, -0.6])
    for profile in ('cubic', 'quintic', 'lspb', 'scurve'):
        config = make_config(JOINTS, 100.0, profile, 'heuristic', [1.0, 1.5, 2.0],
                             [2.0, 3.0, 4.0], 0.0, 20.0)
        for state in (rest, moving):
            for request in (goal, via):
                yield f'{profile} {type(request).__name__}', plan_request(
                    config, state, state.position, request)
        yield f'{profile} stop', plan_stop(config, moving)


@pytest.mark.parametrize('name,motion', list(motions()), ids=lambda x: x
                         if isinstance(x, str) else '')
def test_a_jtc_interpolating_the_points_is_the_plan(name, motion):
    times_ns, positions, velocities, accelerations = controller_points(motion)
    times = times_ns * 1e-9
    assert np.all(np.diff(times_ns) > 0) and times_ns[0] == 0
    start = motion.plan.sample(0.0)
    assert np.array_equal(positions[0], start[0][0])
    assert np.array_equal(velocities[0], start[1][0])
    assert not velocities[-1].any() and np.allclose(positions[-1], motion.end, atol=1e-12)
    assert len(times) < 100  # the pieces' ends, not one per tick
    dense = np.linspace(0.0, motion.plan.duration, 4001)
    expected = motion.plan.sample(dense)[0]
    error = np.abs(hermite(times, positions, velocities, accelerations, dense) - expected)
    assert error.max() < 1e-9, (name, error.max())


def test_quintic_and_scurve_plans_carry_accelerations():
    config = make_config(JOINTS, 100.0, 'quintic', 'heuristic', 1.0, 2.0, 0.0)
    rest = State(np.zeros(3), np.zeros(3), np.zeros(3))
    motion = plan_request(config, rest, rest.position, parse_goal(JOINTS, ['a'], [1.0]))
    assert controller_points(motion)[3] is not None


def test_a_hold_is_two_points_at_rest():
    times_ns, positions, velocities, accelerations = controller_points(held([1.0, 2.0]))
    assert times_ns.tolist() == [0, int(HOLD_SPAN * 1e9)]
    assert positions.tolist() == [[1.0, 2.0]] * 2
    assert not velocities.any() and not accelerations.any()
