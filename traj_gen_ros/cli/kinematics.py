"""
``traj-gen fk`` and ``ik``: forward and inverse kinematics of a URDF file, as tables.

Both build the chain with the core (:class:`traj_gen_ros.core.kinematics.Chain`: Pinocchio,
as the node does): ``--base`` (default the URDF's root link), ``--tool`` and ``--joints``
(default :func:`~traj_gen_ros.core.kinematics.chain_joints`: the moving joints from the
base to the tool, or, without ``--tool``, to where the arm branches; the tool is then the
node's default, the end of the fixed joints below the last joint). Joints of the URDF off
the chain stand at 0. A URDF, link, joint or pose the core refuses, and a pose ``ik``
cannot reach, is a :class:`UsageError` (one line, exit 2), as a plan the solver refuses.

Units: m; rad (deg with ``--degrees``) for revolute and continuous joints and for roll,
pitch, yaw; m for prismatic joints. Roll, pitch, yaw are the URDF's (``<origin rpy>``):
``R = Rz(yaw) Ry(pitch) Rx(roll)``, about the fixed axes. Quaternions are (x, y, z, w).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import json
import math
import sys

import numpy as np
from traj_gen_ros.cli.common import EXIT_OK, finite_number, UsageError
from traj_gen_ros.core.kinematics import (
    Chain,
    chain_joints,
    pose_matrix,
    pose_quaternion,
)
from traj_gen_ros.core.kinematics.inverse import RESTARTS

_DEGREE = math.pi / 180.0
#: Below this |cos(pitch)| the roll is set to 0 and the whole turn about z is the yaw.
_GIMBAL = 1e-9


def rpy_quaternion(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Return the unit quaternion (x, y, z, w) of URDF roll, pitch, yaw (rad)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy])


def rotation_rpy(rotation: np.ndarray) -> np.ndarray:
    """
    Return the URDF roll, pitch, yaw (rad) of a rotation matrix: ``R = Rz Ry Rx``.

    Pitch in [-π/2, π/2], roll and yaw in (-π, π]; at pitch ±π/2 (gimbal lock) roll is 0.
    """
    r = np.asarray(rotation, dtype=float)
    cos_pitch = math.hypot(r[0, 0], r[1, 0])
    pitch = math.atan2(-r[2, 0], cos_pitch)
    if cos_pitch < _GIMBAL:
        return np.array([0.0, pitch, math.atan2(-r[0, 1], r[1, 1])])
    return np.array([math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])])


def pose_from_args(args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the pose of ``X Y Z [--rpy | --quat]``: position (m), unit quaternion (x, y, z, w).

    No orientation: the identity. ``--quat`` is checked by the core's rule (norm 1 within
    1e-3, else refused naming the norm) and normalised, its sign kept.
    """
    position = np.array([args.x, args.y, args.z], dtype=float)
    if args.rpy is not None:
        scale = _DEGREE if args.degrees else 1.0
        return position, rpy_quaternion(*(value * scale for value in args.rpy))
    if args.quat is None:
        return position, np.array([0.0, 0.0, 0.0, 1.0])
    quaternion = np.array(args.quat, dtype=float)
    try:
        pose_matrix(position, quaternion)
    except ValueError as error:
        raise UsageError(f'--quat: {error}') from None
    return position, quaternion / np.linalg.norm(quaternion)


def read_urdf(path: str) -> str:
    """Return the URDF text of ``--urdf`` (``-``: standard input); OSError if unreadable."""
    if path == '-':
        return sys.stdin.read()
    with open(path, encoding='utf-8', errors='replace') as file:
        return file.read()


def load_chain(args: argparse.Namespace) -> Chain:
    """Build the chain ``--urdf``, ``--base``, ``--tool``, ``--joints`` name; UsageError if not."""
    urdf = read_urdf(args.urdf)
    try:
        joints = args.joints or chain_joints(urdf, args.base, args.tool)
        return Chain.from_urdf(urdf, joints, args.base, args.tool)
    except ValueError as error:
        raise UsageError(f'{args.urdf}: {error}') from None
    except ImportError as error:  # Pinocchio missing: a missing package, as matplotlib
        raise UsageError(str(error)) from None


def _scales(chain: Chain, degrees: bool) -> np.ndarray:
    """Return per joint what one user unit is in rad or m (deg: π/180 for angular joints)."""
    return np.where(chain.angular & degrees, _DEGREE, 1.0)


def joint_values(words: Sequence[str] | None, chain: Chain, degrees: bool,
                 default: np.ndarray, what: str) -> np.ndarray:
    """
    Read joint values: one number per joint (commas or spaces) or ``JOINT=VALUE`` words.

    Joints not named keep ``default`` (rad or m); no words: ``default``.
    :return: ``(joints,)`` rad or m.
    """
    values = np.array(default, dtype=float)
    words = [part for word in words or [] for part in word.split(',') if part]
    if not words:
        return values
    scales = _scales(chain, degrees)
    named = ['=' in word for word in words]
    if all(named):
        for word in words:
            name, _, text = word.partition('=')
            if name not in chain.joints:
                raise UsageError(f"{what}: '{name}' is not a joint of the chain; its joints "
                                 f'are {", ".join(chain.joints)}')
            index = chain.joints.index(name)
            values[index] = finite_number(text, f'{what} {name}') * scales[index]
        return values
    if any(named):
        raise UsageError(f'{what}: give one value per joint or JOINT=VALUE words, not both')
    if len(words) != len(chain.joints):
        raise UsageError(f'{what}: {len(words)} values for the {len(chain.joints)} joints '
                         f'{", ".join(chain.joints)}: give one per joint in this order, or '
                         'JOINT=VALUE words')
    return np.array([finite_number(word, what) for word in words]) * scales


def _round(values: object) -> object:
    return (np.round(np.asarray(values, dtype=float), 12) + 0.0).tolist()  # no -0.0


def describe_pose(pose: np.ndarray, degrees: bool) -> dict:
    """Return a pose as position (m), quaternion, roll/pitch/yaw (user unit) and matrix."""
    position, quaternion = pose_quaternion(pose)
    rpy = rotation_rpy(pose[:3, :3]) / (_DEGREE if degrees else 1.0)
    return {'position': _round(position), 'quaternion': _round(quaternion),
            'rpy': _round(rpy), 'matrix': _round(pose)}


def joint_rows(chain: Chain, q: np.ndarray, degrees: bool,
               seed: np.ndarray | None = None) -> list[dict]:
    """Return per joint: name, value, unit, limits (None: none), within limits, seed."""
    scales = _scales(chain, degrees)
    rows = []
    for k, name in enumerate(chain.joints):
        unit = ('deg' if degrees else 'rad') if chain.angular[k] else 'm'
        row = {'name': name, 'unit': unit}
        if seed is not None:
            row['seed'] = _round(seed[k] / scales[k])
        row.update(value=_round(q[k] / scales[k]),
                   lower=_limit(chain.lower[k], scales[k]),
                   upper=_limit(chain.upper[k], scales[k]),
                   within_limits=bool(chain.lower[k] <= q[k] <= chain.upper[k]))
        rows.append(row)
    return rows


def _limit(value: float, scale: float) -> float | None:
    return _round(value / scale) if math.isfinite(value) else None


def _cell(value: float | None) -> str:
    """Return a number in a 12-wide column, 6 decimals, no '-0.000000'; None: 'none'."""
    if value is None:
        return f'{"none":>12}'
    text = f'{value:12.6f}'
    return f'{0.0:12.6f}' if float(text) == 0.0 else text


def format_joints(rows: list[dict]) -> list[str]:
    """Return the joint table: joint, [seed,] value, unit, lower, upper, within limits."""
    width = max(len('joint'), *(len(row['name']) for row in rows)) + 1
    seed = 'seed' in rows[0]
    lines = [f"  {'joint':<{width}}" + (f"{'seed':>12}" if seed else '')
             + f"{'value':>12}  {'unit':<5}{'lower':>12}{'upper':>12}  within limits"]
    for row in rows:
        lines.append(f"  {row['name']:<{width}}" + (_cell(row['seed']) if seed else '')
                     + f"{_cell(row['value'])}  {row['unit']:<5}{_cell(row['lower'])}"
                     f"{_cell(row['upper'])}  {'yes' if row['within_limits'] else 'NO'}")
    return lines


def format_pose(pose: dict, degrees: bool, matrix: bool) -> list[str]:
    """Return the pose table: position, quaternion, roll/pitch/yaw, [rotation matrix]."""
    label = 17
    lines = [f"  {'':<{label}}" + ''.join(f'{axis:>12}' for axis in 'xyzw'),
             f"  {'position (m)':<{label}}" + ''.join(map(_cell, pose['position'])),
             f"  {'quaternion':<{label}}" + ''.join(map(_cell, pose['quaternion'])),
             f"  {'':<{label}}" + ''.join(f'{angle:>12}' for angle in ('roll', 'pitch', 'yaw')),
             f"  {'rpy (deg)' if degrees else 'rpy (rad)':<{label}}"
             + ''.join(map(_cell, pose['rpy']))]
    if matrix:
        for index, row in enumerate(pose['matrix'][:3]):
            lines.append(f"  {'rotation' if index == 0 else '':<{label}}"
                         + ''.join(map(_cell, row[:3])))
    return lines


def _header(chain: Chain, degrees: bool) -> dict:
    return {'chain': chain.describe(), 'base_frame': chain.base_frame,
            'tool_frame': chain.tool_frame, 'joint_names': list(chain.joints),
            'units': {'angle': 'deg' if degrees else 'rad', 'length': 'm'}}


def _print(result: dict, as_json: bool, lines: list[str]) -> None:
    print(json.dumps(result, indent=2, ensure_ascii=False) if as_json else '\n'.join(lines))


def run_fk(args: argparse.Namespace) -> int:
    """``traj-gen fk``: print the chain, its joints and the tool pose in the base frame."""
    chain = load_chain(args)
    q = joint_values(args.values, chain, args.degrees, np.zeros(len(chain.joints)),
                     'joint values')
    result = _header(chain, args.degrees)
    result.update(joints=joint_rows(chain, q, args.degrees),
                  pose=describe_pose(chain.forward(q), args.degrees))
    lines = [result['chain'], *format_joints(result['joints']),
             f'pose of {chain.tool_frame} in {chain.base_frame}:',
             *format_pose(result['pose'], args.degrees, args.matrix)]
    _print(result, args.json, lines)
    return EXIT_OK


def run_ik(args: argparse.Namespace) -> int:
    """``traj-gen ik``: solve the pose and print the joint values and how well they reach it."""
    position, quaternion = pose_from_args(args)
    chain = load_chain(args)
    target = pose_matrix(position, quaternion)
    seed = joint_values(args.seed, chain, args.degrees,
                        np.clip(0.0, chain.lower, chain.upper), '--seed')
    try:
        solution = chain.inverse(target, seed=seed)
    except ValueError as error:  # UnreachablePoseError: how close, which limit stopped it
        raise UsageError(str(error)) from None
    result = _header(chain, args.degrees)
    result.update(
        target=describe_pose(target, args.degrees),
        joints=joint_rows(chain, solution.q, args.degrees, seed),
        position_error_mm=round(solution.position_error * 1e3, 9),
        orientation_error_mrad=round(solution.orientation_error * 1e3, 9),
        iterations=solution.iterations, start=solution.start,
        pose=describe_pose(chain.forward(solution.q), args.degrees))
    start = ('the seed' if solution.start == 'seed'
             else f'{solution.start} of {RESTARTS} (the seed did not converge)')
    lines = [result['chain'], f'target: {chain.tool_frame} in {chain.base_frame}',
             *format_pose(result['target'], args.degrees, False),
             *format_joints(result['joints']),
             f'converged from {start} in {solution.iterations} iterations: '
             f"{result['position_error_mm']:.6f} mm and "
             f"{result['orientation_error_mrad']:.6f} mrad from the target"]
    _print(result, args.json, lines)
    return EXIT_OK
