"""
The node's rooms: the module tree in docs/node-design.md is complete and true (issue 28).

Each room of ``traj_gen_ros/node/`` uses only the rooms listed before it; its
``__init__.py`` holds nothing but its docstring; a module the tree does not mark ``(ROS)``
loads no ROS module (imported in a fresh interpreter), and one it marks does.
"""

import ast
import json
from pathlib import Path
import re
import subprocess
import sys

import pytest
from test_imports_no_ros import ROS_PREFIXES, SCRIPT

REPO = Path(__file__).resolve().parents[2]
NODE = REPO / 'traj_gen_ros' / 'node'
DESIGN = REPO / 'docs' / 'node-design.md'
ENTRY = re.compile(r'^(?P<lead>[│ ]*)[├└]── (?P<name>[\w.]+/?)\s*(?P<rest>.*)$')


def documented_tree() -> tuple[list[str], dict[str, bool]]:
    """Return the rooms in their documented order and ``{module path: loads ROS}``."""
    text = DESIGN.read_text()
    block = text[text.index('```\ntraj_gen_ros/node/\n'):]
    block = block[:block.index('\n```', 4)]
    rooms, modules, room = [], {}, None
    for line in block.splitlines()[2:]:
        found = ENTRY.match(line)
        if not found:
            continue
        depth, name = len(found['lead']) // 4, found['name']
        if name.endswith('/'):
            room = name[:-1]
            rooms.append(room)
            continue
        path = name if depth == 0 else f'{room}/{name}'
        modules[path] = found['rest'].startswith('(ROS)')
    return rooms, modules


def actual_modules() -> list[str]:
    return sorted(str(path.relative_to(NODE)) for path in NODE.rglob('*.py')
                  if path.name != '__init__.py')


def node_imports(path: Path) -> set[str]:
    """Return the rooms (or top-level modules) of traj_gen_ros.node a module imports."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module] + [f'{node.module}.{alias.name}' for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        for name in names:
            if name.startswith('traj_gen_ros.node.'):
                found.add(name.split('.')[2])
    return found


def test_the_tree_lists_every_module_once_and_nothing_else():
    rooms, modules = documented_tree()
    assert sorted(modules) == actual_modules()
    assert sorted(rooms) == sorted(path.name for path in NODE.iterdir()
                                   if (path / '__init__.py').exists())


def test_each_room_uses_only_the_rooms_before_it():
    rooms, _ = documented_tree()
    rank = {room: index for index, room in enumerate(rooms)}
    upward = []
    for room in rooms:
        for path in sorted((NODE / room).glob('*.py')):
            for used in node_imports(path) - {room}:
                if used not in rank or rank[used] > rank[room]:
                    upward.append(f'{room}/{path.name} imports traj_gen_ros.node.{used}')
    assert upward == []


def test_each_rooms_init_holds_only_its_docstring():
    for init in sorted(NODE.glob('*/__init__.py')):
        body = ast.parse(init.read_text()).body
        assert len(body) == 1 and isinstance(body[0], ast.Expr), init
        assert isinstance(body[0].value, ast.Constant) and body[0].value.value.strip(), init


def loaded_by(module: str) -> list[str]:
    """Import ``module`` in a fresh interpreter; return the ROS modules it loaded."""
    result = subprocess.run([sys.executable, '-c', SCRIPT, json.dumps([module])],
                            capture_output=True, text=True, timeout=120, check=True)
    return [name for name in json.loads(result.stdout)
            if name.split('.')[0] in ROS_PREFIXES and not name.startswith('traj_gen_ros')]


@pytest.mark.parametrize('path', sorted(documented_tree()[1]))
def test_ros_free_modules_load_no_ros_and_ros_modules_do(path):
    module = 'traj_gen_ros.node.' + path[:-3].replace('/', '.')
    ros = loaded_by(module)
    if documented_tree()[1][path]:
        assert ros, f'{path} is marked (ROS) in docs/node-design.md but loads no ROS module'
    else:
        assert ros == [], f'{path} is documented ROS-free but loads {ros[:5]}'
