"""
When a request's plan is late for its start tick.

The real handler, stream and answers on a fake clock (no stream thread: the test publishes
the ticks), the answers in an rclpy node.

A plan that the stream overtakes is planned again from the setpoint published last,
exactly as published, and takes over at the next tick; ``~/trajectory`` is the plan from
that setpoint (its start and first point).
"""

import threading

from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import in_process_node  # also isolates the DDS domain
import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.node.messages.parsing import parse_goal
from traj_gen_ros.node.planning.motion import held
from traj_gen_ros.node.planning.pipeline import plan_request
from traj_gen_ros.node.requests.answers import Answers
from traj_gen_ros.node.requests.handler import RequestHandler, SAMPLE_AFTER_FIRST_NS
from traj_gen_ros.node.requests.request import Request
from traj_gen_ros.node.requests.start_tick import MAX_MARGIN_NS, Planner
from traj_gen_ros.node.settings.config import make_config
from traj_gen_ros.node.stream.stream import Stream
from trajectory_msgs.msg import JointTrajectory

PERIOD = 10_000_000  # 100 Hz
JOINTS = ['a', 'b']
CONFIG = make_config(joints=JOINTS, rate_hz=100.0, profile='cubic',
                     via_velocities='heuristic', max_velocity=1.0, max_acceleration=2.0,
                     lspb_acceleration=0.0)


@pytest.fixture
def node():
    with in_process_node('request_timing_test') as node:
        yield node


class Rig:
    """A stream on a fake clock that publishes a tick whenever the test says so."""

    def __init__(self, node):
        self.clock = [10**12]
        self.states, self.statuses, self.trajectories = [], [], []
        self.stream = Stream(held([0.0, 0.0]), JOINTS, lambda: self.clock[0], lambda: PERIOD,
                             self.states.append, print)
        self.answers = Answers(node, lambda: JOINTS)
        self.answers.report = lambda level, text, values, log=True: \
            self.statuses.append((level, text, values))
        self.answers.publish_trajectory = self.trajectories.append
        # Planning is timed on the fake clock too: only the ticks a planner lets out count.
        self.handler = RequestHandler(lambda: CONFIG, self.stream, self.answers,
                                      lambda: self.clock[0], print, lambda: self.clock[0])

    def tick(self, late=0):
        deadline = self.stream.next_start()
        self.clock[0] = deadline + late
        self.stream._ticks.tick(deadline)
        self.stream._ticks.next_deadline(deadline + PERIOD)
        return deadline

    def state(self, index=-1):
        message = deserialize_message(self.states[index], JointState)
        stamp = message.header.stamp.sec * 10**9 + message.header.stamp.nanosec
        return stamp, np.array(message.position), np.array(message.velocity)


def goal(rig, positions, planning_ticks):
    """Execute a goal whose planning lets ``planning_ticks`` ticks go out meanwhile."""
    request = parse_goal(JOINTS, JOINTS, positions)
    calls = []

    def slow_planner(config, state, hold_at, parsed):
        calls.append(state)
        if len(calls) == 1:
            for _ in range(planning_ticks):
                rig.tick(late=30_000)
        return plan_request(config, state, hold_at, parsed)
    values = rig.answers.values('goal', '', 0)
    return rig.handler.execute(Request('goal', values, 0, request), Planner(slow_planner)), calls


def test_a_plan_on_time_starts_at_its_tick(node):
    rig = Rig(node)
    rig.tick()
    motion, calls = goal(rig, [0.5, -0.2], planning_ticks=0)
    assert motion is not None and len(calls) == 1
    start = rig.tick()
    trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
    assert trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec == start
    assert rig.statuses[-1][0] == DiagnosticStatus.OK


def test_a_plan_the_stream_overtook_restarts_from_the_published_setpoint(node):
    rig = Rig(node)
    rig.tick()
    first, _ = goal(rig, [0.5, -0.2], planning_ticks=0)  # a moving arm
    for _ in range(20):
        rig.tick()
    motion, calls = goal(rig, [-0.3, 0.4], planning_ticks=1)  # its start tick went out
    assert motion is not None and len(calls) == 2
    published_at, position, velocity = rig.state()
    # The second attempt starts from exactly the setpoint published while it planned.
    assert calls[1].position.tolist() == position.tolist()
    assert calls[1].velocity.tolist() == velocity.tolist()
    assert np.all(velocity != 0.0)
    # It takes over at the next tick. ~/trajectory is the plan from its start: stamped at
    # the published setpoint, which is its first point.
    trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
    stamp = trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec
    rig.tick()
    assert stamp == published_at
    assert trajectory.points[0].positions.tolist() == position.tolist()
    assert trajectory.points[0].velocities.tolist() == velocity.tolist()
    stamp_ns, new_position, new_velocity = rig.state()
    elapsed = (stamp_ns - published_at) * 1e-9
    expected = motion.plan.sample(elapsed)
    assert np.allclose(new_position, expected[0][0], atol=1e-12)
    assert np.allclose(new_velocity, expected[1][0], atol=1e-12)
    # Within the limits from the published setpoint to the first new one.
    assert np.all(np.abs(new_velocity - velocity) <= CONFIG.max_acceleration * elapsed * 1.001)
    point = trajectory.points[1]
    assert np.allclose(point.positions, motion.plan.sample(1.0 / CONFIG.rate_hz)[0][0],
                       atol=1e-12)
    assert rig.statuses[-1][0] == DiagnosticStatus.OK


def test_a_plan_from_rest_the_stream_overtook_starts_at_the_next_tick_unplanned(node):
    """From rest and still at rest there, a plan is the same plan a tick later."""
    rig = Rig(node)
    rig.tick()
    motion, calls = goal(rig, [0.5, -0.2], planning_ticks=3)
    assert motion is not None and len(calls) == 1  # not planned again
    start = rig.tick()
    trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
    assert trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec == start
    assert trajectory.points[0].velocities.tolist() == [0.0, 0.0]
    assert rig.statuses[-1][0] == DiagnosticStatus.OK


def test_a_request_overtaken_every_time_is_refused_with_the_reason(node):
    rig = Rig(node)
    rig.tick()
    goal(rig, [100.0, -100.0], planning_ticks=0)  # long on its way: every plan ages
    for _ in range(5):
        rig.tick()
    request = parse_goal(JOINTS, JOINTS, [-0.5, 0.2])
    attempts = []

    def always_late(config, state, hold_at, parsed):
        # Each attempt three times as long as the last, from beyond the longest margin: past
        # any start it was given (the margins are twice the last attempt).
        attempts.append(state)
        for _ in range((MAX_MARGIN_NS // PERIOD + 2) * 3 ** (len(attempts) - 1)):
            rig.tick()
        return plan_request(config, state, hold_at, parsed)
    values = rig.answers.values('goal', '', 0)
    assert rig.handler.execute(Request('goal', values, 0, request), Planner(always_late)) is None
    level, text, _ = rig.statuses[-1]
    assert level == DiagnosticStatus.ERROR and 'passed its start 6 times' in text
    rig.tick()
    assert np.all(rig.state()[1] > [0.0, -np.inf]) and rig.state()[1][1] < 0.0  # on its way


def test_margins_from_rest_and_from_a_moving_state_are_kept_apart(node):
    # Plans from a moving state take longer than from rest: a slow one must not push the
    # next from-rest start away, nor a fast one from rest leave a moving start too close.
    rig = Rig(node)
    rig.tick()

    def timed_goal(positions, planning_ns):
        request = parse_goal(JOINTS, JOINTS, positions)

        def planner(config, state, hold_at, parsed):
            rig.clock[0] += planning_ns  # on the fake clock, no tick goes out meanwhile
            return plan_request(config, state, hold_at, parsed)
        now = rig.clock[0]
        values = rig.answers.values('goal', '', 0)
        motion = rig.handler.execute(Request('goal', values, 0, request), Planner(planner))
        assert motion is not None
        trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
        return trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec - now

    def until_at_rest():
        while not np.all(rig.state()[2] == 0.0) or len(rig.states) < 2:
            rig.tick()

    assert timed_goal([0.1, 0.1], 0) <= PERIOD  # from rest: the next tick
    for _ in range(3):
        rig.tick()
    assert timed_goal([0.3, -0.2], 25_000_000) <= PERIOD  # moving, no history yet
    for _ in range(3):
        rig.tick()
    slow = timed_goal([0.4, -0.3], 25_000_000)  # moving: 25 ms of history
    assert 25_000_000 <= slow <= 25_000_000 + PERIOD
    until_at_rest()
    assert timed_goal([0.0, 0.0], 0) <= PERIOD  # from rest again: its own history, 0
    for _ in range(3):
        rig.tick()
    assert timed_goal([0.2, 0.2], 0) >= 25_000_000  # moving: the moving plans' median


def test_after_a_warm_miss_the_next_attempt_starts_one_attempt_away(node):
    # Two attempts overtaken, each while one tick goes out (a period of planning): the
    # third starts at the first tick that far away, not twice as far.
    rig = Rig(node)
    rig.tick()
    goal(rig, [0.5, -0.2], planning_ticks=0)  # a moving arm
    for _ in range(5):
        rig.tick()
    request = parse_goal(JOINTS, JOINTS, [-0.3, 0.4])
    calls = []

    def overtaken_twice(config, state, hold_at, parsed):
        calls.append(rig.clock[0])
        if len(calls) <= 2:
            rig.tick(late=30_000)
        return plan_request(config, state, hold_at, parsed)
    values = rig.answers.values('goal', '', 0)
    assert rig.handler.execute(Request('goal', values, 0, request), Planner(overtaken_twice))
    assert len(calls) == 3
    trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
    start = trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec
    second_attempt = calls[2] - calls[1]  # how long the (warm) second attempt took
    assert second_attempt <= start - calls[2] <= second_attempt + PERIOD


def test_a_cold_miss_replans_from_the_published_setpoint_only_if_a_re_plan_fits(node):
    # Re-plans of this kind took up to 0.9 periods: after a cold miss with the next tick
    # only half a period away, the second attempt plans for the first tick that far, not
    # for the next one (which it would miss: a third attempt). Before any re-plan, the
    # next tick. The longest of the recent re-plans counts, not the last.
    rig = Rig(node)
    rig.tick()
    goal(rig, [0.5, -0.2], planning_ticks=0)  # a moving arm
    rig.tick()
    warm = 9 * PERIOD // 10

    def missed_once(positions, replan_ns=warm):
        request = parse_goal(JOINTS, JOINTS, positions)
        calls = []

        def planner(config, state, hold_at, parsed):
            calls.append((rig.clock[0], state))
            if len(calls) == 1:
                rig.tick(late=PERIOD // 2)  # the start tick went out: a miss
            else:
                rig.clock[0] += replan_ns  # a warm re-plan, no tick meanwhile
            return plan_request(config, state, hold_at, parsed)
        values = rig.answers.values('goal', '', 0)
        assert rig.handler.execute(Request('goal', values, 0, request), Planner(planner))
        trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
        return (trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec,
                calls)

    start, calls = missed_once([-0.3, 0.4])  # no re-plan seen yet
    assert len(calls) == 2 and start == rig.state(-1)[0]  # from the setpoint published
    for replan_ns in (PERIOD // 5, PERIOD // 5):  # the 0.9-period one is still recent
        for _ in range(3):
            rig.tick()
        start, calls = missed_once([0.3, -0.4], replan_ns)
        assert len(calls) == 2
        assert warm <= start - calls[1][0] < warm + PERIOD  # ready for it: no third attempt
        assert start > rig.state(-1)[0]  # not from the setpoint published while planned
        assert np.all(calls[1][1].velocity != 0.0)


def test_a_re_plan_after_a_long_first_attempt_is_not_taken_for_a_quick_one(node):
    # A first attempt of 3 periods (a long path) is retried from a tick further away; that
    # re-plan (0.6 periods) is not what a quick miss can expect: the next cold miss, with
    # the next tick half a period away, still plans from the setpoint published.
    rig = Rig(node)
    rig.tick()
    goal(rig, [0.5, -0.2], planning_ticks=0)  # a moving arm
    rig.tick()

    def two_attempts(positions, first):
        request = parse_goal(JOINTS, JOINTS, positions)
        calls = []

        def planner(config, state, hold_at, parsed):
            calls.append(rig.clock[0])
            if len(calls) == 1:
                first()
            else:
                rig.clock[0] += 6 * PERIOD // 10  # a re-plan, no tick meanwhile
            return plan_request(config, state, hold_at, parsed)
        values = rig.answers.values('goal', '', 0)
        assert rig.handler.execute(Request('goal', values, 0, request), Planner(planner))
        assert len(calls) == 2
        trajectory = deserialize_message(rig.trajectories[-1], JointTrajectory)
        return trajectory.header.stamp.sec * 10**9 + trajectory.header.stamp.nanosec

    def long_path():
        for late in (0, 0, 30_000):
            rig.tick(late=late)
    start = two_attempts([-0.3, 0.4], long_path)
    assert start - rig.state(-1)[0] >= 5 * PERIOD  # twice the long attempt's time away
    while rig.state(-1)[0] < start:
        rig.tick()
    assert two_attempts([0.3, -0.4], lambda: rig.tick(late=PERIOD // 2)) == rig.state(-1)[0]


@pytest.mark.parametrize('due', [SAMPLE_AFTER_FIRST_NS // 2, 4 * SAMPLE_AFTER_FIRST_NS])
def test_trajectory_is_sampled_after_a_first_setpoint_that_is_due_soon(node, due):
    # Sampling holds the GIL: a first setpoint due within SAMPLE_AFTER_FIRST_NS goes out
    # before ~/trajectory is sampled; one due later is not waited for.
    rig = Rig(node)
    rig.tick()
    rig.clock[0] = rig.stream.next_start() - due
    request = parse_goal(JOINTS, JOINTS, [0.5, -0.2])
    waiting = threading.Event()
    wait_published = rig.stream.wait_published

    def waits(time_ns, timeout):
        waiting.set()
        return wait_published(time_ns, timeout)
    rig.stream.wait_published = waits
    trajectories_at_tick = []

    def publish_the_tick_when_waited_for():
        if waiting.wait(5.0):
            trajectories_at_tick.append(len(rig.trajectories))
            rig.tick()
    ticker = threading.Thread(target=publish_the_tick_when_waited_for)
    ticker.start()
    values = rig.answers.values('goal', '', 0)
    try:
        motion = rig.handler.execute(Request('goal', values, 0, request),
                                     Planner(plan_request))
    finally:
        ticker.join(5.0)
    assert motion is not None and rig.statuses[-1][0] == DiagnosticStatus.OK
    assert trajectories_at_tick == [0 if due <= SAMPLE_AFTER_FIRST_NS else 1]
    assert len(rig.trajectories) == 1
