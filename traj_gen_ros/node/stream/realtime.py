"""
Thread priorities: the stream above the request and executor threads, all above normal.

The node's own threads, when the system permits it (``CAP_SYS_NICE`` or an
``RLIMIT_RTPRIO``, as on a robot computer set up for ros2_control):

* the stream thread (:mod:`traj_gen_ros.node.stream.stream`): ``SCHED_FIFO`` :data:`FIFO_PRIORITY`,
  else nice :data:`STREAM_NICE`;
* the request thread and the executor (planning): ``SCHED_FIFO``
  :data:`EXECUTOR_FIFO_PRIORITY`;
* every thread, DDS's included, starts at nice :data:`STREAM_NICE`
  (:func:`favour_calling_thread` before ``rclpy.init()``: threads inherit it).

Linux only; elsewhere, or where it is not permitted, the threads run as they are. The
environment variable :data:`PRIORITY_VARIABLE` (``realtime``, the default, or ``normal``),
read by :func:`choose_priority` before rclpy starts its threads, turns it all off: every
thread stays ``SCHED_OTHER`` at nice 0, beside a ros2_control controller manager whose
real-time loop (``SCHED_FIFO`` 50 by default) is above ours anyway.
"""

from __future__ import annotations

import os
import threading

#: Real-time priority of the stream thread under ``SCHED_FIFO`` (1 lowest, 99 highest):
#: above every normal process, below the kernel's own real-time threads.
FIFO_PRIORITY = 10
#: Real-time priority of the request and executor threads (planning): below the stream's.
EXECUTOR_FIFO_PRIORITY = 5
#: Nice value of the node's threads (the stream's when ``SCHED_FIFO`` is not permitted).
STREAM_NICE = -10
#: The environment variable that chooses the priorities, and its values.
PRIORITY_VARIABLE = 'TRAJ_GEN_ROS_PRIORITY'
PRIORITIES = ('realtime', 'normal')
_raise = [True]  # False: PRIORITY_VARIABLE=normal, every function here leaves threads alone


def choose_priority(environ: dict[str, str]) -> str:
    """
    Read :data:`PRIORITY_VARIABLE` from ``environ``; return it (``realtime`` if unset).

    ``normal`` makes every function here a no-op. ``ValueError`` naming the valid values
    for anything else.
    """
    value = environ.get(PRIORITY_VARIABLE, '') or 'realtime'
    if value not in PRIORITIES:
        raise ValueError(f'{PRIORITY_VARIABLE} must be one of {", ".join(PRIORITIES)}; '
                         f'got {value!r}')
    _raise[0] = value == 'realtime'
    return value


def favour_calling_thread(nice: int = STREAM_NICE) -> bool:
    """
    Lower the calling thread's nice value to ``nice`` if permitted; tell whether it did.

    On Linux the nice value is per thread and threads started later inherit it: called
    before ``rclpy.init()``, it covers the executor and the DDS threads too. Then a thread
    holding the GIL is seldom preempted by normal processes, so the stream thread, which
    needs the GIL for every tick, is not kept waiting for it on a busy machine.
    """
    if not _raise[0]:
        return False
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), nice)
    except (AttributeError, OSError):
        return False
    return True


def realtime_calling_thread(priority: int) -> bool:
    """
    Put the calling thread under ``SCHED_FIFO`` at ``priority`` if permitted; tell if it did.

    Needs ``CAP_SYS_NICE`` or a matching ``RLIMIT_RTPRIO``. On Linux it applies to the
    calling thread only (threads it starts later inherit it).
    """
    if not _raise[0]:
        return False
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (AttributeError, OSError):
        return False
    return True


def raise_priority(priority: int = FIFO_PRIORITY) -> str:
    """
    Give the calling thread priority over normal processes if permitted; say what it got.

    Tries ``SCHED_FIFO`` at ``priority``, then nice :data:`STREAM_NICE`. The stream thread
    sleeps between ticks and needs well under a millisecond per tick, so it cannot starve
    the machine.
    """
    if not _raise[0]:
        return f'normal priority ({PRIORITY_VARIABLE}=normal)'
    if realtime_calling_thread(priority):
        return f'SCHED_FIFO priority {priority}'
    if favour_calling_thread(STREAM_NICE):
        return f'nice {STREAM_NICE}'
    return 'normal priority (not permitted to raise it)'
