"""Garbage collection around a request: off inside, one young collection after, between ticks."""

import gc

import pytest
from traj_gen_ros.node.requests.collection import QUIET_NS, QuietCollection

TICK_NS = 10_000_000


class FakeStream:
    """The stream's next tick at ``TICK_NS``; records the waits for a published setpoint."""

    def __init__(self, waiting=False):
        self.waiting = waiting
        self.waits = []

    def next_start(self):
        return TICK_NS

    def wait_published(self, time_ns, timeout):
        self.waits.append((time_ns, timeout, gc.isenabled()))
        return True


@pytest.fixture
def collections():
    """Record the generation of every collection; leave the collector as it was."""
    seen = []

    def record(phase, info):
        if phase == 'start':
            seen.append(info['generation'])
    enabled = gc.isenabled()
    gc.enable()
    gc.callbacks.append(record)
    yield seen
    gc.callbacks.remove(record)
    (gc.enable if enabled else gc.disable)()


def cycles(count):
    """Allocate ``count`` reference cycles: garbage only a collection frees."""
    for _ in range(count):
        node = []
        node.append(node)


def test_no_automatic_collection_inside_one_young_collection_after(collections):
    stream = FakeStream()
    quiet = QuietCollection(stream, lambda: TICK_NS - 2 * QUIET_NS, lambda: 0.02)
    with quiet.deferred():
        assert not gc.isenabled()
        cycles(20 * gc.get_threshold()[0])  # would have triggered about 20 collections
        assert collections == []
    assert collections == [1]  # generations 0 and 1, once
    assert gc.isenabled()
    assert stream.waits == []  # the next tick 2 ms away: collected at once


def test_a_tick_due_within_the_quiet_time_goes_out_first(collections):
    stream = FakeStream()
    quiet = QuietCollection(stream, lambda: TICK_NS - QUIET_NS // 2, lambda: 0.02)
    with quiet.deferred():
        pass
    # Waited for the setpoint of that very tick, still without automatic collection.
    assert stream.waits == [(TICK_NS, 0.02, False)]
    assert collections == [1] and gc.isenabled()


def test_a_stream_that_publishes_nothing_yet_is_not_waited_for(collections):
    stream = FakeStream(waiting=True)
    quiet = QuietCollection(stream, lambda: TICK_NS - 1, lambda: 0.02)
    with quiet.deferred():
        pass
    assert stream.waits == [] and collections == [1]


def test_a_failing_request_turns_the_collector_back_on(collections):
    quiet = QuietCollection(FakeStream(), lambda: 0, lambda: 0.02)
    with pytest.raises(RuntimeError), quiet.deferred():
        raise RuntimeError('planning failed')
    assert gc.isenabled() and collections == [1]


def test_a_collector_turned_off_outside_stays_off(collections):
    stream = FakeStream()
    quiet = QuietCollection(stream, lambda: TICK_NS - 1, lambda: 0.02)
    gc.disable()
    with quiet.deferred(), quiet.deferred():  # nested: the outer block decides
        cycles(5 * gc.get_threshold()[0])
    assert not gc.isenabled() and collections == [] and stream.waits == []
