"""Every traj_gen_ros.core module loads in a fresh interpreter without any ROS module."""

import json
import pkgutil
import subprocess
import sys

import traj_gen_ros.core

# Top-level names of the ROS 2 Python packages a core import could drag in.
ROS_PREFIXES = ('rclpy', 'rcl_interfaces', 'rcl_logging', 'rcutils', 'rmw', 'rosidl',
                'rpyutils', 'builtin_interfaces', 'std_msgs', 'sensor_msgs',
                'trajectory_msgs', 'diagnostic_msgs', 'geometry_msgs', 'action_msgs',
                'unique_identifier_msgs', 'ament_index_python', 'launch', 'launch_ros',
                'traj_gen_ros.node', 'traj_gen_ros.cli')

SCRIPT = """
import importlib, json, sys
names = json.loads(sys.argv[1])
for name in names:
    importlib.import_module(name)
print(json.dumps(sorted(sys.modules)))
"""


def core_modules() -> list[str]:
    """Every module and package below traj_gen_ros.core, by walking the package."""
    found = ['traj_gen_ros.core']
    for module in pkgutil.walk_packages(traj_gen_ros.core.__path__, 'traj_gen_ros.core.'):
        found.append(module.name)
    return found


def test_the_walk_finds_the_core_subpackages():
    modules = core_modules()
    for name in ('traj_gen_ros.core.trajectory', 'traj_gen_ros.core.exact.unit_roots',
                 'traj_gen_ros.core.jerk_limited.ruckig_backend',
                 'traj_gen_ros.core.jerk_limited.problem'):
        assert name in modules
    assert len(modules) >= 20


def test_importing_every_core_module_loads_no_ros():
    modules = core_modules()
    result = subprocess.run([sys.executable, '-c', SCRIPT, json.dumps(modules)],
                            capture_output=True, text=True, timeout=120, check=True)
    loaded = json.loads(result.stdout)
    assert set(modules) <= set(loaded)  # every one really was imported
    ros = [name for name in loaded
           if name.split('.')[0] in ROS_PREFIXES or name.startswith(ROS_PREFIXES)]
    assert ros == [], f'the core loaded ROS modules: {ros}'
