"""
traj-gen line / arc (the nav_msgs/Path they send) and solve|plot line|arc (offline, a real arm).

The message is built from the parsed command line and checked against scipy's Rotation
(URDF roll, pitch, yaw: extrinsic x, y, z); usage errors are one line, exit 2, before
anything is sent. The offline plan runs on example-robot-data's Panda: its tool ends on the
goal (the core's forward kinematics of the last joint row), its timing within the limits.
"""

import math

from cli_helpers import assert_one_line_error, traj_gen
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from traj_gen_ros.cli.main import build_parser
from traj_gen_ros.cli.tool_path_goal import path_message, plan_end
from traj_gen_ros.cli.tool_path_poses import tool_pose

# ---------------------------------------------------------------- the message sent


def message_of(*words: str):
    return path_message(build_parser().parse_args(list(words)))


def quaternion_of(stamped) -> np.ndarray:
    orientation = stamped.pose.orientation
    return np.array([orientation.x, orientation.y, orientation.z, orientation.w])


def position_of(stamped) -> list:
    position = stamped.pose.position
    return [position.x, position.y, position.z]


def test_line_sends_every_pose_in_order_in_the_frame_given():
    message = message_of('line', '0.4,0.1,0.3', '0.4,-0.1,0.3,3.14159,0,0.5',
                         '-0.2,0.5,0.1,0.6,0,0,0.8', '--frame', 'panda_link0')
    assert message.header.frame_id == 'panda_link0'
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (0, 0)
    assert [position_of(pose) for pose in message.poses] == [
        [0.4, 0.1, 0.3], [0.4, -0.1, 0.3], [-0.2, 0.5, 0.1]]
    assert all(pose.header.frame_id == '' for pose in message.poses)  # the path's applies
    assert quaternion_of(message.poses[0]).tolist() == [0.0, 0.0, 0.0, 1.0]
    expected = Rotation.from_euler('xyz', [3.14159, 0, 0.5]).as_quat()
    assert abs(quaternion_of(message.poses[1]) @ expected) == pytest.approx(1.0, abs=1e-12)
    assert quaternion_of(message.poses[2]) == pytest.approx([0.6, 0, 0, 0.8], abs=1e-15)


def test_rpy_in_degrees_are_sent_as_the_quaternion_of_those_angles():
    message = message_of('line', '0.3,0,0.5,180,-30,45', '--degrees')
    expected = Rotation.from_euler('xyz', [180, -30, 45], degrees=True)
    got = Rotation.from_quat(quaternion_of(message.poses[0]))
    assert (got.inv() * expected).magnitude() < 1e-12
    assert np.linalg.norm(quaternion_of(message.poses[0])) == pytest.approx(1.0, abs=1e-15)
    assert message.header.frame_id == ''  # the node's base_frame


def test_a_quaternion_within_1e_3_of_norm_1_is_normalised_keeping_its_sign():
    message = message_of('arc', '0.1,0,0', '0,0.1,0,-0.6,0,0,-0.8008', '--frame', 'tool')
    norm = math.hypot(0.6, 0.8008)
    assert quaternion_of(message.poses[1]) == pytest.approx(
        [-0.6 / norm, 0.0, 0.0, -0.8008 / norm], abs=1e-15)
    assert len(message.poses) == 2 and message.header.frame_id == 'tool'


def test_negative_coordinates_are_values_not_options():
    message = message_of('line', '-0.4,-0.1,-0.3', '-1e-2,2,3')
    positions = [position_of(pose) for pose in message.poses]
    assert positions == [[-0.4, -0.1, -0.3], [-0.01, 2.0, 3.0]]


def test_tool_pose_of_three_six_and_seven_numbers():
    position, quaternion = tool_pose([1, 2, 3], False, 'p')
    assert position.tolist() == [1, 2, 3] and quaternion.tolist() == [0, 0, 0, 1]
    _, quaternion = tool_pose([0, 0, 0, 0, math.pi / 2, 0], False, 'p')
    assert quaternion == pytest.approx([0, math.sqrt(0.5), 0, math.sqrt(0.5)], abs=1e-15)
    _, quaternion = tool_pose([0, 0, 0, 0, 0, 0, 1.0005], False, 'p')
    assert quaternion.tolist() == [0, 0, 0, 1]


def test_plan_end_is_the_last_point_of_the_nodes_plan():
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    plan = JointTrajectory(joint_names=['a', 'b'], points=[
        JointTrajectoryPoint(positions=[0.0, 1.0]), JointTrajectoryPoint(positions=[0.5, -2.0])])
    assert plan_end(plan) == (['a', 'b'], [0.5, -2.0])


@pytest.mark.parametrize(('words', 'error'), [
    (['line', '0.4,0.1'], "traj-gen line: error: argument POSE: pose '0.4,0.1' has 2 "
     'numbers: give 3 (X,Y,Z, m), 6 (and roll, pitch, yaw) or 7 (and a quaternion x, y, z, '
     'w) (see traj-gen line --help)'),
    (['line', '0.4,x,0.3'], "traj-gen line: error: argument POSE: pose '0.4,x,0.3' is not "
     'numbers separated by commas: give X,Y,Z or X,Y,Z,R,P,Y or X,Y,Z,QX,QY,QZ,QW (see '
     'traj-gen line --help)'),
    (['line', '0.4,inf,0.3'], "traj-gen line: error: argument POSE: pose '0.4,inf,0.3': "
     'every number must be finite (see traj-gen line --help)'),
    (['arc', '0.4,0.1,0.3'], 'traj-gen arc: error: arc takes exactly two poses, the interim '
     'point and the goal; got 1'),
    (['arc', '0.4,0.1,0.3', '0,0,1', '1,0,0'], 'traj-gen arc: error: arc takes exactly two '
     'poses, the interim point and the goal; got 3'),
    (['line', '0.4,0.1,0.3', '0.3,0,0.5,0,0,0,0.5'], 'traj-gen line: error: pose 2: '
     'quaternion (x, y, z, w) [0.0, 0.0, 0.0, 0.5] has norm 0.5: a rotation needs norm 1 '
     '(within 0.001)'),
    (['line', '0.3,0,0.5,0,0,0,0'], 'traj-gen line: error: pose 1: quaternion (x, y, z, w) '
     '[0.0, 0.0, 0.0, 0.0] has norm 0: a rotation needs norm 1 (within 0.001)'),
    (['line', '0.3,0,0.5', '--timeout', '0'], 'traj-gen line: error: --timeout must be > 0 s'),
    (['line'], 'traj-gen line: error: the following arguments are required: POSE (see '
     'traj-gen line --help)'),
])
def test_usage_errors_are_one_line_and_exit_2_before_anything_is_sent(words, error):
    result = traj_gen(*words)
    assert assert_one_line_error(result) == error
    assert result.stdout == ''
