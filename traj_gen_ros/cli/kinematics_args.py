"""
The arguments of ``traj-gen fk``, ``ik`` and ``pose``: parsers only, nothing heavy.

:mod:`traj_gen_ros.cli.main` builds every parser at start, so this module imports no
kinematics (lxml, Pinocchio) and no ROS; :mod:`traj_gen_ros.cli.kinematics` runs ``fk``
and ``ik``, :mod:`traj_gen_ros.cli.ros` sends ``pose``.

Grammar (docs/cli.md): joint values are one number per joint of the chain, in its order
(commas or spaces: ``0,-0.785,0`` or ``0 -0.785 0``), or ``NAME=VALUE`` words as for
``traj-gen goal`` (the joints not named at their default); a pose is ``X Y Z`` in metres
and an orientation, ``--rpy R P Y`` (URDF roll, pitch, yaw: fixed axes x, y, z; rad, or
deg with ``--degrees``) or ``--quat X Y Z W`` (norm 1 within 1e-3), identity by default.
"""

from __future__ import annotations

import argparse
import math

FK_EXAMPLES = """\
examples:
  traj-gen fk --urdf panda.urdf 0 -0.785 0 -2.356 0 1.571 0.785
  traj-gen fk --urdf panda.urdf panda_joint4=-90 panda_joint6=90 --degrees --matrix
  traj-gen fk --urdf ur10.urdf --tool tool0 shoulder_lift_joint=-1.57 --json
  xacro robot.urdf.xacro | traj-gen fk --urdf - --tool tool0
"""

IK_EXAMPLES = """\
examples:
  traj-gen ik --urdf panda.urdf 0.307 0 0.387 --quat 1 0 0 0
  traj-gen ik --urdf panda.urdf 0.4 0.1 0.3 --rpy 180 0 45 --degrees \\
      --seed 0,-45,0,-135,0,90,45
  traj-gen ik --urdf ur10.urdf --tool tool0 0.6 0.2 0.4 --rpy 3.1416 0 0 --json
"""

POSE_EXAMPLES = """\
examples:
  traj-gen pose 0.307 0 0.387 --quat 1 0 0 0 --wait
  traj-gen pose 0.4 0.1 0.3 --rpy 180 0 45 --degrees --frame panda_link0
  traj-gen pose 0 0 0.05 --frame panda_hand_tcp      (5 cm along the tool's own z)
"""


def finite(text: str) -> float:
    """Parse one finite number (an argparse ``type``)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' must be finite")
    return value


def add_pose_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``X Y Z [--rpy R P Y | --quat X Y Z W]``: the tool pose ``what`` names."""
    for axis in 'xyz':
        parser.add_argument(axis, type=finite, metavar=axis.upper(),
                            help=f'{axis} of {what}, m')
    orientation = parser.add_mutually_exclusive_group()
    orientation.add_argument(
        '--rpy', nargs=3, type=finite, metavar=('R', 'P', 'Y'),
        help='orientation as roll, pitch, yaw about the fixed x, y, z axes (the URDF '
             "<origin rpy>'s convention), rad (deg with --degrees)")
    orientation.add_argument(
        '--quat', nargs=4, type=finite, metavar=('X', 'Y', 'Z', 'W'),
        help='orientation as a quaternion x y z w (norm 1 within 1e-3; normalised)')


def _add_chain_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument('--urdf', required=True, metavar='FILE',
                        help="the robot description (URDF, xacro expanded); '-' reads it "
                             'from standard input')
    parser.add_argument('--base', metavar='LINK',
                        help="the link poses are expressed in (default the URDF's root)")
    parser.add_argument('--tool', metavar='LINK',
                        help='the link whose pose is computed (default: the end of the '
                             'fixed joints below the last joint, as the node chooses its '
                             'tool_frame)')
    parser.add_argument('--joints', nargs='+', metavar='JOINT',
                        help='the joints the chain moves, in the order of the values '
                             '(default: every moving joint from the base to the tool; '
                             'without --tool, to where the arm branches, e.g. into a '
                             "gripper's fingers)")
    parser.add_argument('--degrees', action='store_true',
                        help='angles in degrees (joint values of revolute and continuous '
                             'joints, roll/pitch/yaw); prismatic joints stay in metres')
    parser.add_argument('--json', action='store_true', help='print JSON instead of text')


def add_kinematics_parsers(commands: argparse._SubParsersAction) -> None:
    """Add the ``fk`` and ``ik`` subcommands to ``traj-gen``'s ``commands``."""
    fk = commands.add_parser(
        'fk', help='forward kinematics of a URDF: the tool pose at joint values',
        description='Build the chain from --base to --tool of a URDF file (Pinocchio, as '
                    'the node does) and print the joints, then the tool pose in the base '
                    'frame: position (m), quaternion (x, y, z, w) and roll, pitch, yaw.',
        epilog=FK_EXAMPLES)
    fk.add_argument('values', nargs='*', metavar='VALUE',
                    help='one joint value per joint of the chain in its order (commas or '
                         'spaces), or JOINT=VALUE words (joints not named at 0); none: '
                         'all at 0. Write them together, before --joints')
    _add_chain_arguments(fk)
    fk.add_argument('--matrix', action='store_true',
                    help='also print the rotation matrix')

    ik = commands.add_parser(
        'ik', help='inverse kinematics of a URDF: joint values that reach a tool pose',
        description="Solve the joint values within the URDF's limits that put --tool at "
                    'the pose X Y Z (m) and orientation given, in the --base frame, '
                    'nearest --seed, as the node solves a pose goal (from the seed, then '
                    'fixed restarts; 0.01 mm and 0.1 mrad). Prints the joint values, the '
                    'residual errors, the iterations and the start that converged. A pose '
                    'that cannot be reached is an error (exit 2) saying how close it came '
                    'and which joint limit stopped it.',
        epilog=IK_EXAMPLES)
    add_pose_arguments(ik, 'the tool in the base frame')
    _add_chain_arguments(ik)
    ik.add_argument('--seed', nargs='+', metavar='VALUE',
                    help='where to start and what to stay near: one value per joint '
                         '(commas or spaces) or JOINT=VALUE words (default: every joint at '
                         '0, or at its nearest limit)')


def add_pose_parser(commands: argparse._SubParsersAction,
                    add_ros_arguments: object) -> None:
    """Add ``pose`` (``add_ros_arguments``: the options ``goal`` and ``via`` share)."""
    pose = commands.add_parser(
        'pose', help='send a tool pose goal to a running generator node',
        description='Publish a geometry_msgs/PoseStamped to NODE/pose_goal: the tool pose '
                    'X Y Z (m) and orientation in --frame; the node solves the inverse '
                    'kinematics and moves there. Wait for the matching NODE/status and '
                    'print it. Exit codes as for goal.',
        epilog=POSE_EXAMPLES)
    add_pose_arguments(pose, 'the tool in --frame')
    pose.add_argument('--frame', default='', metavar='F',
                      help="header.frame_id: '' (the default) or the node's base_frame, "
                           'another link (its current frame), or the tool_frame (relative '
                           'to the tool: a jog)')
    add_ros_arguments(pose, degrees_help='roll, pitch, yaw in degrees (sent as a quaternion)')
