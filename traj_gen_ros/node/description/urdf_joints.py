"""
The joints of a URDF document, read as urdfdom reads them, and nothing else.

No ROS import. Only what the node uses is read, with lxml: each ``<joint>`` directly
under ``<robot>``, its ``name``, ``type``, ``<limit>`` and ``<mimic>``. Everything else
(links, meshes, ``<transmission>``, ``<gazebo>``, ``<ros2_control>``, a joint's
``<axis>``/``<dynamics>``/...) is not read, so an unexpanded xacro value there is no
error, as for ``robot_state_publisher`` (urdfdom never parses a ``<transmission>``).
What is read follows urdfdom (``urdf_parser/src/joint.cpp``):

- ``name`` and ``type`` are required; the type is one of ``revolute``, ``continuous``,
  ``prismatic``, ``fixed``, ``floating``, ``planar``; no two joints share a name;
- ``<limit>``: ``lower`` and ``upper`` default to 0, ``effort`` and ``velocity`` are
  required; every value given must be a number (rad or m, N·m or N, rad/s or m/s);
- ``<mimic>``: ``joint`` (the joint followed) is required, ``multiplier`` (default 1) and
  ``offset`` (default 0) must be numbers.

Every joint is checked so, used or not (urdfdom refuses the whole document over any of
them); a refusal is a one-line ``ValueError`` naming the joint, the element and the
attribute. Which joints need a ``<limit>`` is
:func:`traj_gen_ros.node.description.joint_limits.urdf_limits`' business.
"""

from __future__ import annotations

from dataclasses import dataclass
import re

from lxml import etree

TYPES = ('revolute', 'continuous', 'prismatic', 'fixed', 'floating', 'planar')
_XML_DECLARATION = re.compile(r'^\s*<\?xml[^>]*\?>')


def _one_line(text: object) -> str:
    return ' '.join(str(text).split())


@dataclass(frozen=True)
class UrdfJoint:
    """
    One ``<joint>`` as the node reads it.

    :ivar name: the joint's name.
    :ivar type: ``revolute``, ``continuous``, ``prismatic``, ``fixed``, ``floating`` or
        ``planar``.
    :ivar limit: the ``<limit>`` attributes read (``lower``, ``upper``, ``effort``,
        ``velocity``; rad or m, N·m or N, rad/s or m/s), or None without ``<limit>``.
    :ivar mimic: the name of the joint it mimics, or None.
    """

    name: str
    type: str  # noqa: A003 - the URDF attribute's name
    limit: dict[str, float] | None
    mimic: str | None


def read_joints(urdf_xml: str | bytes) -> dict[str, UrdfJoint]:
    """
    Read every ``<joint>`` of a URDF document (only what the node uses; urdfdom's rules).

    :param urdf_xml: the XML text (an XML declaration with an encoding is allowed).
    :return: the joints by name, in document order.
    :raises ValueError: not well-formed XML, not a ``<robot>``, or a joint without a name
        or type, of an unknown type, defined twice, or with a ``<limit>``/``<mimic>`` that
        lacks a required attribute or has one that is not a number; one line saying why.
    """
    if isinstance(urdf_xml, str):
        urdf_xml = _XML_DECLARATION.sub('', urdf_xml, count=1)
    if not urdf_xml.strip():
        raise ValueError('invalid URDF: the robot description is empty')
    try:
        root = etree.fromstring(urdf_xml, etree.XMLParser(resolve_entities=False,
                                                          no_network=True))
    except etree.XMLSyntaxError as error:
        raise ValueError(f'invalid URDF: not well-formed XML: {_one_line(error)}') from None
    if root.tag != 'robot':
        raise ValueError(f'invalid URDF: the root element is <{root.tag}>, not <robot>')
    joints: dict[str, UrdfJoint] = {}
    for number, element in enumerate(root.iterchildren('joint'), start=1):
        joint = _read_joint(element, number)
        if joint.name in joints:
            raise ValueError(f"invalid URDF: joint '{joint.name}' is defined twice")
        joints[joint.name] = joint
    return joints


def _read_joint(element: etree._Element, number: int) -> UrdfJoint:
    """Read one ``<joint>`` (the ``number``-th, for a nameless one's message)."""
    name = element.get('name')
    if not name:
        raise ValueError(f'invalid URDF: joint {number} (line {element.sourceline}) has no '
                         'name attribute')
    kind = element.get('type')
    if kind not in TYPES:
        given = 'no type attribute' if kind is None else f"type '{kind}'"
        raise ValueError(f"invalid URDF: joint '{name}' has {given}: the type must be one of "
                         f'{", ".join(TYPES)}')
    limit = element.find('limit')
    values = None
    if limit is not None:
        values = {key: _number(limit, name, key, default) for key, default in
                  (('lower', 0.0), ('upper', 0.0), ('effort', None), ('velocity', None))}
    mimic = element.find('mimic')
    leader = None
    if mimic is not None:
        leader = mimic.get('joint')
        if not leader:
            raise ValueError(f"invalid URDF: joint '{name}': <mimic> has no joint attribute "
                             '(the joint it follows)')
        _number(mimic, name, 'multiplier', 1.0)
        _number(mimic, name, 'offset', 0.0)
    return UrdfJoint(name, kind, values, leader)


def _number(element: etree._Element, joint: str, key: str, default: float | None) -> float:
    """Read attribute ``key`` of ``element`` as a float; ``default`` None: required."""
    text = element.get(key)
    if text is None:
        if default is None:
            raise ValueError(f"invalid URDF: joint '{joint}': <{element.tag}> has no {key} "
                             'attribute (required)')
        return default
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"invalid URDF: joint '{joint}': <{element.tag}> {key}={text!r} is "
                         'not a number') from None
