"""
Continuous joints over DDS: every kind of request takes them the short way (issue 28).

A URDF whose ``joint_1`` is ``continuous``, the setpoint starting at 10 rad: ``~/goal``
and ``~/follow_joint_trajectory`` go through the same pipeline, so both end a target of
-0.1 rad at -0.1 + 2·2π = 12.466 rad (2.466 rad on), not at -0.1 after unwinding 10.1 rad.
The action's trajectory is shifted as a whole by the 2πk that puts its first point nearest
the start, as ``joint_trajectory_controller`` does, before its start is checked.
"""

import math

from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticStatus
from node_harness import action_session, action_types, JOINTS, via_message
import pytest

FollowJointTrajectory, _ = action_types()

START = 10.0
TARGET = -0.1
NEAREST = TARGET + 2 * 2 * math.pi  # 12.466 rad
JOINT_TYPES = ['continuous', 'revolute', 'revolute', 'revolute', 'revolute', 'revolute']


def urdf() -> str:
    """Return a six-joint URDF: ``joint_1`` continuous, the others within ±3 rad."""
    links = ''.join(f'<link name="link_{index}"/>' for index in range(7))
    joints = ''.join(
        f'<joint name="{name}" type="{kind}"><parent link="link_{index}"/>'
        f'<child link="link_{index + 1}"/><axis xyz="0 0 1"/>'
        + ('<limit effort="9" velocity="10"/>' if kind == 'continuous' else
           '<limit lower="-3" upper="3" effort="9" velocity="10"/>') + '</joint>'
        for index, (name, kind) in enumerate(zip(JOINTS, JOINT_TYPES, strict=True)))
    return f'<?xml version="1.0"?><robot name="wheel">{links}{joints}</robot>'


@pytest.fixture(scope='module')
def session(tmp_path_factory):
    parameters = tmp_path_factory.mktemp('continuous') / 'parameters.yaml'
    xml = urdf().replace('"', '\\"')
    parameters.write_text('/**:\n  ros__parameters:\n'
                          f'    robot_description: "{xml}"\n'
                          f'    initial_positions: [{START}, 0.0, 0.0, 0.0, 0.0, 0.0]\n')
    with action_session('--params-file', str(parameters)) as session:
        yield session


@pytest.fixture
def at_start(session):
    """Bring joint_1 back to 10 rad (the long way is the short one from the 12.466 end)."""
    probe, _ = session
    probe.wait_at_rest(20.0)
    if abs(probe.position()[0] - START) > 1e-9:
        status, _ = probe.goal({'joint_1': START})
        assert status.level == DiagnosticStatus.OK, status.message
        probe.wait_at_rest(20.0)
    assert probe.position()[0] == pytest.approx(START, abs=1e-9)
    return session


def run_goal(session, points, names=('joint_1',)):
    """Send an action goal of ``[(positions, time)]``; wait for its result and rest."""
    probe, client = session
    goal = FollowJointTrajectory.Goal(trajectory=via_message(list(names), points))
    future = client.send_goal_async(goal)
    probe.spin_until(future.done, 10.0, 'the goal response')
    result_future = future.result().get_result_async()
    probe.spin_until(result_future.done, 30.0, 'the result')
    response = result_future.result()
    probe.wait_at_rest(20.0)
    return response.status, response.result


def test_a_goal_takes_the_short_way(at_start):
    probe, _ = at_start
    status, _ = probe.goal({'joint_1': TARGET})
    assert status.level == DiagnosticStatus.OK, status.message
    assert probe.wait_at_rest(20.0)[0] == pytest.approx(NEAREST, abs=1e-9)


def test_an_action_goal_takes_the_short_way_and_is_not_slowed(at_start):
    probe, _ = at_start
    first = len(probe.trajectories)
    status, result = run_goal(at_start, [([TARGET], 3.0)])
    assert status == GoalStatus.STATUS_SUCCEEDED, result.error_string
    assert probe.position()[0] == pytest.approx(NEAREST, abs=1e-9)
    plan = probe.trajectories[first]
    # 2.466 rad in 3 s fits the limits: executed as timed (unwinding 10.1 rad was slowed).
    last = plan.points[-1].time_from_start
    assert last.sec + last.nanosec * 1e-9 == pytest.approx(3.0, abs=1e-6)
    assert 'slowed' not in result.error_string


def test_an_action_goal_is_shifted_as_a_whole_before_its_start_is_checked(at_start):
    # Point 0 at time 0 is the start two turns down: the same angle, so it passes the
    # start tolerance once shifted; the path keeps its shape (+0.5 rad), two turns up.
    status, result = run_goal(at_start, [([START - 2 * 2 * math.pi], 0.0),
                                         ([START - 2 * 2 * math.pi + 0.5], 1.0)])
    assert status == GoalStatus.STATUS_SUCCEEDED, result.error_string
    probe, _ = at_start
    assert probe.position()[0] == pytest.approx(START + 0.5, abs=1e-9)
