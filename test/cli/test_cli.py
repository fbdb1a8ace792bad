"""traj-gen solve/plot as a user runs them: subprocesses, checked against the lecture."""

import json
import math
import subprocess
import sys

from cli_helpers import (
    assert_one_line_error,
    env,
    legend_covers,
    marks_of,
    ok,
    REPO,
    solve_json,
    TIMEOUT,
    traj_gen,
)
import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np
import pytest
from traj_gen_ros import core
from traj_gen_ros.cli import plot
from traj_gen_ros.cli.main import build_parser, MATPLOTLIB_REQUIREMENT
from traj_gen_ros.cli.plan import make_plan

# The lecture's LSPB via example (points 10 35 25 10 deg, durations 2 1 3, |θ̈| = 50 deg/s²)
# from Craig's formulas, and the values the lecture prints.
T1 = 2 - math.sqrt(4 - 2 * 25 / 50)
V12 = 25 / (2 - T1 / 2)
T4 = 3 - math.sqrt(9 - 2 * 15 / 50)
V34 = -15 / (3 - T4 / 2)
V23 = -10.0
T2 = abs(V23 - V12) / 50
T3 = abs(V34 - V23) / 50
LSPB_EXACT = {'blend_times': [T1, T2, T3, T4], 'linear_velocities': [V12, V23, V34],
              'linear_durations': [2 - T1 - T2 / 2, 1 - T2 / 2 - T3 / 2, 3 - T4 - T3 / 2]}
LSPB_LECTURE = {'blend_times': [0.27, 0.47, 0.098, 0.10],
                'linear_velocities': [13.4, -10.0, -5.09],
                'linear_durations': [1.50, 0.72, 2.85]}
LSPB_ARGS = ['lspb', '--points', '10', '35', '25', '10', '--durations', '2', '1', '3',
             '--acceleration', '50', '--degrees']
CUBIC_ARGS = ['cubic', '--points', '15', '75', '--duration', '3', '--degrees']


# ---------------------------------------------------------------- solve


def test_solve_cubic_15_to_75_in_3_s_prints_the_lecture_coefficients():
    result = solve_json(*CUBIC_ARGS)
    assert result['kind'] == 'polynomial' and result['degree'] == 3
    assert result['units'] == {'position': 'deg', 'time': 's'}
    assert result['duration'] == pytest.approx(3.0)
    (joint,), = result['coefficients']  # one segment, one joint
    assert joint == pytest.approx([15.0, 0.0, 20.0, -40.0 / 9.0])
    assert joint[3] == pytest.approx(-4.44, abs=0.005)

    text = ok('solve', *CUBIC_ARGS)
    assert 'a0 + a1 t + a2 t² + a3 t³' in text
    row = next(line for line in text.splitlines() if line.split()[:1] == ['joint_1'])
    assert row.split() == ['joint_1', '15.0000', '0.0000', '20.0000', '-4.4444']


def test_solve_lspb_via_reproduces_the_lecture_table():
    result = solve_json(*LSPB_ARGS)
    assert result['kind'] == 'lspb' and result['duration'] == pytest.approx(6.0)
    assert result['blend_acceleration'] == pytest.approx([50.0])
    for key, expected in LSPB_EXACT.items():
        assert result[key][0] == pytest.approx(expected, rel=1e-9), key
        assert result[key][0] == pytest.approx(LSPB_LECTURE[key], abs=0.006), key

    text = ok('solve', *LSPB_ARGS)
    names = {'t1': T1, 't2': T2, 't3': T3, 't4': T4, 'θ̇12': V12, 'θ̇23': V23, 'θ̇34': V34,
             't12': LSPB_EXACT['linear_durations'][0], 't23': LSPB_EXACT['linear_durations'][1],
             't34': LSPB_EXACT['linear_durations'][2]}
    tokens = text.split()
    for name, value in names.items():
        index = tokens.index(name)
        assert tokens[index + 1] == '=' and tokens[index + 2] == f'{value:.4f}', name
    assert '13.3975' in text and '-10.0000' in text and '-5.0862' in text
    assert text.splitlines()[1] == 'joint_1: |θ̈| = 50.0000 deg/s²'


def test_tables_name_joints_joint_1_joint_2():
    text = ok('solve', 'min-time', '--points', '0,0', '1,2', '--max-velocity', '1',
              '--max-acceleration', '2')
    assert [line.split(':')[0] for line in text.splitlines() if line.startswith('joint')] == [
        'joint_1', 'joint_2']
    text = ok('solve', 'quintic', '--points', '0,0', '1,-0.5', '--duration', '2')
    assert [line.split()[0] for line in text.splitlines()[-2:]] == ['joint_1', 'joint_2']


def test_solve_in_radians_matches_degrees_scaled():
    scale = math.pi / 180
    radians = solve_json('lspb', '--points', *(f'{q * scale!r}' for q in (10, 35, 25, 10)),
                         '--durations', '2', '1', '3', '--acceleration', f'{50 * scale!r}')
    assert radians['units']['position'] == 'rad'
    assert radians['blend_times'][0] == pytest.approx(LSPB_EXACT['blend_times'], rel=1e-9)
    assert np.allclose(radians['linear_velocities'][0],
                       np.array(LSPB_EXACT['linear_velocities']) * scale, rtol=1e-9)


def test_solve_multi_joint_points_with_negative_values_and_min_time():
    quintic = solve_json('quintic', '--points', '-1,0', '1,-0.5', '--duration', '2')
    assert quintic['joints'] == 2 and quintic['degree'] == 5
    joint0, joint1 = quintic['coefficients'][0]
    assert joint0[:3] == pytest.approx([-1.0, 0.0, 0.0])
    assert joint0[3] == pytest.approx(10 * 2.0 / 2**3)  # a3 = 10 (qf - q0) / T³
    assert joint1[3] == pytest.approx(10 * -0.5 / 2**3)

    timed = solve_json('min-time', '--points', '0,0', '1,2', '--max-velocity', '1',
                       '--max-acceleration', '2', '--shape', 'lspb')
    # joint_2 binds: D = 2 >= v²/a, so T = D/v + v/a = 2.5 s; joint_1 is stretched to it.
    assert timed['duration'] == pytest.approx(2.5)
    assert timed['profile'] == 'min-time lspb'
    assert max(abs(v) for v in timed['linear_velocities'][1]) == pytest.approx(1.0)

    via = solve_json('cubic-via', '--points', '0', '1', '0.5', '--durations', '1', '1',
                     '--velocities', 'continuous')
    assert len(via['coefficients']) == 2 and via['segment_starts'] == [0.0, 1.0]


# ---------------------------------------------------------------- plot


def dark_rows(image: np.ndarray) -> list[int]:
    """Rows where most pixels are dark: the top and bottom frame lines of each panel."""
    dark = image[..., :3].max(axis=2) < 0.35
    rows = dark.mean(axis=1) > 0.5
    return [int(row) for row in np.flatnonzero(np.diff(rows.astype(int)) == 1) + 1]


@pytest.mark.parametrize('args', [CUBIC_ARGS, LSPB_ARGS], ids=['cubic', 'lspb_via'])
def test_plot_writes_a_png_of_the_given_size_with_three_panels(tmp_path, args):
    output = tmp_path / 'plot.png'
    info = json.loads(ok('plot', *args, '-o', str(output), '--size', '800x600', '--json'))
    assert info['panels'] == ['position [deg]', 'velocity [deg/s]', 'acceleration [deg/s²]']
    assert (info['width'], info['height']) == (800, 600)

    image = mpimg.imread(output)
    assert image.shape[:2] == (600, 800)
    # Three panels stacked: two frame lines (top, bottom) per panel, in order down the image.
    frames = dark_rows(image)
    assert len(frames) == 6, frames
    for panel, (top, bottom) in enumerate(zip(frames[0::2], frames[1::2], strict=True)):
        assert panel * 200 <= (top + bottom) / 2 < (panel + 1) * 200, frames  # its third
        assert bottom - top > 120, frames  # three panels of similar height share the image
        inside = image[top + 3:bottom - 2, 100:780, :3]
        curve = (inside.max(axis=2) - inside.min(axis=2)) > 0.3  # coloured, not grey/white
        assert curve.any(axis=1).mean() > 0.3, panel  # a trajectory line crosses the panel


def test_plot_legend_stands_beside_the_panels_and_via_points_are_marked():
    plan = make_plan(build_parser().parse_args(['plot', *LSPB_ARGS, '-o', 'unused.png']))
    figure = plot.draw_trajectory(plan.trajectory, marks=(plan.point_times, plan.points),
                                  unit=plan.unit, size=(800, 600))
    try:
        assert legend_covers(figure) == []
        assert [text.get_text() for text in figure.legends[0].get_texts()] == [
            'joint_1', 'start, goal', 'via points', 'blends']
        assert marks_of(figure, 'via points') == ([[2.0, 3.0]], [[35.0, 25.0]])
        assert marks_of(figure, 'start, goal') == ([[0.0, 6.0]], [[10.0, 10.0]])
    finally:
        plt.close(figure)


def test_plot_legend_of_six_joints_covers_no_line():
    # The goal: joint_5 to -1.0 (and joint_2 to 0.4), the other joints at 0.
    goal = np.array([0.0, 0.4, 0.0, 0.0, -1.0, 0.0])
    figure = plot.draw_trajectory(core.quintic(np.zeros(6), goal, 1.0),
                                  marks=([0.0, 1.0], np.array([np.zeros(6), goal])))
    try:
        assert legend_covers(figure) == []
        assert [text.get_text() for text in figure.legends[0].get_texts()] == [
            *(f'joint_{joint}' for joint in range(1, 7)), 'start, goal']
        assert marks_of(figure, 'via points') == ([], [])
    finally:
        plt.close(figure)


def test_plot_shades_lspb_blends(tmp_path):
    def shaded_columns(*args: str) -> int:
        output = tmp_path / f'{args[0]}.png'
        ok('plot', *args, '-o', str(output), '--size', '800x600')
        image = mpimg.imread(output)[..., :3]
        # The blend shade: the first colour (C0, blue) at 12 % over white.
        shade = np.array([1.0, 1.0, 1.0]) * 0.88 + np.array([0.12, 0.47, 0.71]) * 0.12
        close = np.abs(image - shade).max(axis=2) < 0.02
        return int((close.mean(axis=0) > 0.5).sum())

    blended = shaded_columns(*LSPB_ARGS)
    assert blended > 10
    assert shaded_columns(*CUBIC_ARGS) == 0


# ---------------------------------------------------------------- errors and help


@pytest.mark.parametrize('args', [
    [],
    ['solve'],
    ['solve', 'septic', '--points', '0', '1', '--duration', '1'],
    ['solve', 'cubic', '--points', '0', 'x', '--duration', '1'],
    ['solve', 'cubic', '--duration', '1'],
    ['solve', 'cubic', '--points', '0,0', '1', '--duration', '1'],
    ['solve', 'cubic', '--points', '0', '1', '--durations', '1', '2'],
    ['solve', 'cubic', '--points', '0', '1', '2', '--duration', '1'],
    ['solve', 'cubic', '--points', '0', '1', '--duration', '-1'],
    ['solve', 'lspb', '--points', '0', '1', '--duration', '1'],
    ['solve', *LSPB_ARGS[:-3], '--acceleration', '5', '--degrees'],
    ['solve', 'min-time', '--points', '0', '1', '--max-velocity', '1'],
    ['solve', 'cubic', '--points', '0', '1', '--duration', '1', '--bogus'],
    ['plot', *CUBIC_ARGS],
    ['plot', *CUBIC_ARGS, '-o', '/nonexistent/dir/plot.png'],
    ['plot', *CUBIC_ARGS, '-o', 'x.png', '--size', 'big'],
    ['plot', '-o', 'x.png'],
    ['goal', 'joint_1'],
    ['goal', 'joint_1=abc'],
    ['via', '--joints', 'a', 'b', '--point', '0', '@1'],
    ['via', '--joints', 'a', '--point', '0', '@1', '--point', '1'],
], ids=lambda args: ' '.join(args) or 'nothing')
def test_bad_arguments_give_one_line_and_exit_2(args):
    line = assert_one_line_error(traj_gen(*args))
    assert line.startswith('traj-gen'), line


@pytest.mark.parametrize('args', [
    ['plot', *CUBIC_ARGS, '-o', 'never.png'],
    ['plot', '--topic', '/trajectory_generator/trajectory', '-o', 'never.png', '--timeout', '30'],
], ids=['plan', 'topic'])
def test_plot_without_matplotlib_says_what_to_install_and_exits_2(tmp_path, args):
    # `import matplotlib` fails as in an environment without it (None in sys.modules).
    script = ('import sys\n'
              "sys.modules['matplotlib'] = None\n"
              'from traj_gen_ros.cli.main import main\n'
              'sys.exit(main(sys.argv[1:]))\n')
    result = subprocess.run([sys.executable, '-c', script, *args], cwd=tmp_path, env=env(),
                            capture_output=True, text=True, timeout=TIMEOUT)
    line = assert_one_line_error(result, code=2)
    assert line.startswith('traj-gen plot: error: plot needs matplotlib'), line
    assert 'pip install matplotlib==3.11.2' in line and 'python3-matplotlib' in line, line
    assert 'internal error' not in line
    assert not (tmp_path / 'never.png').exists()


def test_the_matplotlib_named_in_that_error_is_the_pinned_one():
    pins = (REPO / 'requirements.txt').read_text().split()
    assert MATPLOTLIB_REQUIREMENT in pins


def test_solver_refusal_names_the_fix_and_the_joint():
    line = assert_one_line_error(traj_gen('solve', *LSPB_ARGS[:-3], '--acceleration', '5',
                                          '--degrees'))
    assert line.startswith("traj-gen solve: error: lspb: lspb_via: joint 'joint_1': "), line
    assert line.endswith('the smallest acceleration that fits is 15.91'), line


@pytest.mark.parametrize('command', ['solve', 'plot', 'goal', 'via'])
def test_every_subcommand_has_help_with_examples(command):
    text = ok(command, '--help')
    assert f'usage: traj-gen {command}' in text
    assert 'examples:' in text and f'traj-gen {command} ' in text


def test_offline_commands_import_no_ros(tmp_path):
    script = (
        'import sys\n'
        'from traj_gen_ros.cli import main as cli\n'
        f'assert cli.main({["solve", *LSPB_ARGS]!r}) == 0\n'
        f'assert cli.main({["plot", *CUBIC_ARGS, "-o", str(tmp_path / "p.png")]!r}) == 0\n'
        "loaded = [m for m in sys.modules if m.startswith(('rclpy', 'rcl_', 'sensor_msgs'))]\n"
        'assert not loaded, loaded\n')
    result = subprocess.run([sys.executable, '-c', script], cwd=REPO, env=env(),
                            capture_output=True, text=True, timeout=TIMEOUT)
    assert result.returncode == 0, result.stderr


def test_console_script_is_declared_next_to_the_generator():
    setup = (REPO / 'setup.py').read_text()
    assert "'traj-gen = traj_gen_ros.cli.main:main'," in setup
    assert "'generator = traj_gen_ros.node.generator:main'," in setup
