"""
The tree of a URDF robot description: links, joints and the path between two links.

No Pinocchio here: the links and joints are read by :mod:`.urdf_reading` (lxml, with
urdfdom's meaning); this module connects them into one tree and answers what choosing a
chain asks of it: the path between two links, mimic leaders, the default tool
(:meth:`UrdfTree.fixed_end`), where an arm ends (:meth:`UrdfTree.arm_end`) and the
joints of a chain nobody named (:func:`chain_joints`).

Units: rad or m.
"""

from __future__ import annotations

from traj_gen_ros.core.kinematics.urdf_reading import (  # noqa: F401 - re-exported
    LISTED,
    listing,
    Mimic,
    read_urdf,
    SCALAR_TYPES,
    TreeJoint,
    TYPES,
)


class UrdfTree:
    """
    The links and joints of a URDF and how they connect (a tree with one root link).

    :ivar links: every link's name, in document order.
    :ivar joints: every joint by name, in document order.
    :ivar root: the root link (the one link that is no joint's child).
    """

    def __init__(self, links: list[str], joints: dict[str, TreeJoint]) -> None:
        """Connect ``links`` by ``joints``; refuse anything but a tree with one root."""
        self.links = tuple(links)
        self.joints = joints
        known = set(links)
        self._parent_joint: dict[str, TreeJoint] = {}
        self._children: dict[str, list[TreeJoint]] = {link: [] for link in links}
        for joint in joints.values():
            for link in (joint.parent, joint.child):
                if link not in known:
                    raise ValueError(f'invalid URDF: joint {joint.name!r} names link '
                                     f'{link!r}, which the URDF does not have')
            if joint.child in self._parent_joint:
                raise ValueError(f'invalid URDF: link {joint.child!r} is the child of two '
                                 f'joints, {self._parent_joint[joint.child].name!r} and '
                                 f'{joint.name!r}')
            self._parent_joint[joint.child] = joint
            self._children[joint.parent].append(joint)
        roots = [link for link in links if link not in self._parent_joint]
        if len(roots) != 1:
            raise ValueError(f'invalid URDF: {len(roots)} root links ({listing(roots)}); a '
                             'robot description is one tree of links')
        self.root = roots[0]
        for joint in joints.values():
            if joint.mimic is not None and joint.mimic.leader not in joints:
                raise ValueError(f'invalid URDF: joint {joint.name!r} mimics joint '
                                 f'{joint.mimic.leader!r}, which the URDF does not have')
        for joint in joints.values():
            if joint.mimic is not None and joint.type in SCALAR_TYPES:
                self.mimic_root(joint.name)  # refuses circles and non-scalar leaders

    @classmethod
    def parse(cls, urdf_text: str | bytes) -> UrdfTree:
        """
        Read the tree of a URDF document (:func:`.urdf_reading.read_urdf`).

        :raises ValueError: not well-formed XML, not a ``<robot>``, a link or joint
            without a name or defined twice, a joint of an unknown type or without its
            links, a limit or mimic value that is not a number, not one tree; one line
            saying why.
        """
        return cls(*read_urdf(urdf_text))

    def check_link(self, name: str, role: str) -> str:
        """Return ``name`` if it is a link; else refuse, naming ``role`` and valid links."""
        if name not in self._children:
            raise ValueError(f'unknown {role} {name!r}: the URDF has no such link; its links '
                             f'are {listing(self.links)}')
        return name

    def joints_to(self, link: str) -> list[TreeJoint]:
        """Return the joints from the root down to ``link``, root first."""
        joints = []
        while link in self._parent_joint:
            joint = self._parent_joint[link]
            joints.append(joint)
            link = joint.parent
        return joints[::-1]

    def path(self, base: str, tool: str) -> tuple[list[TreeJoint], list[TreeJoint]]:
        """
        Return the joints on the way from ``base`` to ``tool``.

        :return: ``(up, down)``: the joints from ``base`` up to the last link the two
            share, then from there down to ``tool``; ``up`` is empty when ``base`` is an
            ancestor of ``tool`` (the usual chain).
        """
        to_base, to_tool = self.joints_to(base), self.joints_to(tool)
        shared = 0
        while (shared < min(len(to_base), len(to_tool))
               and to_base[shared] is to_tool[shared]):
            shared += 1
        return to_base[shared:][::-1], to_tool[shared:]

    def mimic_root(self, name: str) -> tuple[str, float, float]:
        """
        Return ``(leader, multiplier, offset)``: joint ``name`` as a function of a joint.

        Follows ``<mimic>`` through leaders that mimic others to one that mimics none;
        a joint that mimics none is ``(name, 1, 0)``.

        :raises ValueError: mimic joints that follow each other in a circle, or a leader
            that is not a revolute, continuous or prismatic joint.
        """
        multiplier, offset, seen = 1.0, 0.0, [name]
        mimic = self.joints[name].mimic
        while mimic is not None:
            offset += multiplier * mimic.offset
            multiplier *= mimic.multiplier
            name = mimic.leader
            if name in seen:
                raise ValueError(f'invalid URDF: the mimic joints {", ".join(seen)} follow '
                                 'each other in a circle')
            seen.append(name)
            if self.joints[name].type not in SCALAR_TYPES:
                raise ValueError(f'invalid URDF: joint {seen[-2]!r} mimics {name!r}, a '
                                 f'{self.joints[name].type} joint')
            mimic = self.joints[name].mimic
        return name, multiplier, offset

    def followers(self, leader: str) -> list[str]:
        """Return the joints that follow ``leader`` (directly or through other mimics)."""
        return [name for name, joint in self.joints.items()
                if joint.mimic is not None and joint.type in SCALAR_TYPES
                and self.mimic_root(name)[0] == leader]

    def fixed_end(self, link: str) -> str:
        """
        Return the end of the fixed joints below ``link``, if there is only one; else ``link``.

        Follows ``fixed`` joints only from ``link``; a link reached so with no ``fixed``
        child is an end. One end: that link (the Panda's ``panda_hand_tcp`` below
        ``panda_link7``); several (UR's ``ee_link`` and ``tool0``) or none: ``link``.
        """
        ends, todo = [], [link]
        while todo:
            current = todo.pop()
            fixed = [joint.child for joint in self._children[current] if joint.type == 'fixed']
            if fixed:
                todo.extend(fixed)
            else:
                ends.append(current)
        return ends[0] if len(ends) == 1 else link

    def moving_branches(self, link: str) -> list[str]:
        """
        Return the child links of ``link`` that lead to motion, in document order.

        A child counts when its joint, or a joint anywhere below it, is revolute,
        continuous or prismatic (mimic joints included).
        """
        branches = []
        for joint in self._children[link]:
            todo = [joint]
            while todo:
                current = todo.pop()
                if current.type in SCALAR_TYPES:
                    branches.append(joint.child)
                    break
                todo.extend(self._children[current.child])
        return branches

    def arm_end(self, base: str) -> str:
        """
        Return the last link of the unbranched arm below ``base``.

        From ``base`` down, as long as exactly one child leads to motion
        (:meth:`moving_branches`), follow it; stop where none does (the end of the arm) or
        several do (a gripper's fingers, a second arm). Panda: ``panda_hand``, where the
        two fingers branch off; UR10: ``wrist_3_link``.
        """
        link = base
        while True:
            branches = self.moving_branches(link)
            if len(branches) != 1:
                return link
            link = branches[0]

    def chain_joints(self, base: str, tool: str) -> list[str]:
        """
        Return the joints that move ``tool`` relative to ``base``, from ``base`` on.

        Each revolute, continuous or prismatic joint on :meth:`path`, in path order; a
        mimic joint stands for its leader (:meth:`mimic_root`), and each joint is named
        once. Fixed, floating and planar joints are left out.
        """
        up, down = self.path(base, tool)
        names: list[str] = []
        for joint in (*up, *down):
            if joint.type in SCALAR_TYPES:
                leader = self.mimic_root(joint.name)[0]
                if leader not in names:
                    names.append(leader)
        return names


def chain_joints(urdf_text: str | bytes, base_frame: str | None = None,
                 tool_frame: str | None = None) -> tuple[str, ...]:
    """
    Return the joints of the chain from ``base_frame`` to ``tool_frame``, from the base on.

    The ``joints`` a :meth:`~traj_gen_ros.core.kinematics.chain.Chain.from_urdf` of that
    chain needs when nobody names them (``traj-gen fk``/``ik``): every revolute,
    continuous or prismatic joint on the path, a mimic joint replaced by its leader
    (:meth:`UrdfTree.chain_joints`).

    :param base_frame: a link; None or '': the URDF's root link.
    :param tool_frame: a link; None or '': the end of the unbranched arm below the base
        (:meth:`UrdfTree.arm_end`: the Panda's ``panda_hand``, above its fingers); a
        chain of these joints then takes the usual default tool (the Panda's
        ``panda_hand_tcp`` or ``panda_grasptarget``).
    :raises ValueError: an invalid URDF, an unknown link (listing the links), or a chain
        with no revolute, continuous or prismatic joint (saying where the arm branches,
        when that is why).
    """
    if isinstance(urdf_text, bytes):
        urdf_text = urdf_text.decode('utf-8', errors='replace')
    tree = UrdfTree.parse(urdf_text)
    base = tree.root if not base_frame else tree.check_link(base_frame, 'base_frame')
    tool = tree.arm_end(base) if not tool_frame else tree.check_link(tool_frame, 'tool_frame')
    names = tree.chain_joints(base, tool)
    if names:
        return tuple(names)
    if tool_frame:
        raise ValueError(f'the chain from {base!r} to {tool!r} has no revolute, continuous '
                         'or prismatic joint: choose a tool_frame below a moving joint')
    branches = tree.moving_branches(tool)
    where = (f'it branches at {tool!r} into {listing(branches)}' if branches
             else f'no joint below {base!r} moves')
    raise ValueError(f'no arm below {base!r} to take the joints from: {where}; name the '
                     'tool_frame (or the joints)')
