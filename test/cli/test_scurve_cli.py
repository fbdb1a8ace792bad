"""traj-gen solve/plot scurve as a user runs them (subprocesses), Ruckig as the oracle."""

import json

from cli_helpers import assert_one_line_error, ok, solve_json, traj_gen
import matplotlib.image as mpimg
import pytest
from ruckig_oracle import ruckig_duration

LIMITS = ['--max-velocity', '1', '--max-acceleration', '2', '--max-jerk', '5']


def test_solve_scurve_prints_each_joints_seven_phases():
    result = solve_json('scurve', '--points', '0,0', '1,-2', *LIMITS)
    expected, _ = ruckig_duration([0, 0], [1, -2], [0, 0], [0, 0], [1, 1], [2, 2], [5, 5])
    assert result['kind'] == 'scurve' and result['joints'] == 2
    assert result['duration'] == pytest.approx(expected, rel=1e-9)
    assert result['duration'] == pytest.approx(2.9)  # 2/1 + 1/2 + 2/5: velocity-limited
    assert result['peak_jerk'] == pytest.approx([5.0, 5.0])
    for rows in result['phases']:
        assert [row['phase'] for row in rows] == [str(phase) for phase in range(1, 8)]
        assert sum(row['duration'] for row in rows) == pytest.approx(result['duration'])
        assert all(row['jerk'] in (pytest.approx(5.0), 0.0, pytest.approx(-5.0))
                   for row in rows)
        assert rows[-1]['velocity'] == pytest.approx(0.0, abs=1e-9)
        assert rows[-1]['acceleration'] == pytest.approx(0.0, abs=1e-9)
    # Joint 1 (2 rad) reaches every limit: 0.4 s jerk, 0.1 s at 2 rad/s², cruise at 1 rad/s.
    joint = result['phases'][1]
    assert [row['duration'] for row in joint] == pytest.approx([0.4, 0.1, 0.4, 1.1, 0.4,
                                                               0.1, 0.4])
    assert joint[1]['acceleration'] == pytest.approx(-2.0)
    assert joint[3]['velocity'] == pytest.approx(-1.0)

    text = ok('solve', 'scurve', '--points', '0,0', '1,-2', *LIMITS)
    assert 'scurve: 2 joints, 2 points, duration 2.9000 s' in text
    assert 'joint_2: peak |jerk| 5.0000 rad/s³' in text
    assert '  4           0.9000    1.1000      0.0000        0.0000     -1.0000' in text


def test_solve_scurve_from_a_fast_start_brakes_first():
    result = solve_json('scurve', '--points', '0', '1', *LIMITS, '--v0', '3')
    expected, _ = ruckig_duration([0], [1], [3], [0], [1], [2], [5])
    assert result['duration'] == pytest.approx(expected, rel=1e-9)
    rows = result['phases'][0]
    assert [row['phase'] for row in rows[:3]] == ['brake 1', 'brake 2', '1']
    assert rows[0]['jerk'] == pytest.approx(-5.0)


def test_solve_scurve_with_a_duration_and_through_via_points():
    result = solve_json('scurve', '--points', '0', '1', '--duration', '4', *LIMITS)
    assert result['duration'] == 4.0 and result['point_times'] == [0.0, 4.0]
    via = solve_json('scurve', '--points', '0', '1', '0.5', *LIMITS)
    times = via['point_times']
    assert via['duration'] == pytest.approx(times[-1]) and len(times) == 3
    assert [row['phase'] for row in via['phases'][0]][6:8] == ['1.7', '2.1']
    # Through the points at their times: each segment's phases cover it exactly.
    first = sum(row['duration'] for row in via['phases'][0][:7])
    assert first == pytest.approx(times[1])


def test_scurve_refusals_are_one_line():
    line = assert_one_line_error(traj_gen('solve', 'scurve', '--points', '0,0', '1,-2',
                                          '--duration', '2', *LIMITS))
    assert 'minimum duration is 2.9 s' in line
    line = assert_one_line_error(traj_gen('solve', 'scurve', '--points', '0', '1',
                                          '--max-velocity', '1', '--max-acceleration', '2'))
    assert 'scurve needs --max-velocity, --max-acceleration and --max-jerk' in line
    line = assert_one_line_error(traj_gen('solve', 'scurve', '--points', '0', '1', '2',
                                          '--durations', '0.5', '0.5', *LIMITS))
    assert 'segment 0' in line and 'smallest duration that works' in line


def test_plot_scurve_has_a_jerk_panel_and_cubic_keeps_three(tmp_path):
    output = tmp_path / 'scurve.png'
    info = json.loads(ok('plot', 'scurve', '--points', '0,0', '1,-2', *LIMITS, '-o',
                         str(output), '--json', '--size', '600x800'))
    assert info['panels'] == ['position [rad]', 'velocity [rad/s]', 'acceleration [rad/s²]',
                              'jerk [rad/s³]']
    assert mpimg.imread(output).shape[:2] == (800, 600)
    cubic = json.loads(ok('plot', 'cubic', '--points', '0', '1', '--duration', '2', '-o',
                          str(tmp_path / 'cubic.png'), '--json'))
    assert cubic['panels'] == ['position [rad]', 'velocity [rad/s]', 'acceleration [rad/s²]']
