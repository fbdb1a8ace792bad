"""
The kinematic chain from ``base_frame`` to ``tool_frame`` of a URDF, for a set of joints.

:meth:`Chain.from_urdf` chooses and checks the chain (:mod:`.chain_choice` on the tree
of :mod:`.urdf_tree`, lxml), then has Pinocchio build the model (:mod:`.pinocchio_model`);
the chain then gives forward kinematics (:meth:`Chain.forward`, :meth:`Chain.frame_pose`),
the Jacobian and its rate (:meth:`Chain.jacobian`, :meth:`Chain.jacobian_rate`:
:mod:`.tool_jacobian`) and inverse kinematics (:meth:`Chain.inverse`, :mod:`.inverse`).

Units: rad (m for prismatic joints) per joint, in the order of ``joints``; poses are
``(4, 4)`` homogeneous transforms in ``base_frame``, metres. Defaults: ``base_frame`` the
URDF's root link; ``tool_frame`` the end of the fixed joints below the child link of the
last joint (:meth:`.UrdfTree.fixed_end`). A chain keeps one Pinocchio ``Data``: it is not
thread-safe; give each thread its own :meth:`Chain.copy`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from traj_gen_ros.core.kinematics.chain_choice import ChainChoice, choose_chain, describe_chain
from traj_gen_ros.core.kinematics.configuration import Configuration
from traj_gen_ros.core.kinematics.inverse import IkSolution, solve
from traj_gen_ros.core.kinematics.pinocchio_model import build_model
from traj_gen_ros.core.kinematics.tool_jacobian import ToolJacobian
from traj_gen_ros.core.kinematics.urdf_tree import UrdfTree


def joint_values(q: Sequence[float] | np.ndarray, joints: tuple[str, ...], what: str = 'q',
                 taker: str = '') -> np.ndarray:
    """
    Return joint positions ``q`` as floats, checked: a value per joint, each finite.

    ``(joints,)`` or ``(samples, joints)``; only ``(joints,)`` where ``taker`` (the method
    that takes it) is given. Else a ``ValueError`` naming ``what`` and the joint.
    """
    try:
        array = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f'{what} must be numbers, one per joint') from None
    if array.ndim not in (1, 2) or array.shape[-1] != len(joints):
        raise ValueError(f'{what} has shape {array.shape}: expected ({len(joints)},) '
                         f'or (samples, {len(joints)}), one value per joint of '
                         f'{", ".join(joints)}')
    bad = ~np.isfinite(array)
    if bad.any():
        index = np.argwhere(bad)[0]
        raise ValueError(f'{what} of joint {joints[index[-1]]!r} is '
                         f'{array[tuple(index)]}: every position must be finite')
    if taker and array.ndim != 1:
        raise ValueError(f'{what} has shape {array.shape}: {taker} takes ({len(joints)},)')
    return array


def _frozen(values: Any) -> np.ndarray:
    array = np.array(values)
    array.setflags(write=False)
    return array


class Chain:
    """
    Forward and inverse kinematics of one chain; build it with :meth:`from_urdf`.

    :ivar joints: the joint names, in the order of every ``q``.
    :ivar base_frame: the link whose frame poses are expressed in.
    :ivar tool_frame: the link whose pose :meth:`forward` gives.
    :ivar links: every link of the URDF (any can be a :meth:`frame_pose`).
    :ivar lower: the URDF's lower position limits, ``(joints,)``, rad or m (-inf: none).
    :ivar upper: the URDF's upper position limits, likewise (+inf: none).
    :ivar angular: per joint, True for revolute and continuous joints (rad), False for
        prismatic ones (m).
    :ivar periodic: per joint, True where a whole turn is the same pose of every link
        (revolute and continuous joints that no other joint mimics).
    """

    def __init__(self, pin: Any, model: Any, tree: UrdfTree, choice: ChainChoice) -> None:
        """Wrap a built model; use :meth:`from_urdf`."""
        self._pin, self._model, self._tree, self._choice = pin, model, tree, choice
        self._data = model.createData()
        joints, base_frame, tool_frame = choice.joints, choice.base_frame, choice.tool_frame
        self.joints, self.base_frame, self.tool_frame = joints, base_frame, tool_frame
        self.links = tree.links
        self._configuration = Configuration(pin, model, tree, joints)
        self.lower, self.upper, self.angular, self.periodic = (_frozen(array) for array in (
            [tree.joints[name].lower for name in joints],
            [tree.joints[name].upper for name in joints],
            [tree.joints[name].type != 'prismatic' for name in joints],
            self._configuration.periodic))
        self._frames = {link: model.getFrameId(link, pin.FrameType.BODY) for link in tree.links}
        self._tool, self._base = self._frames[tool_frame], self._frames[base_frame]
        self._base_is_world = base_frame == tree.root
        self._jacobian = ToolJacobian(pin, model, self._data, self._configuration,
                                      self._tool, self._base, self._base_is_world,
                                      choice.base_moves)

    @classmethod
    def from_urdf(cls, urdf_text: str | bytes, joints: Sequence[str],
                  base_frame: str | None = None,
                  tool_frame: str | None = None,
                  held: Mapping[str, float] | None = None) -> Chain:
        """
        Build the chain from ``base_frame`` to ``tool_frame`` that ``joints`` move.

        :param urdf_text: the URDF document (the ``robot_description``; bytes are read as
            UTF-8).
        :param joints: the joint names, in the order of every ``q``; each a revolute,
            continuous or prismatic joint of the URDF that mimics none.
        :param base_frame: a link; None (or '', an unset string parameter): the URDF's
            root link.
        :param tool_frame: a link; None (or ''): the end of the fixed joints below the
            child link of ``joints[-1]`` where there is one end, else that child link.
        :param held: positions (rad or m) of other joints, by name (:meth:`hold`).
        :raises ValueError: the URDF is not valid or Pinocchio cannot read it; a joint
            unknown, not movable, a mimic joint or named twice; an unknown link (the
            message lists the links); a chain that does not contain every joint (the
            message names the missing ones and the joints the chain has).
        :raises ImportError: Pinocchio is not installed.
        """
        if isinstance(urdf_text, bytes):
            urdf_text = urdf_text.decode('utf-8', errors='replace')
        tree = UrdfTree.parse(urdf_text)
        choice = choose_chain(tree, joints, base_frame, tool_frame)
        pin, model = build_model(urdf_text)
        chain = cls(pin, model, tree, choice)
        if held:
            chain.hold(held)
        return chain

    def copy(self) -> Chain:
        """Return the same chain with its own Pinocchio ``Data`` (for another thread)."""
        twin = Chain(self._pin, self._model, self._tree, self._choice)
        twin.hold(self.held)
        return twin

    def hold(self, values: Mapping[str, float]) -> None:
        """
        Hold joints that are not the chain's at ``values`` (rad or m, by name).

        A name that is no revolute, continuous or prismatic joint of the URDF, the chain's
        own joints and mimic joints (they follow their leaders) are ignored; a joint not
        named keeps its value (at first 0). Floating and planar joints stay at the identity.

        :raises ValueError: a value is not a finite number.
        """
        self._configuration.hold(values)

    @property
    def held(self) -> dict[str, float]:
        """Return the positions of every other movable joint, by name (rad or m)."""
        return self._configuration.held

    def describe(self) -> str:
        """Return one line naming the chain: base → tool, the joints, the others on the way."""
        return describe_chain(self._tree, self._choice, self.held)

    def _placement(self, config: np.ndarray, frame: int) -> Any:
        """Return Pinocchio's SE3 of ``frame`` in ``base_frame`` at one configuration."""
        pin = self._pin
        pin.forwardKinematics(self._model, self._data, config)
        placement = pin.updateFramePlacement(self._model, self._data, frame)
        if self._base_is_world:
            return placement
        return pin.updateFramePlacement(self._model, self._data, self._base).actInv(placement)

    def _poses(self, config: np.ndarray, frame: int) -> np.ndarray:
        if config.ndim == 1:
            return self._placement(config, frame).homogeneous
        return np.array([self._placement(row, frame).homogeneous for row in config])

    def forward(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """
        Return the pose of ``tool_frame`` in ``base_frame`` at joint positions ``q``.

        :param q: ``(joints,)`` or ``(samples, joints)``, rad or m.
        :return: ``(4, 4)`` (or ``(samples, 4, 4)``) homogeneous transform(s), metres.
        """
        return self._poses(self._configuration.config(joint_values(q, self.joints)), self._tool)

    def frame_pose(self, link: str, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Return the pose of any ``link`` in ``base_frame`` at ``q``, as :meth:`forward`."""
        frame = self._frames.get(link)
        if frame is None:
            self._tree.check_link(link, 'link')
        return self._poses(self._configuration.config(joint_values(q, self.joints)), frame)

    def _pose_and_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``(R, p, J)`` of the tool in ``base_frame`` at ``(joints,)`` positions."""
        return self._jacobian.pose_and_jacobian(q)

    def jacobian(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """
        Return the tool's Jacobian at ``(joints,)`` positions ``q``: ``(6, joints)``.

        Rows: the velocity of the ``tool_frame`` origin (m/s), then its angular velocity
        (rad/s), both relative to ``base_frame`` and in its axes, per unit joint velocity.
        """
        return self._pose_and_jacobian(joint_values(q, self.joints, taker='the Jacobian'))[2]

    def pose_and_jacobian(self, q: Sequence[float] | np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """
        Return the tool's pose ``(4, 4)`` and Jacobian ``(6, joints)`` at ``q``, in one pass.

        :meth:`forward` and :meth:`jacobian` together, for callers that need both at every
        step (the joint path of a tool path, :mod:`traj_gen_ros.core.cartesian`).
        """
        rotation, translation, jacobian = self._pose_and_jacobian(
            joint_values(q, self.joints, taker='pose_and_jacobian'))
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = rotation, translation
        return pose, jacobian

    def jacobian_rate(self, q: Sequence[float] | np.ndarray,
                      rate: Sequence[float] | np.ndarray) -> np.ndarray:
        """
        Return ``J̇``, the time derivative of :meth:`jacobian` at joint velocity ``rate``.

        ``(6, joints)``, along ``q + t·rate``: the tool's acceleration is ``J q̈ + J̇ q̇``
        (``J̇ q̇`` the drift), and a minimum-norm joint path's curvature needs ``J̇ᵀ`` too.
        Pinocchio's ``getFrameJacobianTimeVariation`` (``LOCAL_WORLD_ALIGNED``); for a
        ``base_frame`` that the joints move, see :mod:`.tool_jacobian`.
        """
        q = joint_values(q, self.joints, taker='jacobian_rate')
        rate = joint_values(rate, self.joints, 'rate', 'jacobian_rate')
        return self._jacobian.rate(q, rate)

    def _tool_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        placement = self._placement(self._configuration.config(q), self._tool)
        return placement.rotation, placement.translation

    def inverse(self, target: np.ndarray, seed: Sequence[float],
                lower: Sequence[float] | None = None, upper: Sequence[float] | None = None,
                *, position_tolerance: float = 1e-5,
                orientation_tolerance: float = 1e-4) -> IkSolution:
        """
        Return the joint positions that put ``tool_frame`` at ``target``, nearest ``seed``.

        See :func:`traj_gen_ros.core.kinematics.inverse.solve` for the method.

        :param target: the tool pose in ``base_frame``, ``(4, 4)``, metres.
        :param seed: ``(joints,)``, rad or m: where to start and what to stay near.
        :param lower: lower position limits ``(joints,)``; None: :attr:`lower`.
        :param upper: upper position limits ``(joints,)``; None: :attr:`upper`.
        :param position_tolerance: m (default 0.01 mm).
        :param orientation_tolerance: rad (default 0.1 mrad).
        :raises UnreachablePoseError: no start converged within the limits (a ``ValueError``
            saying how close it came and which joint limits stopped it).
        :raises ValueError: an invalid target, seed or limits.
        """
        return solve(self, target, joint_values(seed, self.joints, 'seed'),
                     self.lower if lower is None else lower,
                     self.upper if upper is None else upper,
                     position_tolerance, orientation_tolerance)
