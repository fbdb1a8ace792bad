"""
What the node logs of ``~/follow_joint_trajectory`` goals: once each, at the right level.

A refused goal is one WARN line saying ``follow_joint_trajectory refused: <reason>`` (the
kind once, no second line for its abort); a cancel that braked to rest is INFO.
"""

from action_msgs.msg import GoalStatus
from node_harness import action_types, JOINTS, Probe, running_node, via_message
import numpy as np
from rclpy.action import ActionClient

FollowJointTrajectory, _ = action_types()
ACTION = '/trajectory_generator/follow_joint_trajectory'
Result = FollowJointTrajectory.Result


def send(probe, client, points, names=JOINTS):
    """Send a goal of ``[(positions, time)]``; wait for its accepted handle."""
    future = client.send_goal_async(
        FollowJointTrajectory.Goal(trajectory=via_message(names, points)))
    probe.spin_until(future.done, 10.0, 'the goal response')
    return future.result()


def result(probe, handle, timeout=20.0):
    """Wait for the result: ``(status, error_code)``."""
    future = handle.get_result_async()
    probe.spin_until(future.done, timeout, 'the result')
    return future.result().status, future.result().result.error_code


def test_the_log_says_a_refusal_once_and_a_cancel_is_not_a_warning():
    with running_node() as node:
        probe = Probe()
        client = ActionClient(probe, FollowJointTrajectory, ACTION)
        try:
            probe.wait_ready()
            probe.spin_until(lambda: client.server_is_ready(), 20.0, 'the action server')
            handle = send(probe, client, [([0.1], 1.0)], names=['elbow'])
            assert result(probe, handle, 5.0)[1] == Result.INVALID_JOINTS
            rest = probe.wait_at_rest()
            handle = send(probe, client, [(rest, 0.0), (rest + 1.0, 3.0)])
            probe.spin_until(lambda: np.abs(probe.latest().velocity).max() > 0.3, 10.0,
                             'the motion under way')
            future = handle.cancel_goal_async()
            probe.spin_until(future.done, 10.0, 'the cancel response')
            assert result(probe, handle)[0] == GoalStatus.STATUS_CANCELED
            log = probe.spin_until(lambda: 'goal canceled' in node.output() and node.output(),
                                   10.0, 'the cancel logged')
        finally:
            client.destroy()
            probe.destroy_node()
    refused = [line for line in log.splitlines() if "unknown joint 'elbow'" in line]
    assert len(refused) == 1, refused  # one line, the kind said once
    assert refused[0].startswith('[WARN]'), refused
    assert refused[0].endswith('follow_joint_trajectory refused: the goal names unknown joint '
                               f"'elbow'; known joints: {JOINTS}"), refused
    canceled = [line for line in log.splitlines() if 'goal canceled' in line]
    assert len(canceled) == 1 and canceled[0].startswith('[INFO]'), canceled
    assert canceled[0].endswith('follow_joint_trajectory goal canceled: canceled: braked to '
                                'rest'), canceled
