"""The stream on a fake clock: ticks, splicing at an unpublished tick or the last published one."""

import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from stream_rig import make_stream, PERIOD, tick
from traj_gen_ros.core.trajectory import Trajectory
from traj_gen_ros.node.planning.motion import held, PlannedMotion
from traj_gen_ros.node.stream.stream import Stream


def decoded(data):
    message = deserialize_message(data, JointState)
    return np.array(message.position), np.array(message.velocity)


def test_a_motion_starts_at_its_tick_if_ready_before_it_is_published():
    stream, clock, published, _ = make_stream()
    tick(stream, clock)
    start = stream.next_start()
    assert start > clock[0]
    assert stream.splice(start, held([1.0, 1.0])) == start
    assert tick(stream, clock) == start
    assert decoded(published[-1])[0].tolist() == [1.0, 1.0]
    assert stream.next_start() > clock[0]


def ramp(velocity):
    """Return a motion from (0.1, 0.2) at ``velocity`` (rad/s) for 1 s."""
    coefficients = np.zeros((1, 2, 2))
    coefficients[0, 0] = [0.1, 0.2]
    coefficients[0, 1] = velocity
    return PlannedMotion(Trajectory(np.array([0.0, 1.0]), coefficients), 'ramp',
                         np.array([0.1, 0.2]) + velocity)


def test_a_motion_planned_from_the_last_published_setpoint_takes_over_at_the_next_tick():
    stream, clock, published, _ = make_stream()
    tick(stream, clock)
    start = tick(stream, clock, late=50_000)  # the start tick went out from the hold
    assert stream.splice(start, ramp(1.0)) is None  # sampled 50 us after it
    assert stream.last_published() == start + 50_000
    assert stream.splice(start + 50_000, ramp(1.0)) == start + PERIOD
    assert tick(stream, clock, late=50_000) == start + PERIOD
    position, velocity = decoded(published[-1])
    assert np.allclose(position, [0.1 + 0.01, 0.2 + 0.01]) and velocity.tolist() == [1, 1]
    # Once a setpoint after the start is out, splicing there would jump: refused.
    assert stream.splice(start + 50_000, ramp(-1.0)) is None
    assert decoded(published[-1])[1].tolist() == [1.0, 1.0]


def test_a_non_finite_setpoint_is_never_published_the_stream_holds():
    stream, clock, published, errors = make_stream()
    tick(stream, clock)
    broken = Trajectory(np.array([0.0, 1.0]), np.full((1, 2, 2), np.nan))
    start = stream.next_start()
    assert stream.splice(start, PlannedMotion(broken, 'broken', np.zeros(2))) == start
    for _ in range(3):
        tick(stream, clock)
        position, velocity = decoded(published[-1])
        assert position.tolist() == [0.1, 0.2] and velocity.tolist() == [0.0, 0.0]
    assert len(errors) == 1 and 'non-finite' in errors[0]


def test_a_failed_command_publish_still_marks_the_setpoint_sent():
    """joint_states went out: an answer waiting on it is not held up by the command's failure."""
    clock = [10**12]
    published = []

    def failing(position, velocity):
        raise RuntimeError('command publisher gone')
    stream = Stream(held([0.1, 0.2]), ['a', 'b'], lambda: clock[0], lambda: PERIOD,
                    published.append, print, publish_command=failing)
    deadline = stream.next_start()
    clock[0] = deadline
    try:
        stream._ticks.tick(deadline)
    except RuntimeError as error:
        assert 'command publisher gone' in str(error)  # the ticker logs it
    else:
        raise AssertionError('the failure was swallowed')
    assert len(published) == 1
    assert stream.last_sent() == (deadline, False)
    assert stream.wait_published(deadline, 0.0)
