"""
The test tree's shared set-up: the helpers in ``test/support`` and the ``dds`` marker.

Every test below ``test/dds/`` runs a node (a subprocess, or an rclpy node in this process)
and talks to it over DDS; it is marked ``dds`` here, so ``pytest -m "not dds"`` is the
fast run of everything else. A test elsewhere that needs DDS carries the marker itself.
"""

from pathlib import Path
import sys

import pytest

TEST = Path(__file__).resolve().parent
sys.path.insert(0, str(TEST / 'support'))


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark every test below ``test/dds/`` with ``dds``."""
    dds = TEST / 'dds'
    for item in items:
        if dds in Path(item.fspath).resolve().parents:
            item.add_marker(pytest.mark.dds)
