"""
Every profile at extreme durations, positions and limits: a right plan or a ValueError.

A plan must never be silently wrong: where float64 cannot represent a plan (coefficients
that overflow or underflow, a time-stretch that vanishes), the profile refuses with a
ValueError saying why. Where it returns, the plan is finite and meets the analytic
positions at 0, T/2 and T (rest-to-rest moves are symmetric in time: the midpoint is
halfway; through one via point at T/2 of two equal segments, that point).
"""

import numpy as np
import pytest
import traj_gen_ros as tg

EXTREMES = (1e300, 1e308, 1.7e308)
BIG = 1e308  # a limit "as good as none"


def rest_to_rest(a, b, duration=None):
    """Expect the ends, and halfway at T/2: (fraction of the duration, position) pairs."""
    return [(0.0, a), (0.5, 0.5 * (a + b)), (1.0, b)]


def through(a, m, b):
    """Expect the ends, and the via point of two equal segments at T/2."""
    return [(0.0, a), (0.5, m), (1.0, b)]


def ends(a, b):
    return [(0.0, a), (1.0, b)]


def cases():
    for x in EXTREMES:
        # Durations of x seconds for a move of 1 rad (or one of 1 rad per segment).
        yield f'cubic T={x:g}', lambda x=x: tg.cubic(0.0, 1.0, x), rest_to_rest(0.0, 1.0)
        yield f'quintic T={x:g}', lambda x=x: tg.quintic(0.0, 1.0, x), rest_to_rest(0.0, 1.0)
        yield f'lspb T={x:g}', lambda x=x: tg.lspb(0.0, 1.0, x, 1.0), rest_to_rest(0.0, 1.0)
        yield (f'scurve T={x:g}', lambda x=x: tg.scurve(0.0, 1.0, x, 1.0, 1.0, 1.0),
               ends(0.0, 1.0))
        for name in ('cubic_via', 'quintic_via'):
            yield (f'{name} T={x:g}',
                   lambda x=x, name=name: getattr(tg, name)([0.0, 1.0, 0.0], [x, x]),
                   through(0.0, 1.0, 0.0))
        yield (f'lspb_via T={x:g}', lambda x=x: tg.lspb_via([0.0, 1.0, 0.0], [x, x], 1.0),
               [(0.0, 0.0), (1.0, 0.0)])
        yield (f'scurve_via T={x:g}',
               lambda x=x: tg.scurve_via([0.0, 1.0, 0.0], [x, x], 1.0, 1.0, 1.0),
               through(0.0, 1.0, 0.0))
        for profile in tg.PROFILES:
            yield (f'plan_path {profile} T={x:g}',
                   lambda x=x, profile=profile: tg.plan_path(
                       [0.0, 1.0, 0.0], [x, x], profile, max_velocity=1.0,
                       max_acceleration=1.0, max_jerk=1.0, blend_acceleration=1.0),
                   [(0.0, 0.0), (1.0, 0.0)])
        # Positions of magnitude x, in 1 s, with limits as good as none.
        yield f'cubic q={x:g}', lambda x=x: tg.cubic(0.0, x, 1.0), rest_to_rest(0.0, x)
        yield f'cubic q=-{x:g}..{x:g}', lambda x=x: tg.cubic(-x, x, 1.0), rest_to_rest(-x, x)
        yield f'quintic q={x:g}', lambda x=x: tg.quintic(0.0, x, 1.0), rest_to_rest(0.0, x)
        yield (f'quintic q=-{x:g}..{x:g}', lambda x=x: tg.quintic(-x, x, 1.0),
               rest_to_rest(-x, x))
        yield f'lspb q={x:g}', lambda x=x: tg.lspb(0.0, x, 1.0, BIG), rest_to_rest(0.0, x)
        yield (f'scurve q={x:g}', lambda x=x: tg.scurve(0.0, x, 1.0, BIG, BIG, BIG),
               ends(0.0, x))
        for name in ('cubic_via', 'quintic_via'):
            yield (f'{name} q={x:g}',
                   lambda x=x, name=name: getattr(tg, name)([0.0, x, 0.0], [1.0, 1.0]),
                   through(0.0, x, 0.0))
        yield (f'lspb_via q={x:g}', lambda x=x: tg.lspb_via([0.0, x, 0.0], [1.0, 1.0], BIG),
               [(0.0, 0.0), (1.0, 0.0)])
        yield (f'scurve_via q={x:g}',
               lambda x=x: tg.scurve_via([0.0, x, 0.0], [1.0, 1.0], BIG, BIG, BIG),
               through(0.0, x, 0.0))
        yield f'hold q={x:g}', lambda x=x: tg.hold([x, -x]), [(0.0, [x, -x]), (1.0, [x, -x])]
        for profile in tg.PROFILES:
            yield (f'min_time {profile} q={x:g}',
                   lambda x=x, profile=profile: tg.min_time(0.0, x, 1.0, 1.0, profile,
                                                            max_jerk=1.0),
                   ends(0.0, x) if profile == 'scurve' else rest_to_rest(0.0, x))
            yield (f'min_time {profile} q={x:g}, limits 1e308',
                   lambda x=x, profile=profile: tg.min_time(0.0, x, BIG, BIG, profile,
                                                            max_jerk=BIG),
                   ends(0.0, x) if profile == 'scurve' else rest_to_rest(0.0, x))
            yield (f'plan_path {profile} q={x:g}',
                   lambda x=x, profile=profile: tg.plan_path(
                       [0.0, x, 0.0], None, profile, max_velocity=BIG,
                       max_acceleration=BIG, max_jerk=BIG),
                   [(0.0, 0.0), (1.0, 0.0)])
        # Braking from x rad/s, and from 1 rad/s at a limit of 1/x.
        yield (f'brake v={x:g}', lambda x=x: tg.brake(0.0, x, 1.0),
               [(0.0, 0.0), (0.5, 0.375 * x * x), (1.0, 0.5 * x * x)])
        yield (f'brake a={1 / x:g}', lambda x=x: tg.brake(0.0, 1.0, 1.0 / x),
               [(0.0, 0.0), (0.5, 0.375 * x), (1.0, 0.5 * x)])
        yield (f'scurve_brake v={x:g}', lambda x=x: tg.scurve_brake(0.0, x, 0.0, 1.0, 1.0),
               None)
        yield (f'scurve_brake q={x:g}', lambda x=x: tg.scurve_brake(x, 1.0, 0.0, BIG, BIG),
               None)
    # Limits far below and far above 1, from a 1 rad move.
    for limit in (1e-300, 1e300, BIG):
        for profile in tg.PROFILES:
            yield (f'min_time {profile} limits {limit:g}',
                   lambda limit=limit, profile=profile: tg.min_time(
                       0.0, 1.0, limit, limit, profile, max_jerk=limit),
                   ends(0.0, 1.0) if profile == 'scurve' else rest_to_rest(0.0, 1.0))


CASES = list(cases())


@pytest.mark.parametrize('plan, expected', [case[1:] for case in CASES],
                         ids=[case[0] for case in CASES])
def test_a_plan_is_right_or_a_value_error(plan, expected):
    # Numeric warnings are errors (pytest.ini): an overflow may not slip through either.
    try:
        trajectory = plan()
    except ValueError as error:
        assert str(error)  # says why
        return
    assert np.isfinite(trajectory.duration)
    assert np.isfinite(trajectory.coefficients).all()
    assert np.isfinite(trajectory.breakpoints).all()
    duration = trajectory.duration
    if expected is None:  # a brake: it ends at rest
        velocity = trajectory.sample(duration)[1]
        assert np.all(np.abs(velocity) <= 1e-9 * np.abs(trajectory.coefficients[0, 1]))
        return
    for fraction, position in expected:
        got = trajectory.sample(fraction * duration)[0][0]
        want = np.broadcast_to(np.asarray(position, dtype=float), got.shape)
        # Rounding is relative to the positions the plan passes (its pieces' starts).
        scale = max(np.max(np.abs(trajectory.coefficients[:, 0])),
                    np.max(np.abs([p for _, p in expected])), 1.0)
        assert np.all(np.abs(got - want) <= 1e-9 * scale), (fraction, got, want)


def test_the_known_defect_lspb_over_the_largest_durations_is_right():
    for duration in (2e154, 1e200, 1e308, 1.7e308):
        plan = tg.lspb(0.0, 1.0, duration, 1.0)
        assert plan.sample(0.5 * duration)[0][0, 0] == pytest.approx(0.5, abs=1e-12)
        assert plan.sample(duration)[0][0, 0] == pytest.approx(1.0, abs=1e-12)


def test_refusals_say_why():
    with pytest.raises(ValueError, match='polynomial segments must last at most 1e[+]60 s'):
        tg.cubic(0.0, 1.0, 1e300)
    with pytest.raises(ValueError, match='cubic: the inputs leave the range of float64'):
        tg.cubic(-1.7e308, 1.7e308, 1.0)
