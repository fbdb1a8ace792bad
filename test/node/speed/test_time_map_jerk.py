"""
The speed override's ramp under ``scurve`` (a jerk limit): the commanded jerk, exactly.

The commanded state of a plan run at ``f(t)`` is ``f v(τ)``, ``f² a(τ) + ḟ v(τ)`` and jerk
``f³ j(τ) + 3 f ḟ a(τ) + f̈ v(τ)``; ``(P, f, ḟ, f̈)`` come from the
:class:`~traj_gen_ros.node.speed.time_map.TimeMap` at any time (``f`` is a polynomial on
each 1 ms step), ``v, a, j`` from the plan at ``τ = P - P(start)``: every sample below is
exact, at four times the ramp's grid. The plan: ``scurve`` 0 → (3, -1.5) rad, 1 rad/s,
2 rad/s², 10 rad/s³: 3.7 s (jerk phases of 0.2 s at its start and end, cruise from 0.5 s
to 3.2 s of its own time).
"""

import numpy as np
import pytest
from traj_gen_ros import quintic_via
from traj_gen_ros.core.timing import min_time
from traj_gen_ros.core.trajectory import state_at, Trajectory
from traj_gen_ros.node.speed.plan_window import jerk_at, PlanWindow
from traj_gen_ros.node.speed.time_map import TimeMap

MS = 1_000_000
T0 = 1_000_000 * MS  # 1000 s on the node clock
A_MAX = np.array([2.0, 2.0])
J_MAX = np.array([10.0, 10.0])
SUB = 4  # samples per 1 ms step


def scurve_plan():
    """Return the module's plan: scurve 0 → (3, -1.5) rad in 3.7 s."""
    plan = min_time(np.zeros(2), np.array([3.0, -1.5]), np.ones(2), A_MAX, 'scurve',
                    max_jerk=J_MAX)
    assert plan.duration == pytest.approx(3.7)
    return plan


def commanded(changes: dict[int, float], end_ms: int = 20000, plan=None,
              a_max=A_MAX, j_max=J_MAX) -> dict[str, float]:
    """
    Run the plan with the factor asked for changing at ``changes`` (ms: factor).

    Return the worst ``|jerk| / max_jerk``, ``|acceleration| / max_acceleration`` and the
    change of the acceleration between two samples over ``max_jerk × Δt`` (its
    continuity), over every joint and sample until the plan ends; and ``paused``, the
    first time (ms) the factor is 0, if it is. A plan that jerks harder than ``max_jerk``
    itself is held to its own peak (docs/node.md).
    """
    plan = plan or scurve_plan()
    time_map = TimeMap(a_max, j_max, origin_ns=T0)
    start = time_map.at(T0, lambda time_ns, clock: None)[0]
    window = PlanWindow(plan)
    j_max = np.maximum(j_max, window.peak_jerk)

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
        worst['jerk'] = max(worst['jerk'], float(np.max(np.abs(jerk) / j_max)))
        worst['acceleration'] = max(worst['acceleration'],
                                    float(np.max(np.abs(acceleration) / a_max)))
        if previous is not None:
            worst['step'] = max(worst['step'], float(np.max(
                np.abs(acceleration - previous) / (j_max * step_ns * 1e-9))))
        previous = acceleration
        if f == 0.0 and 'paused' not in worst:
            worst['paused'] = k / SUB
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


#: An action goal's shape: quintics through five points at 0.6 s each (2.4 s), within
#: 4 rad/s² but jerking up to 53 rad/s³ itself, under a max_jerk of 20.
QUINTIC = quintic_via(np.array([[0, 0], [0.3, -0.2], [0.9, -0.5], [1.6, -0.6], [2.0, -0.5]],
                               dtype=float), np.full(4, 0.6))


@pytest.mark.parametrize('asked_ms', [300, 1000, 1700])
def test_a_pause_of_quintic_pieces_keeps_their_limits_and_comes_to_rest(asked_ms):
    """Bernstein bounds (not exact) over quintics: still within the limits, and it pauses."""
    a_max = np.array([4.0, 4.0])
    assert np.all(QUINTIC.peaks()[1] <= a_max) and QUINTIC.peak_jerk().max() > 50.0
    worst = commanded({asked_ms: 0.0, asked_ms + 1500: 1.0}, plan=QUINTIC, a_max=a_max,
                      j_max=np.full(2, 20.0))
    assert worst['acceleration'] <= 1.0 + 1e-6, worst
    assert worst['jerk'] <= 1.0 + 1e-6, worst
    assert worst['step'] <= 1.0 + 1e-6, worst
    assert asked_ms < worst['paused'] < asked_ms + 700, worst  # paused, then resumed


@pytest.mark.parametrize('splice_ms', [450, 500, 555])
def test_a_plan_spliced_in_mid_ramp_is_checked_from_the_next_step_on(splice_ms):
    """
    A brake verified against the plan before a splice is not followed on the new one.

    Plan A cruises at 1 rad/s; the factor ramps 1 → 0.5 (ticks 0.3 ms off the grid); plan
    B (1 rad/s, jerking at +10 rad/s³ from its start) is spliced at the next tick. Only
    the 1 ms step in progress at the splice was decided against A (docs/node.md).
    """
    plan_a = Trajectory(np.array([0.0, 100.0]), np.array([[[0.0], [1.0], [0.0], [0.0]]]))
    plan_b = Trajectory(np.array([0.0, 0.15, 100.0]), np.array(
        [[[0.0], [1.0], [0.0], [10.0 / 6.0]], [[0.0], [1.1125], [0.75], [0.0]]]))
    windows = PlanWindow(plan_a), PlanWindow(plan_b)
    time_map = TimeMap(A_MAX[:1], J_MAX[:1], origin_ns=T0)
    origin = time_map.at(T0, lambda time_ns, clock: None)[0]
    spliced = []  # (start ns, plan clock there)

    def plan_state(time_ns, clock):
        if spliced and time_ns >= spliced[0][0]:
            return windows[1], clock - spliced[0][1]
        return windows[0], clock - origin

    worst = 0.0
    for k in range(1500 * SUB):
        time_ns = T0 + 300_000 + k * MS // SUB
        if k % SUB == 0:
            time_map.commit(time_ns, plan_state)
            if k == 400 * SUB:
                time_map.set_target(0.5, time_ns, plan_state)
            if k == splice_ms * SUB:
                spliced.append((time_ns + MS, time_map.at(time_ns + MS, plan_state)[0]))
                time_map.forget()
        clock, f, rate, curvature = time_map.at(time_ns, plan_state)
        window, tau = plan_state(time_ns, clock)
        v, a, j = window.state(tau)
        if spliced and time_ns >= spliced[0][0] + 2 * MS:  # after the step in progress
            worst = max(worst, float(np.max(np.abs(f ** 3 * j + 3 * f * rate * a
                                                   + curvature * v) / J_MAX[:1])),
                        float(np.max(np.abs(f * f * a + rate * v) / A_MAX[:1])))
    assert 0.9 < worst <= 1.0 + 1e-6
