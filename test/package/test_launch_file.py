"""
launch/generator.launch.py: it compiles and passes the right arguments to launch_ros.

The real ROS 2 ``launch`` and ``launch_ros`` packages are NOT available here (they are not
on PyPI; a ROS install has them), so ``ros2 launch`` itself is not run. Instead, tiny
stand-ins for the few classes the file uses are put into ``sys.modules`` for the duration
of one test only; each records what it was given, and their signatures are those of ROS 2
Jazzy's (keyword-only where Jazzy's are), so a misspelt or missing argument fails here
too. That colcon installs the file is checked in test_colcon_build.py.
"""

import importlib.util
from pathlib import Path
import py_compile
import sys
import types

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
LAUNCH_FILE = REPO / 'launch' / 'generator.launch.py'


class Recorder:
    """Base of the stand-ins: keeps the arguments it was built with."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        self.args = args
        self.kwargs = kwargs


class LaunchDescription(Recorder):
    def __init__(self, initial_entities: list | None = None, *,
                 deprecated_reason: str | None = None) -> None:
        super().__init__(initial_entities)
        self.entities = list(initial_entities or [])


class DeclareLaunchArgument(Recorder):
    def __init__(self, name: str, *, default_value: object = None, description: object = None,
                 choices: list | None = None, **kwargs: object) -> None:
        super().__init__(name, default_value=default_value, description=description,
                         choices=choices, **kwargs)
        self.name = name
        self.default_value = default_value
        self.description = description
        self.choices = choices


class LaunchConfiguration(Recorder):
    def __init__(self, variable_name: str, *, default: object = None) -> None:
        super().__init__(variable_name, default=default)
        self.variable_name = variable_name


class PathJoinSubstitution(Recorder):
    def __init__(self, substitutions: list) -> None:
        super().__init__(substitutions)
        self.substitutions = substitutions


class FindPackageShare(Recorder):
    def __init__(self, package: str) -> None:
        super().__init__(package)
        self.package = package


class Node(Recorder):
    def __init__(self, *, executable: str, package: object = None, name: object = None,
                 namespace: object = None, exec_name: object = None,
                 parameters: list | None = None, remappings: list | None = None,
                 ros_arguments: list | None = None, arguments: list | None = None,
                 **kwargs: object) -> None:
        super().__init__(executable=executable, package=package, name=name,
                         namespace=namespace, exec_name=exec_name, parameters=parameters,
                         remappings=remappings, ros_arguments=ros_arguments,
                         arguments=arguments, **kwargs)


def stub_modules() -> dict[str, types.ModuleType]:
    """Return stand-in modules for the names the launch file imports."""
    contents = {
        'launch': {'LaunchDescription': LaunchDescription},
        'launch.actions': {'DeclareLaunchArgument': DeclareLaunchArgument},
        'launch.substitutions': {'LaunchConfiguration': LaunchConfiguration,
                                 'PathJoinSubstitution': PathJoinSubstitution},
        'launch_ros': {},
        'launch_ros.actions': {'Node': Node},
        'launch_ros.substitutions': {'FindPackageShare': FindPackageShare},
    }
    modules = {}
    for name, attributes in contents.items():
        module = types.ModuleType(name)
        module.__dict__.update(attributes)
        modules[name] = module
    return modules


@pytest.fixture
def description(monkeypatch) -> LaunchDescription:
    for name, module in stub_modules().items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('generator_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    result = module.generate_launch_description()
    assert isinstance(result, LaunchDescription)
    return result


def test_launch_file_compiles(tmp_path):
    py_compile.compile(str(LAUNCH_FILE), cfile=str(tmp_path / 'launch.pyc'), doraise=True)


def test_generator_node_with_the_installed_config_by_default(description):
    arguments = [e for e in description.entities if isinstance(e, DeclareLaunchArgument)]
    nodes = [e for e in description.entities if isinstance(e, Node)]
    assert [a.name for a in arguments] == ['params_file', 'namespace', 'use_sim_time']
    assert len(nodes) == 1 and len(description.entities) == 4

    params_file, namespace, use_sim_time = arguments
    default = params_file.default_value
    assert isinstance(default, PathJoinSubstitution)
    share, *rest = default.substitutions
    assert isinstance(share, FindPackageShare) and share.package == 'traj_gen_ros'
    assert rest == ['config', 'generator.yaml']  # what setup.py installs under share/
    assert (REPO / 'config' / 'generator.yaml').is_file()
    assert namespace.default_value == ''
    assert use_sim_time.default_value == 'false' and use_sim_time.choices == ['true', 'false']
    assert all(a.description for a in arguments)

    node = nodes[0].kwargs
    assert node['package'] == 'traj_gen_ros'
    assert node['executable'] == 'generator'  # setup.py's console script
    assert node['name'] == 'trajectory_generator'
    assert node['output'] == 'screen'
    assert isinstance(node['namespace'], LaunchConfiguration)
    assert node['namespace'].variable_name == 'namespace'
    file_parameter, overrides = node['parameters']
    assert isinstance(file_parameter, LaunchConfiguration)
    assert file_parameter.variable_name == 'params_file'
    assert list(overrides) == ['use_sim_time']
    assert overrides['use_sim_time'].variable_name == 'use_sim_time'
    assert node['remappings'] is None and node['arguments'] is None


def test_default_config_matches_the_node_under_any_name():
    # The launch file renames nothing, but a user's namespace must still match '/**'.
    config = yaml.safe_load((REPO / 'config' / 'generator.yaml').read_text())
    assert list(config) == ['/**'] and 'ros__parameters' in config['/**']


def test_setup_installs_the_launch_file_and_package_xml_declares_launch():
    setup = (REPO / 'setup.py').read_text()
    assert "('share/' + package_name + '/launch', glob('launch/*.launch.py'))" in setup
    manifest = (REPO / 'package.xml').read_text()
    assert '<exec_depend>launch</exec_depend>' in manifest
    assert '<exec_depend>launch_ros</exec_depend>' in manifest
