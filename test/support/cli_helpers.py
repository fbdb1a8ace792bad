"""traj-gen run as a user runs it, and what its plots show: helpers of the CLI tests."""

import json
import os
from pathlib import Path
import subprocess
import sys

REPO = Path(__file__).resolve().parents[2]


TIMEOUT = 120  # s per command: generous, the machine is shared


def env() -> dict:
    variables = dict(os.environ)
    variables['PYTHONPATH'] = os.pathsep.join(
        [str(REPO)] + [p for p in variables.get('PYTHONPATH', '').split(os.pathsep) if p])
    return variables


def traj_gen(*args: str) -> subprocess.CompletedProcess:
    """Run `traj-gen ARGS` from the work tree (test_install.py runs the installed script)."""
    return subprocess.run([sys.executable, '-m', 'traj_gen_ros.cli.main', *args], cwd=REPO,
                          env=env(), capture_output=True, text=True, timeout=TIMEOUT)


def ok(*args: str) -> str:
    result = traj_gen(*args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == '', result.stderr
    return result.stdout


def solve_json(*args: str) -> dict:
    return json.loads(ok('solve', *args, '--json'))


def assert_one_line_error(result: subprocess.CompletedProcess, code: int = 2) -> str:
    assert result.returncode == code, (result.returncode, result.stdout, result.stderr)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert 'Traceback' not in result.stderr + result.stdout
    return lines[0]


def legend_covers(figure) -> list:
    """
    Return what the figure's one legend covers, in display coordinates (pixels).

    The axes its box overlaps and every point of a drawn line (curves and marks) inside it:
    both empty when the legend stands beside the panels.
    """
    figure.canvas.draw()
    legend, = figure.legends
    box = legend.get_window_extent()
    corners = box.get_points()
    assert all(figure.bbox.contains(x, y) for x, y in corners), (box, figure.bbox)  # not cut
    covered = [panel.get_ylabel() for panel in figure.axes
               if box.overlaps(panel.get_window_extent())]
    for panel in figure.axes:
        for line in panel.get_lines():
            points = line.get_transform().transform(line.get_xydata())
            covered += [(line.get_label(), x, y) for x, y in points if box.contains(x, y)]
    return covered


def marks_of(figure, gid: str) -> tuple[list, list]:
    """Return the times and positions marked ``gid`` on the position panel, all joints."""
    lines = [line for line in figure.axes[0].get_lines() if line.get_gid() == gid]
    return ([list(line.get_xdata()) for line in lines],
            [list(line.get_ydata()) for line in lines])
