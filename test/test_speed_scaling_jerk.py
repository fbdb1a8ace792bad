"""
The speed override's ramp under ``scurve`` (a jerk limit): the commanded jerk, exactly.

The commanded state of a plan run at ``f(t)`` is ``f v(τ)``, ``f² a(τ) + ḟ v(τ)`` and jerk
``f³ j(τ) + 3 f ḟ a(τ) + f̈ v(τ)``; ``(P, f, ḟ, f̈)`` come from the
:class:`~traj_gen_ros.node.speed_scaling.TimeMap` at any time (``f`` is a polynomial on
each 1 ms step), ``v, a, j`` from the plan at ``τ = P - P(start)``: every sample below is
exact, at four times the ramp's grid. The plan: ``scurve`` 0 → (3, -1.5) rad, 1 rad/s,
2 rad/s², 10 rad/s³: 3.7 s (jerk phases of 0.2 s at its start and end, cruise from 0.5 s
to 3.2 s of its own time).
"""

import numpy as np
import pytest
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.core.trajectory import state_at
from traj_gen_ros.node.speed_ramp import jerk_at, PlanWindow
from traj_gen_ros.node.speed_scaling import TimeMap

MS = 1_000_000
T0 = 1_000_000 * MS  # 1000 s on the node clock
A_MAX = np.array([2.0, 2.0])
J_MAX = np.array([10.0, 10.0])
SUB = 4  # samples per 1 ms step


def commanded(changes: dict[int, float], end_ms: int = 20000) -> dict[str, float]:
    """
    Run the plan with the factor asked for changing at ``changes`` (ms: factor).

    Return the worst ``|jerk| / max_jerk``, ``|acceleration| / max_acceleration`` and the
    change of the acceleration between two samples over ``max_jerk × Δt`` (its
    continuity), over every joint and sample until the plan ends.
    """
    plan = min_time(np.zeros(2), np.array([3.0, -1.5]), np.ones(2), A_MAX, 'scurve',
                    max_jerk=J_MAX)
    assert plan.duration == pytest.approx(3.7)
    time_map = TimeMap(A_MAX, J_MAX, origin_ns=T0)
    start = time_map.at(T0, lambda time_ns, clock: None)[0]
    window = PlanWindow(plan)

    def plan_state(time_ns, clock):
        tau = clock - start
        return None if tau >= plan.duration else (window, tau)

    worst = {'jerk': 0.0, 'acceleration': 0.0, 'step': 0.0}
    previous = None
    step_ns = MS // SUB
    for k in range(end_ms * SUB):
        time_ns = T0 + k * step_ns
        if k % SUB == 0:  # the stream publishes, then a factor arrives
            time_map.commit(time_ns, plan_state)
            if k // SUB in changes:
                time_map.set_target(changes[k // SUB], time_ns, plan_state)
        clock, f, rate, curvature = time_map.at(time_ns, plan_state)
        tau = clock - start
        if tau >= plan.duration:
            break
        _, v, a = state_at(plan, tau)
        j = jerk_at(plan, tau)
        acceleration = f * f * a + rate * v
        jerk = f ** 3 * j + 3.0 * f * rate * a + curvature * v
        worst['jerk'] = max(worst['jerk'], float(np.max(np.abs(jerk) / J_MAX)))
        worst['acceleration'] = max(worst['acceleration'],
                                    float(np.max(np.abs(acceleration) / A_MAX)))
        if previous is not None:
            worst['step'] = max(worst['step'], float(np.max(
                np.abs(acceleration - previous) / (J_MAX * step_ns * 1e-9))))
        previous = acceleration
    else:
        raise AssertionError('the plan did not end')
    return worst


# Bursts (ms: factor) whose ramps run while the plan cruises (a = j = 0), and paused.
BURSTS = {
    'pause, resume, pause in one message each': {800: 0.0, 810: 1.0, 820: 0.0, 1300: 1.0},
    'a burst 0/1/0/1/0.3 then pause and resume': {
        800: 0.0, 810: 1.0, 820: 0.0, 1300: 1.0, 1305: 0.0, 1310: 1.0, 1700: 0.3,
        2000: 0.0, 2600: 1.0, 2602: 0.0, 3400: 1.0},
}
#: Ramps that overlap the plan's own jerk phases: the known limit (docs/node.md).
OVERLAPPING = {
    'from the start: 0 while it jerks up to speed': {50: 0.0, 700: 1.0, 705: 0.3},
    'slowed to 0.3 in its acceleration phase': {300: 0.3, 4000: 1.0},
    "a ramp into the plan's final jerk phase": {2113: 1.0, 2877: 0.3, 3983: 1.0,
                                                4470: 0.7},
}


@pytest.mark.parametrize('changes', BURSTS.values(), ids=BURSTS.keys())
def test_the_ramp_keeps_jerk_and_acceleration_within_the_limits(changes):
    worst = commanded(changes)
    assert worst['jerk'] <= 1.0 + 1e-6, worst
    assert worst['acceleration'] <= 1.0 + 1e-6, worst
    # The acceleration is continuous: it changes by at most max_jerk × Δt.
    assert worst['step'] <= 1.0 + 1e-6, worst


@pytest.mark.parametrize('changes', OVERLAPPING.values(), ids=OVERLAPPING.keys())
def test_a_ramp_over_the_plans_jerk_phases_keeps_jerk_within_the_limit(changes):
    worst = commanded(changes)
    assert worst['acceleration'] <= 1.0 + 1e-6, worst
    assert worst['jerk'] <= 1.0 + 1e-6, worst
