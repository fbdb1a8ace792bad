"""Install traj_gen_ros the ament_python way: scripts in lib/<pkg>, marker in the index."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'traj_gen_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'benchmarks']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
    ],
    # What requirements.txt pins, unpinned: the ROS packages come from the ROS install.
    install_requires=['setuptools', 'numpy', 'matplotlib', 'lxml', 'ruckig', 'pin'],
    zip_safe=True,
    maintainer='traj_gen_ros maintainers',
    maintainer_email='maintainers@traj-gen-ros.org',
    description='Craig ch. 7 joint trajectories (cubic, quintic, via points, LSPB), ROS 2 node',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'generator = traj_gen_ros.node.generator:main',
            'traj-gen = traj_gen_ros.cli.main:main',
        ],
    },
)
