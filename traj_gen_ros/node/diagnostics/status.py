"""
What the node reports on ``/diagnostics``, built without ROS.

:mod:`traj_gen_ros.node.diagnostics.publisher` publishes it about once a second as one
``diagnostic_msgs/DiagnosticStatus``; this module holds the pieces and builds its level,
message and key/values:

* :class:`RateMeter` counts the setpoints the stream publishes (one integer increment per
  tick, on the stream thread) and turns the count into the achieved rate over the window
  since the last report; it also counts the late ticks, where the stream held its
  schedule back (:mod:`traj_gen_ros.node.stream.clock`), for the log and ``/diagnostics``;
* :class:`RequestCounts` counts the answers: accepted, refused, superseded;
* :class:`MotionLog` knows the accepted motions and their start times, so it can say
  which one is in progress and how long it has left (or ``holding``);
* :func:`node_status` puts them together: WARN when the achieved rate is below
  ``RATE_WARN_FRACTION`` of ``rate_hz``, when the last robot description was refused, or
  when the setpoint has a joint outside its position range, OK otherwise; the measured
  state's own status (``joint_topic``,
  :meth:`traj_gen_ros.node.robot.measured_state.MeasuredState.status`) can raise it to ERROR.

Units: Hz, s, ns where named.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

OK = 0
WARN = 1
ERROR = 2
#: The achieved stream rate below this fraction of ``rate_hz`` is a warning.
RATE_WARN_FRACTION = 0.9
#: A window shorter than this (s) gives no rate (the first report, a jump of the clock).
MIN_WINDOW = 0.5


class RateMeter:
    """Count published setpoints; report the achieved rate per window (Hz)."""

    def __init__(self, now_s: float) -> None:
        """Start the first window at ``now_s`` (s, the node clock)."""
        self.count = 0
        self._window = (now_s, 0)
        #: Late ticks since start, and how long the schedule was held back by them (ns).
        self.late_ticks = 0
        self.held_back_ns = 0
        self._late = (0, 0, 0)  # since the last late_report: ticks, longest gap, held back

    def late(self, gap_ns: int, held_ns: int) -> None:
        """
        Count a late tick (the stream thread): ``gap_ns`` after the setpoint before it.

        ``held_ns`` of that gap held the schedule back (ns, node clock).
        """
        self.late_ticks += 1
        self.held_back_ns += held_ns
        ticks, longest, held = self._late
        self._late = (ticks + 1, max(longest, gap_ns), held + held_ns)

    def late_report(self) -> tuple[int, int, int]:
        """Return the late ticks since the last call, the longest gap and the hold-back (ns)."""
        report, self._late = self._late, (0, 0, 0)
        return report

    def wrap(self, publish: Callable[[bytes], None]) -> Callable[[bytes], None]:
        """Return ``publish`` counting each call (the stream thread's only extra work)."""
        def counted(data: bytes) -> None:
            publish(data)
            self.count += 1
        return counted

    def rate(self, now_s: float) -> float | None:
        """Return the setpoints per second since the last call (None: window too short)."""
        start, count = self._window
        elapsed = now_s - start
        if elapsed < MIN_WINDOW:
            if elapsed < 0.0:
                self._window = (now_s, self.count)
            return None
        current = self.count
        self._window = (now_s, current)
        return (current - count) / elapsed


@dataclass
class RequestCounts:
    """How many requests were answered accepted (OK), refused (ERROR), superseded (WARN)."""

    accepted: int = 0
    refused: int = 0
    superseded: int = 0

    def count(self, level: int, values: dict[str, str]) -> None:
        """Count one ``~/status`` answer of ``level`` (0 OK, 1 WARN, 2 ERROR)."""
        if level == OK:
            self.accepted += 1
        elif level == WARN:
            self.superseded += int(values.get('superseded', '1'))
        else:
            self.refused += 1


class MotionLog:
    """The accepted motions on the node clock: which one runs now, and what follows."""

    def __init__(self) -> None:
        """Start holding."""
        self._motions: list[tuple[int, str, float]] = []  # (start ns, profile, duration s)

    def record(self, start_ns: int, profile: str, duration: float) -> None:
        """Note a motion spliced in at ``start_ns``: it replaces what would start later."""
        kept = [motion for motion in self._motions if motion[0] < start_ns]
        self._motions = kept[-1:] + [(start_ns, profile, duration)]

    def describe(self, now_ns: int, time_left: Callable[[int], float] | None = None) -> str:
        """
        Say what runs at ``now_ns``: ``quintic, 1.234 s left`` or ``holding``.

        ``time_left(now_ns)``: the plan time left (s) on the plan clock (speed scaling:
        :meth:`~traj_gen_ros.node.stream.speed_view.SpeedView.time_left`); None:
        duration − time since its start.
        """
        started = [motion for motion in self._motions if motion[0] <= now_ns]
        text = 'holding'
        if started:
            start_ns, profile, duration = started[-1]
            left = (duration - (now_ns - start_ns) * 1e-9 if time_left is None
                    else time_left(now_ns))
            if left > 0.0:
                text = f'{profile}, {left:.3f} s left'
        waiting = [motion for motion in self._motions if motion[0] > now_ns]
        if waiting:
            start_ns, profile, _ = waiting[-1]
            text += f'; next: {profile} in {(start_ns - now_ns) * 1e-9:.3f} s'
        return text


def node_status(*, rate: float | None, rate_hz: float, joints: int, profile: str,
                motion: str, limits: str, urdf_source: str, urdf_problem: str,
                counts: RequestCounts, outside: str = '',
                feedback: tuple[int, str, list[tuple[str, str]]] | None = None,
                late: tuple[int, int] = (0, 0),
                kinematics: str = '') -> tuple[int, str, list[tuple[str, str]]]:
    """
    Build the node's diagnostic status: ``(level, message, [(key, value), …])``.

    :param rate: achieved stream rate over the last window, Hz (None: not measured yet).
    :param rate_hz: the configured rate, Hz.
    :param motion: :meth:`MotionLog.describe`.
    :param limits: the limits in force and their sources (``describe_sources``).
    :param urdf_source: where the URDF in force came from, or ``none``.
    :param urdf_problem: why the last robot description was refused ('' if none was).
    :param outside: the setpoint's joints outside their range (``outside_ranges``), or ''.
    :param feedback: the measured state's level, problem and values, or None (standalone).
    :param late: the late ticks since start and how long they held the schedule back (ns).
    :param kinematics: the kinematic chain in force, or why a URDF gives none ('' without
        a URDF).
    """
    problems = []
    feedback_level = OK
    if feedback is not None and feedback[1]:
        feedback_level = feedback[0]
        problems.append(feedback[1])
    if rate is not None and rate < RATE_WARN_FRACTION * rate_hz:
        problems.append(f'stream rate {rate:.1f} Hz is below '
                        f'{RATE_WARN_FRACTION:.0%} of rate_hz {rate_hz:g}')
    if urdf_problem:
        problems.append(urdf_problem)
    if outside:
        problems.append(f'{outside}: it may hold there or move toward its range')
    measured = 'not measured yet' if rate is None else f'{rate:.1f}'
    if problems:
        level, message = max(WARN, feedback_level), '; '.join(problems)
    else:
        shown = f'{rate:.1f}' if rate is not None else f'{rate_hz:g}'
        level, message = OK, f'streaming {joints} joints at {shown} Hz; {motion}'
    values = [
        ('stream rate (Hz)', measured),
        ('rate_hz', f'{rate_hz:g}'),
        ('joints', str(joints)),
        ('profile', profile),
        ('motion', motion),
        ('limits', limits),
        ('robot_description', urdf_source),
        ('accepted', str(counts.accepted)),
        ('refused', str(counts.refused)),
        ('superseded', str(counts.superseded)),
        ('late ticks', str(late[0])),
        ('held back (s)', f'{late[1] * 1e-9:.3f}'),
    ]
    if urdf_problem:
        values.append(('robot_description refused', urdf_problem))
    if kinematics:
        values.append(('kinematics', kinematics))
    if outside:
        values.append(('outside range', outside))
    if feedback is not None:
        values += feedback[2]
    return level, message, values
