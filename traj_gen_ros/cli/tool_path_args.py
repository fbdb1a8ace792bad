"""
The arguments of ``traj-gen line``, ``arc`` and ``solve|plot line|arc``: parsers only.

:mod:`traj_gen_ros.cli.main` builds every parser at start, so this module imports no
kinematics and no ROS: :mod:`traj_gen_ros.cli.tool_path_goal` builds the message that
``line`` and ``arc`` send, :mod:`traj_gen_ros.cli.tool_path_commands` solves and plots
offline.

Grammar (docs/cli.md): a tool pose is one word of numbers separated by commas, ``X,Y,Z``
(m; the identity orientation, as ``traj-gen pose`` without ``--rpy``/``--quat``),
``X,Y,Z,R,P,Y`` (and the URDF roll, pitch, yaw: fixed axes x, y, z; rad, deg with
``--degrees``) or ``X,Y,Z,QX,QY,QZ,QW`` (and a quaternion x, y, z, w of norm 1 within
1e-3). ``solve line|arc`` and ``plot line|arc`` are parsed by their own parser
(:func:`tool_path_parser`): their arguments are not those of the joint-space profiles.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
import math

#: The sending subcommands, each with the node's topic (and request kind) it publishes to.
TOPICS = {'line': 'cartesian_path', 'arc': 'circular_goal'}
#: What a pose word may hold: its count of numbers and what they are.
POSE_FIELDS = {3: 'X,Y,Z', 6: 'X,Y,Z,R,P,Y', 7: 'X,Y,Z,QX,QY,QZ,QW'}
#: The node's default limits of the tool (its parameters max_linear_velocity, ...).
TOOL_DEFAULTS = {'max_linear_velocity': 0.25, 'max_linear_acceleration': 1.2,
                 'max_angular_velocity': math.pi / 2}
#: The node's default joint limits (its parameters max_velocity, max_acceleration).
JOINT_DEFAULTS = {'max_velocity': 1.0, 'max_acceleration': 2.0}

LINE_EXAMPLES = """\
examples:
  traj-gen line 0.4,0.1,0.3,180,0,0 0.4,-0.1,0.3,180,0,0 --degrees --wait
  traj-gen line 0,0,0.05 --frame panda_hand_tcp       (5 cm along the tool's own z)
  traj-gen line 0.5,0,0.3,1,0,0,0 0.5,0.2,0.3,1,0,0,0 0.3,0.2,0.3,1,0,0,0 --json
"""

ARC_EXAMPLES = """\
examples:
  traj-gen arc 0.45,0.1,0.3,180,0,0 0.4,0.2,0.3,180,0,0 --degrees --wait
  traj-gen arc 0.05,0.05,0 0.1,0,0 --frame panda_hand_tcp   (a half circle, tool frame)
"""

OFFLINE_EXAMPLES = """\
examples:
  traj-gen {command} line --urdf panda.urdf --start 0,-0.785,0,-2.356,0,1.571,0.785 \\
      --to 0.4,0.1,0.45,1,0,0,0 0.4,-0.1,0.45,1,0,0,0 --blend-radius 0.05{output}
  traj-gen {command} arc --urdf panda.urdf --start 0,-0.785,0,-2.356,0,1.571,0.785 \\
      --to 0.35,0.1,0.5,1,0,0,0 0.307,0.2,0.59,1,0,0,0{output}
"""


def pose_word(text: str) -> list[float]:
    """Parse one pose word, ``X,Y,Z[,R,P,Y | ,QX,QY,QZ,QW]``, into numbers (argparse type)."""
    try:
        values = [float(part) for part in text.split(',')]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"pose '{text}' is not numbers separated by commas: give "
            f"{' or '.join(POSE_FIELDS.values())}") from None
    if len(values) not in POSE_FIELDS:
        raise argparse.ArgumentTypeError(
            f"pose '{text}' has {len(values)} numbers: give 3 ({POSE_FIELDS[3]}, m), 6 "
            f'(and roll, pitch, yaw) or 7 (and a quaternion x, y, z, w)')
    if not all(math.isfinite(value) for value in values):
        raise argparse.ArgumentTypeError(f"pose '{text}': every number must be finite")
    return values


def _number(text: str, positive: bool) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not (math.isfinite(value) and (value > 0 if positive else value >= 0)):
        raise argparse.ArgumentTypeError(
            f"'{text}' must be a finite number {'>' if positive else '>='} 0")
    return value


def _positive(text: str) -> float:
    return _number(text, positive=True)


def _non_negative(text: str) -> float:
    return _number(text, positive=False)


def _positive_list(text: str) -> list[float]:
    """Parse ``'1'`` or ``'1,2.5'``: limits, each finite and > 0 (an argparse ``type``)."""
    return [_positive(part) for part in text.split(',')]


def _size(text: str) -> tuple[int, int]:
    width, _, height = text.lower().partition('x')
    if not (width.isdigit() and height.isdigit()
            and all(16 <= int(value) <= 10000 for value in (width, height))):
        raise argparse.ArgumentTypeError(
            f"'{text}' is not WIDTHxHEIGHT in pixels (16 to 10000 each), e.g. 1000x1100")
    return int(width), int(height)


def _add_poses(parser: argparse.ArgumentParser, kind: str) -> None:
    if kind == 'arc':
        help_text = ('two poses, the interim point (its orientation is not used) and the '
                     'goal: X,Y,Z[,R,P,Y | ,QX,QY,QZ,QW] each')
    else:
        help_text = ('the corners the tool moves through in order, the last its goal: '
                     'X,Y,Z[,R,P,Y | ,QX,QY,QZ,QW] each')
    parser.add_argument('poses', nargs='+', type=pose_word, metavar='POSE', help=help_text)


def add_tool_path_parsers(commands: argparse._SubParsersAction,
                          add_ros_arguments: Callable[..., None]) -> None:
    """Add ``line`` and ``arc`` (``add_ros_arguments``: the options ``pose`` takes)."""
    line = commands.add_parser(
        'line', help='send a straight-line tool path to a running generator node',
        description='Publish a nav_msgs/Path to NODE/cartesian_path: the tool moves from '
                    'where it is along straight lines through the poses in order (X,Y,Z m, '
                    "optional orientation), its corners blended by the node's "
                    'blend_radius. Wait for the matching NODE/status and print it. Exit '
                    'codes as for goal.',
        epilog=LINE_EXAMPLES)
    arc = commands.add_parser(
        'arc', help='send a circular tool path to a running generator node',
        description='Publish a nav_msgs/Path of two poses to NODE/circular_goal: the tool '
                    'moves on the circle through where it is, the interim point and the '
                    "goal, its orientation turning from its own to the goal's. Wait for "
                    'the matching NODE/status and print it. Exit codes as for goal.',
        epilog=ARC_EXAMPLES)
    for kind, parser in (('line', line), ('arc', arc)):
        _add_poses(parser, kind)
        parser.add_argument('--frame', default='', metavar='F',
                            help="header.frame_id of the path, for every pose: '' (the "
                                 "default) or the node's base_frame, another link (its "
                                 'current frame), or the tool_frame (relative to the tool)')
        add_ros_arguments(parser, degrees_help='roll, pitch, yaw in degrees (sent as '
                                               'quaternions)')


def _add_offline_arguments(parser: argparse.ArgumentParser, command: str) -> None:
    parser.add_argument('tool_path', choices=('line', 'arc'),
                        help='line: straight lines through the --to poses; arc: the circle '
                             'through the start, the first --to pose and the second')
    parser.add_argument('--urdf', required=True, metavar='FILE',
                        help="the robot description (URDF, xacro expanded); '-' reads it "
                             'from standard input')
    parser.add_argument('--base', metavar='LINK',
                        help="the link the poses are in (default the URDF's root)")
    parser.add_argument('--tool', metavar='LINK',
                        help='the link that moves along the path (default as the node '
                             'chooses its tool_frame)')
    parser.add_argument('--joints', nargs='+', metavar='JOINT',
                        help='the joints of the chain (default: every moving joint from '
                             'the base to the tool)')
    parser.add_argument('--start', nargs='+', required=True, metavar='Q',
                        help='the joint values the tool starts from: one per joint '
                             '(commas or spaces) or JOINT=VALUE words')
    parser.add_argument('--to', nargs='+', required=True, type=pose_word, metavar='POSE',
                        dest='poses',
                        help='line: the corners, the last the goal; arc: the interim point '
                             'and the goal. X,Y,Z[,R,P,Y | ,QX,QY,QZ,QW] in the base frame')
    parser.add_argument('--blend-radius', type=_non_negative, default=0.0, metavar='R',
                        help='line: corners rounded from R before to R after (clipped to '
                             'half the shorter segment), m; 0 (default): stop at each')
    for option, default, metavar, text in (
            ('--max-velocity', JOINT_DEFAULTS['max_velocity'], 'V',
             'joint velocity limit, rad/s or m/s (one, or a comma list per joint)'),
            ('--max-acceleration', JOINT_DEFAULTS['max_acceleration'], 'A',
             'joint acceleration limit, rad/s² or m/s² (one, or one per joint)')):
        parser.add_argument(option, type=_positive_list, default=[default], metavar=metavar,
                            help=f"{text}; default {default:g}, the node's")
    for name, default in TOOL_DEFAULTS.items():
        unit = 'rad/s' if 'angular' in name else (
            'm/s²' if 'acceleration' in name else 'm/s')
        parser.add_argument(f"--{name.replace('_', '-')}", type=_positive, default=default,
                            metavar='V', help=f"the tool's {name.replace('_', ' ')[4:]} "
                            f"limit, {unit}; default {default:.5g}, the node's")
    parser.add_argument('--degrees', action='store_true',
                        help='angles in degrees: --start of revolute joints and roll, '
                             'pitch, yaw (not the limits)')
    parser.add_argument('--json', action='store_true', help='print JSON instead of text')
    if command == 'solve':
        parser.add_argument('--rows', type=int, default=11, metavar='N',
                            help='rows of the table, evenly spaced in time (default 11)')
    else:
        parser.add_argument('-o', '--output', required=True, metavar='FILE.png',
                            help='PNG file to write')
        parser.add_argument('--size', type=_size, default=(1000, 1100), metavar='WxH',
                            help='image size in pixels (default 1000x1100, at 100 dpi)')


def tool_path_parser(argv: Sequence[str], parser_class: type[argparse.ArgumentParser],
                     prog: str) -> argparse.ArgumentParser | None:
    """
    Return the parser of ``solve line|arc`` or ``plot line|arc`` if ``argv`` is one.

    ``None`` for any other command line (``traj-gen``'s own parser reads it). The parser
    returned takes the whole ``argv`` (``solve line …``); its namespace has ``command``
    (``solve`` or ``plot``) and ``tool_path`` (``line`` or ``arc``).
    """
    if len(argv) < 2 or argv[0] not in ('solve', 'plot') or argv[1] not in ('line', 'arc'):
        return None
    command = argv[0]
    root = parser_class(prog=prog)
    commands = root.add_subparsers(dest='command', required=True)
    what = ('print the duration, what bounded the speed and sampled rows' if command ==
            'solve' else 'plot the joints, the tool speed and the 3-D path to a PNG')
    parser = commands.add_parser(
        command, help=what,
        description=f'Plan a tool path offline as the node plans ~/cartesian_path (line) '
                    f'or ~/circular_goal (arc), from the tool pose at --start: the ideal '
                    f"path, the joint path that follows it within the URDF's limits and "
                    f'its time-optimal timing under the joint and tool limits; {what}. A '
                    f'path that cannot be followed is an error (exit 2) saying where.',
        epilog=OFFLINE_EXAMPLES.format(
            command=command, output='' if command == 'solve' else ' -o path.png'))
    _add_offline_arguments(parser, command)
    return root
