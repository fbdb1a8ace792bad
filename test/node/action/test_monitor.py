"""
GoalMonitor without DDS: a real ROS-free stream on a fake clock, an arm that says where it is.

The monitor ends each goal once: SUCCEEDED when the stream has sent the trajectory's end
(and the arm is within its goal tolerance), ABORTED on a path or goal tolerance, a loss of
the measured state or a replacement; it re-seeds where the arm is after a path violation,
or brakes without an arm.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from stream_rig import make_stream, PERIOD, run_until, tick
from traj_gen_ros.node.action.active_goal import ActiveGoal
from traj_gen_ros.node.action.goal_book import GoalBook
from traj_gen_ros.node.action.goal_points import (
    GOAL_TOLERANCE_VIOLATED,
    INVALID_GOAL,
    parse_trajectory_goal,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
)
from traj_gen_ros.node.action.monitor import (
    GoalMonitor,
    MONITOR_PERIOD,
    STALE_AFTER,
)
from traj_gen_ros.node.action.tolerances import ABORTED, default_tolerances, SUCCEEDED
from traj_gen_ros.node.messages.parsing import GoalRequest
from traj_gen_ros.node.planning.pipeline import plan_request
from traj_gen_ros.node.requests.request import Request
from traj_gen_ros.node.settings.config import make_config

JOINTS = ('a', 'b')
CONFIG = make_config(JOINTS, 100.0, 'quintic', 'heuristic', [1.0], [2.0], [0.0])
TARGET = np.array([0.5, 0.0])


class Handle:
    """Stands for rclpy's goal handle: records the feedback published."""

    def __init__(self):
        self.feedback = []

    def publish_feedback(self, feedback):
        self.feedback.append(feedback)


class Arm:
    """A measured arm: where it is, how old that is, and the re-seeds asked of it."""

    def __init__(self, position, reseeds=True):
        self.position = np.array(position, dtype=float)
        self.seconds_old = 0.0
        self.reseeds, self._reseeds = [], reseeds

    def positions(self):
        return self.position

    def velocities(self):
        return np.zeros(2)

    def age(self):
        return self.seconds_old

    def reseed_to_measured(self, reason):
        self.reseeds.append(reason)
        return self._reseeds


class Log:
    def __init__(self):
        self.lines = []

    def info(self, message):
        self.lines.append(('INFO', message))

    def warning(self, message):
        self.lines.append(('WARN', message))

    def error(self, message):
        self.lines.append(('ERROR', message))


def feedback_message():
    return SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(sec=0, nanosec=0)))


class Rig:
    """A 0.5 rad goal of joint 'a' spliced into the stream and watched by a monitor."""

    def __init__(self, arm=None, goal_tolerance=0.0, path_tolerance=0.0, goal_time=0.0):
        self.stream, self.clock, self.published, _ = make_stream((0.0, 0.0), JOINTS)
        tick(self.stream, self.clock)
        start_ns = self.stream.next_start()
        state, hold_at = self.stream.start_state(start_ns)
        motion = plan_request(CONFIG, state, hold_at, GoalRequest(np.array([0]), TARGET[:1]))
        goal = parse_trajectory_goal(JOINTS, ['a'], [([0.5], (), (), 1.0)], 0)
        request = Request('follow_joint_trajectory', {}, 0, goal)
        assert self.stream.splice(start_ns, motion, request) == start_ns
        self.handle = Handle()
        tolerances = default_tolerances(2, path_tolerance, goal_tolerance, goal_time, 0.0)
        self.active = ActiveGoal(self.handle, goal, request, tolerances, start_ns=start_ns,
                                 end_ns=start_ns + int(round(motion.plan.duration * 1e9)),
                                 target=motion.end)
        self.book = GoalBook(active=self.active)
        self.ended, self.brakes, self.log = [], [], Log()
        self.arm = arm
        self.monitor = GoalMonitor(
            self.stream, lambda: CONFIG, lambda: self.clock[0], self.book,
            brake=lambda: self.brakes.append(self.clock[0]), arm=arm, log=self.log,
            end=lambda handle, *end: self.ended.append(end), feedback=feedback_message)

    def until(self, time_ns):
        """
        Run the stream to ``time_ns``, the monitor every ``MONITOR_PERIOD`` as its timer does.

        Returns whether the monitor watches on.
        """
        watching = True
        while self.stream.next_start() <= time_ns:
            run_until(self.stream, self.clock, self.clock[0] + int(MONITOR_PERIOD * 1e9))
            watching = self.monitor.watch()
        return watching


def test_without_an_arm_the_goal_succeeds_once_its_end_was_sent():
    rig = Rig()
    assert rig.until(rig.active.start_ns + 500_000_000)
    assert rig.ended == [] and rig.monitor.goal_waits()
    assert len(rig.handle.feedback) >= 20  # the feedback goes out at every round
    assert rig.until(rig.active.end_ns - PERIOD)  # the end is not sent yet
    assert rig.ended == []
    assert not rig.until(rig.active.end_ns + PERIOD)
    assert rig.ended == [(SUCCEEDED, SUCCESSFUL, '')]
    assert rig.book.active is None and not rig.monitor.goal_waits()
    assert rig.log.lines == [('INFO', 'follow_joint_trajectory goal succeeded')]


def test_an_arm_off_the_goal_keeps_it_waiting_then_aborts_after_the_goal_time():
    arm = Arm([0.3, 0.0])
    rig = Rig(arm, goal_tolerance=0.02, goal_time=0.5)
    rig.until(rig.active.end_ns + 100_000_000)
    assert rig.ended == [] and rig.monitor.goal_waits()  # no re-seed meanwhile (JTC)
    rig.until(rig.active.end_ns + 450_000_000)
    assert rig.ended == []  # the goal time counts from the first setpoint at rest
    rig.until(rig.active.end_ns + 550_000_000)
    assert rig.ended == [(ABORTED, GOAL_TOLERANCE_VIOLATED,
                          "joint 'a' is at 0.3 rad, 0.2 rad from 0.5 rad: above "
                          'goal_tolerance 0.02 rad 0.5 s after the end')]
    assert not rig.monitor.goal_waits() and arm.reseeds == []


def test_an_arm_that_arrives_while_the_goal_waits_succeeds():
    arm = Arm([0.3, 0.0])
    rig = Rig(arm, goal_tolerance=0.02, goal_time=0.0)  # 0: no time limit
    rig.until(rig.active.end_ns + 2_000_000_000)
    assert rig.ended == []
    arm.position = np.array([0.49, 0.0])
    rig.until(rig.active.end_ns + 2_100_000_000)
    assert rig.ended == [(SUCCEEDED, SUCCESSFUL, '')]


@pytest.mark.parametrize('reseeds', [True, False], ids=['re-seeded', 'braked'])
def test_a_path_violation_aborts_and_re_seeds_where_the_arm_is_or_brakes(reseeds):
    arm = Arm([0.0, 0.0], reseeds)
    rig = Rig(arm, path_tolerance=0.1)
    rig.until(rig.active.start_ns + 200_000_000)
    assert rig.ended == []  # 0.2 s in, the setpoint is still within 0.1 rad of the arm
    rig.until(rig.active.start_ns + 700_000_000)
    (status, code, text), = rig.ended
    assert (status, code) == (ABORTED, PATH_TOLERANCE_VIOLATED)
    assert text.startswith("joint 'a' is at 0 rad, ") and 'above path_tolerance 0.1' in text
    assert arm.reseeds == ['path tolerance violated']
    assert len(rig.brakes) == (0 if reseeds else 1)


def test_a_stale_measured_state_is_not_judged():
    arm = Arm([0.0, 0.0])
    arm.seconds_old = STALE_AFTER + 0.01
    rig = Rig(arm, path_tolerance=0.1, goal_tolerance=0.02, goal_time=0.5)
    rig.until(rig.active.end_ns + 600_000_000)
    assert rig.ended == []  # neither its path nor its goal: ended by the timeout instead
    rig.monitor.measured_state_lost('no measured state on /robot for 0.5 s')
    assert rig.ended == [(ABORTED, PATH_TOLERANCE_VIOLATED,
                          'no measured state on /robot for 0.5 s')]


def test_a_replaced_goal_is_ended_once_even_before_its_handle_exists():
    rig = Rig()
    rig.active.handle = None  # rclpy has not made it yet
    rig.active.replaced = 'replaced by a ~/goal request (request_id 7)'
    rig.book.active, rig.book.replaced = None, [rig.active]
    assert not rig.monitor.watch()
    assert rig.ended == [] and rig.active.early_end == (
        ABORTED, INVALID_GOAL, 'replaced by a ~/goal request (request_id 7)')
    rig.monitor.end_goal(rig.active, SUCCEEDED, SUCCESSFUL, '')  # a second end: ignored
    assert rig.active.early_end[0] == ABORTED
    assert rig.log.lines == []  # logged when it is applied, with its handle
