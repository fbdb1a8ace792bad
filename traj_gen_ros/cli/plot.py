"""
PNG plots of joint trajectories: position, velocity and acceleration against time.

matplotlib with the Agg backend (no display needed); no ROS. One figure of three stacked
panels sharing the time axis, one line per joint; given points are marked and, for LSPB,
each joint's parabolic blends are shaded in its colour. Jerk-limited (S-curve) plans get
a fourth panel, jerk.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use('Agg')

import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402
from traj_gen_ros.cli.common import joint_names as default_joint_names  # noqa: E402

DPI = 100
PANELS = ('position', 'velocity', 'acceleration')
_DENSE_SAMPLES = 1000


def sample_trajectory(trajectory: object, samples: int = _DENSE_SAMPLES
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Sample a core ``Trajectory`` densely, with every breakpoint included.

    :param trajectory: a :class:`traj_gen_ros.core.trajectory.Trajectory`.
    :param samples: evenly spaced samples, to which the breakpoints are added.
    :return: times ``(n,)`` and positions, velocities, accelerations ``(n, joints)``.
    """
    times = np.union1d(np.linspace(0.0, trajectory.duration, samples),
                       np.asarray(trajectory.breakpoints).reshape(-1))
    positions, velocities, accelerations = trajectory.sample(times)
    return times, positions, velocities, accelerations


def sample_jerk(trajectory: object, times: np.ndarray) -> np.ndarray:
    """
    Return the jerk (third derivative) of a core ``Trajectory`` at ``times``: ``(n, joints)``.

    Each joint's piece is looked up in its own breakpoints (zero-length pieces skipped)
    and its ascending coefficients differentiated three times at the local time.
    """
    times = np.clip(np.asarray(times, dtype=float), 0.0, trajectory.duration)
    breakpoints = np.asarray(trajectory.breakpoints)
    if breakpoints.ndim == 1:
        breakpoints = np.repeat(breakpoints[:, None], trajectory.joint_count, axis=1)
    coefficients = trajectory.coefficients
    jerks = np.zeros((times.size, trajectory.joint_count))
    for joint in range(trajectory.joint_count):
        piece = np.searchsorted(breakpoints[1:-1, joint], times, side='right')
        local = times - breakpoints[piece, joint]
        for power in range(coefficients.shape[1] - 1, 2, -1):
            factor = power * (power - 1) * (power - 2)
            jerks[:, joint] += factor * coefficients[piece, power, joint] * local ** (power - 3)
    return jerks


def blend_intervals(trajectory: object) -> list[list[tuple[float, float]]]:
    """
    Return each joint's blend intervals ``[(start, end), …]`` of an LSPB trajectory.

    Empty lists for any other trajectory (it has no ``blend_times``).
    """
    if not hasattr(trajectory, 'blend_times'):
        return [[] for _ in range(trajectory.joint_count)]
    starts = np.asarray(trajectory.breakpoints)[0::2]  # blend, line, …, blend
    ends = starts + trajectory.blend_times
    return [[(float(s), float(e)) for s, e in zip(starts[:, j], ends[:, j], strict=True)]
            for j in range(trajectory.joint_count)]


def plot_trajectory(trajectory: object, output: str, *, unit: str = 'rad',
                    marks: tuple[np.ndarray, np.ndarray] | None = None,
                    size: tuple[int, int] = (900, 900), title: str = '',
                    joint_names: Sequence[str] | None = None, jerk: bool = False) -> dict:
    """
    Write a PNG of a core ``Trajectory``: see :func:`plot_samples`.

    :param trajectory: the trajectory to sample densely.
    :param output: PNG path.
    :param unit: position unit for the axis labels.
    :param marks: ``(times (points,), positions (points, joints))`` to mark.
    :param size: image size in pixels, ``(width, height)``.
    :param title: figure title.
    :param joint_names: legend names, default ``joint_1``, ``joint_2``, … (the node's).
    :param jerk: add a fourth panel, jerk (for S-curve plans).
    :return: what was written (see :func:`plot_samples`).
    """
    times, positions, velocities, accelerations = sample_trajectory(trajectory)
    return plot_samples(times, positions, velocities, accelerations, output, unit=unit,
                        marks=marks, blends=blend_intervals(trajectory), size=size,
                        title=title, joint_names=joint_names,
                        jerks=sample_jerk(trajectory, times) if jerk else None)


def plot_samples(times: np.ndarray, positions: np.ndarray, velocities: np.ndarray,
                 accelerations: np.ndarray, output: str, *, unit: str = 'rad',
                 marks: tuple[np.ndarray, np.ndarray] | None = None,
                 blends: list[list[tuple[float, float]]] | None = None,
                 size: tuple[int, int] = (900, 900), title: str = '',
                 joint_names: Sequence[str] | None = None,
                 jerks: np.ndarray | None = None) -> dict:
    """
    Write three stacked panels (position, velocity, acceleration vs time) to a PNG.

    :param times: sample times, s, ``(n,)``.
    :param positions: ``(n, joints)``; velocities and accelerations likewise.
    :param output: PNG path.
    :param unit: position unit for the axis labels.
    :param marks: ``(times, positions)`` of points to mark on the position panel.
    :param blends: per joint, ``(start, end)`` intervals to shade on every panel.
    :param size: image size in pixels, ``(width, height)``, at :data:`DPI`.
    :param title: figure title.
    :param joint_names: legend names, default ``joint_1``, ``joint_2``, … (the node's).
    :param jerks: ``(n, joints)`` jerk samples: a fourth panel when given.
    :return: ``{'output', 'width', 'height', 'panels', 'joints'}``; ``panels`` lists the
        figure's axes by their y labels.
    """
    joints = positions.shape[1]
    names = list(joint_names) if joint_names else default_joint_names(joints)
    width, height = size
    series = [positions, velocities, accelerations]
    labels = [f'position [{unit}]', f'velocity [{unit}/s]', f'acceleration [{unit}/s²]']
    if jerks is not None:
        series.append(jerks)
        labels.append(f'jerk [{unit}/s³]')
    figure, axes = plt.subplots(len(series), 1, sharex=True, figsize=(width / DPI, height / DPI),
                                dpi=DPI, layout='constrained')
    try:
        colors = plt.rcParams['axes.prop_cycle'].by_key()['color']
        for panel, values, label in zip(axes, series, labels, strict=True):
            for joint in range(joints):
                color = colors[joint % len(colors)]
                panel.plot(times, values[:, joint], color=color, linewidth=1.6,
                           label=names[joint])
                for start, end in (blends[joint] if blends else []):
                    panel.axvspan(start, end, color=color, alpha=0.12, linewidth=0)
            panel.set_ylabel(label)
            panel.grid(True, alpha=0.3)
        if marks is not None:
            mark_times, mark_positions = (np.asarray(m, dtype=float) for m in marks)
            for joint in range(joints):
                axes[0].plot(mark_times, mark_positions[:, joint], 'o', markersize=6,
                             markerfacecolor='white', color=colors[joint % len(colors)],
                             label='points' if joint == 0 else None)
        if blends and any(blends):
            axes[0].axvspan(0, 0, color='grey', alpha=0.12, label='blends')
        axes[0].legend(loc='best', fontsize='small')
        axes[-1].set_xlabel('time [s]')
        if title:
            figure.suptitle(title)
        figure.savefig(output, dpi=DPI, format='png')
        panels = [panel.get_ylabel() for panel in figure.axes]
    finally:
        plt.close(figure)
    return {'output': str(output), 'width': width, 'height': height, 'panels': panels,
            'joints': joints}
