"""A ROS-free ``Stream`` on a fake node clock, ticked by hand (no thread, no DDS)."""

from traj_gen_ros.node.planning.motion import held
from traj_gen_ros.node.stream.stream import Stream

#: The stream period (ns): 100 Hz.
PERIOD = 10_000_000


def make_stream(start=(0.1, 0.2), names=('a', 'b')):
    """Return ``(stream, clock, published, errors)``: held at ``start``, clock ``clock[0]``."""
    clock = [10**12]
    published, errors = [], []
    stream = Stream(held(list(start)), list(names), lambda: clock[0], lambda: PERIOD,
                    published.append, errors.append)
    return stream, clock, published, errors


def tick(stream, clock, late=0):
    """Publish the next tick of the grid, sampled ``late`` ns after its deadline."""
    deadline = stream.next_start()
    clock[0] = deadline + late
    stream._ticks.tick(deadline)
    stream._ticks.next_deadline(deadline + PERIOD)  # as the stream thread does after a tick
    return deadline


def run_until(stream, clock, time_ns):
    """Publish every tick up to ``time_ns`` (ns, node clock)."""
    while stream.next_start() <= time_ns:
        tick(stream, clock)
