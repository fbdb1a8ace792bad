"""
The request thread takes ``~/goal``-style messages itself; the executor never runs them.

A real rclpy node and a publisher in this process (isolated domain): messages published
while an executor spins the node reach the subscription's callback on the request
thread, with their message info, and the thread ends promptly when stopped.
"""

import threading
import time

from node_harness import in_process_node  # also isolates the DDS domain
import pytest
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState
from traj_gen_ros.node.requests.thread import NotForTheExecutor, RequestThread


@pytest.fixture
def node():
    with in_process_node('request_thread_test') as node:
        yield node


def test_requests_run_on_their_thread_not_the_executor(node):
    received = []  # (position, received_timestamp, thread name)
    arrived = threading.Event()

    def on_goal(message, info):
        received.append((message.position[0], info['received_timestamp'],
                         threading.current_thread().name))
        if len(received) == 3:
            arrived.set()
    subscription = node.create_subscription(JointState, 'goal', on_goal, 10,
                                            callback_group=NotForTheExecutor())
    publisher = node.create_publisher(JointState, 'goal', 10)
    requests = RequestThread(node.context, [subscription], print)
    requests.start()
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    try:
        deadline = time.monotonic() + 10.0
        while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        sent = time.time_ns()
        for position in (1.0, 2.0, 3.0):
            publisher.publish(JointState(name=['a'], position=[position]))
        while not arrived.is_set() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)  # would run on_goal here if it could
    finally:
        began = time.monotonic()
        requests.stop()
        stopped_in = time.monotonic() - began
        executor.shutdown()
    assert [position for position, _, _ in received] == [1.0, 2.0, 3.0]
    assert all(thread == 'requests' for _, _, thread in received)
    assert all(stamp >= sent for _, stamp, _ in received)  # DDS's arrival, system clock
    assert stopped_in < 1.0  # woken by its guard condition (at worst its 0.1 s timeout)
