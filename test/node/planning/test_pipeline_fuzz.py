"""
Reliability (issue 5): generated malformed and valid requests through the planning layer.

parse -> validate -> plan, the node's own code path without ROS (FUZZ_CASES cases, default
2,000; make fuzz runs more), from a moving schedule; figures in out/reliability_fuzz.json
(the live node's layer: test/dds/test_reliability_fuzz.py).
"""

from collections import Counter
import json
import os

from fuzz_record import record
import numpy as np
from reliability_cases import (
    envelope,
    full_rows,
    JOINTS,
    make_case,
    MAX_ACCELERATION,
    MAX_VELOCITY,
    PROFILES,
    refusal_ok,
)
from traj_gen_ros.node.messages.parsing import parse_goal, parse_via, RequestError
from traj_gen_ros.node.planning.motion import held
from traj_gen_ros.node.planning.pipeline import plan_request
from traj_gen_ros.node.planning.sampling import sample_motion
from traj_gen_ros.node.settings.config import DEFAULT_MAX_JERK, make_config
from traj_gen_ros.node.stream.schedule import Schedule

CASES = int(os.environ.get('FUZZ_CASES', '2000'))


SEED = int(os.environ.get('FUZZ_SEED', '5'))


def check_plan(case, motion, state, hold, profile, a_limit, rate):
    """Judge an accepted plan: finite, starts at the state, ends at rest, limits, range."""
    plan = motion.plan
    duration = plan.duration
    times = np.unique(np.concatenate([sample_motion(motion, rate)[0],
                                      np.linspace(0.0, duration, 401)]))
    q, v, a = plan.sample(times)
    assert np.isfinite(q).all() and np.isfinite(v).all() and np.isfinite(a).all()
    scale = 1.0 + np.abs(state.position)
    assert np.all(np.abs(q[0] - state.position) <= 1e-9 * scale), 'does not start at the state'
    assert np.allclose(v[0], state.velocity, atol=1e-6), 'velocity jumps at the start'
    rows, row_times = full_rows(case, hold)
    if case.kind == 'goal' or profile != 'lspb' or len(rows) == 1:
        assert np.allclose(motion.end, rows[-1], rtol=0, atol=1e-9), 'wrong end'
    if duration > 0:
        qe, ve, _ = plan.sample(np.array([duration]))
        assert np.allclose(qe[0], motion.end, atol=1e-6 * (1 + np.abs(motion.end)).max())
        assert np.allclose(ve[0], 0.0, atol=1e-6), 'not at rest at the end'
    v_limit = np.maximum(MAX_VELOCITY, np.abs(state.velocity))
    if profile == 'scurve':  # bounded jerk: the velocity goes on by a0 |a0| / (2 j_max)
        v_limit = np.maximum(v_limit, np.abs(state.velocity + state.acceleration * np.abs(
            state.acceleration) / (2.0 * DEFAULT_MAX_JERK)))
    assert np.all(np.abs(v) <= v_limit * (1 + 1e-6) + 1e-9), 'velocity limit'
    assert np.all(np.abs(a) <= a_limit * (1 + 1e-6) + 1e-9), 'acceleration limit'
    if profile == 'scurve':  # from the state's acceleration, jerk within the default limit
        assert np.allclose(a[0], state.acceleration, atol=1e-6), 'acceleration jumps'
        assert np.all(plan.peak_jerk() <= DEFAULT_MAX_JERK * (1 + 1e-6)), 'jerk limit'
    moving = bool(np.any(state.velocity != 0.0) or
                  (profile in ('quintic', 'scurve') and np.any(state.acceleration != 0.0)))
    low, high = envelope(times, state.position, moving, rows, row_times, profile, case.kind,
                         duration)
    slack = 1e-9 * (1 + np.abs(q))
    assert np.all(q >= low - slack) and np.all(q <= high + slack), 'outside the commanded range'


def run_planning_cases(count: int, seed: int) -> dict:
    """Run ``count`` cases through planning as the node does; return the figures."""
    rng = np.random.default_rng(seed)
    schedule = Schedule(held(np.zeros(6)))
    now = 0
    figures = Counter()
    categories = Counter()
    for number in range(count):
        config = make_config(
            JOINTS, float(rng.choice([100.0, 250.0, 500.0])), str(rng.choice(PROFILES)),
            str(rng.choice(['heuristic', 'continuous'])), MAX_VELOCITY, MAX_ACCELERATION,
            float(rng.choice([0.0, 3.0])))
        now += int(rng.uniform(0.0, 0.6) * 1e9)
        state = schedule.setpoint(now)
        hold = schedule.end_position(now)
        case = make_case(rng, state.position)
        label = f'case {number} ({case.category}, {case.kind}, {config.profile})'
        try:
            if case.kind == 'goal':
                request = parse_goal(JOINTS, case.names, case.positions)
                motion = plan_request(config, state, hold, request)
            else:
                request = parse_via(JOINTS, case.names, case.points)
                motion = plan_request(config, state, hold, request)
        except RequestError as error:
            assert refusal_ok(case, str(error)), f'{label}: unexpected refusal: {error}'
            figures['refused'] += 1
            categories[f'{case.category}: refused'] += 1
            continue
        assert case.expect is None, f'{label}: accepted, expected refusal /{case.expect}/'
        try:
            check_plan(case, motion, state, hold, config.profile, config.profile_acceleration,
                       config.rate_hz)
        except AssertionError as error:
            raise AssertionError(f'{label}: {error}; case={case}; state={state}') from None
        schedule.splice(now, motion, now)
        figures['executed'] += 1
        categories[f'{case.category}: executed'] += 1
    figures['tried'] = count
    figures['seed'] = seed
    return {**figures, 'categories': dict(sorted(categories.items()))}


def test_generated_requests_through_the_planning_layer():
    figures = run_planning_cases(CASES, SEED)
    record('planning', figures)
    print('\nplanning layer:', json.dumps(figures))
    assert figures['tried'] >= 2000 or 'FUZZ_CASES' in os.environ
    assert figures['refused'] > figures['tried'] // 4 and figures['executed'] > 100
