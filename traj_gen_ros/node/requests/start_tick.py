"""
When a new motion starts: the start tick, and planning again when the stream passes it.

Steps 3 and 4 of a request (docs/node-design.md, "When a new motion starts"): the
request is planned from the schedule's state at a stream tick not yet published and
spliced in there; if the stream published that tick while it was planned, it is planned
again from a later one (:meth:`StartTick.plan_and_splice`). No ROS here.

Units: ns of the node clock.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from dataclasses import dataclass
import statistics
import threading

import numpy as np
from traj_gen_ros.core.kinematic_limits import JointError
from traj_gen_ros.node.messages.parsing import RequestError
from traj_gen_ros.node.planning.motion import PlannedMotion, State
from traj_gen_ros.node.requests.request import Refusals, Request
from traj_gen_ros.node.settings.config import Config
from traj_gen_ros.node.stream.stream import Stream

#: A new motion starts at the first tick at least the median planning time of the last
#: RECENT requests of its kind and profile, from rest or from a moving state as this one
#: (several times longer), away, so that it is ready by then (a few hundred us: most
#: often the very next tick; with no such request yet, the slowest RECENT of any kind).
#: One whose start tick the stream published while it was planned is planned again, the
#: first QUICK_RETRIES times if the attempt took at most RETRY_PERIODS periods: from the
#: last published setpoint (to take over at the next tick) when the next tick is at least
#: a warm attempt's time away (the first time: the longest of the last RECENT such
#: re-plans of its kind, if there were any; the second: the attempt just made), else from
#: the first tick that is. Else, and after that, from a tick further away: twice the time
#: the attempt took, and at least twice the margin before (a loaded machine whose planning
#: times vary widely is caught up with), at most PLAN_ATTEMPTS times in all. Margins are
#: capped at MAX_MARGIN_NS, or twice the attempt where planning takes longer (a long tool
#: path). A plan from rest whose start passed while the schedule still rests there is
#: spliced at the next tick as it is: planned from the same setpoint, it is the same plan.
RECENT = 5
MAX_MARGIN_NS = 500_000_000
PLAN_ATTEMPTS = 6
RETRY_PERIODS = 2
QUICK_RETRIES = 2


@dataclass(frozen=True)
class Planner:
    """
    How a request is planned at its start tick: ``plan(config, state, hold_at, parsed)``.

    ``state`` is the schedule's at the start tick, ``hold_at`` where the joints a request
    does not name come to rest, ``parsed`` the request's :attr:`Request.parsed`. The
    pipeline (:func:`~traj_gen_ros.node.planning.pipeline.plan_request`) for every request
    that moves somewhere, a brake for ``~/stop`` and the action's cancel.
    """

    plan: Callable[[Config, State, np.ndarray, object], PlannedMotion]
    #: Plans from the commanded state (the speed scaling factor applied) and is never
    #: slowed (``PlannedMotion.unscaled``): a brake, at full authority. It is given the
    #: motion in effect at the start and its own time there (``Stream.running_at``) in
    #: place of ``parsed``: a line or an arc brakes along its path.
    commanded: bool = False


class StartTick:
    """The start tick of each new motion, from the recent planning times of its kind."""

    def __init__(self, stream: Stream, answers: Refusals, now_ns: Callable[[], int],
                 log_error: Callable[[str], None], elapsed_ns: Callable[[], int]) -> None:
        """Place motions in ``stream``; ``elapsed_ns`` times the planning (ns)."""
        self._stream = stream
        self._answers = answers
        self._now_ns = now_ns
        self._log_error = log_error
        self._elapsed_ns = elapsed_ns
        #: Held while a motion is spliced in and its listeners told, and by a brake from
        #: start to end: a brake (``~/stop``, a lost measured state) never waits for a
        #: request being planned, and a request planned meanwhile is not spliced after it.
        self.guard = threading.RLock()
        self._epoch = 0  # brakes so far: a request planned across one is dropped
        # How long the last requests of each (kind, profile, from a moving state), and of
        # any, took to plan (ns).
        self._recent_ns: dict[tuple[str, str, bool], collections.deque[int]] = {}
        self._any_recent_ns: collections.deque[int] = collections.deque([0], maxlen=RECENT)
        # How long the last re-plans after a quick miss (warm) took (ns).
        self._warm_ns: dict[tuple[str, str, bool], collections.deque[int]] = {}

    def preempt(self) -> None:
        """Drop every request being planned now: a brake takes over (call under :attr:`guard`)."""
        with self.guard:
            self._epoch += 1

    def plan_and_splice(self, request: Request, planner: Planner, config: Config,
                        spliced: Callable[[int, PlannedMotion], None] = lambda start, m: None
                        ) -> tuple[PlannedMotion, int, int, int] | None:
        """
        Plan and splice ``request``: the motion, when planned, its start and first tick.

        Times in ns; ``None`` when it was refused (answered ERROR).

        First from the tick at least the recent median planning time away. If the stream
        published it meanwhile, up to ``QUICK_RETRIES`` times: again from the setpoint it
        published last if the next tick is a warm re-plan's time away (the longest of the
        recent re-plans of its kind, after a cold miss; the attempt just made, after a
        warm one), else from the first tick that is, unless planning took over ``RETRY_PERIODS``
        periods (a long path); then, and after that, from a tick at least twice the last
        attempt's time and twice the last margin away.

        ``spliced(start_ns, motion)`` is called under :attr:`guard` once the motion is in.
        A request (not a brake) across which :meth:`preempt` was called is refused.
        """
        epoch = self._epoch
        # Plans from rest are closed forms; from a moving state they take several times
        # longer: each has its own history.
        moving = self._stream.moving_at(self._stream.next_start())
        key = (request.kind, config.profile, moving)
        recent_ns = self._recent_ns.setdefault(key, collections.deque(maxlen=RECENT))
        warm_ns = self._warm_ns.setdefault(key, collections.deque(maxlen=RECENT))
        # Nothing alike yet (the first preempting goal, say): the slowest of any kind.
        margin_ns = int(statistics.median(recent_ns) if recent_ns else max(self._any_recent_ns))
        start_ns = max(request.stamp_ns, self._stream.next_start(margin_ns))
        planning_ns = 0
        quick = False  # whether this attempt follows a quick miss
        for attempt in range(PLAN_ATTEMPTS):
            began = self._elapsed_ns()
            now_ns = self._now_ns()
            # A brake plans from the commanded state, the rest from the plan's own (speed
            # scaling: docs/node.md).
            state, hold_at = self._stream.start_state(start_ns, scaled=not planner.commanded)
            parsed = (self._stream.running_at(start_ns) if planner.commanded
                      else request.parsed)
            try:
                motion = planner.plan(config, state, hold_at, parsed)
            except RequestError as error:
                self._answers.refused(request, str(error))
                return None
            except JointError as error:  # the core knows joints by index: name them
                self._answers.refused(request, error.named(config.joints))
                return None
            except Exception as error:  # noqa: BLE001 - a bad request must never kill the node
                self._log_error(f'unexpected failure planning {request.kind}: {error!r}')
                self._answers.refused(request, f'internal error: {error}')
                return None
            elapsed_ns = self._elapsed_ns() - began
            if quick:  # a re-plan after a quick miss: what the next cold miss expects
                warm_ns.append(min(elapsed_ns, RETRY_PERIODS * config.period_ns))
            with self.guard:
                if not planner.commanded and self._epoch != epoch:
                    self._answers.refused(request, 'a brake (~/stop, or the measured state '
                                          'lost) came while it was planned: not executed')
                    return None
                first_ns = self._stream.splice(start_ns, motion, request)
                if first_ns is None and _at_rest(state):  # still valid if still there
                    start_ns = max(request.stamp_ns, self._stream.next_start())
                    if _same(state, self._stream.start_state(
                            start_ns, scaled=not planner.commanded)[0]):
                        first_ns = self._stream.splice(start_ns, motion, request)
                if first_ns is not None:
                    spliced(start_ns, motion)
            planning_ns += elapsed_ns
            if first_ns is not None:
                recent_ns.append(min(elapsed_ns, MAX_MARGIN_NS))
                self._any_recent_ns.append(recent_ns[-1])
                request.values['planning_time'] = f'{planning_ns * 1e-9:.6f}'
                request.values['attempts'] = str(attempt + 1)
                return motion, now_ns, start_ns, first_ns
            quick = attempt < QUICK_RETRIES and elapsed_ns <= RETRY_PERIODS * config.period_ns
            if quick:
                # A warm re-plan is faster than a cold first attempt; after a warm one,
                # the next takes about as long.
                expected_ns = elapsed_ns if attempt > 0 else max(warm_ns, default=0)
                if self._stream.next_start() - self._now_ns() >= expected_ns:
                    start_ns = max(request.stamp_ns, self._stream.last_published())
                else:
                    start_ns = max(request.stamp_ns, self._stream.next_start(expected_ns))
            else:
                # At most MAX_MARGIN_NS ahead, unless planning takes longer than that.
                margin_ns = min(max(2 * elapsed_ns, 2 * margin_ns),
                                max(MAX_MARGIN_NS, 2 * elapsed_ns))
                start_ns = max(request.stamp_ns, self._stream.next_start(margin_ns))
        self._answers.refused(request, f'the stream passed its start {PLAN_ATTEMPTS} times '
                              f'while it was planned (the last attempt took '
                              f'{elapsed_ns * 1e-9:.3f} s); resend it')
        return None


def _at_rest(state: State) -> bool:
    """Tell whether ``state`` is at rest (no velocity, no acceleration)."""
    return not (np.any(state.velocity) or np.any(state.acceleration))


def _same(first: State, second: State) -> bool:
    """Tell whether two setpoints are the same: a plan from one is a plan from the other."""
    return all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
