"""
The chain's joint values as Pinocchio's configuration vector, and back for velocities.

The API speaks one value per joint of the node's joint set, in the node's order (rad or
m). Pinocchio's configuration ``q`` (``model.nq`` values) differs: a ``continuous`` joint
is ``(cos θ, sin θ)`` (nq 2, nv 1), a ``floating`` joint 7 values (position, quaternion),
a ``planar`` joint 4. :class:`Configuration` converts at this boundary:

- the chain's joints take the given values;
- every other ``revolute``/``continuous``/``prismatic`` joint is held at the value
  :meth:`Configuration.hold` gave it (e.g. the measured state), else at 0;
- a ``<mimic>`` joint follows its leader, ``multiplier * leader + offset``, also through
  a leader that mimics another (Pinocchio's ``buildModelFromXML`` models mimic joints as
  independent joints in 3.x and 4.x, so the relation is applied here);
- ``floating`` and ``planar`` joints are held at Pinocchio's neutral configuration, the
  identity: only the chain counts.

The chain's Jacobian columns follow the same rule (:attr:`Configuration.selection`): a
leader's column also carries ``multiplier`` times each follower's column.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
import math
from typing import Any

import numpy as np
from traj_gen_ros.core.kinematics.urdf_tree import SCALAR_TYPES, UrdfTree


class Configuration:
    """
    Joint values (``(joints,)`` or ``(samples, joints)``) to Pinocchio configurations.

    :ivar joints: the chain's joints, the node's order.
    :ivar periodic: per joint, True where ``θ + 2πk`` is the same pose of every link (a
        revolute or continuous joint that no other joint mimics).
    :ivar selection: ``(model.nv, joints)``: Pinocchio's velocity vector from the joints'.
    """

    def __init__(self, pin: Any, model: Any, tree: UrdfTree, joints: Sequence[str]) -> None:
        """Map ``joints`` (already checked to be scalar, non-mimic URDF joints)."""
        self.joints = tuple(joints)
        scalar = [joint for joint in tree.joints.values() if joint.type in SCALAR_TYPES]
        self.names = tuple(joint.name for joint in scalar)
        position = {name: index for index, name in enumerate(self.names)}
        models = [model.joints[model.getJointId(name)] for name in self.names]
        nq = np.array([joint_model.nq for joint_model in models])
        idx_q = np.array([joint_model.idx_q for joint_model in models], dtype=int)
        idx_v = np.array([joint_model.idx_v for joint_model in models], dtype=int)
        self._plain = np.flatnonzero(nq == 1)
        self._plain_q = idx_q[self._plain]
        self._circle = np.flatnonzero(nq == 2)
        self._cos_q = idx_q[self._circle]
        roots = {joint.name: tree.mimic_root(joint.name) for joint in scalar if joint.mimic}
        self._followers = np.array([position[name] for name in roots], dtype=int)
        self._leaders = np.array([position[roots[name][0]] for name in roots], dtype=int)
        self._multiplier = np.array([roots[name][1] for name in roots], dtype=float)
        self._offset = np.array([roots[name][2] for name in roots], dtype=float)
        # What q moves: the chain's joints and the joints that mimic them, each as
        # multiplier * q[column] + offset, split by Pinocchio's nq (1, or 2 for cos/sin).
        moved = [(name, self.joints.index(name), 1.0, 0.0) for name in self.joints]
        moved += [(name, self.joints.index(leader), multiplier, offset)
                  for name, (leader, multiplier, offset) in roots.items()
                  if leader in self.joints]
        self._direct = [self._split(moved, position, nq, idx_q, size) for size in (1, 2)]
        self._neutral = np.asarray(pin.neutral(model), dtype=float)
        self._held = np.zeros(len(self.names))
        self.hold({})
        led = {leader for leader, _, _ in roots.values()}
        self.periodic = np.array([tree.joints[name].type in ('revolute', 'continuous')
                                  and name not in led for name in self.joints])
        self.selection = np.zeros((model.nv, len(self.joints)))
        for name, column, multiplier, _ in moved:
            self.selection[idx_v[position[name]], column] += multiplier

    @staticmethod
    def _split(moved: list, position: dict, nq: np.ndarray, idx_q: np.ndarray,
               size: int) -> tuple | None:
        """Return ``(idx_q, columns, multipliers, offsets)`` of the moved joints of nq ``size``."""
        rows = [entry for entry in moved if nq[position[entry[0]]] == size]
        if not rows:
            return None
        index = np.array([idx_q[position[name]] for name, *_ in rows], dtype=int)
        columns = np.array([column for _, column, _, _ in rows], dtype=int)
        multipliers = np.array([multiplier for _, _, multiplier, _ in rows])
        offsets = np.array([offset for *_, offset in rows])
        if (multipliers == 1.0).all() and (offsets == 0.0).all():
            return index, columns, None, None
        return index, columns, multipliers, offsets

    def _fill(self, config: np.ndarray, values: np.ndarray) -> None:
        """Write scalar joint values ``(scalar,)`` into ``config`` ``(nq,)``."""
        config[self._plain_q] = values[self._plain]
        circle = values[self._circle]
        config[self._cos_q] = np.cos(circle)
        config[self._cos_q + 1] = np.sin(circle)

    def hold(self, values: Mapping[str, float]) -> None:
        """
        Hold the joints named in ``values`` that are not the chain's at those values.

        A name the URDF's revolute, continuous or prismatic joints lack, a joint of the
        chain and a mimic joint (it follows its leader) are ignored; a joint held before
        and not named keeps its value.

        :param values: joint name → position, rad or m (e.g. the measured state).
        :raises ValueError: a value named here is not a finite number.
        """
        index = {name: position for position, name in enumerate(self.names)}
        ignored = set(self.joints) | {self.names[position] for position in self._followers}
        held = self._held.copy()
        for name, value in values.items():
            if name not in index or name in ignored:
                continue
            try:
                number = float(value)
            except (TypeError, ValueError):
                number = math.nan
            if not math.isfinite(number):
                raise ValueError(f'held position {value!r} of joint {name!r} is not a finite '
                                 'number (rad or m)')
            held[index[name]] = number
        self._held = held
        base = self._neutral.copy()
        self._fill(base, self._follow(held))
        self._base = base

    @property
    def held(self) -> dict[str, float]:
        """Return every joint held at a value, by name (rad or m), mimic joints as they follow."""
        values = self._follow(self._held.copy())
        chain = set(self.joints)
        return {name: float(values[position]) for position, name in enumerate(self.names)
                if name not in chain}

    def _follow(self, values: np.ndarray) -> np.ndarray:
        """Set the mimic joints of ``values`` (``(..., scalar)``, in place) from leaders."""
        values[..., self._followers] = (self._multiplier * values[..., self._leaders]
                                        + self._offset)
        return values

    def config(self, q: np.ndarray) -> np.ndarray:
        """Return Pinocchio's configuration(s) for joint values ``q`` (checked, float)."""
        if q.ndim == 1:
            config = self._base.copy()
        else:
            config = np.tile(self._base, (q.shape[0], 1))
        plain, circle = self._direct
        if plain is not None:
            index, columns, multipliers, offsets = plain
            values = q[..., columns]
            config[..., index] = values if multipliers is None else (
                multipliers * values + offsets)
        if circle is not None:
            index, columns, multipliers, offsets = circle
            angles = q[..., columns]
            if multipliers is not None:
                angles = multipliers * angles + offsets
            config[..., index] = np.cos(angles)
            config[..., index + 1] = np.sin(angles)
        return config
