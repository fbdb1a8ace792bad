"""
The ``traj-gen`` command: plan, print and plot Craig ch. 7 trajectories from a shell.

``solve`` and ``plot`` run the ROS-free core solver, ``fk`` and ``ik`` its kinematics of a
URDF file (:mod:`traj_gen_ros.cli.kinematics`), ``solve|plot line|arc`` its tool paths
(:mod:`traj_gen_ros.cli.tool_path_commands`); ``goal``, ``via``, ``pose``, ``line``, ``arc``
and ``plot --topic`` talk to a running generator node (:mod:`traj_gen_ros.cli.ros`, which
imports rclpy only when one of them runs).

Argument grammar: every ``--points`` value is one point; a point of several joints is
written with commas (``--points 0,0 1,2 0.5,-1``). Per-joint values (acceleration, limits,
boundary velocities) are one number for all joints or a comma list, one per joint.
``--durations`` (alias ``--duration``) gives one duration per segment. Joints are named
joint_1, joint_2, … in the order of a point's values (as the node's default joints); points
keep Craig's names from 1 (t1, θ̇12, t12). fk and ik name them as the URDF does.

Exit codes: 0 success, 1 not accepted by the node (its answer, with the reason, on stdout
as an acceptance is), 2 bad arguments, a plan the solver refuses, a pose ik cannot reach
or a missing package (matplotlib for ``plot``, Pinocchio for ``fk``/``ik``), 3 no answer
from ROS in time, 4 an internal error (a bug: please report it). Errors of traj-gen itself
are one line on stderr.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import json
import math
import re
import sys

from traj_gen_ros.cli.common import (  # shared with cli_ros, which must not import this module
    EXIT_INTERNAL,
    EXIT_NO_ANSWER,
    EXIT_OK,
    EXIT_USAGE,
    NoAnswerError,
    report_plot,
    UsageError,
)
from traj_gen_ros.cli.kinematics_args import add_kinematics_parsers, add_pose_parser
from traj_gen_ros.cli.plan import make_plan, Plan
from traj_gen_ros.cli.report import describe, format_text
from traj_gen_ros.cli.tool_path_args import add_tool_path_parsers, tool_path_parser

PROG = 'traj-gen'
# What requirements.txt pins; named in the error when matplotlib is missing.
MATPLOTLIB_REQUIREMENT = 'matplotlib==3.11.2'
PROFILES = ('cubic', 'quintic', 'lspb', 'cubic-via', 'quintic-via', 'min-time', 'scurve')
_UNSIGNED = r'(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?'
# Lets argparse take '-1,2' (a point of two joints) as a value, not as an option.
_NUMBER_LIST = re.compile(rf'^-{_UNSIGNED}(,[-+]?{_UNSIGNED})*$')

SOLVE_EXAMPLES = """\
examples:
  traj-gen solve cubic --points 15 75 --duration 3 --degrees
  traj-gen solve lspb --points 10 35 25 10 --durations 2 1 3 --acceleration 50 --degrees
  traj-gen solve quintic --points 0,0 1,-0.5 --duration 2 --json
  traj-gen solve cubic-via --points 0 1 0.5 --durations 1 1 --velocities continuous
  traj-gen solve min-time --points 0,0 1,2 --max-velocity 1 --max-acceleration 2 --shape lspb
  traj-gen solve scurve --points 0,0 1,2 --max-velocity 1 --max-acceleration 2 --max-jerk 10
  traj-gen solve line --urdf panda.urdf --start 0,-0.785,0,-2.356,0,1.571,0.785 \
      --to 0.4,0.1,0.45,1,0,0,0      (a tool path: see traj-gen solve line --help)
"""

PLOT_EXAMPLES = """\
examples:
  traj-gen plot cubic --points 15 75 --duration 3 --degrees -o cubic.png
  traj-gen plot lspb --points 10 35 25 10 --durations 2 1 3 --acceleration 50 --degrees \\
      -o lspb_via.png --size 1000x900
  traj-gen plot scurve --points 0 1 0.5 --max-velocity 1 --max-acceleration 2 \
      --max-jerk 10 -o scurve.png
  traj-gen plot --topic /trajectory_generator/trajectory -o node.png --timeout 10
  traj-gen plot arc --urdf panda.urdf --start … --to INTERIM GOAL -o arc.png  (see --help)
"""

GOAL_EXAMPLES = """\
examples:
  traj-gen goal joint_1=0.5 joint_2=-1.0
  traj-gen goal joint_1=15 --degrees --wait
  traj-gen goal joint_3=1 --node /arm/trajectory_generator --timeout 5
"""

VIA_EXAMPLES = """\
examples:
  traj-gen via --joints joint_1 joint_2 --point 0.5 0.3 @1.5 --point 1 -0.2 @3
  traj-gen via --joints joint_1 --degrees --point 35 @2 --point 25 @3 --point 10 @6 --wait
  traj-gen via --joints joint_1 joint_2 --point 0.5 0.3 --point 1 -0.2   (timed by the node)
"""

# The per-joint numbers solve and plot take after --velocities: option, metavar, help.
_PER_JOINT_OPTIONS = (
    ('--v0', 'V', 'start velocity (cubic, quintic, lspb, *-via), default rest'),
    ('--vf', 'V', 'end velocity (cubic, quintic), default rest'),
    ('--a0', 'A', 'start acceleration (quintic), default 0'),
    ('--af', 'A', 'end acceleration (quintic), default 0'),
    ('--max-velocity', 'V', 'min-time: velocity limit (one, or one per joint)'),
    ('--max-acceleration', 'A', 'min-time: acceleration limit (one, or one per joint)'),
    ('--max-jerk', 'J', 'scurve: jerk limit (one, or one per joint)'),
)


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser that raises :class:`UsageError` and takes '-1,2' as a value."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault('formatter_class', argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NUMBER_LIST

    def error(self, message: str) -> None:
        raise UsageError(f'{message} (see {self.prog} --help)', self.prog)


def number_list(text: str) -> list[float]:
    """Parse ``'1'`` or ``'1,-2.5'`` into floats (an argparse ``type``)."""
    try:
        values = [float(part) for part in text.split(',')]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a number or a comma list of numbers") from None
    if not all(math.isfinite(value) for value in values):
        raise argparse.ArgumentTypeError(f"'{text}' must be finite")
    return values


def positive_size(text: str) -> tuple[int, int]:
    """Parse ``WIDTHxHEIGHT`` in pixels (an argparse ``type``)."""
    match = re.fullmatch(r'(\d+)[xX](\d+)', text)
    if not match or not all(16 <= int(value) <= 10000 for value in match.groups()):
        raise argparse.ArgumentTypeError(
            f"'{text}' is not WIDTHxHEIGHT in pixels (16 to 10000 each), e.g. 900x900")
    return int(match[1]), int(match[2])


def add_plan_arguments(parser: argparse.ArgumentParser, optional_profile: bool) -> None:
    """Add the arguments shared by ``solve`` and ``plot``."""
    parser.add_argument(
        'profile', choices=PROFILES, nargs='?' if optional_profile else None,
        help='cubic | quintic (one segment: 2 points, 1 duration), lspb (2 points and 1 '
             'duration, or via points), cubic-via | quintic-via (via points), min-time '
             '(duration from --max-velocity/--max-acceleration), scurve (jerk-limited, '
             'seven phases, with --max-jerk too: minimum time unless --durations)')
    parser.add_argument(
        '--points', nargs='+', type=number_list, metavar='P',
        help='positions, one value per point: q0 [q1 …] qf; joints of a point separated by '
             'commas (0,0 1,2)')
    parser.add_argument(
        '--durations', '--duration', nargs='+', type=float, metavar='T',
        help='one duration per segment, s')
    parser.add_argument(
        '--acceleration', type=number_list, metavar='A',
        help='lspb: blend acceleration |θ̈| (one, or one per joint)')
    parser.add_argument(
        '--velocities', choices=('heuristic', 'continuous'), default='heuristic',
        help='via-point velocities for cubic-via/quintic-via (and min-time via points): '
             "Craig's heuristic or continuous acceleration (default heuristic)")
    for option, metavar, text in _PER_JOINT_OPTIONS:
        parser.add_argument(option, type=number_list, metavar=metavar, help=text)
    parser.add_argument('--shape', choices=('lspb', 'cubic', 'quintic'), default='lspb',
                        help='min-time: the profile to time (default lspb)')
    parser.add_argument('--degrees', action='store_true',
                        help='positions (and their derivatives) in degrees; radians by default')
    parser.add_argument('--json', action='store_true', help='print JSON instead of text')


def build_parser() -> argparse.ArgumentParser:
    """Return the ``traj-gen`` parser with its subcommands."""
    parts = __doc__.replace('``', '').strip().split('\n\n')
    parser = _Parser(
        prog=PROG, description='\n\n'.join(parts[:1] + parts[2:]),
        epilog='Run "traj-gen SUBCOMMAND --help" for examples.')
    commands = parser.add_subparsers(dest='command', metavar='SUBCOMMAND', required=True)

    solve = commands.add_parser(
        'solve', help='plan and print the coefficients / the LSPB table',
        description='Plan with the core solver and print what the book prints: a0 … an per '
                    'segment and joint for polynomials; blend times, linear velocities and '
                    'linear durations (t1, θ̇12, t12, …) for LSPB.',
        epilog=SOLVE_EXAMPLES)
    add_plan_arguments(solve, optional_profile=False)

    plot = commands.add_parser(
        'plot', help='plot position, velocity and acceleration (and jerk for scurve) to a PNG',
        description='Plan like "solve" (or record the node\'s ~/trajectory with --topic) and '
                    'write a PNG of three stacked panels: position, velocity and '
                    'acceleration against time (a fourth, jerk, for scurve); points '
                    'marked, LSPB blends shaded.',
        epilog=PLOT_EXAMPLES)
    add_plan_arguments(plot, optional_profile=True)
    plot.add_argument('-o', '--output', required=True, metavar='FILE.png',
                      help='PNG file to write')
    plot.add_argument('--size', type=positive_size, default=(900, 900), metavar='WxH',
                      help='image size in pixels (default 900x900, at 100 dpi)')
    plot.add_argument('--topic', metavar='TOPIC',
                      help='plot one trajectory_msgs/JointTrajectory received on TOPIC '
                           '(e.g. /trajectory_generator/trajectory) instead of planning')
    plot.add_argument('--timeout', type=float, default=10.0, metavar='S',
                      help='--topic: seconds to wait for a message (default 10)')

    add_kinematics_parsers(commands)
    goal = commands.add_parser(
        'goal', help='send a goal to a running generator node',
        description='Publish a sensor_msgs/JointState goal to NODE/goal, wait for the '
                    'matching NODE/status and print it (on stdout, accepted or not). Exit '
                    '0 when accepted, 1 when refused or superseded, 3 when there is no '
                    'answer.',
        epilog=GOAL_EXAMPLES)
    goal.add_argument('positions', nargs='+', metavar='JOINT=POSITION',
                      help='target of each named joint; others keep their target')
    add_ros_arguments(goal)

    via = commands.add_parser(
        'via', help='send via points to a running generator node',
        description='Publish trajectory_msgs/JointTrajectory via points to NODE/via_points, '
                    'wait for the matching NODE/status and print it. Each --point gives '
                    'one position per joint and its time from the start as @T; with no @T '
                    'on any point the node times the path from its limits. Exit codes as '
                    'for goal.',
        epilog=VIA_EXAMPLES)
    via.add_argument('--joints', nargs='+', required=True, metavar='JOINT',
                     help='joint names, in the order of the --point values')
    via.add_argument('--point', nargs='+', action='append', required=True,
                     metavar='Q', dest='points',
                     help='one position per joint, then @T (seconds from the start)')
    add_ros_arguments(via)
    add_pose_parser(commands, add_ros_arguments)
    add_tool_path_parsers(commands, add_ros_arguments)
    return parser


def add_ros_arguments(parser: argparse.ArgumentParser,
                      degrees_help: str = 'positions in degrees (sent in radians)') -> None:
    """Add the options shared by ``goal``, ``via``, ``pose``, ``line`` and ``arc``."""
    parser.add_argument('--node', default='/trajectory_generator',
                        help='full name of the generator node (default /trajectory_generator)')
    parser.add_argument('--timeout', type=float, default=10.0, metavar='S',
                        help='seconds to wait for the node and its answer (default 10)')
    parser.add_argument('--wait', action='store_true',
                        help='after acceptance, wait until the motion has ended')
    parser.add_argument('--joint-states', metavar='TOPIC',
                        help="--wait: the node's JointState topic (default: joint_states "
                             "in the node's namespace)")
    parser.add_argument('--degrees', action='store_true', help=degrees_help)
    parser.add_argument('--json', action='store_true', help='print the status as JSON')
    parser.add_argument('--plot', metavar='FILE.png',
                        help="after acceptance, plot the node's plan of this request (its "
                             '~/trajectory) with the points sent marked: start and goal as '
                             'circles, via points as diamonds')
    parser.add_argument('--size', type=positive_size, default=(900, 900), metavar='WxH',
                        help='--plot: image size in pixels (default 900x900)')


# ---------------------------------------------------------------------------- planning


def run_solve(args: argparse.Namespace) -> int:
    """``traj-gen solve``: print the coefficients or the LSPB table."""
    result = describe(make_plan(args))
    print(json.dumps(result, indent=2, ensure_ascii=False) if args.json else format_text(result))
    return EXIT_OK


def require_plotting() -> object:
    """
    Import :mod:`traj_gen_ros.cli.plot`, or raise UsageError saying to install matplotlib.

    matplotlib is a runtime requirement (requirements.txt, setup.py, package.xml), but a
    user may run ``traj-gen`` from an environment without it; that is not a bug (exit 4)
    but a missing package (exit 2) with the command that installs it.
    """
    try:
        from traj_gen_ros.cli import plot as plotting
    except ImportError as error:
        if (error.name or '').startswith('traj_gen_ros'):
            raise
        raise UsageError(
            f'plot needs matplotlib, which cannot be imported ({_one_line(error)}): '
            f'install it with "pip install {MATPLOTLIB_REQUIREMENT}" or, on a ROS '
            'install, "apt install python3-matplotlib"') from None
    return plotting


def run_plot(args: argparse.Namespace) -> int:
    """``traj-gen plot``: write the PNG of a plan or of a trajectory from a topic."""
    plotting = require_plotting()  # before any planning or waiting for ROS
    if args.topic is not None:
        if args.profile is not None:
            raise UsageError('give either a profile or --topic, not both')
        from traj_gen_ros.cli import ros as cli_ros
        return cli_ros.run_plot_topic(args)
    if args.profile is None:
        raise UsageError('plot needs a profile (e.g. plot cubic …) or --topic TOPIC')

    plan = make_plan(args)
    info = plotting.plot_trajectory(
        plan.trajectory, args.output, unit=plan.unit,
        marks=(plan.point_times, plan.points), size=args.size,
        title=_plot_title(plan), jerk=plan.profile == 'scurve')
    report_plot(info, args.json)
    return EXIT_OK


def _plot_title(plan: Plan) -> str:
    points = ' → '.join(','.join(f'{value:g}' for value in point) for point in plan.points)
    return f'{plan.profile}: {points} {plan.unit} in {plan.trajectory.duration:.3g} s'


def run_ros(args: argparse.Namespace) -> int:
    """``traj-gen goal`` / ``via`` / ``pose`` / ``line`` / ``arc``: send to a running node."""
    if args.plot:
        require_plotting()  # before waiting for ROS: a missing matplotlib is said at once
    from traj_gen_ros.cli import ros as cli_ros
    return cli_ros.run_request(args)


def run_kinematics(args: argparse.Namespace) -> int:
    """``traj-gen fk`` / ``traj-gen ik``: kinematics of a URDF file, offline."""
    from traj_gen_ros.cli import kinematics  # lxml and the core's kinematics: only for these
    return kinematics.run_fk(args) if args.command == 'fk' else kinematics.run_ik(args)


def run_tool_path(args: argparse.Namespace) -> int:
    """``traj-gen solve|plot line|arc``: a tool path planned offline from a URDF."""
    if args.command == 'plot':
        require_plotting()
    from traj_gen_ros.cli import tool_path_commands  # the core's kinematics: only for these
    return tool_path_commands.run(args)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``traj-gen`` with ``argv`` (default ``sys.argv[1:]``); return the exit status."""
    parser = build_parser()
    command = 'traj-gen'
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        args = (tool_path_parser(argv, _Parser, PROG) or parser).parse_args(argv)
        command = f'traj-gen {args.command}'
        runner = {'solve': run_solve, 'plot': run_plot, 'goal': run_ros, 'via': run_ros,
                  'pose': run_ros, 'line': run_ros, 'arc': run_ros, 'fk': run_kinematics,
                  'ik': run_kinematics}
        return (run_tool_path if 'tool_path' in args else runner[args.command])(args)
    except UsageError as error:
        print(f'{error.prog or command}: error: {_one_line(error)}', file=sys.stderr)
        return EXIT_USAGE
    except NoAnswerError as error:
        print(f'{command}: {error}', file=sys.stderr)
        return EXIT_NO_ANSWER
    except OSError as error:
        print(f'{command}: error: {_one_line(error)}', file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f'{command}: interrupted', file=sys.stderr)
        return 130
    except Exception as error:  # noqa: BLE001 - one line, never a traceback
        print(f'{command}: internal error: {type(error).__name__}: {_one_line(error)}',
              file=sys.stderr)
        return EXIT_INTERNAL


def _one_line(error: BaseException) -> str:
    return ' '.join(str(error).split())


if __name__ == '__main__':
    # Run the importable module, not this __main__ copy, so that cli_ros shares its classes.
    from traj_gen_ros.cli.main import main as _main
    sys.exit(_main())
