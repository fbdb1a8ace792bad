"""
Late ticks without DDS: the stream holds its schedule back instead of jumping.

The stream on a fake node clock and a fake monotonic clock (the stream thread's own
activity, :meth:`Ticker.idle_ns`): a tick published long after the one before it, while
the thread did not run, continues the motion from the last setpoint as if
``LATE_PERIODS`` periods had passed; the rest of the motion ends that much later.
"""

import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
import traj_gen_ros as tg
from traj_gen_ros.core.trajectory import state_at
from traj_gen_ros.node.planning.motion import held, PlannedMotion
from traj_gen_ros.node.speed.time_map import TimeMap
from traj_gen_ros.node.stream.clock import LATE_PERIODS, StreamClock
from traj_gen_ros.node.stream.stream import Stream

PERIOD = 10_000_000  # ns: 100 Hz
STALL = 300_000_000  # ns
START = np.array([0.1, 0.2])
GOAL = np.array([1.1, -0.8])
DURATION = 1.0  # s


class Rig:
    """A stream on fake clocks, ticked by hand as its thread would tick it."""

    def __init__(self, **options):
        self.node = [10 ** 12]
        self.mono = [5 * 10 ** 9]
        self.published, self.late = [], []
        self.stream = Stream(held(START), ['a', 'b'], lambda: self.node[0], lambda: PERIOD,
                             self.published.append, print,
                             on_late=lambda gap, held_ns: self.late.append((gap, held_ns)),
                             **options)
        self.stream._ticker.monotonic_ns = lambda: self.mono[0]
        self.stream._ticker.idle_ns()  # its activity on the fake monotonic clock from now

    def wait(self, ns, stalled=False):
        """Let ``ns`` pass on both clocks; awake (a wake-up each period) unless ``stalled``."""
        step = ns if stalled else PERIOD
        while ns > 0:
            self.node[0] += min(step, ns)
            self.mono[0] += min(step, ns)
            ns -= step
            if not stalled:
                self.stream._ticker._alive()

    def tick(self, after=PERIOD, stalled=False):
        """Publish the next setpoint ``after`` ns after the last; return (stamp ns, q, v)."""
        self.wait(after, stalled)
        self.stream._publish_tick(self.node[0])
        self.stream._next_tick_ns = self.node[0] + PERIOD  # as the thread does after a tick
        message = deserialize_message(self.published[-1], JointState)
        return (message.header.stamp.sec * 10 ** 9 + message.header.stamp.nanosec,
                np.array(message.position), np.array(message.velocity))

    def start_motion(self, plan):
        """Splice ``plan`` (from START at rest) at the next tick; return that tick (ns)."""
        start = self.stream.next_start()
        self.stream.start_state(start)
        assert self.stream.splice(start, PlannedMotion(plan, 'quintic', GOAL)) == start
        return start


def test_the_clock_is_held_back_by_the_gap_beyond_the_allowance():
    clock = StreamClock()
    assert clock.sample(1000, 0, 100, 1000) == 1000 - (1000 - LATE_PERIODS * 100)
    assert (clock.held_ns, clock.late_ticks) == (800, 1)
    assert clock.at(2000) == 1200 and clock.node(1200) == 2000
    assert clock.sample(1300, 1000, 100, 300) == 400  # 3 periods, the thread idle: late
    assert (clock.held_ns, clock.late_ticks) == (900, 2)
    assert clock.sample(1500, 1300, 100, 200) == 600  # 2 periods: on time
    assert clock.sample(1800, 1500, 100, 100) == 900  # the thread was awake: followed
    assert clock.sample(5000, -(2 ** 62), 100, 10 ** 9) == 4100  # the first setpoint
    assert clock.late_ticks == 2


def test_after_a_stall_the_motion_continues_from_the_last_setpoint_and_ends_later():
    rig = Rig()
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    samples = [rig.tick() for _ in range(30)]
    stamp, q, v = samples[-1]
    assert np.allclose(q, state_at(plan, (stamp - start) * 1e-9)[0], atol=1e-12)
    assert np.linalg.norm(v) > 1.0  # in full motion
    after = rig.tick(after=STALL, stalled=True)
    assert after[0] == stamp + STALL
    # The plan LATE_PERIODS periods after the last setpoint, not STALL after it.
    expected = state_at(plan, (stamp - start + LATE_PERIODS * PERIOD) * 1e-9)
    assert np.allclose(after[1], expected[0], atol=1e-12)
    assert np.allclose(after[2], expected[1], atol=1e-12)
    held_ns = STALL - LATE_PERIODS * PERIOD
    assert rig.late == [(STALL, held_ns)]
    samples.append(after)
    while np.any(samples[-1][2]):
        assert rig.stream.last_sent() == (samples[-1][0], True)
        samples.append(rig.tick())
    stamps = np.array([s[0] for s in samples])
    positions = np.array([s[1] for s in samples])
    assert np.allclose(positions[-1], GOAL, atol=1e-12)
    # It came to rest the hold-back later than planned (to the tick).
    assert abs(stamps[-1] - (start + DURATION * 1e9 + held_ns)) <= PERIOD
    # No step larger than the plan moves in LATE_PERIODS periods.
    peak = np.abs(plan.sample(np.linspace(0.0, DURATION, 2001))[1]).max(axis=0)
    steps = np.abs(np.diff(positions, axis=0))
    assert np.all(steps <= peak * LATE_PERIODS * PERIOD * 1e-9 + 1e-12)
    assert rig.stream.last_sent() == (stamps[-1], False)  # an action goal ends there


def test_a_simulated_clock_that_moves_in_big_steps_is_followed():
    """The thread was awake all along (use_sim_time, /clock at a few Hz): no hold-back."""
    rig = Rig()
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    rig.tick()
    stamp, q, _ = rig.tick(after=STALL)
    assert np.allclose(q, state_at(plan, (stamp - start) * 1e-9)[0], atol=1e-12)
    assert rig.late == []


def test_without_hold_back_a_late_tick_samples_the_node_time():
    """command_out_type JointTrajectory: the controller runs the plans on its own clock."""
    rig = Rig(hold_back=False)
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    rig.tick()
    stamp, q, _ = rig.tick(after=STALL, stalled=True)
    assert np.allclose(q, state_at(plan, (stamp - start) * 1e-9)[0], atol=1e-12)
    assert rig.late == []


def test_while_the_stream_is_overdue_a_motion_starts_at_the_last_setpoint():
    rig = Rig()
    rig.tick()
    first = rig.start_motion(tg.quintic(START, GOAL, DURATION))
    last = rig.tick(after=first - rig.node[0])[0]
    for _ in range(20):
        last = rig.tick()[0]
    rig.wait(STALL, stalled=True)  # the stream thread is stuck: its next tick is late
    assert rig.stream.next_start(margin_ns=PERIOD) == last == rig.stream.last_published()
    state, _ = rig.stream.start_state(last)
    reverse = tg.quintic(state.position, START, DURATION, v0=state.velocity,
                         a0=state.acceleration)
    first_tick = rig.stream.splice(last, PlannedMotion(reverse, 'quintic', START))
    assert first_tick is not None and first_tick <= rig.node[0]  # out at the late tick
    stamp, q, v = rig.tick(after=0, stalled=True)
    expected = state_at(reverse, LATE_PERIODS * PERIOD * 1e-9)
    assert np.allclose(q, expected[0], atol=1e-12) and np.allclose(v, expected[1], atol=1e-12)
    assert rig.stream.wait_published(first_tick, 0.0)
    assert len(rig.late) == 1
    # Not overdue any more: the next start is a tick to come.
    assert rig.stream.next_start() > rig.stream.last_published()


def test_a_plan_made_before_a_late_tick_is_not_spliced_after_it():
    """Its start state was taken on the clock before the hold-back: planned again."""
    rig = Rig()
    rig.tick()
    rig.start_motion(tg.quintic(START, GOAL, DURATION))
    for _ in range(20):
        rig.tick()
    start = rig.stream.next_start()
    rig.stream.start_state(start)
    rig.tick(after=STALL, stalled=True)
    start_after = rig.stream.next_start()
    assert rig.stream.splice(max(start, start_after), held(GOAL)) is None
    rig.stream.start_state(start_after)
    assert rig.stream.splice(start_after, held(GOAL)) == start_after


def test_the_speed_ramp_runs_on_the_held_back_clock():
    """A factor change after a stall ramps from the last setpoint: velocity continuous."""
    limits = np.array([4.0, 4.0])
    rig = Rig(time_map=TimeMap(limits, origin_ns=10 ** 12))
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    rig.start_motion(plan)
    samples = [rig.tick() for _ in range(20)]
    samples.append(rig.tick(after=STALL, stalled=True))
    assert rig.stream.factor_in_force() == 1.0
    assert rig.stream.set_factor(0.5) == []
    samples += [rig.tick() for _ in range(40)]
    assert rig.stream.factor_in_force() == 0.5
    stamps = np.array([s[0] for s in samples]) * 1e-9
    velocities = np.array([s[2] for s in samples])
    # Between consecutive setpoints the velocity changes within the acceleration limits
    # (the plan's own, and the ramp's) over the stream clock's advance: at most
    # LATE_PERIODS periods, even across the stall.
    advance = np.minimum(np.diff(stamps), LATE_PERIODS * PERIOD * 1e-9)
    peak = np.abs(plan.sample(np.linspace(0.0, DURATION, 2001))[2]).max(axis=0)
    assert np.all(np.abs(np.diff(velocities, axis=0)) <=
                  (np.maximum(peak, limits) * advance[:, None]) * 1.01 + 1e-9)
    while np.any(samples[-1][2]):
        samples.append(rig.tick())
    assert np.allclose(samples[-1][1], GOAL, atol=1e-12)
