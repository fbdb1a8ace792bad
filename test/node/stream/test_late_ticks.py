"""
Late ticks without DDS: the stream holds its schedule back instead of jumping.

The stream on a fake node clock and a fake monotonic clock (when the stream thread was
last on time, :meth:`Ticker.behind_ns`): a tick published long after the one before it
continues the motion from the last setpoint as if ``LATE_PERIODS`` periods had passed;
the rest of the motion ends that much later. On a simulated clock only if the thread was
kept from its schedule meanwhile: ``/clock`` may move in big steps.
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

    def __init__(self, simulated=False, **options):
        self.node = [10 ** 12]
        self.mono = [5 * 10 ** 9]
        self.published, self.late = [], []
        self.stream = Stream(held(START), ['a', 'b'], lambda: self.node[0], lambda: PERIOD,
                             self.published.append, print,
                             on_late=lambda gap, held_ns: self.late.append((gap, held_ns)),
                             simulated=lambda: simulated, **options)
        self.stream._ticker.monotonic_ns = lambda: self.mono[0]
        self.stream._ticker.behind_ns()  # on time on the fake monotonic clock from now

    def wait(self, ns, stalled=False):
        """
        Let ``ns`` pass on both clocks up to the next deadline.

        The thread waits on time (a wake-up each period, the deadline still ahead) unless
        ``stalled``: then it is kept from running all along.
        """
        step = ns if stalled else PERIOD
        while ns > 0:
            if not stalled:
                self.stream._ticker._on_time()
            self.node[0] += min(step, ns)
            self.mono[0] += min(step, ns)
            ns -= step

    def tick(self, after=PERIOD, stalled=False):
        """Publish the next setpoint ``after`` ns after the last; return (stamp ns, q, v)."""
        self.wait(after, stalled)
        self.stream._ticks.tick(self.node[0])
        self.stream._ticks.next_deadline(self.node[0] + PERIOD)  # as the thread does next
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
    behind, simulated = [0], [False]
    clock = StreamClock(lambda peek: behind[0], lambda: simulated[0])
    assert clock.sample(1000, 0, 100) == 1000 - (1000 - LATE_PERIODS * 100)
    assert (clock.held_ns, clock.late_ticks) == (800, 1)
    assert clock.at(2000) == 1200 and clock.node(1200) == 2000
    assert clock.overdue(1300, 1000, 100) and not clock.overdue(1200, 1000, 100)
    assert clock.sample(1300, 1000, 100) == 400  # 3 periods: late
    assert (clock.held_ns, clock.late_ticks) == (900, 2)
    assert clock.sample(1500, 1300, 100) == 600  # 2 periods: on time
    simulated[0] = True
    behind[0] = 100
    assert clock.sample(1800, 1500, 100) == 900  # the thread was on time: followed
    behind[0] = 300
    assert clock.sample(2100, 1800, 100) == 1100  # the thread was kept from it: late
    assert clock.sample(5000, -(2 ** 62), 100) == 4000  # the first setpoint: never late
    assert clock.late_ticks == 3
    # rate_hz 10 times higher from the next tick: the gap was still the old period's.
    clock = StreamClock()
    clock.sample(1000, 900, 100)
    assert clock.sample(1100, 1000, 10) == 1100 and clock.late_ticks == 0
    assert clock.sample(1121, 1100, 10) == 1120 and clock.late_ticks == 1
    never = StreamClock(hold_back=False)
    assert never.sample(10 ** 9, 0, 100) == 10 ** 9 and not never.overdue(10 ** 9, 0, 100)


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


def test_on_a_simulated_clock_a_tick_kept_waiting_after_its_deadline_is_late_too():
    """Woken on time, then kept from the sample (the lock, the GIL, the CPU): late too."""
    rig = Rig(simulated=True)
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    stamp = rig.tick()[0]
    rig.wait(PERIOD)  # on time up to the deadline
    rig.wait(2 * PERIOD, stalled=True)  # then kept 2 periods from the sample
    after, q, _ = rig.tick(after=0, stalled=True)
    assert after - stamp == 3 * PERIOD
    expected = state_at(plan, (stamp - start + LATE_PERIODS * PERIOD) * 1e-9)[0]
    assert np.allclose(q, expected, atol=1e-12)
    assert rig.late == [(3 * PERIOD, PERIOD)]


def test_a_simulated_clock_that_moves_in_big_steps_is_followed_a_stalled_node_is_not():
    """use_sim_time, /clock at a few Hz: the thread waited on time all along."""
    rig = Rig(simulated=True)
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    rig.tick()
    stamp, q, _ = rig.tick(after=STALL)
    assert np.allclose(q, state_at(plan, (stamp - start) * 1e-9)[0], atol=1e-12)
    assert rig.late == []
    after, q, _ = rig.tick(after=STALL, stalled=True)
    expected = state_at(plan, (stamp - start + LATE_PERIODS * PERIOD) * 1e-9)[0]
    assert np.allclose(q, expected, atol=1e-12)
    assert rig.late == [(STALL, STALL - LATE_PERIODS * PERIOD)]


def test_on_the_system_clock_every_gap_beyond_the_allowance_is_held_back():
    """Late by a few periods, the thread waiting on time meanwhile or not."""
    rig = Rig()
    rig.tick()
    plan = tg.quintic(START, GOAL, DURATION)
    start = rig.start_motion(plan)
    stamp = rig.tick()[0]
    after, q, _ = rig.tick(after=3 * PERIOD)
    expected = state_at(plan, (stamp - start + LATE_PERIODS * PERIOD) * 1e-9)[0]
    assert np.allclose(q, expected, atol=1e-12)
    assert rig.late == [(3 * PERIOD, PERIOD)]
    stamp, q, _ = rig.tick(after=LATE_PERIODS * PERIOD)  # the allowance itself: not late
    assert np.allclose(q, state_at(plan, (stamp - start - PERIOD) * 1e-9)[0], atol=1e-12)
    assert len(rig.late) == 1


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
    assert rig.stream.speed.factor_in_force() == 1.0
    assert rig.stream.speed.set_factor(0.5) == []
    samples += [rig.tick() for _ in range(40)]
    assert rig.stream.speed.factor_in_force() == 0.5
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
