"""
Real arms at a working start, for the tool path tests end to end (issue 30).

Example-robot-data's Panda and UR10 and pybullet's KUKA iiwa (by their keys in
:data:`kinematics_robots.ROBOTS`, each to its default tool), each at the start (rad) the
tests move its tool from; :func:`arm_fixture` makes a test module's ``arm`` fixture of
some of them, :func:`moved` the poses to move to.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from kinematics_robots import robot_urdf, ROBOTS
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from traj_gen_ros.core.kinematics import Chain

#: Each arm's start (rad), by its key in :data:`kinematics_robots.ROBOTS`.
STARTS = {
    'erd-panda': (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785),
    'erd-ur10': (0.3, -1.2, 1.6, -1.9, -1.57, 0.4),
    'pybullet-iiwa': (0.0, 0.6, 0.0, -1.3, 0.0, 0.9, 0.0),
}


def real_arm(config: pytest.Config, key: str) -> tuple[Chain, np.ndarray]:
    """
    Return the chain of arm ``key`` (to its default tool) and its start (rad).

    :param config: pytest's config (``request.config``): the URDFs are in its cache; the
        test skips where they cannot be fetched.
    """
    robot = ROBOTS[key]
    chain = Chain.from_urdf(robot_urdf(config, robot.source, robot.name),
                            robot.joints, tool_frame=robot.default_tool)
    return chain, np.array(STARTS[key])


def arm_fixture(keys: Iterable[str]):
    """
    Return a module-scoped fixture ``arm`` of :func:`real_arm`, one case per key, sorted.

    In a test module: ``arm = arm_fixture(['erd-panda', 'erd-ur10'])``.
    """
    @pytest.fixture(scope='module', params=sorted(keys))
    def arm(request: pytest.FixtureRequest) -> tuple[Chain, np.ndarray]:
        return real_arm(request.config, request.param)
    return arm


def moved(pose: np.ndarray, offset: Sequence[float],
          rotvec: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """
    Return ``pose`` ``(4, 4)`` moved by ``offset`` (m) and turned by ``rotvec`` (rad).

    Both in the base frame: the position plus ``offset``, the orientation pre-multiplied
    by the rotation of axis-angle vector ``rotvec``.
    """
    result = pose.copy()
    result[:3, 3] += offset
    result[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix() @ pose[:3, :3]
    return result
