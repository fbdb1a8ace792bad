"""ament_pep257 docstring conventions over the package, as the ROS 2 templates do."""

from pathlib import Path

from ament_pep257.main import main
import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = main(argv=[str(REPO / 'traj_gen_ros'), str(REPO / 'test'), str(REPO / 'launch')])
    assert rc == 0, 'Found code style errors / warnings'
