"""MeasuredState: a driver's JointState read by name, deviations, the timeout (no ROS)."""

import math

import numpy as np
import pytest
from traj_gen_ros.node.diagnostics.status import ERROR, OK, WARN
from traj_gen_ros.node.robot.measured_state import check_timeout, MeasuredState

JOINTS = ('shoulder', 'elbow', 'wrist')


def measured(tolerance=(0.05,), timeout=0.5):
    return MeasuredState(JOINTS, '/robot/joint_states', list(tolerance), timeout)


def test_positions_are_read_by_name_in_any_order_extra_joints_ignored():
    state = measured()
    names = ['gripper', 'wrist', 'shoulder', 'elbow']
    position = state.read(names, [9.0, 0.3, 0.1, 0.2], 5.0, [0.0, 3.0, 1.0, 2.0])
    assert position.tolist() == [0.1, 0.2, 0.3]
    assert state.velocity.tolist() == [1.0, 2.0, 3.0]
    assert (state.received_at, state.valid, state.lost) == (5.0, 1, False)
    # The same names again (mapped once) and a message without velocities.
    assert state.read(names, [9.0, 0.6, 0.4, 0.5], 5.1).tolist() == [0.4, 0.5, 0.6]
    assert state.velocity is None


def test_a_message_lacking_a_joint_or_not_finite_is_ignored_and_counted():
    state = measured()
    assert state.read(['shoulder', 'elbow'], [0.1, 0.2], 1.0) is None
    assert state.read(JOINTS, [0.1, 0.2], 1.0) is None  # lengths disagree
    assert state.read(JOINTS, [0.1, math.nan, 0.3], 1.0) is None
    assert (state.incomplete, state.non_finite, state.valid) == (2, 1, 0)
    assert state.position is None
    assert state.read(JOINTS, [0.1, 0.2, 0.3], 1.0, [0.0, math.inf, 0.0]) is not None
    assert state.velocity is None  # a non-finite velocity is dropped, the positions kept


def test_the_deviation_names_the_joint_farthest_beyond_its_tolerance():
    state = measured(tolerance=(0.05, 0.2, 0.0))  # 0: never re-seeded for the wrist
    assert state.deviation(np.zeros(3)) is None  # nothing measured yet
    state.read(JOINTS, [0.04, -0.3, 5.0], 1.0)
    index, offset = state.deviation(np.zeros(3))
    assert (index, offset) == (1, -0.3)  # elbow: 0.1 beyond; the wrist is not checked
    assert state.deviation(np.array([0.0, -0.2, 0.0])) is None  # exactly at 0.1: within
    line = state.note_reseed(index, offset)
    assert line == ('elbow measured -0.3000 rad from the held setpoint (state_tolerance '
                    '0.2): holding where the arm is')
    assert state.reseeds == 1 and state.last_reseed == line


def test_the_timeout_counts_from_the_last_valid_message_and_refusals_say_why():
    state = measured(timeout=0.5)
    assert state.refusal() == 'waiting for the measured state on /robot/joint_states'
    assert not state.timed_out(100.0)  # no message yet: waiting, not lost
    state.read(JOINTS, [0.0, 0.0, 0.0], 10.0)
    assert state.refusal() is None
    assert not state.timed_out(10.5) and state.timed_out(10.5 + 1e-9)
    state.lost = True
    assert state.refusal() == 'no measured state on /robot/joint_states for 0.5 s'
    state.read(JOINTS, [0.0, 0.0, 0.0], 11.0)
    assert not state.lost  # a valid message ends the loss
    assert not measured(timeout=0.0).timed_out(1e9)  # 0: never


def test_diagnostics_levels_and_values():
    state = measured()
    assert state.status()[:2] == (WARN, 'waiting for the measured state on /robot/joint_states')
    state.read(JOINTS, [0.0, 0.0, 0.0], 1.0)
    level, problem, values = state.status()
    assert (level, problem) == (OK, '')
    assert dict(values)['measured messages'] == '1' and dict(values)['re-seeds'] == '0'
    state.lost = True
    assert state.status()[0] == ERROR


@pytest.mark.parametrize('value', [-0.1, math.inf, math.nan, True, 'soon'])
def test_a_bad_timeout_is_refused_saying_what_is_valid(value):
    with pytest.raises(ValueError, match='joint_topic_timeout must be a finite number of '
                                         r'seconds >= 0 \(0: never\)'):
        check_timeout(value)


def test_a_bad_state_tolerance_names_the_parameter():
    with pytest.raises(ValueError, match='state_tolerance'):
        measured(tolerance=(-0.1,))
