"""ament_flake8 over the package, tests and benchmarks, as the ROS 2 templates do."""

from pathlib import Path

from ament_flake8.main import main_with_errors
import pytest

REPO = Path(__file__).resolve().parents[2]
PATHS = [REPO / 'traj_gen_ros', REPO / 'test', REPO / 'benchmarks', REPO / 'launch',
         REPO / 'setup.py']


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = main_with_errors(argv=['--config', str(REPO / 'setup.cfg')]
                                  + [str(path) for path in PATHS if path.exists()])
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
