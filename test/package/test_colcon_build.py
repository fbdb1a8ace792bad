"""colcon (from PyPI) builds the package as ament_python; the installed executable runs."""

import json
import os
from pathlib import Path
import subprocess
import sys

from catkin_pkg.package import parse_package
from node_harness import node_env, NodeProcess, Probe, REPO
import pytest
import rclpy

pytestmark = pytest.mark.dds  # the colcon-installed node is run and heard over DDS
COLCON = Path(sys.executable).with_name('colcon')


def colcon(*args: str, cwd: Path, env: dict) -> str:
    result = subprocess.run([str(COLCON), '--log-base', 'log', *args], cwd=cwd, env=env,
                            capture_output=True, text=True, timeout=240)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_colcon_build_installs_a_runnable_ament_python_package(tmp_path):
    (tmp_path / 'src').mkdir()
    (tmp_path / 'src' / 'traj_gen_ros').symlink_to(REPO, target_is_directory=True)
    env = node_env(extra_pythonpath=False)
    env.pop('PYTHONPATH', None)  # the installed copy, not the repository, must be used
    env['PATH'] = os.pathsep.join([str(COLCON.parent), env.get('PATH', '')])

    # catkin_pkg parsed package.xml: colcon sees an ament_python package, not plain Python.
    listing = colcon('list', '--base-paths', 'src', cwd=tmp_path, env=env)
    assert 'traj_gen_ros' in listing and '(ros.ament_python)' in listing, listing
    colcon('build', '--base-paths', 'src', '--build-base', 'build', '--install-base',
           'install', cwd=tmp_path, env=env)

    prefix = tmp_path / 'install' / 'traj_gen_ros'
    generator = prefix / 'lib' / 'traj_gen_ros' / 'generator'
    assert generator.is_file() and os.access(generator, os.X_OK)
    assert (prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
            / 'traj_gen_ros').is_file()
    manifest = prefix / 'share' / 'traj_gen_ros' / 'package.xml'
    package = parse_package(str(manifest))
    assert package.name == 'traj_gen_ros'
    assert package.get_build_type() == 'ament_python'
    config = prefix / 'share' / 'traj_gen_ros' / 'config' / 'generator.yaml'
    assert config.is_file()
    launch_file = prefix / 'share' / 'traj_gen_ros' / 'launch' / 'generator.launch.py'
    assert launch_file.read_text() == (REPO / 'launch' / 'generator.launch.py').read_text()
    assert not (REPO / 'build').exists() and not list(REPO.glob('*.egg-info'))

    # The command-line tool is installed beside the node and runs from the install space.
    traj_gen = prefix / 'lib' / 'traj_gen_ros' / 'traj-gen'
    solved = subprocess.run(
        ['bash', '-c', f'source {tmp_path / "install" / "setup.bash"} && exec {traj_gen} '
         'solve cubic --points 15 75 --duration 3 --json'],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60)
    assert solved.returncode == 0, solved.stderr
    assert json.loads(solved.stdout)['coefficients'][0][0][2] == 20.0  # Craig's a2

    # What `ros2 run traj_gen_ros generator` does: source the workspace, run the script.
    script = f'source {tmp_path / "install" / "setup.bash"} && exec {generator} "$@"'
    rclpy.init()
    node = NodeProcess(command=['bash', '-c', script, 'generator'], env=env,
                       params_file=config, cwd=tmp_path)
    try:
        probe = Probe(name='colcon_probe')
        probe.wait_ready(timeout=30)
        assert list(probe.latest().name) == [f'joint_{i}' for i in range(1, 7)]
        probe.destroy_node()
    finally:
        rclpy.shutdown()
        code = node.stop()
        output = node.output()
        node.close()
    assert code == 0, output
    assert 'Traceback' not in output, output
