"""
traj-gen line / arc (the nav_msgs/Path they send) and solve|plot line|arc (offline, a real arm).

The message is built from the parsed command line and checked against scipy's Rotation
(URDF roll, pitch, yaw: extrinsic x, y, z); usage errors are one line, exit 2, before
anything is sent. The offline plan runs on example-robot-data's Panda: its tool ends on the
goal (the core's forward kinematics of the last joint row), its timing within the limits.
"""

import json
import math

from cli_helpers import assert_one_line_error, ok, traj_gen
from example_robot_data import example_robot_data_urdfs
from kinematics_robots import ROBOTS
import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from traj_gen_ros.cli.main import build_parser
from traj_gen_ros.cli.tool_path_args import tool_path_parser
from traj_gen_ros.cli.tool_path_commands import bound_runs, plan_tool_path, tool_speeds
from traj_gen_ros.cli.tool_path_goal import path_message, plan_end
from traj_gen_ros.cli.tool_path_plot import draw_tool_path
from traj_gen_ros.cli.tool_path_poses import tool_pose
from traj_gen_ros.core.kinematics import Chain, chain_joints, pose_distance
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

#: The Panda's "ready" joints (rad): its tool panda_hand_tcp points down at about
#: (0.307, 0, 0.487) m in panda_link0.
READY = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
START = ','.join(f'{value:g}' for value in READY)
DOWN = '1,0,0,0'  # the tool's z down: a quaternion (x, y, z, w)

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


# ---------------------------------------------------------------- offline: solve, plot


@pytest.fixture(scope='module')
def panda(request) -> str:
    spec = ROBOTS['erd-panda']
    return str(example_robot_data_urdfs(request.config)[spec.name])


@pytest.fixture(scope='module')
def chain(panda) -> Chain:
    with open(panda, encoding='utf-8') as file:
        urdf = file.read()
    return Chain.from_urdf(urdf, chain_joints(urdf, None, None), None, None)


def solve(panda: str, shape: str, *words: str, start: str = START) -> dict:
    return json.loads(ok('solve', shape, '--urdf', panda, '--start', start, *words, '--json'))


def goal_matrix(position, quaternion=(1.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_quat(quaternion).as_matrix()
    matrix[:3, 3] = position
    return matrix


def plan_of(panda: str, *words: str, start: str = START):
    """Plan as the CLI plans, in this process: to check the samples of the plan."""
    argv = ['solve', *words[:1], '--urdf', panda, '--start', start, *words[1:]]
    return plan_tool_path(tool_path_parser(argv, type(build_parser()), 'traj-gen')
                          .parse_args(argv))


def tool_positions(chain: Chain, plan, times: np.ndarray) -> np.ndarray:
    return chain.forward(plan.timed.trajectory.sample(times)[0])[:, :3, 3]


def test_solve_line_ends_on_the_goal_and_keeps_the_tool_on_the_line(panda, chain):
    goal = [0.407, 0.1, 0.437]
    result = solve(panda, 'line', '--to', f'{goal[0]},{goal[1]},{goal[2]},{DOWN}')
    start = chain.forward(READY)
    assert result['start']['pose']['position'] == pytest.approx(start[:3, 3], abs=1e-9)
    end = np.array(result['end']['joints'])
    distance, angle = pose_distance(chain.forward(end), goal_matrix(goal))
    assert distance < 1e-4 and angle < 1e-3, (distance, angle)
    assert result['end']['position_error_mm'] == pytest.approx(distance * 1e3, abs=1e-5)
    rows = result['rows']
    assert rows[0]['t'] == 0.0 and rows[-1]['t'] == pytest.approx(result['duration'])
    assert rows[0]['positions'] == pytest.approx(READY, abs=1e-9)
    assert rows[-1]['positions'] == pytest.approx(end, abs=1e-9)
    assert rows[-1]['fraction'] == pytest.approx(1.0, abs=1e-9)
    # One line: length |goal - start| and the orientation's turn (start is 0.4 mrad off).
    turn = pose_distance(start, goal_matrix(goal))[1]
    assert result['length'] == pytest.approx(
        math.hypot(np.linalg.norm(np.subtract(goal, start[:3, 3])), turn), rel=1e-9)
    assert [piece['kind'] for piece in result['pieces']] == ['line']
    # Within every limit: the joints exactly (peaks), the tool at the rows.
    assert max(result['peaks']['joint_velocity']) <= 1.0 * (1 + 1e-9)
    assert max(result['peaks']['joint_acceleration']) <= 2.0 * (1 + 1e-9)
    assert max(row['tool_speed'] for row in rows) <= 0.25 * (1 + 1e-6)
    # The bounds cover the path, in order, and the text names the tool's speed limit.
    bounds = result['bounds']
    assert bounds[0]['start'] == 0.0 and bounds[-1]['end'] == pytest.approx(1.0)
    assert all(a['end'] == b['start'] for a, b in zip(bounds, bounds[1:], strict=False))
    assert 'max_linear_velocity' in result['bounded_by']


def test_the_tool_follows_the_line_at_the_speed_the_table_gives(panda, chain):
    """An oracle: the forward kinematics of the timed joints, differentiated numerically."""
    plan = plan_of(panda, 'line', '--to', f'0.407,0.1,0.437,{DOWN}')
    start, goal = chain.forward(READY)[:3, 3], np.array([0.407, 0.1, 0.437])
    times = np.linspace(0.0, plan.timed.duration, 401)
    points = tool_positions(chain, plan, times)
    direction = (goal - start) / np.linalg.norm(goal - start)
    off_line = np.linalg.norm(np.cross(points - start, direction), axis=1)
    assert off_line.max() < 1e-4, off_line.max()
    step = 1e-5
    inner = times[1:-1]
    differences = (tool_positions(chain, plan, inner + step)
                   - tool_positions(chain, plan, inner - step)) / (2 * step)
    _, speed, _ = tool_speeds(plan, inner)
    assert np.abs(np.linalg.norm(differences, axis=1) - speed).max() < 2e-3
    assert speed.max() == pytest.approx(0.25, abs=1e-6)  # the tool's limit bounds it


def test_a_corner_stops_the_tool_unless_it_is_blended(panda, chain):
    corner, goal = [0.407, 0.1, 0.487], [0.407, -0.1, 0.487]
    words = ['line', '--to', f'{",".join(map(str, corner))},{DOWN}',
             f'{",".join(map(str, goal))},{DOWN}']
    stop = plan_of(panda, *words)
    assert [piece.kind for piece in stop.path.pieces] == ['line', 'line']
    at_corner = float(np.interp(stop.path.waypoint_s[1], stop.timed.s, stop.timed.times))
    assert tool_speeds(stop, np.array([at_corner]))[1][0] == pytest.approx(0.0, abs=1e-9)
    reached = tool_positions(chain, stop, np.array([at_corner]))[0]
    assert np.linalg.norm(reached - corner) < 1e-4

    blended = plan_of(panda, *words, '--blend-radius', '0.05')
    assert [piece.kind for piece in blended.path.pieces] == ['line', 'blend', 'line']
    times = np.linspace(0.0, blended.timed.duration, 2001)
    points = tool_positions(chain, blended, times)
    # The blend is the circle tangent to both lines 0.05 m from the corner (corner_blend.py):
    # the lines turn by β = 135°, its radius is ρ = d / tan(β/2), and its midpoint is
    # ρ / sin((π - β)/2) - ρ from the corner. The tool passes there within 0.1 mm.
    beta = math.radians(135.0)
    rho = 0.05 / math.tan(beta / 2)
    closest = np.linalg.norm(points - corner, axis=1).min()
    assert closest == pytest.approx(rho / math.sin((math.pi - beta) / 2) - rho, abs=1.5e-4)
    assert blended.timed.duration < stop.timed.duration
    _, speed, _ = tool_speeds(blended, times)
    assert speed[(times > 0.2) & (times < blended.timed.duration - 0.2)].min() > 0.05


def test_solve_arc_stays_on_the_circle_through_the_three_points(panda, chain):
    interim, goal = np.array([0.407, 0.1, 0.487]), np.array([0.507, 0.0, 0.487])
    rpy = [180.0, 0.0, 45.0]
    ready_degrees = ','.join(f'{value:.12g}' for value in np.degrees(READY))
    result = solve(panda, 'arc', '--to', ','.join(map(str, interim)),
                   ','.join(map(str, [*goal, *rpy])), '--degrees', start=ready_degrees)
    assert result['start']['joints'] == pytest.approx(np.degrees(READY), abs=1e-9)
    assert [piece['kind'] for piece in result['pieces']] == ['arc']
    target = goal_matrix(goal, Rotation.from_euler('xyz', rpy, degrees=True).as_quat())
    end = np.radians(result['end']['joints'])  # --degrees: revolute joints in deg
    distance, angle = pose_distance(chain.forward(end), target)
    assert distance < 1e-4 and angle < 1e-3, (distance, angle)

    plan = plan_of(panda, 'arc', '--to', ','.join(map(str, interim)),
                   ','.join(map(str, [*goal, *rpy])), '--degrees', start=ready_degrees)
    assert plan.q_start == pytest.approx(READY, abs=1e-10)
    start = chain.forward(READY)[:3, 3]
    # The circumcentre of start, interim, goal (numpy, in their plane).
    a, b = interim - start, goal - start
    normal = np.cross(a, b)
    centre = start + ((a @ a) * np.cross(b, normal) + (b @ b) * np.cross(normal, a)) \
        / (2 * normal @ normal)
    radius = np.linalg.norm(start - centre)
    assert np.linalg.norm(goal - centre) == pytest.approx(radius, abs=1e-12)
    assert np.linalg.norm(interim - centre) == pytest.approx(radius, abs=1e-12)
    points = tool_positions(chain, plan, np.linspace(0.0, plan.timed.duration, 401))
    assert np.abs(np.linalg.norm(points - centre, axis=1) - radius).max() < 1e-4
    assert np.abs((points - centre) @ normal / np.linalg.norm(normal)).max() < 1e-4


def test_solve_text_prints_duration_bounds_and_rows(panda):
    text = ok('solve', 'line', '--urdf', panda, '--start', START, '--to',
              f'0.407,0.1,0.437,{DOWN}', '--rows', '3')
    lines = text.splitlines()
    assert lines[0].startswith('kinematic chain panda_link0 -> panda_hand_tcp: 7 joints')
    assert lines[1].startswith('line through 1 pose, blend radius 0 m: line; length ')
    assert lines[2] == ('limits: joints 1 rad/s, 2 rad/s²; tool 0.25 m/s, 1.2 m/s², '
                        '1.5708 rad/s')
    assert lines[3].startswith('duration ') and '; speed bounded by ' in lines[3]
    assert lines[4].split()[:4] == ['t', '(s)', 's', '(%)']
    first, middle, last = (line.split() for line in lines[6:9])
    assert first[:4] == ['0.0000', '0.00', '0.0000', '0.0000']
    assert [float(value) for value in first[4:]] == pytest.approx(READY, abs=1e-6)
    assert last[1] == '100.00' and last[2] == '0.0000'
    assert lines[-1].startswith('end: panda_hand_tcp 0.0000')


def test_plot_writes_a_png_with_the_joints_the_speed_and_the_path(panda, tmp_path):
    output = tmp_path / 'line.png'
    info = json.loads(ok('plot', 'line', '--urdf', panda, '--start', START, '--to',
                         f'0.407,0.1,0.487,{DOWN}', f'0.407,-0.1,0.487,{DOWN}',
                         '--blend-radius', '0.05', '-o', str(output), '--json',
                         '--size', '800x900'))
    data = output.read_bytes()
    assert data[:8] == b'\x89PNG\r\n\x1a\n'
    assert (int.from_bytes(data[16:20], 'big'), int.from_bytes(data[20:24], 'big')) == \
        (800, 900)
    assert (info['width'], info['height'], info['joints']) == (800, 900, 7)
    assert info['panels'][:4] == ['position [rad, m]', 'velocity [rad/s, m/s]',
                                  'acceleration [rad/s², m/s²]', 'tool speed [m/s]']


def test_the_figure_marks_the_poses_the_blend_and_the_bounding_limits(panda):
    plan = plan_of(panda, 'line', '--to', f'0.407,0.1,0.487,{DOWN}',
                   f'0.407,-0.1,0.487,{DOWN}', '--blend-radius', '0.05')
    figure = draw_tool_path(plan, (1000, 1100))
    try:
        position, _, _, speed, view, above = figure.axes
        assert view.name == '3d'
        assert [line.get_gid() for line in view.get_lines()][:3] == ['line', 'blend', 'line']
        corners = [line for line in position.get_lines() if line.get_gid() == 'corners']
        times = np.interp(plan.path.waypoint_s, plan.timed.s, plan.timed.times)
        assert len(corners) == 7 and list(corners[0].get_xdata()) == [times[1]]
        shaded = [patch.get_x() for patch in speed.patches]
        runs = bound_runs(plan)
        assert shaded == pytest.approx([run['start_time'] for run in runs])
        labels = [text.get_text() for text in figure.legends[0].get_texts()]
        assert {f'bounded by {run["limit"]}' for run in runs} <= set(labels)
        assert 'max_linear_velocity 0.25 m/s' in labels and 'path: blends' in labels
        tool, = [line for line in speed.get_lines() if line.get_gid() == 'tool speed']
        assert max(tool.get_ydata()) == pytest.approx(0.25, abs=1e-6)
    finally:
        plt.close(figure)


@pytest.mark.parametrize(('words', 'error'), [
    (['arc', '--to', '0.4,0,0.5', '0.5,0,0.4', '0.5,0.1,0.4'], 'traj-gen solve: error: arc '
     'takes exactly two poses, the interim point and the goal; got 3'),
    (['arc', '--to', '0.4,0.1,0.5', '0.5,0,0.4', '--blend-radius', '0.1'], 'traj-gen solve: '
     'error: --blend-radius is for line: an arc has no corners'),
    (['line', '--to', '0.4,0.1,0.5', '--max-velocity', '1,2'], 'traj-gen solve: error: '
     '--max-velocity: 2 limits for the 7 joints panda_joint1, panda_joint2, panda_joint3, '
     'panda_joint4, panda_joint5, panda_joint6, panda_joint7: give one for all or one per '
     'joint'),
    (['line', '--to', '0.4,0.1,0.5', '--max-linear-velocity', '0'], 'traj-gen solve: error: '
     "argument --max-linear-velocity: '0' must be a finite number > 0 (see traj-gen solve "
     '--help)'),
    (['line', '--to', '0.4,0.1,0.5', '--rows', '1'], 'traj-gen solve: error: --rows must be '
     'at least 2 (the start and the end), not 1'),
    (['line', '--to', '0.307,0,0.487,1,0,0,0', '0.307,0,0.487,1,0,0,0'], 'traj-gen solve: '
     'error: line: straight path: poses[1] repeats poses[0] (within 1e-06 m and 1e-06 rad), '
     'a segment of zero length; drop the repeated pose'),
])
def test_offline_usage_errors_are_one_line_exit_2(panda, words, error):
    result = traj_gen('solve', words[0], '--urdf', panda, '--start', START, *words[1:])
    assert assert_one_line_error(result) == error


def test_a_path_out_of_reach_is_refused_saying_where(panda, chain):
    result = traj_gen('plot', 'line', '--urdf', panda, '--start', START, '--to',
                      f'1.5,0,0.5,{DOWN}', '-o', 'never.png')
    line = assert_one_line_error(result)
    assert line.startswith('traj-gen plot: error: line: the tool path leaves the reach of '
                           'the arm at '), line
    # "... at F % of the tool path (s = S of L): ...": L the line's length, S = F·L.
    fraction = float(line.split(' at ')[1].split(' %')[0])
    s, length = (float(word) for word in line.split('(s = ')[1].split(')')[0].split(' of '))
    start = chain.forward(READY)
    goal = goal_matrix([1.5, 0.0, 0.5])
    assert length == pytest.approx(math.hypot(np.linalg.norm(goal[:3, 3] - start[:3, 3]),
                                              pose_distance(start, goal)[1]), abs=1e-5)
    assert fraction == pytest.approx(100 * s / length, abs=0.005)
    assert 0 < fraction < 100
    result = traj_gen('solve', 'line', '--urdf', panda, '--start', '0,0', '--to', '0.4,0,0.4')
    assert assert_one_line_error(result).startswith(
        'traj-gen solve: error: --start: 2 values for the 7 joints panda_joint1')
