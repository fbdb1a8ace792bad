"""The speed override's inputs (ROS-free): the log lines of the factor's changes."""

import pytest
from traj_gen_ros.node.speed.factor import ChangeReport, REPORT_PERIOD


def test_a_lone_change_is_said_at_once():
    report = ChangeReport()
    assert report.change(10.0, 'a') == 'a'
    assert report.held is None
    assert report.change(10.0 + REPORT_PERIOD, 'b') == 'b'  # a period later: at once too


def test_a_burst_says_its_first_then_its_last_a_period_after():
    report = ChangeReport(1.0)
    assert report.change(0.0, '0.9') == '0.9'
    for index, line in enumerate(['0.8', '0.7', '0.1']):
        assert report.change(0.01 * (index + 1), line) is None
    assert report.held == '0.1'
    assert report.due(0.999) is None  # not before a period has passed since '0.9'
    assert report.due(1.0) == '0.1 (the last of 3 changes since)'
    assert report.held is None and report.due(5.0) is None
    # The next change within a period of that line is held again.
    assert report.change(1.5, '0.2') is None
    assert report.due(2.0) == '0.2'


def test_a_burst_that_returns_to_the_line_said_adds_none():
    report = ChangeReport(1.0)
    assert report.change(0.0, '1') == '1'
    assert report.change(0.2, '0') is None
    assert report.change(0.4, '1') is None
    assert report.due(1.0) is None
    assert report.held is None


@pytest.mark.parametrize('times', [[0.0, 0.3, 0.6, 0.9, 1.2, 1.5, 1.8, 2.1],
                                   [0.0, 0.3, 0.6, 0.9, 1.2, 1.5, 1.8, 2.1, 2.4],
                                   [0.0, 0.001, 0.002, 3.0, 3.5]])
def test_lines_are_a_period_apart_and_the_last_value_is_said(times):
    """A slider moved steadily: at most one line per period, ending with its last value."""
    report = ChangeReport(1.0)
    said = []
    for index, now in enumerate(times):
        line = report.change(now, str(index))
        if line is not None:
            said.append((now, line))
        held = report.due(now)
        if held is not None:
            said.append((now, held))
    held = report.due(times[-1] + 1.0)
    if held is not None:
        said.append((times[-1] + 1.0, held))
    moments = [now for now, _ in said]
    assert all(b - a >= 1.0 for a, b in zip(moments, moments[1:], strict=False))
    assert said[0][1] == '0' and said[-1][1].startswith(str(len(times) - 1))
