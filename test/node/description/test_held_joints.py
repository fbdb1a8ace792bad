"""
The URDF's joints outside ``joints`` held at their measured values (issue 29), no ROS.

pybullet's Panda with ``joints`` panda_joint1..6 and the tool ``panda_grasptarget``:
panda_joint7 is on the chain but not the node's. A measured message (MeasuredState)
naming it reaches every thread's chain (HeldJoints, RobotKinematics); each chain changes
only when its own thread takes it. Every pose is judged by ``numpy_chain`` (the URDF's
origins and axes in numpy, mimic joints as ``multiplier * leader + offset``).
"""

import dataclasses
import math
import sys
import threading

import numpy as np
from numpy_chain import NumpyChain
from planning_rig import config as rig_config
from pybullet_urdfs import pybullet_urdfs
import pytest
from traj_gen_ros.node.description.held_joints import HeldJoints
from traj_gen_ros.node.description.kinematics import build_kinematics
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.planning.pose_goal import joint_goal, PoseRequest
from traj_gen_ros.node.robot.measured_state import MeasuredState

ARM = [f'panda_joint{index}' for index in range(1, 8)]
JOINTS = ARM[:6]
READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571])
TOOL = 'panda_grasptarget'


@pytest.fixture(scope='module')
def urdf(request) -> str:
    return pybullet_urdfs(request.config)['panda'].read_text()


def node_side(urdf_text, joints=JOINTS):
    """Return ``(held, measured state writing to it, kinematics reading it)``."""
    held = HeldJoints()
    measured = MeasuredState(joints, '/robot/joint_states', 0.05, 0.5, held)
    return held, measured, build_kinematics(urdf_text, joints, '', TOOL, held)


def message(values):
    """Return ``(names, positions)`` of a driver's message, in reverse order."""
    names = list(values)[::-1]
    return names, [values[name] for name in names]


def oracle(chain, q, **others):
    return chain.pose(TOOL, dict(zip(JOINTS, q, strict=True)) | others)


def test_a_measured_joint_outside_joints_reaches_every_threads_chain(urdf):
    numpy_chain = NumpyChain(urdf)
    held, measured, kinematics = node_side(urdf)
    assert 'held on the way: panda_joint7=0' in kinematics.describe()
    values = dict(zip(JOINTS, READY, strict=True)) | {
        'panda_joint7': 0.5, 'panda_finger_joint1': 0.02,
        'panda_finger_joint2': 0.0,  # mimics finger_joint1: follows it, not this
        'gripper_cam': 3.0}  # no joint of the URDF: ignored
    names, positions = message(values)
    assert measured.read(names, positions, 1.0) is not None
    assert measured.position.tolist() == READY.tolist()  # the node's joints, as before
    expected = oracle(numpy_chain, READY, panda_joint7=0.5)
    at_zero = oracle(numpy_chain, READY, panda_joint7=0.0)
    assert np.linalg.norm(expected[:3, :3] - at_zero[:3, :3]) > 0.5  # 0.5 rad about z
    for chain in (kinematics.for_requests(), kinematics.for_stream()):
        assert np.allclose(chain.forward(READY), expected, atol=1e-9)
        finger = chain.frame_pose('panda_rightfinger', READY)
        assert np.allclose(finger, numpy_chain.pose(
            'panda_rightfinger', values | {'panda_finger_joint2': 0.02}), atol=1e-9)
    assert 'held on the way: panda_joint7=0.5' in kinematics.describe()


def test_a_chain_changes_only_when_its_own_thread_takes_it(urdf):
    numpy_chain = NumpyChain(urdf)
    _, measured, kinematics = node_side(urdf)
    names, positions = message(dict(zip(JOINTS, READY, strict=True)) | {'panda_joint7': 0.5})
    measured.read(names, positions, 1.0)
    requests, stream = kinematics.for_requests(), kinematics.for_stream()
    positions[0] = -0.3  # panda_joint7, listed first
    measured.read(names, positions, 1.1)
    half = oracle(numpy_chain, READY, panda_joint7=0.5)
    # A plan or a tick under way keeps the values it started with ...
    assert np.allclose(requests.forward(READY), half, atol=1e-9)
    assert np.allclose(stream.forward(READY), half, atol=1e-9)
    # ... and takes the new ones the next time its thread takes its chain.
    assert kinematics.for_requests() is requests
    moved = oracle(numpy_chain, READY, panda_joint7=-0.3)
    assert np.allclose(requests.forward(READY), moved, atol=1e-9)
    assert np.allclose(stream.forward(READY), half, atol=1e-9)
    assert np.allclose(kinematics.for_stream().forward(READY), moved, atol=1e-9)


def test_non_finite_missing_and_refused_messages_keep_the_last_values(urdf):
    held, measured, kinematics = node_side(urdf)
    base = dict(zip(JOINTS, READY, strict=True))
    measured.read(*message(base | {'panda_joint7': 0.5, 'panda_finger_joint1': 0.01}), 1.0)
    first = held.values
    assert dict(first) == {'panda_joint7': 0.5, 'panda_finger_joint1': 0.01}
    measured.read(*message(base | {'panda_joint7': 0.5, 'panda_finger_joint1': 0.01}), 1.1)
    assert held.values is first  # nothing changed: nothing replaced, no chain re-held
    measured.read(*message(base | {'panda_joint7': math.nan, 'panda_finger_joint1': 0.03}),
                  1.2)
    assert dict(held.values) == {'panda_joint7': 0.5, 'panda_finger_joint1': 0.03}
    measured.read(*message(base | {'panda_finger_joint1': 0.04}), 1.3)  # joint7 not named
    assert dict(held.values) == {'panda_joint7': 0.5, 'panda_finger_joint1': 0.04}
    lacking = {name: value for name, value in base.items() if name != 'panda_joint3'}
    assert measured.read(*message(lacking | {'panda_joint7': 1.0}), 1.4) is None
    not_finite = base | {'panda_joint2': math.inf, 'panda_joint7': 1.0}
    assert measured.read(*message(not_finite), 1.5) is None
    assert held.values['panda_joint7'] == 0.5  # refused messages hold nothing
    assert kinematics.for_requests().held['panda_joint7'] == 0.5


def test_without_a_measured_state_the_other_joints_stand_at_zero(urdf):
    numpy_chain = NumpyChain(urdf)
    kinematics = build_kinematics(urdf, JOINTS, '', TOOL)
    assert np.allclose(kinematics.for_requests().forward(READY),
                       oracle(numpy_chain, READY), atol=1e-9)
    assert kinematics.for_stream() is not None and kinematics.chain is not None
    empty = build_kinematics('', JOINTS)
    assert empty.for_requests() is None and empty.for_stream() is None
    assert empty.describe() == empty.problem


def test_a_pose_goal_in_the_tool_frame_is_solved_with_the_measured_joint(urdf):
    """A 4 cm jog along the tool's own x: that axis turns with panda_joint7 (0.5 rad)."""
    numpy_chain = NumpyChain(urdf)
    _, measured, kinematics = node_side(urdf)
    measured.read(*message(dict(zip(JOINTS, READY, strict=True)) | {'panda_joint7': 0.5}),
                  1.0)
    config = dataclasses.replace(
        rig_config(joints=JOINTS, max_velocity=[1.0] * 6), kinematics=kinematics)
    jog = np.eye(4)
    jog[0, 3] = 0.04
    request = PoseRequest(TOOL, jog)
    goal = joint_goal(config, request, State(READY, np.zeros(6), np.zeros(6)))
    reached = oracle(numpy_chain, goal.positions, panda_joint7=0.5)
    expected = oracle(numpy_chain, READY, panda_joint7=0.5) @ jog
    assert np.linalg.norm(reached[:3, 3] - expected[:3, 3]) < 1e-5
    assert np.linalg.norm(reached[:3, :3] - expected[:3, :3]) < 1e-4
    # Held at 0 instead, the tool's x would point 0.5 rad away: 1.9 cm off.
    wrong = oracle(numpy_chain, READY) @ jog
    assert np.linalg.norm(wrong[:3, 3] - expected[:3, 3]) > 0.015


def test_a_reader_thread_sees_one_messages_values_whole(urdf):
    """The executor writes panda_joint6 and 7 together; the request thread takes them."""
    joints = ARM[:5]
    held, measured, kinematics = node_side(urdf, joints)
    names = [*joints, 'panda_joint6', 'panda_joint7']
    messages = 4000
    seen = []
    reading, done = threading.Event(), threading.Event()

    def write():
        reading.wait(60.0)
        for index in range(1, messages + 1):
            measured.read(names, [*READY[:5], index * 1e-4, index * 1e-4], float(index))
        done.set()

    def take():
        while not done.is_set():
            values = kinematics.for_requests().held
            seen.append((values['panda_joint6'], values['panda_joint7']))
            reading.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=write), threading.Thread(target=take)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(60.0)
    finally:
        sys.setswitchinterval(interval)
    assert (0.0, 0.0) in seen and len(set(seen)) > 2  # it read while the values changed
    assert all(six == seven for six, seven in seen)
    assert dict(held.values) == {'panda_joint6': messages * 1e-4,
                                 'panda_joint7': messages * 1e-4}
