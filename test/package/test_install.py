"""
`make` installs the package into .venv: its two console scripts exist and run the work tree.

Only meaningful in the venv the Makefile builds (`make test`); elsewhere (a ROS install's
`colcon test`) the scripts live in lib/traj_gen_ros and test_colcon_build.py covers them.
"""

import importlib.metadata
import json
import os
from pathlib import Path
import subprocess
import sys

from node_harness import node_env, NodeProcess, REPO
import pytest
from traj_gen_ros.cli import main as cli
from traj_gen_ros.node import generator as generator_node

VENV = REPO / '.venv'
BIN = VENV / 'bin'
TIMEOUT = 120  # s: generous, the machine is shared

pytestmark = [pytest.mark.skipif(Path(sys.prefix).resolve() != VENV.resolve(),
                                 reason='runs in the .venv that `make` builds'),
              pytest.mark.dds]  # the installed node is run and heard over DDS


def bare_env() -> dict:
    """Return the environment of a user's shell: no PYTHONPATH pointing at the repository."""
    env = node_env(extra_pythonpath=False)
    env.pop('PYTHONPATH', None)
    return env


def test_console_scripts_are_registered_and_resolve_to_the_mains():
    scripts = {entry.name: entry for entry in importlib.metadata.entry_points(
        group='console_scripts') if entry.dist.name.replace('_', '-') == 'traj-gen-ros'}
    assert sorted(scripts) == ['generator', 'traj-gen']
    assert scripts['traj-gen'].load() is cli.main
    assert scripts['generator'].load() is generator_node.main


@pytest.mark.parametrize('name', ['generator', 'traj-gen'])
def test_scripts_are_in_the_venv_bin(name):
    script = BIN / name
    assert script.is_file() and os.access(script, os.X_OK), script
    assert script.read_text().splitlines()[0] == f'#!{BIN / "python"}'


def test_traj_gen_runs_the_work_tree_from_anywhere(tmp_path):
    helped = subprocess.run([str(BIN / 'traj-gen'), '--help'], cwd=tmp_path, env=bare_env(),
                            capture_output=True, text=True, timeout=TIMEOUT)
    assert helped.returncode == 0, helped.stderr
    assert helped.stdout.startswith('usage: traj-gen')

    solved = subprocess.run(
        [str(BIN / 'traj-gen'), 'solve', 'cubic', '--points', '15', '75', '--duration', '3',
         '--degrees', '--json'],
        cwd=tmp_path, env=bare_env(), capture_output=True, text=True, timeout=TIMEOUT)
    assert solved.returncode == 0, solved.stderr
    assert json.loads(solved.stdout)['coefficients'][0][0][2] == 20.0  # Craig's a2

    # Editable: the package the venv imports is this work tree, not a stale copy.
    where = subprocess.run([str(BIN / 'python'), '-c',
                            'import traj_gen_ros; print(traj_gen_ros.__file__)'],
                           cwd=tmp_path, env=bare_env(), capture_output=True, text=True,
                           timeout=TIMEOUT)
    assert Path(where.stdout.strip()) == REPO / 'traj_gen_ros' / '__init__.py', where.stderr


def test_generator_script_starts_the_node(tmp_path):
    # A configuration the node refuses: it must get as far as reading its parameters.
    node = NodeProcess('-p', 'profile:=septic', command=[str(BIN / 'generator')],
                       env=bare_env(), params_file=None, cwd=tmp_path)
    try:
        code = node.process.wait(60)
        output = node.output()
    finally:
        node.close()
    assert code == 1, output
    assert ('invalid parameters: profile must be one of lspb, cubic, quintic, scurve; '
            "got 'septic'") in output
    assert 'Traceback' not in output


def test_make_run_uses_the_installed_generator():
    makefile = (REPO / 'Makefile').read_text()
    assert '\t$(VENV)/bin/generator --ros-args --params-file config/generator.yaml\n' \
        in makefile
    stamp_rule = next(line for line in makefile.splitlines() if line.startswith('$(STAMP):'))
    for needed in ('requirements.txt', 'requirements-dev.txt', 'setup.py', 'setup.cfg'):
        assert needed in stamp_rule.split(), stamp_rule
