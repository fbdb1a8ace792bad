"""concatenate: a brake then a move as one Trajectory, sampled like the two one after the other."""

import numpy as np
import pytest
import traj_gen_ros as tg
from traj_gen_ros.core.sequences import concatenate, tail


def test_a_brake_then_a_quintic_samples_as_each_in_turn():
    brake = tg.brake([0.0, 1.0], [1.0, -0.5], 2.0)  # per-joint breakpoints, degree 2
    rest = brake.sample(brake.duration)[0][0]
    move = tg.quintic(rest, rest + [0.3, -0.2], 1.5)
    both = concatenate([brake, tg.hold(rest), move])
    assert both.degree == 5 and both.breakpoints.ndim == 1
    assert both.duration == pytest.approx(brake.duration + 1.5, abs=1e-15)
    early = np.linspace(0.0, brake.duration, 41)
    late = np.linspace(0.0, 1.5, 41)
    for mine, theirs in ((both.sample(early), brake.sample(early)),
                         (both.sample(brake.duration + late), move.sample(late))):
        for ours, reference in zip(mine, theirs, strict=True):
            np.testing.assert_allclose(ours, reference, atol=1e-12)


def test_joint_counts_must_agree():
    with pytest.raises(ValueError, match=r'joint counts differ \(\[1, 2\]\)'):
        concatenate([tg.hold([0.0]), tg.hold([0.0, 1.0])])


def test_tail_samples_as_the_trajectory_from_its_start():
    move = tg.quintic([0.0, 1.0], [0.5, -0.2], 1.5)
    both = concatenate([move, tg.quintic([0.5, -0.2], [0.0, 0.0], 1.0)])
    rest = tail(both, 1.2)
    assert rest.duration == pytest.approx(1.3, abs=1e-15)
    times = np.linspace(0.0, 1.3, 27)
    for ours, reference in zip(rest.sample(times), both.sample(1.2 + times), strict=True):
        np.testing.assert_allclose(ours, reference, atol=1e-12)
    with pytest.raises(ValueError, match=r'outside \[0, 2.5\] s'):
        tail(both, 2.6)
