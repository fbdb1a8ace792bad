"""
The PNG of ``traj-gen plot line|arc``: the joints in time, the tool's speed, the 3-D path.

matplotlib with the Agg backend (:mod:`traj_gen_ros.cli.plot` chooses it). On the left,
sharing the time axis: joint positions, velocities and accelerations (one line per
joint; start, goal and the corners or interim point marked at the times the path reaches
them), then the tool's speed along the path ``|dp/ds|·ṡ`` (m/s) with its limit
``max_linear_velocity`` dashed and the time shaded by the limit that bounds the speed
there (:attr:`TimedPath.bounds`, merged by :func:`.tool_path_commands.bound_runs`). On the
right, the tool path in the base frame, in 3-D and seen from above: the ideal path by
pieces (lines, blends, the arc), the tool where the joints put it (``chain.forward``,
dotted), the poses given (``path.waypoints``: start, corners or interim point, goal) and
each blend's ends.
"""

from __future__ import annotations

import math

from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
import numpy as np
from traj_gen_ros.cli import plot as plotting  # the Agg backend, DPI, write_png
from traj_gen_ros.cli.tool_path_commands import bound_runs, tool_speeds, ToolPathPlan

_SAMPLES = 1500
_PIECE_STYLE = {'line': ('tab:blue', 'lines'), 'arc': ('tab:blue', 'arc'),
                'blend': ('tab:orange', 'blends')}
_BOUND_COLORS = ('tab:green', 'tab:red', 'tab:purple', 'tab:brown', 'tab:olive', 'tab:cyan',
                 'tab:pink', 'tab:gray')


def plot_tool_path(plan: ToolPathPlan, output: str, size: tuple[int, int],
                   degrees: bool = False) -> dict:
    """Write :func:`draw_tool_path`'s figure to ``output``; return where, size and panels."""
    return plotting.write_png(draw_tool_path(plan, size, degrees), output,
                              len(plan.chain.joints))


def draw_tool_path(plan: ToolPathPlan, size: tuple[int, int], degrees: bool = False
                   ) -> Figure:
    """Return the figure the module describes (the caller closes it)."""
    timed, chain = plan.timed, plan.chain
    times = np.union1d(np.linspace(0.0, timed.duration, _SAMPLES), timed.times)
    positions, velocities, accelerations = timed.trajectory.sample(times)
    scales = np.where(chain.angular & degrees, 180.0 / math.pi, 1.0)
    unit = 'deg' if degrees else 'rad'
    width, height = size
    figure = plotting.plt.figure(figsize=(width / plotting.DPI, height / plotting.DPI),
                                 dpi=plotting.DPI, layout='constrained')
    try:
        grid = figure.add_gridspec(4, 2, width_ratios=(3, 2))
        panels = [figure.add_subplot(grid[0, 0])]
        panels += [figure.add_subplot(grid[row, 0], sharex=panels[0]) for row in (1, 2, 3)]
        colors = plotting.plt.rcParams['axes.prop_cycle'].by_key()['color']
        handles = []
        for panel, values, label in zip(
                panels[:3], (positions, velocities, accelerations),
                (f'position [{unit}, m]', f'velocity [{unit}/s, m/s]',
                 f'acceleration [{unit}/s², m/s²]'), strict=True):
            for joint, name in enumerate(chain.joints):
                line, = panel.plot(times, values[:, joint] * scales[joint], linewidth=1.4,
                                   color=colors[joint % len(colors)], label=name)
                if panel is panels[0]:
                    handles.append(line)
            panel.set_ylabel(label)
            panel.grid(True, alpha=0.3)
            panel.tick_params(labelbottom=False)
        handles += _mark_waypoints(panels[0], plan, scales, colors)
        handles += _speed_panel(panels[3], plan, times)
        _path_view(figure.add_subplot(grid[0:2, 1], projection='3d'), plan, handles)
        _path_view(figure.add_subplot(grid[2:4, 1]), plan, None)
        figure.legend(handles=handles, loc='outside lower center', ncol=4, fontsize='small')
        goal = plan.poses[-1][:3, 3]
        figure.suptitle(f'{plan.shape} to ({goal[0]:.3g}, {goal[1]:.3g}, {goal[2]:.3g}) m in '
                        f'{timed.duration:.3g} s: {chain.tool_frame} in {chain.base_frame}')
    except BaseException:
        plotting.plt.close(figure)
        raise
    return figure


def _waypoint_times(plan: ToolPathPlan) -> np.ndarray:
    """Return when the path reaches (or rounds) each waypoint: ``s(t)`` inverted on the grid."""
    return np.interp(plan.path.waypoint_s, plan.timed.s, plan.timed.times)


def _mark_waypoints(panel: object, plan: ToolPathPlan, scales: np.ndarray,
                    colors: list[str]) -> list[Line2D]:
    """Mark start and goal (circles) and the corners or the interim point (diamonds)."""
    times = _waypoint_times(plan)
    joints = plan.timed.trajectory.sample(times)[0] * scales
    last = len(times) - 1
    keys = []
    for rows, marker, label in (([0, last], 'o', 'start, goal'),
                                (list(range(1, last)), 'D', 'corners' if plan.shape == 'line'
                                 else 'interim point')):
        if not rows:
            continue
        for joint in range(joints.shape[1]):
            panel.plot(times[rows], joints[rows, joint], marker, markersize=5,
                       markerfacecolor='white', color=colors[joint % len(colors)], gid=label)
        keys.append(Line2D([], [], linestyle='', marker=marker, markersize=5,
                           markerfacecolor='white', color='0.3', label=label))
    return keys


def _speed_panel(panel: object, plan: ToolPathPlan, times: np.ndarray) -> list[object]:
    """Draw the tool's speed, its limit dashed, the time shaded by the bounding limit."""
    _, speed, _ = tool_speeds(plan, times)
    limit = plan.limits['max_linear_velocity']
    panel.plot(times, speed, color='black', linewidth=1.6, gid='tool speed')
    keys = [Line2D([], [], color='black', linewidth=1.6, label='tool speed |dp/ds|·ṡ')]
    if math.isfinite(limit) and limit <= 1.5 * max(float(speed.max()), 1e-9):
        panel.axhline(limit, color='black', linestyle='--', linewidth=1.0)
        keys.append(Line2D([], [], color='black', linestyle='--', linewidth=1.0,
                           label=f'max_linear_velocity {limit:g} m/s'))
    shades: dict[str, str] = {}
    for run in bound_runs(plan):
        color = shades.setdefault(run['limit'], _BOUND_COLORS[len(shades) % len(_BOUND_COLORS)])
        panel.axvspan(run['start_time'], run['end_time'], color=color, alpha=0.18, linewidth=0)
    keys += [Patch(color=color, alpha=0.18, linewidth=0, label=f'bounded by {name}')
             for name, color in shades.items()]
    panel.set_ylabel('tool speed [m/s]')
    panel.set_xlabel('time [s]')
    panel.grid(True, alpha=0.3)
    panel.set_ylim(bottom=0.0)
    return keys


def _path_view(view: object, plan: ToolPathPlan, handles: list | None) -> None:
    """
    Draw the tool path by pieces, the tool the joints carry, the poses and the blends' ends.

    In 3-D on a 3-D ``view``, else seen from above (x, y) with equal axes; legend keys are
    added to ``handles`` unless it is None.
    """
    path, chain, timed = plan.path, plan.chain, plan.timed
    axes = slice(0, 3 if view.name == '3d' else 2)
    options = {'depthshade': False} if view.name == '3d' else {}
    labelled = set()
    for piece in path.pieces:
        count = max(2, int(_SAMPLES * (piece.end - piece.start) / path.length))
        points = path.sample(np.linspace(piece.start, piece.end, count)).position[:, axes]
        color, label = _PIECE_STYLE[piece.kind]
        view.plot(*points.T, color=color, linewidth=2.4 if piece.kind == 'blend' else 1.6,
                  gid=piece.kind)
        if piece.kind == 'blend':
            view.scatter(*points[[0, -1]].T, color=color, s=12, **options)
        if handles is not None and label not in labelled:
            labelled.add(label)
            handles.append(Line2D([], [], color=color, linewidth=2, label=f'path: {label}'))
    carried = chain.forward(timed.trajectory.sample(
        np.linspace(0.0, timed.duration, 200))[0])[:, :3, 3]
    view.plot(*carried[:, axes].T, color='black', linestyle=':', linewidth=1.0, gid='tool')
    waypoints = path.waypoints[:, :3, 3]
    view.scatter(*waypoints[[0, -1], axes].T, marker='o', s=40, facecolors='white',
                 edgecolors='black', zorder=3, **options)
    if len(waypoints) > 2:
        view.scatter(*waypoints[1:-1, axes].T, marker='D', s=30, facecolors='white',
                     edgecolors='tab:red', zorder=3, **options)
    for index, point in enumerate(waypoints[:, axes]):
        view.text(*point, f' {index}', fontsize='small')
    if handles is not None:
        handles.append(Line2D([], [], color='black', linestyle=':',
                              label='tool (forward of q)'))
    everything = np.vstack([waypoints, carried])[:, axes]
    middle = (everything.max(axis=0) + everything.min(axis=0)) / 2
    half = 0.55 * max(float((everything.max(axis=0) - everything.min(axis=0)).max()), 2e-3)
    view.set_xlim(middle[0] - half, middle[0] + half)
    view.set_ylim(middle[1] - half, middle[1] + half)
    view.set_xlabel('x [m]')
    view.set_ylabel('y [m]')
    if view.name == '3d':
        view.set_zlim(middle[2] - half, middle[2] + half)
        view.set_zlabel('z [m]', labelpad=8)
        view.set_box_aspect((1, 1, 1), zoom=0.85)
        view.set_title(f'tool path in {chain.base_frame} (poses numbered, start 0)',
                       fontsize='small')
    else:
        view.set_aspect('equal')
        view.grid(True, alpha=0.3)
        view.set_title('seen from above', fontsize='small')
