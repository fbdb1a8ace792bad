"""A three-joint Config and states at rest, shared by the planning tests (no ROS)."""

import numpy as np
from traj_gen_ros.node.planning.motion import State
from traj_gen_ros.node.settings.config import make_config

JOINTS = ['a', 'b', 'c']


def config(**changes):
    values = {'joints': JOINTS, 'rate_hz': 100.0, 'profile': 'quintic',
              'via_velocities': 'heuristic', 'max_velocity': [1.0, 2.0, 3.0],
              'max_acceleration': 4.0, 'lspb_acceleration': 0.0}
    values.update(changes)
    return make_config(**values)


def rest(position=(0.0, 0.0, 0.0)):
    position = np.array(position, dtype=float)
    return State(position, np.zeros(3), np.zeros(3))
