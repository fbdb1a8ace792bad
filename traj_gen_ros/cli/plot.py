"""
PNG plots of joint trajectories: position, velocity and acceleration against time.

matplotlib with the Agg backend (no display needed); no ROS. One figure of three stacked
panels sharing the time axis, one line per joint, the legend beside them; the start, goal
and via points are marked and, for LSPB, each joint's parabolic blends are shaded in its
colour. Jerk-limited (S-curve) plans get a fourth panel, jerk.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use('Agg')

from matplotlib.axes import Axes  # noqa: E402  (the backend must be chosen first)
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from traj_gen_ros.cli.common import joint_names as default_joint_names  # noqa: E402

DPI = 100
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


def plot_trajectory(trajectory: object, output: str, **options: object) -> dict:
    """Write the PNG of :func:`draw_trajectory` (``options`` are its keywords) to ``output``."""
    figure = draw_trajectory(trajectory, **options)
    return write_png(figure, output, trajectory.joint_count)


def write_png(figure: Figure, output: str, joints: int) -> dict:
    """
    Save ``figure`` as a PNG at :data:`DPI` and close it.

    :return: ``{'output', 'width', 'height', 'panels', 'joints'}``: the path, the size in
        pixels, the panels by their y labels and the number of joints plotted.
    """
    try:
        figure.savefig(output, dpi=DPI, format='png')
        panels = [panel.get_ylabel() for panel in figure.axes]
        width, height = (int(round(inches * DPI)) for inches in figure.get_size_inches())
    finally:
        plt.close(figure)
    return {'output': str(output), 'width': width, 'height': height, 'panels': panels,
            'joints': joints}


def draw_trajectory(trajectory: object, *, jerk: bool = False, **options: object) -> Figure:
    """
    Return the figure of a core ``Trajectory``, sampled densely: see :func:`draw_samples`.

    LSPB blends are shaded; ``jerk`` adds a fourth panel, jerk (for S-curve plans).
    ``options`` are :func:`draw_samples`'s keywords but ``blends`` and ``jerks``.
    """
    times, positions, velocities, accelerations = sample_trajectory(trajectory)
    return draw_samples(times, positions, velocities, accelerations,
                        blends=blend_intervals(trajectory),
                        jerks=sample_jerk(trajectory, times) if jerk else None, **options)


def draw_samples(times: np.ndarray, positions: np.ndarray, velocities: np.ndarray,
                 accelerations: np.ndarray, *, unit: str = 'rad',
                 marks: tuple[np.ndarray, np.ndarray] | None = None,
                 blends: list[list[tuple[float, float]]] | None = None,
                 size: tuple[int, int] = (900, 900), title: str = '',
                 joint_names: Sequence[str] | None = None,
                 jerks: np.ndarray | None = None) -> Figure:
    """
    Return the figure of three stacked panels, position, velocity and acceleration vs time.

    The legend stands beside the panels, outside every axes, so it never covers a line or
    a mark. The caller closes the figure (``plt.close``).

    :param times: sample times, s, ``(n,)``.
    :param positions: ``(n, joints)``; velocities and accelerations likewise.
    :param unit: position unit for the axis labels.
    :param marks: ``(times (points,), positions (points, joints))`` of the given points,
        in order: on the position panel the first and last are marked as start and goal
        (circles), the ones between as via points (diamonds).
    :param blends: per joint, ``(start, end)`` intervals to shade on every panel.
    :param size: image size in pixels, ``(width, height)``, at :data:`DPI`.
    :param title: figure title.
    :param joint_names: legend names, default ``joint_1``, ``joint_2``, … (the node's).
    :param jerks: ``(n, joints)`` jerk samples: a fourth panel when given.
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
        handles = []
        for panel, values, label in zip(axes, series, labels, strict=True):
            for joint in range(joints):
                color = colors[joint % len(colors)]
                line, = panel.plot(times, values[:, joint], color=color, linewidth=1.6,
                                   label=names[joint])
                if panel is axes[0]:
                    handles.append(line)
                for start, end in (blends[joint] if blends else []):
                    panel.axvspan(start, end, color=color, alpha=0.12, linewidth=0)
            panel.set_ylabel(label)
            panel.grid(True, alpha=0.3)
        if marks is not None:
            handles += _mark_points(axes[0], marks, colors)
        if blends and any(blends):
            handles.append(Patch(color='grey', alpha=0.12, linewidth=0, label='blends'))
        figure.legend(handles=handles, loc='outside right upper', fontsize='small')
        axes[-1].set_xlabel('time [s]')
        if title:
            figure.suptitle(title)
    except BaseException:
        plt.close(figure)
        raise
    return figure


def _mark_points(panel: Axes, marks: tuple[np.ndarray, np.ndarray],
                 colors: Sequence[str]) -> list[Line2D]:
    """Mark start and goal (circles) and the via points between (diamonds); legend keys."""
    mark_times, mark_positions = (np.asarray(m, dtype=float) for m in marks)
    ends = [0, len(mark_times) - 1]
    vias = list(range(1, len(mark_times) - 1))
    styles = [(ends, 'o', 'start, goal'), (vias, 'D', 'via points')]
    keys = []
    for rows, marker, label in styles:
        if not rows:
            continue
        for joint in range(mark_positions.shape[1]):
            panel.plot(mark_times[rows], mark_positions[rows, joint], marker, markersize=6,
                       markerfacecolor='white', color=colors[joint % len(colors)],
                       gid=label)
        keys.append(Line2D([], [], linestyle='', marker=marker, markersize=6,
                           markerfacecolor='white', color='0.3', label=label))
    return keys
