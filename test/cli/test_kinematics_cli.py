"""
traj-gen fk / ik as a user runs them: real URDFs, checked against the core and an oracle.

fk's pose is checked against the core's Chain.forward and, independently, against the
numpy chain of the URDF's origins and axes (test/support/numpy_chain.py) and scipy's
Rotation; ik round trips (fk → ik → fk) within 0.01 mm and 0.1 mrad; refusals are one
line with exit code 2, as a plan the solver refuses.
"""

import json
import math
import subprocess
import sys

from cli_helpers import assert_one_line_error, env, ok, REPO, TIMEOUT, traj_gen
from example_robot_data import example_robot_data_urdfs
from kinematics_robots import FLOATING_ARM, ROBOTS
import numpy as np
from numpy_chain import NumpyChain
from pybullet_urdfs import pybullet_urdfs
import pytest
from scipy.spatial.transform import Rotation
from traj_gen_ros.cli.kinematics import pose_from_args, rotation_rpy, rpy_quaternion
from traj_gen_ros.cli.main import build_parser, main
from traj_gen_ros.core.kinematics import Chain, pose_distance, pose_matrix

#: One revolute joint about z (±0.5 rad) and a prismatic one along the arm (0 … 0.3 m).
SWING = """<robot name="swing">
  <link name="base"/><link name="arm"/><link name="tip"/>
  <joint name="swing" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/>
  </joint>
  <joint name="reach" type="prismatic">
    <parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" effort="1" velocity="1"/>
  </joint>
</robot>
"""


def urdf_path(config, key: str):
    spec = ROBOTS[key]
    paths = pybullet_urdfs(config) if spec.source == 'pybullet' else \
        example_robot_data_urdfs(config)
    return paths[spec.name]


def within_limits(chain: Chain, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    low = np.where(np.isfinite(chain.lower), chain.lower, -math.pi)
    high = np.where(np.isfinite(chain.upper), chain.upper, math.pi)
    return rng.uniform(low, high)


def fk_json(*args: str) -> dict:
    return json.loads(ok('fk', *args, '--json'))


def ik_json(*args: str) -> dict:
    return json.loads(ok('ik', *args, '--json'))


def numbers(words: list) -> list:
    return [f'{value:.12g}' for value in words]


@pytest.fixture
def swing(tmp_path):
    path = tmp_path / 'swing.urdf'
    path.write_text(SWING)
    return str(path)


# ---------------------------------------------------------------- fk


@pytest.mark.parametrize('key', sorted(ROBOTS))
def test_fk_of_a_real_arm_is_the_cores_and_the_numpy_chains_pose(pytestconfig, key):
    spec = ROBOTS[key]
    path = urdf_path(pytestconfig, key)
    text = path.read_text()
    chain = Chain.from_urdf(text, spec.joints)
    q = within_limits(chain, seed=len(key))
    result = fk_json('--urdf', str(path), *numbers(q))
    # The default chain: the arm's joints in order, the node's default tool.
    assert result['joint_names'] == list(spec.joints)
    assert result['tool_frame'] == spec.default_tool
    assert result['base_frame'] == chain.base_frame
    pose = np.array(result['pose']['matrix'])
    assert pose == pytest.approx(chain.forward(q), abs=1e-11)
    oracle = NumpyChain(text).pose(spec.default_tool, dict(zip(spec.joints, q, strict=True)))
    assert pose == pytest.approx(oracle, abs=1e-9)
    assert result['pose']['position'] == pytest.approx(oracle[:3, 3], abs=1e-9)
    # Quaternion and roll/pitch/yaw of the same rotation, by scipy.
    rotation = Rotation.from_matrix(oracle[:3, :3])
    quaternion = np.array(result['pose']['quaternion'])
    assert quaternion[3] >= 0
    assert abs(quaternion @ rotation.as_quat()) == pytest.approx(1.0, abs=1e-9)
    assert Rotation.from_euler('xyz', result['pose']['rpy']).as_matrix() == pytest.approx(
        oracle[:3, :3], abs=1e-9)
    assert [row['value'] for row in result['joints']] == pytest.approx(q, abs=1e-11)
    assert all(row['within_limits'] and row['unit'] == 'rad' for row in result['joints'])


def test_fk_text_lists_the_chain_the_joints_and_the_pose(pytestconfig):
    path = urdf_path(pytestconfig, 'erd-panda')
    ready = [0, -0.785, 0, -2.356, 0, 1.571, 0.785]
    text = ok('fk', '--urdf', str(path), *numbers(ready), '--matrix')
    lines = text.splitlines()
    assert lines[0].startswith('kinematic chain panda_link0 -> panda_hand_tcp: 7 joints '
                               'panda_joint1, panda_joint2')
    assert lines[1].split() == ['joint', 'value', 'unit', 'lower', 'upper', 'within', 'limits']
    assert lines[5].split() == ['panda_joint4', '-2.356000', 'rad', '-3.071800', '-0.069800',
                                'yes']
    chain = Chain.from_urdf(path.read_text(), ROBOTS['erd-panda'].joints)
    pose = chain.forward(ready)
    assert lines[9] == 'pose of panda_hand_tcp in panda_link0:'
    rows = {line[:19].strip(): line[19:].split() for line in lines[10:]}
    assert [float(v) for v in rows['position (m)']] == pytest.approx(pose[:3, 3], abs=6e-7)
    assert [float(v) for v in rows['rpy (rad)']] == pytest.approx(
        Rotation.from_matrix(pose[:3, :3]).as_euler('xyz'), abs=1e-6)
    assert [float(v) for v in rows['rotation']] == pytest.approx(pose[0, :3], abs=1e-6)
    assert '-0.000000' not in text


def test_fk_in_degrees_and_by_name_on_a_written_arm(swing):
    # swing 20°, reach 0.1 m (metres, --degrees or not): the tip 0.6 m out at 20°.
    result = fk_json('--urdf', swing, 'swing=20', 'reach=0.1', '--degrees')
    angle = math.radians(20)
    assert result['pose']['position'] == pytest.approx(
        [0.6 * math.cos(angle), 0.6 * math.sin(angle), 0.0], abs=1e-12)
    assert result['pose']['rpy'] == pytest.approx([0.0, 0.0, 20.0], abs=1e-9)  # degrees
    assert result['units'] == {'angle': 'deg', 'length': 'm'}
    assert [(row['name'], row['unit'], row['value'], row['lower'], row['upper'])
            for row in result['joints']] == [
        ('swing', 'deg', pytest.approx(20.0), pytest.approx(math.degrees(-0.5)),
         pytest.approx(math.degrees(0.5))), ('reach', 'm', 0.1, 0.0, 0.3)]
    # A joint not named stands at 0; out of its limits is computed and flagged.
    result = fk_json('--urdf', swing, 'reach=0.4')
    assert result['pose']['position'] == pytest.approx([0.9, 0.0, 0.0])
    assert [row['within_limits'] for row in result['joints']] == [True, False]
    assert ' NO' in ok('fk', '--urdf', swing, '0,0.4')  # commas as --points


def test_fk_of_a_floating_base_mimic_continuous_and_prismatic_chain(tmp_path):
    path = tmp_path / 'floating.urdf'
    path.write_text(FLOATING_ARM)
    q = [0.7, -2.9, 0.15]
    result = fk_json('--urdf', str(path), '--tool', 'tool', *numbers(q))
    assert result['joint_names'] == ['j1', 'j2', 'j3']  # j4 mimics j1; 'float' is no joint
    oracle = NumpyChain(FLOATING_ARM).pose('tool', dict(zip(('j1', 'j2', 'j3'), q,
                                                            strict=True)))
    assert np.array(result['pose']['matrix']) == pytest.approx(oracle, abs=1e-9)
    continuous = result['joints'][1]
    assert continuous['lower'] is None and continuous['upper'] is None
    # Another base: the tool in l1's frame. j1 is below it only as j4's leader: last.
    values = dict(zip(('j1', 'j2', 'j3'), q, strict=True))
    result = fk_json('--urdf', str(path), '--base', 'l1', '--tool', 'tool',
                     *(f'{name}={value}' for name, value in values.items()))
    assert result['joint_names'] == ['j2', 'j3', 'j1']
    assert np.array(result['pose']['matrix']) == pytest.approx(
        NumpyChain(FLOATING_ARM).pose('tool', values, 'l1'), abs=1e-9)


# ---------------------------------------------------------------- ik


@pytest.mark.parametrize('key', ['pybullet-iiwa', 'erd-ur10', 'pybullet-xarm6'])
def test_ik_round_trip_from_a_pose_fk_gives(pytestconfig, key):
    spec = ROBOTS[key]
    path = str(urdf_path(pytestconfig, key))
    chain = Chain.from_urdf(urdf_path(pytestconfig, key).read_text(), spec.joints)
    q = within_limits(chain, seed=7)
    pose = fk_json('--urdf', path, *numbers(q))['pose']
    target = pose_matrix(pose['position'], pose['quaternion'])
    seed = q + 0.2  # near the solution: from the seed, nearest it
    result = ik_json('--urdf', path, *numbers(pose['position']), '--quat',
                     *numbers(pose['quaternion']), '--seed', ','.join(numbers(seed)))
    solved = np.array([row['value'] for row in result['joints']])
    assert [row['seed'] for row in result['joints']] == pytest.approx(seed)
    assert all(row['within_limits'] for row in result['joints'])
    assert np.all((chain.lower <= solved) & (solved <= chain.upper))
    distance, angle = pose_distance(target, chain.forward(solved))
    assert distance <= 1e-5 and angle <= 1e-4
    assert result['position_error_mm'] == pytest.approx(distance * 1e3, abs=1e-6)
    assert result['orientation_error_mrad'] == pytest.approx(angle * 1e3, abs=1e-6)
    assert result['start'] == 'seed' and result['iterations'] >= 1
    # fk of ik's answer: the pose asked for.
    again = fk_json('--urdf', path, *numbers(solved))['pose']
    distance, angle = pose_distance(target, pose_matrix(again['position'],
                                                        again['quaternion']))
    assert distance <= 1e-5 and angle <= 1e-4


def test_ik_from_roll_pitch_yaw_in_degrees_and_its_text(pytestconfig):
    path = urdf_path(pytestconfig, 'erd-panda')
    chain = Chain.from_urdf(path.read_text(), ROBOTS['erd-panda'].joints)
    text = ok('ik', '--urdf', str(path), '0.4', '0.1', '0.3', '--rpy', '180', '0', '45',
              '--degrees', '--seed', '0,-45,0,-135,0,90,45')
    lines = text.splitlines()
    assert lines[1] == 'target: panda_hand_tcp in panda_link0'
    assert lines[7].split()[:3] == ['joint', 'seed', 'value']
    rows = [line.split() for line in lines[8:15]]
    assert [row[0] for row in rows] == list(chain.joints)
    assert all(row[3] == 'deg' and row[-1] == 'yes' for row in rows)
    solved = np.radians([float(row[2]) for row in rows])
    target = pose_matrix([0.4, 0.1, 0.3], Rotation.from_euler(
        'xyz', [180, 0, 45], degrees=True).as_quat())
    distance, angle = pose_distance(target, chain.forward(solved))
    assert distance <= 2e-5 and angle <= 2e-4  # the table's 6 decimals of a degree
    assert lines[15].startswith('converged from the seed in ')
    assert lines[15].endswith(' mrad from the target')


def test_ik_refusals_say_how_close_and_which_limit(swing):
    # At 1 rad the swing is past its upper limit (0.5 rad): it stops there.
    target = [0.6 * math.cos(1.0), 0.6 * math.sin(1.0), 0.0]
    line = assert_one_line_error(traj_gen('ik', '--urdf', swing, *numbers(target), '--rpy',
                                          '0', '0', '1'))
    assert line.startswith('traj-gen ik: error: no joint positions within the limits put '
                           "'tip' at the target pose: the closest found (from the seed and "
                           '24 restarts) is '), line
    assert "joint 'swing' at its upper limit 0.5 rad" in line and ' mm and ' in line
    # Out of reach along the arm (0.8 m at most): the prismatic joint at its upper limit,
    # in metres.
    line = assert_one_line_error(traj_gen('ik', '--urdf', swing, '2', '0', '0'))
    assert "joint 'reach' at its upper limit 0.3 m" in line
    assert '1200.000 mm and 0.000 mrad from it' in line
    # A reachable one: the joints that reach it, analytically.
    result = ik_json('--urdf', swing, '0.7', '0', '0')
    assert [row['value'] for row in result['joints']] == pytest.approx([0.0, 0.2], abs=1e-6)
    assert result['start'] == 'seed'


@pytest.mark.parametrize('arguments, expected', [
    (['fk', '0.1'], 'joint values: 1 values for the 2 joints swing, reach: give one per '
                    'joint in this order, or JOINT=VALUE words'),
    (['fk', 'elbow=1'], "joint values: 'elbow' is not a joint of the chain; its joints are "
                        'swing, reach'),
    (['fk', 'swing=1', '0.2'], 'joint values: give one value per joint or JOINT=VALUE '
                               'words, not both'),
    (['fk', 'swing=x'], "joint values swing: 'x' is not a number"),
    (['fk', '--tool', 'gripper'], "swing.urdf: unknown tool_frame 'gripper': the URDF has no "
                                  "such link; its links are 'base', 'arm', 'tip'"),
    (['fk', '--joints', 'reach', '--base', 'arm'], None),  # valid: the control case
    (['fk', '--joints', 'swing', '--base', 'arm'], "swing.urdf: the chain from 'arm' to "
                                                   "'arm' does not contain joint(s) 'swing'"),
    (['ik', '1', '0', '0', '--quat', '0', '0', '0', '0.5'],
     '--quat: quaternion (x, y, z, w) [0.0, 0.0, 0.0, 0.5] has norm 0.5: a rotation needs '
     'norm 1 (within 0.001)'),
    (['ik', '1', '0', '0', '--quat', '0', '0', '0', '0'], 'has norm 0: a rotation needs'),
    (['ik', '1', '0', '--rpy', '0', '0', '1'], 'the following arguments are required: Z'),
    (['ik', '1', '0', '0', '--rpy', '0', '0', '1', '--quat', '0', '0', '0', '1'],
     'argument --quat: not allowed with argument --rpy'),
    (['ik', '1', '0', 'inf'], "argument Z: 'inf' must be finite"),
    (['ik', '0.7', '0', '0', '--seed', '1,2,3'], '--seed: 3 values for the 2 joints'),
])
def test_bad_arguments_are_one_line_errors_with_exit_2(swing, capsys, arguments, expected):
    command, *rest = arguments
    code = main([command, '--urdf', swing, *rest])
    captured = capsys.readouterr()
    if expected is None:
        assert code == 0, captured.err
        return
    assert code == 2, captured
    assert captured.out == ''
    line, = captured.err.splitlines()
    assert line.startswith(f'traj-gen {command}: error: ') and expected in line, line


def test_missing_and_invalid_urdf_files_are_one_line_errors(tmp_path):
    line = assert_one_line_error(traj_gen('fk', '--urdf', str(tmp_path / 'none.urdf')))
    assert 'No such file or directory' in line and 'none.urdf' in line
    bad = tmp_path / 'bad.urdf'
    bad.write_text('<robot name="x"><link name="a"/>')
    line = assert_one_line_error(traj_gen('ik', '--urdf', str(bad), '0', '0', '0'))
    assert line.startswith(f'traj-gen ik: error: {bad}: invalid URDF: not well-formed XML')
    line = assert_one_line_error(traj_gen('fk', '0'))
    assert line == ('traj-gen fk: error: the following arguments are required: --urdf '
                    '(see traj-gen fk --help)')


def test_the_urdf_can_come_from_standard_input():
    result = subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', 'fk', '--urdf',
                             '-', 'reach=0.2', '--json'], input=SWING, cwd=REPO, env=env(),
                            capture_output=True, text=True, timeout=TIMEOUT)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)['pose']['position'] == pytest.approx([0.7, 0.0, 0.0])


# ---------------------------------------------------------------- poses from the command line


def test_rpy_to_quaternion_and_back_agree_with_scipy():
    rng = np.random.default_rng(3)
    angles = np.vstack([rng.uniform([-math.pi, -math.pi / 2, -math.pi],
                                    [math.pi, math.pi / 2, math.pi], size=(200, 3)),
                        [[0.3, math.pi / 2, -0.4], [0.3, -math.pi / 2, 1.2],  # gimbal lock
                         [math.pi, 0, 0], [0, 0, math.pi], [0, 0, 0]]])
    for roll, pitch, yaw in angles:
        expected = Rotation.from_euler('xyz', [roll, pitch, yaw])  # extrinsic: URDF rpy
        quaternion = rpy_quaternion(roll, pitch, yaw)
        assert np.linalg.norm(quaternion) == pytest.approx(1.0, abs=1e-15)
        assert abs(quaternion @ expected.as_quat()) == pytest.approx(1.0, abs=1e-12)
        matrix = expected.as_matrix()
        back = rotation_rpy(matrix)
        assert Rotation.from_euler('xyz', back).as_matrix() == pytest.approx(matrix, abs=1e-9)
        if abs(abs(pitch) - math.pi / 2) > 1e-3:
            assert back == pytest.approx(expected.as_euler('xyz'), abs=1e-9)
    assert rotation_rpy(np.eye(3)) == pytest.approx([0.0, 0.0, 0.0])


@pytest.mark.parametrize('orientation, degrees, expected', [
    ([], False, [0.0, 0.0, 0.0, 1.0]),
    (['--quat', '0', '0', '0', '1.0009'], False, [0.0, 0.0, 0.0, 1.0]),  # normalised
    (['--quat', '0', '0.7071', '0', '-0.7071'], False,
     [0.0, math.sqrt(0.5), 0.0, -math.sqrt(0.5)]),  # sign kept
    (['--rpy', '90', '0', '0'], True, [math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]),
    (['--rpy', '0', '0', str(math.pi)], False, [0.0, 0.0, 1.0, 0.0]),
])
def test_the_pose_words_become_a_position_and_a_unit_quaternion(orientation, degrees, expected):
    degrees = ['--degrees'] if degrees else []
    arguments = ['pose', '0.4', '-0.1', '0.3', *orientation, *degrees]
    position, quaternion = pose_from_args(build_parser().parse_args(arguments))
    assert position == pytest.approx([0.4, -0.1, 0.3])
    assert quaternion == pytest.approx(expected, abs=1e-12)
    assert np.linalg.norm(quaternion) == pytest.approx(1.0, abs=1e-15)


# ---------------------------------------------------------------- help, imports, packages


@pytest.mark.parametrize('command', ['fk', 'ik', 'pose'])
def test_the_kinematics_subcommands_have_help_with_examples(command):
    text = ok(command, '--help')
    assert f'usage: traj-gen {command}' in text
    assert 'examples:' in text and f'traj-gen {command} ' in text


def test_fk_and_ik_import_no_ros_and_the_other_commands_no_kinematics(swing):
    script = (
        'import sys\n'
        'from traj_gen_ros.cli import main as cli\n'
        f'assert cli.main({["solve", "cubic", "--points", "0", "1", "--duration", "1"]!r}) == 0\n'
        "assert not [m for m in sys.modules if m.startswith(('lxml', 'pinocchio', "
        "'traj_gen_ros.core.kinematics'))]\n"
        f'assert cli.main({["fk", "--urdf", swing, "0.1,0.2"]!r}) == 0\n'
        f'assert cli.main({["ik", "--urdf", swing, "0.6", "0", "0"]!r}) == 0\n'
        "loaded = [m for m in sys.modules if m.startswith(('rclpy', 'rcl_', 'geometry_msgs'))]\n"
        'assert not loaded, loaded\n')
    result = subprocess.run([sys.executable, '-c', script], cwd=REPO, env=env(),
                            capture_output=True, text=True, timeout=TIMEOUT)
    assert result.returncode == 0, result.stderr


def test_fk_without_pinocchio_says_what_to_install_and_exits_2(swing):
    script = ('import sys\n'
              "sys.modules['pinocchio'] = None\n"
              'from traj_gen_ros.cli.main import main\n'
              'sys.exit(main(sys.argv[1:]))\n')
    result = subprocess.run([sys.executable, '-c', script, 'fk', '--urdf', swing], cwd=REPO,
                            env=env(), capture_output=True, text=True, timeout=TIMEOUT)
    line = assert_one_line_error(result, code=2)
    assert line.startswith('traj-gen fk: error: kinematics needs Pinocchio: pip install '
                           'pin==4.1.0'), line
