"""
A stand-in robot for the tests: follows Float64MultiArray commands, publishes joint_states.

Run as a subprocess (``python test/support/standin_robot.py --help``). Each joint follows the
latest command with a first-order lag (time constant ``--tau`` s) and is published on
``--states`` at ``--rate`` Hz, names in reverse order, after ``--extra`` joints. A
message ``[index, offset]`` on ``--nudge`` moves joint ``index`` by ``offset`` rad and
holds it there for ``--nudge-hold`` s ("by hand": the commands are ignored meanwhile);
the first nudge also ends ``--omit`` (a joint left out of the messages until then).
``--offset`` adds a constant bias to the published positions (a miscalibrated encoder:
the robot follows the commands, its measured state is off by that much). Velocities are
published too (the lag's rate of change), plus ``--velocity-offset`` (a joint that does
not settle, as its driver reports it); ``--no-velocity`` publishes none, as some
drivers. A message on ``--freeze`` lists joint indices that stop following from then on
(empty: all follow again); ``[seconds]`` on ``--pause`` publishes nothing for that long
(the robot still follows: its driver's state output stalled).

``--integrate``: the commands are velocities (a ``forward_velocity_controller``): each
joint moves at ``--velocity-scale`` times the latest command (a drive that reaches only
that fraction of it; 1: exactly) from the moment it arrives until the next one (the
position is advanced at every command and every step by the time that really passed), and
publishes that velocity. It holds still until the first command; a frozen or nudged joint
does not move meanwhile.
"""

import argparse
import math
import sys
import time

import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray


def parse(argv):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--joints', default='joint_1,joint_2,joint_3,joint_4,joint_5,joint_6')
    parser.add_argument('--start', default='', help='start positions, comma separated (rad)')
    parser.add_argument('--extra', default='', help='extra joint names listed first')
    parser.add_argument('--frozen', default='', help='a joint that never follows')
    parser.add_argument('--omit', default='',
                        help='a joint left out of every message until the first nudge')
    parser.add_argument('--stop-after', type=float, default=0.0, help='s; 0: never')
    parser.add_argument('--reliability', default='reliable', choices=['reliable', 'best_effort'])
    parser.add_argument('--tau', type=float, default=0.02, help='lag time constant, s')
    parser.add_argument('--rate', type=float, default=100.0, help='Hz')
    parser.add_argument('--commands', default='/robot/commands')
    parser.add_argument('--states', default='/robot/joint_states')
    parser.add_argument('--nudge', default='/robot/nudge')
    parser.add_argument('--nudge-hold', type=float, default=1.0, help='s')
    parser.add_argument('--offset', default='',
                        help='bias of the published positions, comma separated (rad)')
    parser.add_argument('--velocity-offset', default='',
                        help='bias of the published velocities, comma separated (rad/s)')
    parser.add_argument('--no-velocity', action='store_true', help='publish no velocities')
    parser.add_argument('--freeze', default='/robot/freeze')
    parser.add_argument('--pause', default='/robot/pause')
    parser.add_argument('--integrate', action='store_true',
                        help='the commands are velocities (rad/s): integrate them')
    parser.add_argument('--velocity-scale', type=float, default=1.0,
                        help='with --integrate: the velocity reached per velocity commanded')
    return parser.parse_args(argv)


class StandInRobot(Node):
    def __init__(self, args):
        super().__init__('standin_robot')
        self.args = args
        self.names = args.joints.split(',')
        self.position = [float(x) for x in args.start.split(',')] if args.start \
            else [0.0] * len(self.names)
        self.command = None
        self.held_until = [0.0] * len(self.names)
        self.began = time.monotonic()
        self.omitting = bool(args.omit)
        self.offset = [float(x) for x in args.offset.split(',')] if args.offset \
            else [0.0] * len(self.names)
        self.velocity_offset = [float(x) for x in args.velocity_offset.split(',')] \
            if args.velocity_offset else [0.0] * len(self.names)
        self.velocity = [0.0] * len(self.names)
        self.frozen = {self.names.index(args.frozen)} if args.frozen else set()
        self.silent_until = 0.0
        reliability = (ReliabilityPolicy.RELIABLE if args.reliability == 'reliable'
                       else ReliabilityPolicy.BEST_EFFORT)
        self.publisher = self.create_publisher(
            JointState, args.states, QoSProfile(depth=10, reliability=reliability))
        self.create_subscription(Float64MultiArray, args.commands, self.on_command, 10)
        self.create_subscription(Float64MultiArray, args.nudge, self.on_nudge, 10)
        self.create_subscription(Float64MultiArray, args.freeze, self.on_freeze, 10)
        self.create_subscription(Float64MultiArray, args.pause, self.on_pause, 10)
        self.period = 1.0 / args.rate
        self.stepped = time.monotonic()
        self.create_timer(self.period, self.step)

    def on_command(self, message):
        if len(message.data) == len(self.names):
            if self.args.integrate:
                self.integrate(time.monotonic())  # the previous command up to now
            self.command = list(message.data)

    def on_nudge(self, message):
        self.omitting = False
        index, offset = int(message.data[0]), message.data[1]
        self.position[index] += offset
        self.held_until[index] = time.monotonic() + self.args.nudge_hold

    def on_freeze(self, message):
        self.frozen = {int(index) for index in message.data}

    def on_pause(self, message):
        self.silent_until = time.monotonic() + message.data[0]

    def integrate(self, now):
        """Move each joint at the scaled latest velocity command since the last call."""
        elapsed, self.stepped = now - self.stepped, now
        if self.command is None:
            return
        for index in range(len(self.names)):
            velocity = 0.0
            if index not in self.frozen and now >= self.held_until[index]:
                velocity = self.command[index] * self.args.velocity_scale
            self.position[index] += velocity * elapsed
            self.velocity[index] = velocity

    def step(self):
        now = time.monotonic()
        if self.args.stop_after and now - self.began > self.args.stop_after:
            return
        gain = 1.0 - math.exp(-self.period / self.args.tau)
        if self.args.integrate:
            self.integrate(now)
        elif self.command is not None:
            for index in range(len(self.names)):
                step = 0.0
                if index not in self.frozen and now >= self.held_until[index]:
                    step = (self.command[index] - self.position[index]) * gain
                self.position[index] += step
                self.velocity[index] = step / self.period
        if now < self.silent_until:
            return
        names = [n for n in self.args.extra.split(',') if n] + self.names[::-1]
        measured = [p + o for p, o in zip(self.position, self.offset, strict=True)]
        positions = [0.5] * (len(names) - len(self.names)) + measured[::-1]
        speeds = [v + o for v, o in zip(self.velocity, self.velocity_offset, strict=True)]
        velocities = [0.0] * (len(names) - len(self.names)) + speeds[::-1]
        if self.omitting:
            keep = [i for i, n in enumerate(names) if n != self.args.omit]
            names, positions = [names[i] for i in keep], [positions[i] for i in keep]
            velocities = [velocities[i] for i in keep]
        message = JointState(name=names, position=positions,
                             velocity=[] if self.args.no_velocity else velocities)
        message.header.stamp = self.get_clock().now().to_msg()
        self.publisher.publish(message)


def main(argv=None):
    args = parse(argv)
    rclpy.init()
    node = StandInRobot(args)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
