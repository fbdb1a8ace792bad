"""
One process joining the ROS graph, as ``ros2 topic pub`` and ``ros2 topic echo`` do.

For each node named on the command line: a ``/<name>/goal`` publisher and a
``/<name>/joint_states`` subscription. Waits until every publisher is matched and every
subscription has had a first message, then leaves (exit status 0; 1 after 30 s without).
Imports rclpy alone, so that it starts as lightly as those tools
(``benchmarks/joins.py`` runs it 50 times).

Usage: python benchmarks/joiner.py NODE [NODE ...]
"""

import sys
import time

import rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState

TIMEOUT = 30.0  # s


def join(names: list[str]) -> int:
    """Join, wait until matched and a first setpoint came from each node, leave."""
    rclpy.init()
    node = Node('joiner')
    received = {name: [] for name in names}
    publishers = [node.create_publisher(JointState, f'/{name}/goal', 10) for name in names]
    for name, messages in received.items():
        node.create_subscription(JointState, f'/{name}/joint_states', messages.append, 10)
    deadline = time.monotonic() + TIMEOUT
    try:
        while not (all(received.values())
                   and all(publisher.get_subscription_count() for publisher in publishers)):
            if time.monotonic() > deadline:
                return 1
            rclpy.spin_once(node, timeout_sec=0.01)
        return 0
    finally:
        node.destroy_node()
        rclpy.shutdown()


if __name__ == '__main__':
    sys.exit(join(sys.argv[1:]))
