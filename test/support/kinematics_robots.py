"""
The robot descriptions the kinematics tests use: real URDFs and a few small written ones.

Real ones (:data:`ROBOTS`) come from pybullet_data (:mod:`pybullet_urdfs`) and
example-robot-data (:mod:`example_robot_data`); :func:`robot_urdf` reads one, skipping
where it cannot be fetched. The written ones exercise what the real arms lack: a floating
base, a continuous joint, a prismatic joint and a mimic joint with a multiplier and an
offset on the chain (:data:`FLOATING_ARM`).
"""

from __future__ import annotations

from dataclasses import dataclass

from example_robot_data import example_robot_data_urdfs
from pybullet_urdfs import pybullet_urdfs
import pytest

PANDA = tuple(f'panda_joint{k}' for k in range(1, 8))
UR = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
      'wrist_2_joint', 'wrist_3_joint')


@dataclass(frozen=True)
class Robot:
    source: str  # 'pybullet' or 'erd' (example-robot-data)
    name: str
    joints: tuple[str, ...]
    default_tool: str


ROBOTS = {
    'pybullet-panda': Robot('pybullet', 'panda', PANDA, 'panda_grasptarget'),
    'pybullet-iiwa': Robot('pybullet', 'iiwa', tuple(f'lbr_iiwa_joint_{k}' for k in range(1, 8)),
                           'lbr_iiwa_link_7'),
    'pybullet-xarm6': Robot('pybullet', 'xarm6', tuple(f'joint{k}' for k in range(1, 7)),
                            'link6'),
    'pybullet-xarm6-gripper': Robot('pybullet', 'xarm6_gripper',
                                    tuple(f'joint{k}' for k in range(1, 7)),
                                    'xarm_gripper_base_link'),
    'erd-panda': Robot('erd', 'panda', PANDA, 'panda_hand_tcp'),
    'erd-ur10': Robot('erd', 'ur10', UR, 'wrist_3_link'),
}


def robot_urdf(config: pytest.Config, source: str, name: str) -> str:
    """Return the URDF text of ``name`` from ``source`` ('pybullet' or 'erd')."""
    paths = pybullet_urdfs(config) if source == 'pybullet' else example_robot_data_urdfs(config)
    return paths[name].read_text()


#: world -floating-> base -revolute j1-> l1 -continuous j2-> l2 -prismatic j3-> l3
#: -revolute j4 (mimics j1: -2 j1 + 0.3)-> l4 -fixed-> tool; a side branch holds 'side'.
FLOATING_ARM = """<?xml version="1.0"?>
<robot name="floating_arm">
  <link name="world"/><link name="base"/><link name="l1"/><link name="l2"/>
  <link name="l3"/><link name="l4"/><link name="tool"/><link name="arm_side"/>
  <joint name="float" type="floating">
    <parent link="world"/><child link="base"/><origin xyz="0.3 -0.2 1.0" rpy="0.1 0.2 0.3"/>
  </joint>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/><origin xyz="0 0 0.4"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="continuous">
    <parent link="l1"/><child link="l2"/><origin xyz="0.1 0 0.3" rpy="1.5707963 0 0"/>
    <axis xyz="0 0.6 0.8"/>
  </joint>
  <joint name="j3" type="prismatic">
    <parent link="l2"/><child link="l3"/><origin xyz="0 0.25 0" rpy="0 0.3 0"/>
    <axis xyz="1 0 0"/><limit lower="-0.2" upper="0.3" effort="1" velocity="1"/>
  </joint>
  <joint name="j4" type="revolute">
    <parent link="l3"/><child link="l4"/><origin xyz="0.2 0 0" rpy="0 0 0.5"/>
    <axis xyz="0 1 0"/><limit lower="-6" upper="6" effort="1" velocity="1"/>
    <mimic joint="j1" multiplier="-2" offset="0.3"/>
  </joint>
  <joint name="tool_joint" type="fixed">
    <parent link="l4"/><child link="tool"/><origin xyz="0 0 0.15" rpy="0.2 0 0"/>
  </joint>
  <joint name="side" type="revolute">
    <parent link="base"/><child link="arm_side"/><origin xyz="0 0.5 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>
"""
