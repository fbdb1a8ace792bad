"""
The machine's floor for a fixed-rate stream: a real-time loop with no ROS (issue 28).

Run beside a benchmark, it wakes at ``--rate`` Hz on a grid of absolute deadlines, as the
node's stream thread does (``SCHED_FIFO`` at the stream's priority where permitted, else
nice -10, else as it is; ``traj_gen_ros.node.stream.realtime``), and does nothing else. Its
gaps between wake-ups are what the machine alone does to such a thread (the hypervisor's
steal, the kernel, other real-time work): no node can stream more evenly than this. On
SIGINT or SIGTERM it prints, as JSON, its largest gap (ms), how many gaps exceeded 3
periods, and its wake-up count.

Usage: python benchmarks/wake_floor.py [--rate 500]
"""

import argparse
import json
import os
import signal
import time

from traj_gen_ros.node.stream.realtime import FIFO_PRIORITY, STREAM_NICE

#: Gaps over this many periods are counted (the joins' target).
COUNTED_PERIODS = 3


def raise_priority() -> str:
    """Take the stream thread's priority if permitted; return which one it got."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(FIFO_PRIORITY))
        return f'SCHED_FIFO {FIFO_PRIORITY}'
    except (AttributeError, PermissionError, OSError):
        pass
    try:
        os.setpriority(os.PRIO_PROCESS, 0, STREAM_NICE)
        return f'nice {STREAM_NICE}'
    except (AttributeError, PermissionError, OSError):
        return 'normal'


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=500.0, help='wake-ups per second')
    rate = parser.parse_args().rate
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(True))
    priority = raise_priority()
    period_ns = round(1e9 / rate)
    deadline = last = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
    largest, over, wakeups = 0, 0, 0
    while not stop:
        deadline += period_ns
        now = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
        if deadline > now:
            time.sleep((deadline - now) * 1e-9)
        else:  # late: the next deadline is the next one ahead, as the stream's grid
            deadline = now
        now = time.clock_gettime_ns(time.CLOCK_MONOTONIC)
        gap, last = now - last, now
        largest = max(largest, gap)
        over += gap > COUNTED_PERIODS * period_ns
        wakeups += 1
    print(json.dumps({'largest_gap_ms': round(largest * 1e-6, 3),
                      'largest_gap_periods': round(largest / period_ns, 2),
                      'gaps_over_3_periods': over, 'wakeups': wakeups, 'priority': priority}),
          flush=True)


if __name__ == '__main__':
    main()
