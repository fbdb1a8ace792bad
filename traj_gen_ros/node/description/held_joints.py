"""
The URDF's joints outside ``joints``, held where the measured state last put them.

A kinematic chain stands every joint of the URDF that the node does not command at a held
value (:meth:`Chain.hold`; 0 until one is known): the measured positions of those joints,
where ``joint_topic``'s messages name them
(:class:`~traj_gen_ros.node.robot.measured_state.MeasuredState` writes them here).

Threads: one thread writes (the executor's, as each measured message is read); each chain
is used by one thread (the request thread plans with one, the stream thread publishes
``~/tool_pose`` with another, the executor describes a third). :meth:`HeldJoints.update`
replaces one reference to an immutable mapping, so a reader sees one message's values
whole, never a mix; a :class:`HeldChain` brings its chain up to date only when its own
thread takes it (:meth:`HeldChain.take`), so a plan or a tick computes with one set of
held values from start to end, and no chain is changed by a thread that does not use it.

Units: rad or m.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any


class HeldJoints:
    """The latest measured positions of the joints outside ``joints``, by name (rad or m)."""

    def __init__(self) -> None:
        """Start with none known (the chains hold those joints at 0)."""
        self._values: Mapping[str, float] = MappingProxyType({})

    @property
    def values(self) -> Mapping[str, float]:
        """Return every position measured so far, by name (read-only; replaced whole)."""
        return self._values

    def update(self, values: Mapping[str, float]) -> None:
        """
        Take the positions of one measured message (finite, rad or m), by joint name.

        A joint named before and not now keeps its last value. Called by one thread.
        """
        self._values = MappingProxyType({**self._values, **values})


class HeldChain:
    """One thread's chain, held at the latest measured positions whenever it is taken."""

    def __init__(self, chain: Any, held: HeldJoints) -> None:
        """Wrap ``chain`` (a :class:`~traj_gen_ros.core.kinematics.Chain` of this thread)."""
        self.chain = chain
        self._held = held
        self._applied: Mapping[str, float] | None = None

    def take(self) -> Any:
        """
        Return the chain, first held at the latest measured positions if they changed.

        Call it on the chain's own thread, once per use that must see one set of values
        (a request's plan, a tick): ~8 µs when they changed (the Panda), else a compare.
        """
        values = self._held.values
        if values is not self._applied:
            self.chain.hold(values)
            self._applied = values
        return self.chain
