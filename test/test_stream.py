"""The stream's schedule on a fake clock: ticks, splicing at unpublished ticks, NaN guard."""

import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from traj_gen_ros.motion_planning import held, PlannedMotion
from traj_gen_ros.stream import Stream
from traj_gen_ros.trajectory import Trajectory

PERIOD = 10_000_000


def make_stream():
    clock = [10**12]
    published, errors = [], []
    stream = Stream(held([0.1, 0.2]), ['a', 'b'], lambda: clock[0], lambda: PERIOD,
                    published.append, errors.append)
    return stream, clock, published, errors


def tick(stream, clock):
    clock[0] += PERIOD
    stream._publish_tick()


def decoded(data):
    message = deserialize_message(data, JointState)
    return np.array(message.position), np.array(message.velocity)


def test_a_motion_starts_at_an_unpublished_tick_and_never_at_a_published_one():
    stream, clock, published, _ = make_stream()
    tick(stream, clock)
    start = stream.next_start()
    assert start > clock[0]
    assert not stream.splice(clock[0], held([1.0, 1.0]))  # that tick is out already
    assert stream.splice(start, held([1.0, 1.0]))
    clock[0] = start
    stream._publish_tick()
    assert decoded(published[-1])[0].tolist() == [1.0, 1.0]
    assert stream.next_start() > clock[0]


def test_a_non_finite_setpoint_is_never_published_the_stream_holds():
    stream, clock, published, errors = make_stream()
    tick(stream, clock)
    broken = Trajectory(np.array([0.0, 1.0]), np.full((1, 2, 2), np.nan))
    assert stream.splice(stream.next_start(), PlannedMotion(broken, 'broken', np.zeros(2)))
    for _ in range(3):
        tick(stream, clock)
        position, velocity = decoded(published[-1])
        assert position.tolist() == [0.1, 0.2] and velocity.tolist() == [0.0, 0.0]
    assert len(errors) == 1 and 'non-finite' in errors[0]
