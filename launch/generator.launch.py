"""
Launch the trajectory_generator node with its parameters file.

``ros2 launch traj_gen_ros generator.launch.py`` runs the ``generator`` executable as node
``trajectory_generator`` with the installed ``config/generator.yaml``. Arguments:

- ``params_file:=PATH``: another parameters file (its ``/**`` key matches any node name).
- ``namespace:=NS``: run the node in namespace ``NS`` (default: none), so its topics
  become ``/NS/joint_states``, ``/NS/trajectory_generator/goal``, ….
- ``use_sim_time:=true``: stamp with the ``/clock`` topic's time.

Needs ROS 2 Jazzy's ``launch`` and ``launch_ros`` (not on PyPI: a ROS install has them).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare

PACKAGE = 'traj_gen_ros'


def generate_launch_description() -> LaunchDescription:
    """Return the launch description: three arguments and the generator node."""
    default_params = PathJoinSubstitution([FindPackageShare(PACKAGE), 'config', 'generator.yaml'])
    return LaunchDescription([
        DeclareLaunchArgument(
            'params_file', default_value=default_params,
            description='parameters file of the generator node (YAML, ros__parameters)'),
        DeclareLaunchArgument(
            'namespace', default_value='',
            description='namespace of the generator node and its topics (default: none)'),
        DeclareLaunchArgument(
            'use_sim_time', default_value='false', choices=['true', 'false'],
            description='use the /clock topic for time stamps'),
        Node(
            package=PACKAGE,
            executable='generator',
            name='trajectory_generator',
            namespace=LaunchConfiguration('namespace'),
            parameters=[LaunchConfiguration('params_file'),
                        {'use_sim_time': LaunchConfiguration('use_sim_time')}],
            output='screen',
        ),
    ])
