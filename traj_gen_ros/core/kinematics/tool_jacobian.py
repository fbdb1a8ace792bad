"""
The tool's Jacobian relative to ``base_frame`` and its time derivative, for a chain.

From Pinocchio's frame Jacobians in ``LOCAL_WORLD_ALIGNED`` axes (world axes, about each
frame's origin), restricted to the chain's joints by :attr:`Configuration.selection`
(a leader's column carries its followers'). The chain's ``J`` is relative to the base:

* a base the chain's joints do not move: ``J = R_bᵀ J_t`` (the tool's, in the base's axes);
* a base they move (a ``base_frame`` below a joint of the chain, or a mimic of one): the
  relative twist of two frames of one body tree, ``M = (J_t − J_b + [r]× J_b^ω,
  J_t^ω − J_b^ω)`` with ``r`` from the base's origin to the tool's (the base point's
  velocity plus ``ω_b × r``, subtracted), then ``J = R_bᵀ M``.

``J̇`` differentiates the same: Pinocchio's ``getFrameJacobianTimeVariation`` for ``J̇_t``
and ``J̇_b``, and for a moving base ``d/dt(R_bᵀ M) = R_bᵀ (Ṁ − [ω_b]× M)`` (``Ṙ_b = [ω_b]×
R_b``), ``ṙ = v_t − v_b`` (:func:`relative_rate`).

Rows: linear (m/s) then angular velocity (rad/s) per unit joint velocity (rad/s or m/s).
Shares the chain's Pinocchio ``Data``: as the chain, not thread-safe.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from traj_gen_ros.core.kinematics.configuration import Configuration


def relative_rate(tool_rate: np.ndarray, tool: np.ndarray, base_rate: np.ndarray,
                  base: np.ndarray, lever: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """
    Return ``Ṁ − [ω_b]× M`` (world axes) of the tool's Jacobian relative to a moving base.

    ``M = (J_t − J_b + [r]× J_b^ω, J_t^ω − J_b^ω)`` from the tool's and the base's world
    Jacobians ``tool``, ``base`` and their time derivatives ``tool_rate``, ``base_rate`` at
    joint velocity ``rate``; ``r`` the lever from the base's origin to the tool's, ``ṙ =
    v_t − v_b``, ``ω_b = J_b^ω rate``.
    """
    spin = base[3:] @ rate
    moved = tool - base
    moved[:3] += np.cross(lever, base[3:], axisb=0, axisc=0)
    result = tool_rate - base_rate
    result[:3] += (np.cross(moved[:3] @ rate - np.cross(lever, spin), base[3:], axisb=0,
                            axisc=0)
                   + np.cross(lever, base_rate[3:], axisb=0, axisc=0))
    result[:3] -= np.cross(spin, moved[:3], axisb=0, axisc=0)
    result[3:] -= np.cross(spin, moved[3:], axisb=0, axisc=0)
    return result


class ToolJacobian:
    """
    ``J`` and ``J̇`` of one chain's tool relative to its base (module docstring).

    :param tool: Pinocchio's frame id of ``tool_frame``.
    :param base: likewise of ``base_frame``.
    :param base_is_world: ``base_frame`` is the URDF's root (poses are world poses).
    :param base_moves: a joint of the chain (or a mimic of one) is on the way up from
        ``base_frame`` to where it meets the tool's branch.
    """

    def __init__(self, pin: Any, model: Any, data: Any, configuration: Configuration,
                 tool: int, base: int, base_is_world: bool, base_moves: bool) -> None:
        """Keep what the Jacobians need; ``data`` is the chain's own Pinocchio ``Data``."""
        self._pin, self._model, self._data = pin, model, data
        self._configuration = configuration
        self._tool, self._base = tool, base
        self._base_is_world, self._base_moves = base_is_world, base_moves
        self._axes = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def _world(self, frame: int) -> np.ndarray:
        """Return ``frame``'s world-aligned Jacobian ``(6, joints)`` (computed joints)."""
        jacobian = self._pin.getFrameJacobian(self._model, self._data, frame, self._axes)
        return jacobian @ self._configuration.selection

    def pose_and_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``(R, p, J)`` of the tool in ``base_frame`` at ``(joints,)`` positions."""
        pin, model, data = self._pin, self._model, self._data
        pin.computeJointJacobians(model, data, self._configuration.config(q))
        tool = pin.updateFramePlacement(model, data, self._tool)
        jacobian = self._world(self._tool)
        if self._base_is_world:
            return tool.rotation, tool.translation, jacobian
        base = pin.updateFramePlacement(model, data, self._base)
        rotation_t = base.rotation.T
        if self._base_moves:
            of_base = self._world(self._base)
            lever = tool.translation - base.translation
            jacobian = jacobian - of_base
            jacobian[:3] += np.cross(lever, of_base[3:], axisb=0, axisc=0)
        relative = base.actInv(tool)
        return (relative.rotation, relative.translation,
                np.vstack((rotation_t @ jacobian[:3], rotation_t @ jacobian[3:])))

    def rate(self, q: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """Return ``J̇`` ``(6, joints)`` at positions ``q`` and joint velocity ``rate``."""
        pin, model, data, axes = self._pin, self._model, self._data, self._axes
        selection = self._configuration.selection
        pin.computeJointJacobiansTimeVariation(model, data, self._configuration.config(q),
                                               selection @ rate)
        tool = pin.getFrameJacobianTimeVariation(model, data, self._tool, axes) @ selection
        if self._base_is_world:
            return tool
        base = pin.updateFramePlacement(model, data, self._base)
        if self._base_moves:
            tool_origin = pin.updateFramePlacement(model, data, self._tool).translation
            turning = pin.getFrameJacobianTimeVariation(model, data, self._base,
                                                        axes) @ selection
            tool = relative_rate(tool, self._world(self._tool), turning,
                                 self._world(self._base), tool_origin - base.translation,
                                 rate)
        rotation_t = base.rotation.T
        return np.vstack((rotation_t @ tool[:3], rotation_t @ tool[3:]))
