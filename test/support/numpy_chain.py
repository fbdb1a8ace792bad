"""
An independent oracle for forward kinematics: a URDF's joint origins and axes in numpy.

Written for the tests from the URDF specification alone (no Pinocchio, no project code):
each joint's pose in its parent link is ``origin(xyz, rpy) · motion(axis, value)``, with
``rpy`` the fixed-axis roll, pitch, yaw (``R = Rz(yaw) Ry(pitch) Rx(roll)``) and the axis
normalised; a link's pose in the root is the product down the tree. Mimic joints take
``multiplier * leader + offset``; floating and planar joints stand at the identity.
"""

from __future__ import annotations

from collections.abc import Mapping
import math
import xml.etree.ElementTree as ElementTree

import numpy as np


def _floats(text: str | None, default: tuple[float, ...]) -> np.ndarray:
    return np.array([float(value) for value in text.split()]) if text else np.array(default)


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Return ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Return the rotation by ``angle`` about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def transform(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    result = np.eye(4)
    result[:3, :3], result[:3, 3] = rotation, translation
    return result


class NumpyChain:
    """Every link's pose of a URDF, from joint values by name (rad or m; missing: 0)."""

    def __init__(self, urdf_text: str) -> None:
        root = ElementTree.fromstring(urdf_text)
        self.joints = {}
        self.parent_joint = {}
        for element in root.findall('joint'):
            origin = element.find('origin')
            axis = element.find('axis')
            mimic = element.find('mimic')
            xyz = _floats(origin.get('xyz') if origin is not None else None, (0, 0, 0))
            rpy = _floats(origin.get('rpy') if origin is not None else None, (0, 0, 0))
            direction = _floats(axis.get('xyz') if axis is not None else None, (1, 0, 0))
            joint = {
                'name': element.get('name'), 'type': element.get('type'),
                'parent': element.find('parent').get('link'),
                'child': element.find('child').get('link'),
                'origin': transform(rpy_matrix(*rpy), xyz),
                'axis': direction / (np.linalg.norm(direction) or 1.0),  # fixed: 0 0 0
                'mimic': None if mimic is None else (
                    mimic.get('joint'), float(mimic.get('multiplier', 1)),
                    float(mimic.get('offset', 0))),
            }
            self.joints[joint['name']] = joint
            self.parent_joint[joint['child']] = joint

    def value(self, name: str, values: Mapping[str, float]) -> float:
        mimic = self.joints[name]['mimic']
        if mimic is not None:
            leader, multiplier, offset = mimic
            return multiplier * self.value(leader, values) + offset
        return float(values.get(name, 0.0))

    def motion(self, joint: dict, values: Mapping[str, float]) -> np.ndarray:
        kind = joint['type']
        if kind in ('revolute', 'continuous'):
            return transform(axis_rotation(joint['axis'], self.value(joint['name'], values)),
                             np.zeros(3))
        if kind == 'prismatic':
            return transform(np.eye(3), joint['axis'] * self.value(joint['name'], values))
        return np.eye(4)  # fixed; floating and planar at the identity

    def link_pose(self, link: str, values: Mapping[str, float]) -> np.ndarray:
        """Return ``link``'s pose in the root link."""
        pose = np.eye(4)
        while link in self.parent_joint:
            joint = self.parent_joint[link]
            pose = joint['origin'] @ self.motion(joint, values) @ pose
            link = joint['parent']
        return pose

    def pose(self, link: str, values: Mapping[str, float], base: str | None = None
             ) -> np.ndarray:
        """Return ``link``'s pose in ``base`` (the root if None)."""
        pose = self.link_pose(link, values)
        if base is None:
            return pose
        return np.linalg.inv(self.link_pose(base, values)) @ pose
