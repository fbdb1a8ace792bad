"""
Which chain of a URDF tree a :class:`~traj_gen_ros.core.kinematics.chain.Chain` is.

Before Pinocchio builds anything: ``joints`` checked against the tree (each a revolute,
continuous or prismatic joint that mimics none, named once), ``base_frame`` and
``tool_frame`` resolved to links (their defaults: the root; the end of the fixed joints
below the last joint's child), and the joints on the way between them, which must
include every joint of ``joints`` (or a joint that mimics it). Also the chain's one line
(:func:`describe_chain`). No Pinocchio here (lxml's tree only).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from traj_gen_ros.core.kinematics.urdf_tree import listing, SCALAR_TYPES, UrdfTree


@dataclass(frozen=True)
class ChainChoice:
    """
    The joints (checked), the two links, and every joint on the way between them.

    ``base_moves``: a joint of ``joints`` (or one that mimics it) is on the way up from
    ``base_frame`` (the base is not above the tool: its own pose moves with them).
    """

    joints: tuple[str, ...]
    base_frame: str
    tool_frame: str
    on_path: tuple[str, ...]
    base_moves: bool


def check_joints(tree: UrdfTree, joints: Sequence[str]) -> tuple[str, ...]:
    """
    Return ``joints`` as a tuple if each is a movable joint of ``tree``, named once.

    :raises ValueError: not a sequence of names, empty, a name twice, an unknown joint,
        a fixed/floating/planar joint, or a mimic joint (listing the movable joints).
    """
    if not isinstance(joints, str):
        joints = tuple(joints)
    if isinstance(joints, str) or not all(isinstance(name, str) for name in joints):
        raise ValueError(f'joints must be a sequence of joint names, not {joints!r}')
    movable = [joint.name for joint in tree.joints.values()
               if joint.type in SCALAR_TYPES and joint.mimic is None]
    if not joints:
        raise ValueError(f"joints is empty; the URDF's movable joints are {listing(movable)}")
    twice = sorted({name for name in joints if joints.count(name) > 1})
    if twice:
        raise ValueError(f'joints names {listing(twice)} more than once')
    for name in joints:
        joint = tree.joints.get(name)
        if joint is None:
            raise ValueError(f'unknown joint {name!r}: the URDF has no such joint; its '
                             f'movable joints are {listing(movable)}')
        if joint.type not in SCALAR_TYPES:
            raise ValueError(f'joint {name!r} is a {joint.type} joint: a chain moves only '
                             f'revolute, continuous and prismatic joints')
        if joint.mimic is not None:
            raise ValueError(f'joint {name!r} mimics {joint.mimic.leader!r}: it follows its '
                             'leader and cannot be one of the joints')
    return joints


def choose_chain(tree: UrdfTree, joints: Sequence[str], base_frame: str | None,
                 tool_frame: str | None) -> ChainChoice:
    """
    Check ``joints``, resolve the two links ('' or None: their defaults), find the way.

    :raises ValueError: as :func:`check_joints`; an unknown link (listing the links); a
        chain that does not contain every joint (naming the missing ones and the joints
        the chain has).
    """
    joints = check_joints(tree, joints)
    base = tree.root if not base_frame else tree.check_link(base_frame, 'base_frame')
    if not tool_frame:
        tool = tree.fixed_end(tree.joints[joints[-1]].child)
    else:
        tool = tree.check_link(tool_frame, 'tool_frame')
    up, down = tree.path(base, tool)
    on_path = tuple(joint.name for joint in (*up, *down))
    missing = [name for name in joints if name not in on_path
               and not set(tree.followers(name)) & set(on_path)]
    if missing:
        moving = [name for name in on_path if tree.joints[name].type != 'fixed']
        has = f'its joints are {listing(moving)}' if moving else 'it has no moving joint'
        raise ValueError(f'the chain from {base!r} to {tool!r} does not contain joint(s) '
                         f'{listing(missing)} of joints ({has}): choose a base_frame '
                         'above and a tool_frame below every joint')
    moving = set(joints).union(*(tree.followers(name) for name in joints))
    return ChainChoice(joints, base, tool, on_path, any(joint.name in moving for joint in up))


def describe_chain(tree: UrdfTree, choice: ChainChoice, held: Mapping[str, float]) -> str:
    """Return one line naming the chain: base → tool, the joints, the others on the way."""
    joints = choice.joints
    text = (f'kinematic chain {choice.base_frame} -> {choice.tool_frame}: '
            f'{len(joints)} joints {", ".join(joints)}')
    moving = [name for name in choice.on_path if name not in joints
              and tree.joints[name].type != 'fixed']
    leaders = {name: tree.mimic_root(name)[0] for name in moving
               if tree.joints[name].mimic is not None}
    following = [f'{name} mimics {leader}' for name, leader in leaders.items()
                 if leader in joints]
    others = [f'{name}={held[name]:g}' if name in held else f'{name} (neutral)'
              for name in moving if leaders.get(name) not in joints]
    if following:
        text += '; ' + ', '.join(following)
    if others:
        text += '; held on the way: ' + ', '.join(others)
    return text
