"""
The robot's measured joint state, as the node reads it from ``joint_topic`` (no ROS here).

With ``joint_topic`` set, the arm is the reference (docs/node-design.md, "Measured state"):

* the first message naming every joint of ``joints`` (any order, other joints ignored)
  becomes the initial setpoint; until then the node streams nothing and refuses every
  request with :meth:`MeasuredState.refusal`;
* while the node holds still, a joint measured farther than ``state_tolerance`` from the
  held setpoint makes the node hold where the arm is (:meth:`MeasuredState.deviation`);
* no valid message for ``joint_topic_timeout`` s (:meth:`MeasuredState.timed_out`): the node
  brakes and refuses requests until one arrives.

* :meth:`MeasuredState.fresh_position`: the positions while at most :data:`FRESH_AGE` s
  old and not lost, for the velocity command's position correction;
* the other joints a valid message names (not in ``joints``) go to the kinematic chains
  (:class:`~traj_gen_ros.node.description.held_joints.HeldJoints`): the URDF's joints
  that the node does not command stand where they are measured (a non-finite one keeps
  its last value); only when one changed.

A message lacking a joint or carrying a non-finite position is ignored (counted). Times
are ``time.monotonic()`` seconds (the timeout is wall time even under ``use_sim_time``).

Units: rad (or m), s.
"""

from __future__ import annotations

from collections.abc import Sequence
import math

import numpy as np
from traj_gen_ros.core.validation import per_joint
from traj_gen_ros.node.description.held_joints import HeldJoints
from traj_gen_ros.node.diagnostics.status import ERROR, OK, WARN

#: A measured state older than this (s) corrects no velocity command (issue 28).
FRESH_AGE = 0.1


def check_timeout(value: float) -> float:
    """Check ``joint_topic_timeout`` (s): finite and >= 0 (0: never); return it."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or value < 0.0:
        raise ValueError(f'joint_topic_timeout must be a finite number of seconds >= 0 '
                         f'(0: never), got {value!r}')
    return float(value)


class MeasuredState:
    """The latest valid measured positions in ``joints`` order, and what they tell."""

    def __init__(self, joints: Sequence[str], topic: str, tolerance: object,
                 timeout: float, held: HeldJoints | None = None) -> None:
        """
        Read ``joints`` off messages of ``topic``; raise ``ValueError`` on a bad parameter.

        :param tolerance: ``state_tolerance``, rad: one value or one per joint, >= 0
            (0: a deviation is never re-seeded).
        :param timeout: ``joint_topic_timeout``, s (0: never).
        :param held: where the other joints' positions go (None: nowhere).
        """
        self.joints = tuple(joints)
        self.topic = topic
        self.tolerance = per_joint('state_tolerance', tolerance, len(self.joints),
                                   'non-negative', joints=self.joints)
        self.timeout = check_timeout(timeout)
        self.position: np.ndarray | None = None  # the latest valid positions (rad)
        #: The latest message's velocities (rad/s), None when it had none (or not finite).
        self.velocity: np.ndarray | None = None
        self.received_at = 0.0  # time.monotonic() of the latest valid message
        self.valid = 0
        self.incomplete = 0  # messages lacking one of the joints
        self.non_finite = 0  # messages with a non-finite position for one of the joints
        self.reseeds = 0
        self.last_reseed = ''
        self.lost = False  # the timeout has passed since the latest valid message
        self._names: tuple[str, ...] = ()
        self._columns = np.zeros(0, dtype=int)
        self._held = held
        self._other_names: tuple[str, ...] = ()  # the names not in joints, and their columns
        self._other_columns = np.zeros(0, dtype=int)
        self._other_values: list[float] | None = None  # as last given to held

    def read(self, names: Sequence[str], positions: np.ndarray, now: float,
             velocities: Sequence[float] = ()) -> np.ndarray | None:
        """
        Take one message's ``name``, ``position`` and ``velocity``; return the positions.

        Positions in joint order; ``None`` (and counted) when a joint is missing, the
        lengths disagree or a position is not finite. ``velocities`` (rad/s) are kept in
        :attr:`velocity` when there is one per name, all finite (``JointState`` may leave
        them empty); else :attr:`velocity` is None. ``now`` is ``time.monotonic()`` (s).
        """
        names = tuple(names)
        if names != self._names:  # usually the same list every message: map it once
            found = {name: column for column, name in enumerate(names)}
            if any(name not in found for name in self.joints):
                self.incomplete += 1
                return None
            self._names = names
            self._columns = np.array([found[name] for name in self.joints], dtype=int)
            ours = set(self.joints)
            others = [(column, name) for name, column in found.items() if name not in ours]
            self._other_names = tuple(name for _, name in others)
            self._other_columns = np.array([column for column, _ in others], dtype=int)
            self._other_values = None
        if len(positions) != len(names):
            self.incomplete += 1
            return None
        every = np.asarray(positions, dtype=float)
        position = every[self._columns]
        if not np.isfinite(position).all():
            self.non_finite += 1
            return None
        self.valid += 1
        self.position = position
        if self._held is not None and self._other_names:
            self._hold_others(every[self._other_columns].tolist())
        velocity = None
        if len(velocities) == len(names):
            velocity = np.asarray(velocities, dtype=float)[self._columns]
            velocity = velocity if np.isfinite(velocity).all() else None
        self.velocity = velocity
        self.received_at = now
        self.lost = False
        return position

    def _hold_others(self, values: list[float]) -> None:
        """Give the other joints' positions (rad or m) to ``held`` if any changed."""
        if values == self._other_values:  # the usual case at rest (a NaN never equals)
            return
        self._other_values = values
        self._held.update({name: value for name, value
                           in zip(self._other_names, values, strict=True)
                           if math.isfinite(value)})

    def timed_out(self, now: float) -> bool:
        """Tell whether no valid message arrived for ``timeout`` s (after the first one)."""
        return (self.timeout > 0.0 and self.position is not None
                and now - self.received_at > self.timeout)

    def fresh_position(self, now: float, max_age: float = FRESH_AGE) -> np.ndarray | None:
        """
        Give the latest positions (rad) if at most ``max_age`` s old and not lost, else None.

        ``now`` is ``time.monotonic()`` (s). Called on the stream thread while the executor
        thread reads messages: :meth:`read` replaces :attr:`position` whole (never in
        place), so the array given is one message's; a message arriving meanwhile makes the
        age judged at most one message off.
        """
        position = self.position
        if position is None or self.lost or now - self.received_at > max_age:
            return None
        return position

    def refusal(self) -> str | None:
        """Give the reason every request is refused now, or ``None``."""
        if self.position is None:
            return f'waiting for the measured state on {self.topic}'
        if self.lost:
            return f'no measured state on {self.topic} for {self.timeout:g} s'
        return None

    def deviation(self, setpoint: np.ndarray) -> tuple[int, float] | None:
        """
        Find the joint farthest beyond ``state_tolerance`` from ``setpoint`` and its offset.

        ``(joint index, measured - setpoint in rad)``, or ``None`` when every joint with a
        non-zero tolerance is within it.
        """
        if self.position is None:
            return None
        offset = self.position - setpoint
        excess = np.where(self.tolerance > 0.0, np.abs(offset) - self.tolerance, -1.0)
        index = int(np.argmax(excess))
        if excess[index] <= 0.0:
            return None
        return index, float(offset[index])

    def note_reseed(self, index: int, offset: float) -> str:
        """Count a re-seed; return its log line (naming the joint and the offset)."""
        self.reseeds += 1
        self.last_reseed = (f'{self.joints[index]} measured {offset:+.4f} rad from the '
                            f'held setpoint (state_tolerance '
                            f'{self.tolerance[index]:g}): holding where the arm is')
        return self.last_reseed

    def status(self) -> tuple[int, str, list[tuple[str, str]]]:
        """Give the ``/diagnostics`` part: level, problem ('' if OK), values."""
        level, problem = OK, ''
        if self.position is None:
            level, problem = WARN, f'waiting for the measured state on {self.topic}'
        elif self.lost:
            level, problem = ERROR, (f'no measured state on {self.topic} for '
                                     f'{self.timeout:g} s: braked, refusing requests')
        values = [('joint_topic', self.topic), ('measured messages', str(self.valid)),
                  ('measured ignored (joint missing)', str(self.incomplete)),
                  ('measured ignored (not finite)', str(self.non_finite)),
                  ('re-seeds', str(self.reseeds))]
        if self.last_reseed:
            values.append(('last re-seed', self.last_reseed))
        return level, problem, values
