"""
The ``traj-gen`` command: plan, print and plot Craig ch. 7 trajectories from a shell.

``solve`` and ``plot`` run the ROS-free core solver; ``goal``, ``via`` and
``plot --topic`` talk to a running generator node (:mod:`traj_gen_ros.cli_ros`, which
imports rclpy only when one of them runs).

Argument grammar: every ``--points`` value is one point; a point of several joints is
written with commas (``--points 0,0 1,2 0.5,-1``). Per-joint values (acceleration, limits,
boundary velocities) are one number for all joints or a comma list, one per joint.
``--durations`` (alias ``--duration``) gives one duration per segment. Joints are numbered
from 0 (as in the solver's messages); points keep Craig's names from 1 (t1, θ̇12, t12).

Exit codes: 0 success, 1 not accepted by the node, 2 bad arguments, a plan the solver
refuses or a missing package (matplotlib for ``plot``), 3 no answer from ROS in time, 4 an
internal error (a bug: please report it).
Errors are one line on stderr.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import json
import math
import re
import sys

import numpy as np
from traj_gen_ros.cli_args import (  # shared with cli_ros, which must not import this module
    EXIT_INTERNAL,
    EXIT_OK,
    EXIT_USAGE,
    report_plot,
    UsageError,
)

PROG = 'traj-gen'
# What requirements.txt pins; named in the error when matplotlib is missing.
MATPLOTLIB_REQUIREMENT = 'matplotlib==3.11.2'
PROFILES = ('cubic', 'quintic', 'lspb', 'cubic-via', 'quintic-via', 'min-time')
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
"""

PLOT_EXAMPLES = """\
examples:
  traj-gen plot cubic --points 15 75 --duration 3 --degrees -o cubic.png
  traj-gen plot lspb --points 10 35 25 10 --durations 2 1 3 --acceleration 50 --degrees \\
      -o lspb_via.png --size 1000x900
  traj-gen plot --topic /trajectory_generator/trajectory -o node.png --timeout 10
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
             '(duration from --max-velocity/--max-acceleration)')
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
    parser.add_argument('--v0', type=number_list, metavar='V',
                        help='start velocity (cubic, quintic, lspb, *-via), default rest')
    parser.add_argument('--vf', type=number_list, metavar='V',
                        help='end velocity (cubic, quintic), default rest')
    parser.add_argument('--a0', type=number_list, metavar='A',
                        help='start acceleration (quintic), default 0')
    parser.add_argument('--af', type=number_list, metavar='A',
                        help='end acceleration (quintic), default 0')
    parser.add_argument('--max-velocity', type=number_list, metavar='V',
                        help='min-time: velocity limit (one, or one per joint)')
    parser.add_argument('--max-acceleration', type=number_list, metavar='A',
                        help='min-time: acceleration limit (one, or one per joint)')
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
        'plot', help='plot position, velocity and acceleration to a PNG',
        description='Plan like "solve" (or record the node\'s ~/trajectory with --topic) and '
                    'write a PNG of three stacked panels: position, velocity and '
                    'acceleration against time; points marked, LSPB blends shaded.',
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

    goal = commands.add_parser(
        'goal', help='send a goal to a running generator node',
        description='Publish a sensor_msgs/JointState goal to NODE/goal, wait for the '
                    'matching NODE/status and print it. Exit 0 when accepted, 1 when '
                    'refused (the reason on stderr), 3 when there is no answer.',
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
    return parser


def add_ros_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options shared by ``goal`` and ``via``."""
    parser.add_argument('--node', default='/trajectory_generator',
                        help='full name of the generator node (default /trajectory_generator)')
    parser.add_argument('--timeout', type=float, default=10.0, metavar='S',
                        help='seconds to wait for the node and its answer (default 10)')
    parser.add_argument('--wait', action='store_true',
                        help='after acceptance, wait until the motion has ended')
    parser.add_argument('--joint-states', metavar='TOPIC',
                        help="--wait: the node's JointState topic (default: joint_states "
                             "in the node's namespace)")
    parser.add_argument('--degrees', action='store_true',
                        help='positions in degrees (sent in radians)')
    parser.add_argument('--json', action='store_true', help='print the status as JSON')


# ---------------------------------------------------------------------------- planning


class Plan:
    """A planned trajectory with what the user gave, in the user's units."""

    def __init__(self, trajectory: object, profile: str, points: np.ndarray,
                 point_times: np.ndarray, unit: str) -> None:
        self.trajectory = trajectory
        self.profile = profile
        self.points = points  # (points, joints) in user units
        self.point_times = point_times  # (points,) s
        self.unit = unit


def _per_joint(values: list[float] | None, name: str, joints: int,
               default: float | None = 0.0) -> np.ndarray | None:
    if values is None:
        return None if default is None else np.full(joints, default)
    if len(values) not in (1, joints):
        raise UsageError(f'--{name} has {len(values)} values for {joints} joints: give one, '
                         'or one per joint')
    return np.broadcast_to(np.asarray(values, dtype=float), (joints,))


def make_plan(args: argparse.Namespace) -> Plan:
    """Plan ``args.profile`` with the core solver; raise UsageError on refusal."""
    from traj_gen_ros import profiles

    if not args.points:
        raise UsageError('--points is required (see traj-gen solve --help)')
    counts = {len(point) for point in args.points}
    if len(counts) > 1:
        raise UsageError(f'every point needs the same number of joints, got '
                         f'{" ".join(str(len(p)) for p in args.points)} (joints are '
                         'separated by commas: --points 0,0 1,2)')
    if len(args.points) < 2:
        raise UsageError('--points needs at least two points (start and goal)')
    # The core is linear in the position unit, so degrees are solved as they are: results
    # and the solver's messages then come out in degrees too.
    unit = 'deg' if args.degrees else 'rad'
    points = np.array(args.points, dtype=float)
    joints = points.shape[1]
    path = points
    profile = args.profile

    def joint_values(name: str, default: float | None = 0.0) -> np.ndarray | None:
        return _per_joint(getattr(args, name.replace('-', '_')), name, joints, default)

    def durations(single: bool) -> np.ndarray:
        if args.durations is None:
            raise UsageError(f'{profile} needs --duration{"" if single else "s"}')
        segments = len(points) - 1
        if len(args.durations) != segments:
            raise UsageError(f'{len(points)} points need {segments} duration'
                             f'{"s" if segments > 1 else ""}, got {len(args.durations)}')
        return np.array(args.durations, dtype=float)

    try:
        if profile in ('cubic', 'quintic'):
            if len(points) != 2:
                raise UsageError(f'{profile} takes 2 points (start and goal), got '
                                 f'{len(points)}; use {profile}-via for via points')
            duration = float(durations(True)[0])
            extra = {'v0': joint_values('v0'), 'vf': joint_values('vf')}
            if profile == 'quintic':
                extra.update(a0=joint_values('a0'), af=joint_values('af'))
            solver = profiles.cubic if profile == 'cubic' else profiles.quintic
            trajectory = solver(path[0], path[1], duration, **extra)
            times = np.array([0.0, duration])
        elif profile in ('cubic-via', 'quintic-via'):
            segment_durations = durations(False)
            solver = profiles.cubic_via if profile == 'cubic-via' else profiles.quintic_via
            trajectory = solver(path, segment_durations, args.velocities,
                                v0=joint_values('v0'))
            times = np.concatenate([[0.0], np.cumsum(segment_durations)])
        elif profile == 'lspb':
            acceleration = joint_values('acceleration', None)
            if acceleration is None:
                raise UsageError('lspb needs --acceleration (the blend acceleration |θ̈|)')
            segment_durations = durations(len(points) == 2)
            if len(points) == 2:
                trajectory = profiles.lspb(path[0], path[1], float(segment_durations[0]),
                                           acceleration, v0=joint_values('v0'))
            else:
                trajectory = profiles.lspb_via(path, segment_durations, acceleration,
                                               v0=joint_values('v0'))
            times = np.concatenate([[0.0], np.cumsum(segment_durations)])
        else:
            trajectory, times = _min_time(args, path, joint_values)
    except ValueError as error:
        raise UsageError(f'{profile}: {error}') from None
    if profile == 'min-time':
        profile = f'min-time {args.shape}'
    return Plan(trajectory, profile, points, times, unit)


def _min_time(args: argparse.Namespace, path: np.ndarray,
              joint_values: object) -> tuple[object, np.ndarray]:
    from traj_gen_ros import profiles

    if args.durations is not None:
        raise UsageError('min-time finds the durations itself: drop --durations')
    max_velocity = joint_values('max-velocity', None)
    max_acceleration = joint_values('max-acceleration', None)
    if max_velocity is None or max_acceleration is None:
        raise UsageError('min-time needs --max-velocity and --max-acceleration')
    if len(path) == 2:
        trajectory = profiles.min_time(path[0], path[1], max_velocity, max_acceleration,
                                       profile=args.shape)
        return trajectory, np.array([0.0, trajectory.duration])
    acceleration = joint_values('acceleration', None)
    durations = profiles.via_durations(path, max_velocity, max_acceleration, args.shape,
                                       args.velocities, acceleration)
    if args.shape == 'lspb':
        blend = max_acceleration if acceleration is None else acceleration
        trajectory = profiles.lspb_via(path, durations, blend)
    else:
        solver = profiles.cubic_via if args.shape == 'cubic' else profiles.quintic_via
        trajectory = solver(path, durations, args.velocities)
    return trajectory, np.concatenate([[0.0], np.cumsum(durations)])


# ---------------------------------------------------------------------------- output


def _rows(array: np.ndarray) -> list:
    return np.round(np.asarray(array, dtype=float), 12).tolist()


def describe(plan: Plan) -> dict:
    """Return what ``solve`` prints, as a JSON-ready dict in the user's units."""
    trajectory = plan.trajectory
    result = {
        'profile': plan.profile,
        'units': {'position': plan.unit, 'time': 's'},
        'joints': trajectory.joint_count,
        'duration': trajectory.duration,
        'points': _rows(plan.points),
        'point_times': _rows(plan.point_times),
    }
    if hasattr(trajectory, 'blend_times'):
        # Craig's LSPB table, indexed [joint][point] and [joint][segment].
        blend_accelerations = 2.0 * np.abs(trajectory.coefficients[0::2, 2]).max(axis=0)
        result.update(
            kind='lspb',
            blend_acceleration=_rows(blend_accelerations),
            blend_times=_rows(trajectory.blend_times.T),
            linear_velocities=_rows(trajectory.linear_velocities.T),
            linear_durations=_rows(trajectory.linear_durations.T))
    else:
        # Ascending a0 … an per segment and joint: [segment][joint][power].
        breakpoints = np.asarray(trajectory.breakpoints)
        result.update(
            kind='polynomial',
            degree=trajectory.degree,
            segment_starts=_rows(breakpoints[:-1]),
            segment_durations=_rows(np.diff(breakpoints)),
            coefficients=_rows(trajectory.coefficients.transpose(0, 2, 1)))
    return result


def _pair_label(index: int, count: int) -> str:
    separator = ',' if count >= 10 else ''
    return f'{index + 1}{separator}{index + 2}'


def format_text(result: dict) -> str:
    """Format :func:`describe`'s dict the way the book writes it."""
    unit = result['units']['position']
    joints = result['joints']
    lines = [f"{result['profile']}: {joints} joint{'s' if joints > 1 else ''}, "
             f"{len(result['points'])} points, duration {result['duration']:.4f} s; "
             f'positions in {unit}, times in s']
    if result['kind'] == 'lspb':
        points = len(result['points'])
        for joint in range(joints):
            lines.append(f"joint {joint}: |θ̈| = {result['blend_acceleration'][joint]:.4f} "
                         f'{unit}/s²')
            for index in range(points):
                row = f"  t{index + 1:<3} = {result['blend_times'][joint][index]:9.4f} s"
                if index < points - 1:
                    pair = _pair_label(index, points)
                    velocity = result['linear_velocities'][joint][index]
                    linear = result['linear_durations'][joint][index]
                    row += (f'   θ̇{pair:<4} = {velocity:10.4f} {unit}/s'
                            f'   t{pair:<4} = {linear:9.4f} s')
                lines.append(row)
        return '\n'.join(lines)
    degree = result['degree']
    powers = ''.join(f'{"a" + str(power):>12}' for power in range(degree + 1))
    terms = ' + '.join(['a0', 'a1 t'] + [f'a{p} t{"²³⁴⁵"[p - 2]}' for p in range(2, degree + 1)])
    lines.append(f'θ(t) = {terms}, t from the segment start')
    for segment, coefficients in enumerate(result['coefficients']):
        start = result['segment_starts'][segment]
        duration = result['segment_durations'][segment]
        lines.append(f'segment {segment + 1}: t = {start:.4f} … {start + duration:.4f} s')
        lines.append(f'  joint{powers}')
        for joint, row in enumerate(coefficients):
            lines.append(f'  {joint:<5}' + ''.join(f'{value:12.4f}' for value in row))
    return '\n'.join(lines)


# ---------------------------------------------------------------------------- commands


def run_solve(args: argparse.Namespace) -> int:
    """``traj-gen solve``: print the coefficients or the LSPB table."""
    result = describe(make_plan(args))
    print(json.dumps(result, indent=2, ensure_ascii=False) if args.json else format_text(result))
    return EXIT_OK


def require_plotting() -> object:
    """
    Import :mod:`traj_gen_ros.plotting`, or raise UsageError saying to install matplotlib.

    matplotlib is a runtime requirement (requirements.txt, setup.py, package.xml), but a
    user may run ``traj-gen`` from an environment without it; that is not a bug (exit 4)
    but a missing package (exit 2) with the command that installs it.
    """
    try:
        from traj_gen_ros import plotting
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
        from traj_gen_ros import cli_ros
        return cli_ros.run_plot_topic(args)
    if args.profile is None:
        raise UsageError('plot needs a profile (e.g. plot cubic …) or --topic TOPIC')

    plan = make_plan(args)
    info = plotting.plot_trajectory(
        plan.trajectory, args.output, unit=plan.unit,
        marks=(plan.point_times, plan.points), size=args.size,
        title=_plot_title(plan))
    report_plot(info, args.json)
    return EXIT_OK


def _plot_title(plan: Plan) -> str:
    points = ' → '.join(','.join(f'{value:g}' for value in point) for point in plan.points)
    return f'{plan.profile}: {points} {plan.unit} in {plan.trajectory.duration:.3g} s'


def run_ros(args: argparse.Namespace) -> int:
    """``traj-gen goal`` / ``traj-gen via``: send a request to a running node."""
    from traj_gen_ros import cli_ros
    return cli_ros.run_request(args)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``traj-gen`` with ``argv`` (default ``sys.argv[1:]``); return the exit status."""
    parser = build_parser()
    command = 'traj-gen'
    try:
        args = parser.parse_args(argv)
        command = f'traj-gen {args.command}'
        runner = {'solve': run_solve, 'plot': run_plot, 'goal': run_ros, 'via': run_ros}
        return runner[args.command](args)
    except UsageError as error:
        print(f'{error.prog or command}: error: {_one_line(error)}', file=sys.stderr)
        return EXIT_USAGE
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
    from traj_gen_ros.cli import main as _main
    sys.exit(_main())
