"""
Where a tool is while the node's arm rests: the start and end of the DDS tool tests.

:func:`tool_at_rest` waits for the stream of a :class:`node_harness.Probe` to hold still
and returns the joint positions there with a link's pose, by an independent forward
kinematics (:class:`numpy_chain.NumpyChain`), so that a test of pose goals or tool paths
sets its targets from, and judges its ends by, the pose the node holds.
"""

from __future__ import annotations

from collections.abc import Sequence

from node_harness import Probe
import numpy as np
from numpy_chain import NumpyChain


def tool_at_rest(probe: Probe, chain: NumpyChain, joints: Sequence[str], link: str,
                 timeout: float = 20.0) -> tuple[np.ndarray, np.ndarray]:
    """
    Wait for the node at rest; return its joint positions (rad) and ``link``'s pose there.

    :param joints: the names of the streamed positions, in the order of ``joint_states``.
    :param timeout: how long the arm may take to come to rest (s).
    :returns: the positions ``(joints,)`` and the pose ``(4, 4)`` in the URDF's root link.
    """
    position = probe.wait_at_rest(timeout)
    return position, chain.pose(link, dict(zip(joints, position, strict=True)))
