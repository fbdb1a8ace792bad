"""
A URDF document read with urdfdom's meaning: its links and joints, nothing else.

No Pinocchio here: lxml reads what choosing and checking a chain needs, before Pinocchio
builds the model. Read: each ``<link name>`` and each ``<joint>`` directly under
``<robot>`` (``name``, ``type``, ``<parent link>``, ``<child link>``, ``<limit lower
upper>``, ``<mimic joint multiplier offset>``). Everything else (origins, axes, inertias,
meshes) is left to Pinocchio, which reads it with urdfdom. How they connect is
:class:`~traj_gen_ros.core.kinematics.urdf_tree.UrdfTree`'s.

Position limits: a ``revolute`` or ``prismatic`` joint's ``<limit>`` ``lower``/``upper``
(default 0, as urdfdom); a ``continuous`` joint, and a joint without ``<limit>``, has none
(±inf). Units: rad or m.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
import math
import re

from lxml import etree

#: Joints that carry one scalar coordinate (rad or m), the ones a chain can move.
SCALAR_TYPES = ('revolute', 'continuous', 'prismatic')
TYPES = (*SCALAR_TYPES, 'fixed', 'floating', 'planar')
#: How many link names a refusal lists.
LISTED = 12
_XML_DECLARATION = re.compile(r'^\s*<\?xml[^>]*\?>')


@dataclass(frozen=True)
class Mimic:
    """``<mimic>``: this joint's value is ``multiplier * leader + offset`` (rad or m)."""

    leader: str
    multiplier: float
    offset: float


@dataclass(frozen=True)
class TreeJoint:
    """One ``<joint>``: its type, the links it joins, its position limits and mimic."""

    name: str
    type: str  # noqa: A003 - the URDF attribute's name
    parent: str
    child: str
    lower: float
    upper: float
    mimic: Mimic | None


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


def _number(element: etree._Element, attribute: str, default: float, where: str) -> float:
    text = element.get(attribute)
    if text is None:
        return default
    try:
        return float(text)
    except ValueError:
        raise ValueError(f'invalid URDF: {where}: <{element.tag}> {attribute}={text!r} '
                         'is not a number') from None


def _link_of(element: etree._Element, tag: str, where: str) -> str:
    found = element.find(tag)
    if found is None or not found.get('link'):
        raise ValueError(f'invalid URDF: {where} has no <{tag} link="...">')
    return found.get('link')


def _joint(element: etree._Element, number: int) -> TreeJoint:
    name = element.get('name')
    where = f'joint {name!r}' if name else f'joint number {number}'
    if not name:
        raise ValueError(f'invalid URDF: {where} has no name')
    kind = element.get('type')
    if kind not in TYPES:
        raise ValueError(f'invalid URDF: {where} has type {kind!r}; the types are '
                         f'{", ".join(TYPES)}')
    lower, upper = -math.inf, math.inf
    limit = element.find('limit')
    if limit is not None and kind in ('revolute', 'prismatic'):
        lower = _number(limit, 'lower', 0.0, where)
        upper = _number(limit, 'upper', 0.0, where)
        if not lower <= upper:
            raise ValueError(f'invalid URDF: {where}: <limit> lower {lower:g} > upper '
                             f'{upper:g}')
    mimic = None
    found = element.find('mimic')
    if found is not None:
        if not found.get('joint'):
            raise ValueError(f'invalid URDF: {where}: <mimic> has no joint')
        mimic = Mimic(found.get('joint'), _number(found, 'multiplier', 1.0, where),
                      _number(found, 'offset', 0.0, where))
    return TreeJoint(name, kind, _link_of(element, 'parent', where),
                     _link_of(element, 'child', where), lower, upper, mimic)


def listing(names: Iterable[str]) -> str:
    """Return up to :data:`LISTED` names, quoted, and how many more."""
    names = list(names)
    shown = ', '.join(repr(name) for name in names[:LISTED])
    return shown + (f' and {len(names) - LISTED} more' if len(names) > LISTED else '')


def read_urdf(urdf_text: str | bytes) -> tuple[list[str], dict[str, TreeJoint]]:
    """
    Read the links (document order) and the joints by name of a URDF document.

    :raises ValueError: not well-formed XML, not a ``<robot>``, a link or joint
        without a name or defined twice, a joint of an unknown type or without its
        links, a limit or mimic value that is not a number; one line saying why.
    """
    if isinstance(urdf_text, str):
        urdf_text = _XML_DECLARATION.sub('', urdf_text, count=1)
    if not urdf_text.strip():
        raise ValueError('invalid URDF: the robot description is empty')
    try:
        root = etree.fromstring(urdf_text, etree.XMLParser(resolve_entities=False,
                                                           no_network=True))
    except etree.XMLSyntaxError as error:
        raise ValueError(f'invalid URDF: not well-formed XML: {_one_line(error)}') from None
    if root.tag != 'robot':
        raise ValueError(f'invalid URDF: the root element is <{root.tag}>, not <robot>')
    links: list[str] = []
    for number, element in enumerate(root.iterchildren('link'), start=1):
        name = element.get('name')
        if not name:
            raise ValueError(f'invalid URDF: link number {number} has no name')
        links.append(name)
    if len(set(links)) != len(links):
        twice = sorted({name for name in links if links.count(name) > 1})
        raise ValueError(f'invalid URDF: link(s) {listing(twice)} defined twice')
    joints: dict[str, TreeJoint] = {}
    for number, element in enumerate(root.iterchildren('joint'), start=1):
        joint = _joint(element, number)
        if joint.name in joints:
            raise ValueError(f'invalid URDF: joint {joint.name!r} defined twice')
        joints[joint.name] = joint
    return links, joints
