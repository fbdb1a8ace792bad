"""
``joint_topic`` in: the measured state seeds, re-seeds and watches the node's setpoint.

The ROS side of :mod:`traj_gen_ros.node.robot.measured_state`: a ``sensor_msgs/JointState``
subscription (best effort, so reliable and best-effort publishers both match), read off
the wire (:func:`traj_gen_ros.node.messages.wire.read_joint_state`: positions, and velocities where
the driver reports them) on the executor thread, and a timer that watches
``joint_topic_timeout``:

* the first valid message seeds the stream (:meth:`Stream.seed`): it starts there, at rest;
* a valid message while the node holds still, farther than ``state_tolerance`` from the
  held setpoint: re-seed the setpoint where the arm is from the next tick
  (:meth:`RequestHandler.reseed`), logged (warn) and counted on ``/diagnostics`` — unless
  a listener's goal waits at its end for its tolerances (an action goal: the node keeps
  commanding its end, as ``joint_trajectory_controller`` does);
* no valid message for ``joint_topic_timeout`` s: brake within the limits
  (:meth:`RequestHandler.brake`), tell the listeners (an action server ends its goal), and
  refuse requests until a message arrives.

It is also the :class:`~traj_gen_ros.node.action.monitor.MeasuredArm` an action goal's
tolerances are checked against (:meth:`positions`, :meth:`velocities`, :meth:`age`,
:meth:`reseed_to_measured`).
"""

from __future__ import annotations

import time
from typing import Protocol

import numpy as np
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.node.messages.wire import read_joint_state
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.requests.handler import RequestHandler
from traj_gen_ros.node.robot.measured_state import MeasuredState
from traj_gen_ros.node.stream.stream import Stream

#: Depth of the measured-state subscription (best effort: only the newest matters).
DEPTH = 10
#: The timeout is checked this many times per ``joint_topic_timeout`` (at most every 50 ms).
CHECKS_PER_TIMEOUT = 5


class FeedbackListener(Protocol):
    """A party told of the measured state's loss, that can keep the setpoint where it is."""

    def measured_state_lost(self, reason: str) -> None:
        """Take note: no valid measured state for ``joint_topic_timeout`` s (``reason``)."""

    def goal_waits(self) -> bool:
        """Tell whether a goal runs or waits at its end: the setpoint is not re-seeded then."""


class JointFeedback:
    """The ``joint_topic`` subscription and its timeout timer."""

    def __init__(self, node: Node, measured: MeasuredState, stream: Stream,
                 requests: RequestHandler) -> None:
        """Subscribe to ``measured.topic``; watch its timeout if one is set."""
        self.measured = measured
        self._stream = stream
        self._requests = requests
        self._logger = node.get_logger()
        self._listeners: list[FeedbackListener] = []
        self._subscription = node.create_subscription(
            JointState, measured.topic, self._on_message,
            QoSProfile(depth=DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT), raw=True)
        if measured.timeout > 0.0:
            node.create_timer(min(measured.timeout / CHECKS_PER_TIMEOUT, 0.05),
                              self._check_timeout)

    def add_listener(self, listener: FeedbackListener) -> None:
        """Tell ``listener`` when the measured state is lost; ask it before a re-seed."""
        self._listeners.append(listener)

    @property
    def lost(self) -> bool:
        """Whether no valid measured state arrived for ``joint_topic_timeout`` s."""
        return self.measured.lost

    def positions(self) -> np.ndarray | None:
        """Return where the arm is (rad, joint-set order), None before the first or if lost."""
        return None if self.measured.lost else self.measured.position

    def velocities(self) -> np.ndarray | None:
        """Return how fast the arm moves, in rad/s; None if lost or not reported."""
        return None if self.measured.lost else self.measured.velocity

    def age(self) -> float:
        """Return the seconds since the last valid measured state arrived."""
        return time.monotonic() - self.measured.received_at

    def _on_message(self, data: bytes, info: dict) -> None:
        del info
        fields = read_joint_state(data)
        if fields is None:  # not little-endian CDR: let rclpy read it
            try:
                message = deserialize_message(data, JointState)
            except Exception:  # noqa: BLE001 - a bad message must never kill the node
                self.measured.incomplete += 1
                return
            fields = (message.header.frame_id, message.name, message.position,
                      message.velocity)
        was_lost = self.measured.lost
        position = self.measured.read(fields[1], fields[2], time.monotonic(), fields[3])
        if position is None:
            return
        if was_lost:
            self._logger.info(f'measured state on {self.measured.topic} again: '
                              'accepting requests')
        if self._stream.waiting:
            self._stream.seed(position)
            self._logger.info(f'measured state on {self.measured.topic}: starting from '
                              f'{np.array2string(position, precision=4)}')
            return
        start_ns = self._stream.next_start()
        state, _ = self._stream.start_state(start_ns)
        if self._stream.moving_at(start_ns) or self.measured.deviation(state.position) is None:
            return  # the usual case, without taking the request lock
        if any(listener.goal_waits() for listener in self._listeners):
            return  # the goal's end stays commanded while the goal waits for the arm
        found = []  # the deviation of the attempt that was spliced in (the last one)

        def target(state: State, moving: bool) -> np.ndarray | None:
            return self._reseed_if_idle(state, moving, found)
        if self._requests.reseed(target):
            self._logger.warning(self.measured.note_reseed(*found[-1]))  # counted once

    def _reseed_if_idle(self, state: State, moving: bool, found: list
                        ) -> np.ndarray | None:
        """
        Where to re-seed: the measured state if idle and beyond the tolerance, else None.

        Checked again under the request lock, on every attempt (one that misses its tick
        under load is made again): the deviation goes to ``found``, counted once held.
        """
        if moving or np.any(state.velocity):
            return None
        deviation = self.measured.deviation(state.position)
        if deviation is None:
            return None
        found.append(deviation)
        return self.measured.position.copy()

    def reseed_to_measured(self, reason: str) -> bool:
        """
        Re-seed the setpoint where the arm is from the next tick, moving or not.

        What a path-tolerance violation does.

        The one step at that tick is toward the measured positions by construction (it
        ends there). Logged with ``reason``; False when no measured state is known.
        """
        if self.measured.position is None or self.measured.lost:
            return False
        position = self.measured.position.copy()
        self.measured.reseeds += 1
        self.measured.last_reseed = f'{reason}: holding where the arm is'
        self._logger.warning(self.measured.last_reseed)
        return self._requests.reseed(lambda state, moving: position)

    def _check_timeout(self) -> None:
        measured = self.measured
        if measured.lost or not measured.timed_out(time.monotonic()):
            return
        measured.lost = True
        reason = f'no measured state on {measured.topic} for {measured.timeout:g} s'
        self._logger.error(f'{reason}: braking; refusing requests until it returns')
        self._requests.brake()
        for listener in self._listeners:
            listener.measured_state_lost(reason)
