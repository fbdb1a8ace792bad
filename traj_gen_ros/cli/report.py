"""
``traj-gen solve`` output: coefficients, Craig's LSPB table or the S-curve phase table.

:func:`describe` gives a JSON-ready dictionary of a plan; :func:`format_text` the text a
person reads. Joints are named ``joint_1``, ``joint_2``, … (:func:`joint_names`, the
node's convention); points keep Craig's names from 1 (t1, θ̇12, t12).
"""

from __future__ import annotations

import numpy as np
from traj_gen_ros.cli.common import joint_names
from traj_gen_ros.cli.plan import Plan


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
    if plan.profile == 'scurve':
        result.update(kind='scurve', **_phase_table(trajectory, len(plan.points) - 1))
    elif hasattr(trajectory, 'blend_times'):
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


def _phase_table(trajectory: object, segments: int) -> dict:
    """
    Per joint, each S-curve phase: name, start, duration, jerk, and what it reaches.

    ``acceleration`` and ``velocity`` are the values at the phase's end. Phases are
    named ``1`` … ``7`` (``brake 1``, ``brake 2`` first when the start must brake), or
    ``segment.phase`` through via points; zero-length phases are listed too.
    """
    breakpoints = np.asarray(trajectory.breakpoints)
    coefficients = trajectory.coefficients
    pieces = trajectory.piece_count
    if segments > 1 and pieces == 7 * segments:
        names = [f'{segment + 1}.{phase + 1}' for segment in range(segments)
                 for phase in range(7)]
    elif pieces == 9:
        names = ['brake 1', 'brake 2'] + [str(phase + 1) for phase in range(7)]
    else:
        names = [str(piece + 1) for piece in range(pieces)]
    lengths = np.diff(breakpoints, axis=0)
    jerk = 6.0 * coefficients[:, 3]
    acceleration = 2.0 * coefficients[:, 2] + jerk * lengths
    velocity = (coefficients[:, 1] + 2.0 * coefficients[:, 2] * lengths
                + 3.0 * coefficients[:, 3] * lengths**2)
    phases = [[{'phase': names[piece], 'start': round(float(breakpoints[piece, joint]), 12),
                'duration': round(float(lengths[piece, joint]), 12),
                'jerk': round(float(jerk[piece, joint]), 12),
                'acceleration': round(float(acceleration[piece, joint]), 12),
                'velocity': round(float(velocity[piece, joint]), 12)}
               for piece in range(pieces)] for joint in range(trajectory.joint_count)]
    return {'peak_jerk': _rows(trajectory.peak_jerk()), 'phases': phases}


def _pair_label(index: int, count: int) -> str:
    separator = ',' if count >= 10 else ''
    return f'{index + 1}{separator}{index + 2}'


def format_text(result: dict) -> str:
    """Format :func:`describe`'s dict the way the book writes it."""
    unit = result['units']['position']
    joints = result['joints']
    names = joint_names(joints)
    lines = [f"{result['profile']}: {joints} joint{'s' if joints > 1 else ''}, "
             f"{len(result['points'])} points, duration {result['duration']:.4f} s; "
             f'positions in {unit}, times in s']
    if result['kind'] == 'scurve':
        for joint, rows in enumerate(result['phases']):
            lines.append(f"{names[joint]}: peak |jerk| {result['peak_jerk'][joint]:.4f} "
                         f'{unit}/s³; acceleration and velocity at the end of each phase')
            lines.append(f"  {'phase':<8}{'start':>10}{'duration':>10}{'jerk':>12}"
                         f"{'acceleration':>14}{'velocity':>12}")
            for row in rows:
                lines.append(f"  {row['phase']:<8}{row['start']:10.4f}{row['duration']:10.4f}"
                             f"{row['jerk']:12.4f}{row['acceleration']:14.4f}"
                             f"{row['velocity']:12.4f}")
        return '\n'.join(lines)
    if result['kind'] == 'lspb':
        points = len(result['points'])
        for joint in range(joints):
            lines.append(f"{names[joint]}: |θ̈| = {result['blend_acceleration'][joint]:.4f} "
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
    width = max(len(name) for name in names) + 1
    for segment, coefficients in enumerate(result['coefficients']):
        start = result['segment_starts'][segment]
        duration = result['segment_durations'][segment]
        lines.append(f'segment {segment + 1}: t = {start:.4f} … {start + duration:.4f} s')
        lines.append(f"  {'joint':<{width}}{powers}")
        for name, row in zip(names, coefficients, strict=True):
            lines.append(f'  {name:<{width}}' + ''.join(f'{value:12.4f}' for value in row))
    return '\n'.join(lines)


# ---------------------------------------------------------------------------- commands
