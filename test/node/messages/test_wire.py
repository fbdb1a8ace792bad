"""The CDR bytes: the writers match rclpy field by field; the readers take what rclpy wrote."""

from builtin_interfaces.msg import Duration
from geometry_msgs.msg import PoseStamped
from hypothesis import example, given, settings
from hypothesis import strategies as st
from nav_msgs.msg import Path
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.node.messages.wire import (
    joint_names_cdr,
    joint_state_cdr,
    joint_trajectory_cdr,
    path_cdr,
    peek_path_poses,
    peek_via_points,
    read_goal,
    read_joint_state,
)
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

names = st.text(alphabet='abcdefgh_', min_size=1, max_size=9)


def reference(stamp_ns, joint_names, time_ns, positions, velocities, accelerations, frame_id):
    """Build the message the slow way, with rclpy objects."""
    message = JointTrajectory(joint_names=joint_names, points=[
        JointTrajectoryPoint(positions=p.tolist(), velocities=v.tolist(),
                             accelerations=a.tolist(),
                             time_from_start=Duration(sec=int(t // 10**9),
                                                      nanosec=int(t % 10**9)))
        for p, v, a, t in zip(positions, velocities, accelerations, time_ns, strict=True)])
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    message.header.frame_id = frame_id
    return message


@settings(max_examples=150, deadline=None)
@given(joint_names=st.lists(names, min_size=1, max_size=7), frame_id=st.text('xyz', max_size=6),
       point_count=st.integers(0, 40), stamp_ns=st.integers(0, 2**31 * 10**9 - 1),
       seed=st.integers(0, 99))
def test_written_bytes_deserialise_to_the_same_message(joint_names, frame_id, point_count,
                                                       stamp_ns, seed):
    rng = np.random.default_rng(seed)
    shape = (point_count, len(joint_names))
    positions, velocities, accelerations = (rng.normal(size=shape) * 10.0 ** rng.integers(
        -300, 300, size=shape) for _ in range(3))
    time_ns = np.sort(rng.integers(0, 10**13, size=point_count))
    wire = joint_trajectory_cdr(stamp_ns, joint_names, time_ns, positions, velocities,
                                accelerations, frame_id)
    decoded = deserialize_message(wire, JointTrajectory)
    assert decoded == reference(stamp_ns, joint_names, time_ns, positions, velocities,
                                accelerations, frame_id)


def test_times_beyond_a_duration_message_are_refused():
    one = np.zeros((1, 1))
    with pytest.raises(ValueError, match='time_from_start'):
        joint_trajectory_cdr(0, ['a'], np.array([2**31 * 10**9]), one, one, one)


def test_a_thousand_points_carry_exact_values():
    time_ns = np.arange(1001) * 10_000_000
    positions = np.linspace(0.0, 1.0, 1001)[:, None] * np.arange(1, 7)
    decoded = deserialize_message(
        joint_trajectory_cdr(5, [f'j{i}' for i in range(6)], time_ns, positions,
                             -positions, 2 * positions), JointTrajectory)
    assert len(decoded.points) == 1001
    assert decoded.points[500].time_from_start == Duration(sec=5, nanosec=0)
    np.testing.assert_array_equal(decoded.points[1000].positions, positions[1000])
    np.testing.assert_array_equal(decoded.points[1000].velocities, -positions[1000])
    np.testing.assert_array_equal(decoded.points[1000].accelerations, 2 * positions[1000])
    assert len(decoded.points[0].effort) == 0


@settings(max_examples=150, deadline=None)
@given(joint_names=st.lists(names, max_size=9), stamp_ns=st.integers(0, 2**31 * 10**9 - 1),
       seed=st.integers(0, 99))
def test_joint_state_bytes_match_rclpy(joint_names, stamp_ns, seed):
    rng = np.random.default_rng(seed)
    position, velocity = rng.normal(size=(2, len(joint_names))) * 10.0 ** rng.integers(
        -300, 300, size=(2, len(joint_names)))
    wire = joint_state_cdr(stamp_ns, joint_names_cdr(joint_names), position, velocity)
    expected = JointState(name=joint_names, position=position.tolist(),
                          velocity=velocity.tolist())
    expected.header.stamp.sec, expected.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    assert deserialize_message(wire, JointState) == expected
    assert len(wire) == len(serialize_message(expected))  # same layout, padding included


def test_peek_via_points_reads_frame_id_and_count_off_the_wire():
    message = JointTrajectory(joint_names=['a', 'bb', 'ccc'],
                              points=[JointTrajectoryPoint(positions=[1.0])] * 7)
    message.header.frame_id = 'tag-17'
    data = serialize_message(message)
    assert peek_via_points(data) == ('tag-17', 7)
    assert peek_via_points(data[:12]) == ('', 0)  # truncated: deserialising refuses it


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=12), st.lists(st.text(max_size=9), max_size=7),
       st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=7),
       st.lists(st.floats(-10.0, 10.0), max_size=3), st.integers(0, 2 ** 31 - 1))
def test_read_goal_reads_what_rclpy_serialises(frame_id, names, positions, velocities, sec):
    message = JointState(name=names, position=positions, velocity=velocities)
    message.header.frame_id = frame_id
    message.header.stamp.sec = sec
    data = serialize_message(message)
    expected = deserialize_message(data, JointState)  # rclpy's own reading ('a\0b' is 'a')
    read_frame, read_names, read_positions = read_goal(data)
    assert (read_frame, read_names) == (expected.header.frame_id, list(expected.name))
    np.testing.assert_array_equal(read_positions, np.array(expected.position, dtype=float))
    assert read_positions.dtype == np.float64 and read_positions.flags.writeable
    *same, read_velocities = read_joint_state(data)  # the measured state's: and velocities
    assert same[:2] == [read_frame, read_names]
    np.testing.assert_array_equal(same[2], read_positions)
    np.testing.assert_array_equal(read_velocities, np.array(expected.velocity, dtype=float))


def test_read_goal_leaves_what_it_cannot_read_to_rclpy():
    message = JointState(name=['a', 'b'], position=[1.0, 2.0])
    data = serialize_message(message)
    assert read_goal(data[:-24]) is None  # cut inside the positions
    assert read_goal(data[:14]) is None  # cut inside a name
    moving = serialize_message(JointState(name=['a', 'b'], position=[1.0, 2.0],
                                          velocity=[3.0, 4.0]))
    assert read_joint_state(moving)[3].tolist() == [3.0, 4.0]
    assert read_joint_state(moving[:-16]) is None  # cut inside the velocities
    assert read_goal(b'\x00\x00' + data[2:]) is None  # big-endian CDR: rclpy reads it
    corrupt = bytearray(data)
    corrupt[20:22] = b'\xff\xfe'  # not UTF-8 inside the first name
    assert read_goal(bytes(corrupt)) is None


@pytest.mark.parametrize('frame_id', ['', 'panda_link0', 'ü' * 7])
@pytest.mark.parametrize('count', [0, 1, 3, 1001])
def test_peek_path_poses_reads_the_frame_and_the_pose_count(frame_id, count):
    message = Path()
    message.header.frame_id = frame_id
    message.header.stamp.sec = 12
    message.poses = [PoseStamped() for _ in range(count)]
    data = serialize_message(message)
    assert peek_path_poses(data) == (frame_id, count)
    assert peek_path_poses(data[:9]) == ('', 0)  # too short: deserialising refuses it


@settings(max_examples=150, deadline=None)
@example(frame_id='base\x00link', count=2, stamp_ns=1, seed=0)  # rclpy cuts a string at NUL
@given(frame_id=st.text(max_size=11), count=st.integers(0, 5),
       stamp_ns=st.integers(0, 2**31 * 10**9 - 1), seed=st.integers(0, 99))
def test_path_bytes_match_rclpy(frame_id, count, stamp_ns, seed):
    rng = np.random.default_rng(seed)
    positions = rng.normal(size=(count, 3)) * 10.0 ** rng.integers(-300, 300, size=(count, 3))
    quaternions = rng.normal(size=(count, 4))
    wire = path_cdr(stamp_ns, frame_id, positions, quaternions)
    expected = Path()
    expected.header.frame_id = frame_id
    expected.header.stamp.sec, expected.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    for position, quaternion in zip(positions, quaternions, strict=True):
        pose = PoseStamped(header=expected.header)
        point, orientation = pose.pose.position, pose.pose.orientation
        point.x, point.y, point.z = position.tolist()
        orientation.x, orientation.y, orientation.z, orientation.w = quaternion.tolist()
        expected.poses.append(pose)
    reference = serialize_message(expected)  # a frame_id with a NUL is cut there
    assert deserialize_message(wire, Path) == deserialize_message(reference, Path)
    assert len(wire) == len(reference)  # same layout, padding included
