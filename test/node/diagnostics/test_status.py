"""traj_gen_ros.node.diagnostics.status: the /diagnostics content, without ROS."""

from traj_gen_ros.node.diagnostics.status import (
    MotionLog,
    node_status,
    OK,
    RateMeter,
    RequestCounts,
    WARN,
)


def status(**changes):
    arguments = {'rate': 99.5, 'rate_hz': 100.0, 'joints': 6, 'profile': 'quintic',
                 'motion': 'holding', 'urdf_source': 'none', 'urdf_problem': '',
                 'limits': 'joint_1: position unlimited, 2 rad/s (max_velocity)',
                 'counts': RequestCounts(3, 2, 1)}
    arguments.update(changes)
    return node_status(**arguments)


def test_ok_status_with_every_value():
    level, message, values = status()
    assert level == OK and message == 'streaming 6 joints at 99.5 Hz; holding'
    assert dict(values) == {
        'stream rate (Hz)': '99.5', 'rate_hz': '100', 'joints': '6', 'profile': 'quintic',
        'motion': 'holding', 'limits': 'joint_1: position unlimited, 2 rad/s (max_velocity)',
        'robot_description': 'none', 'accepted': '3', 'refused': '2', 'superseded': '1',
        'late ticks': '0', 'held back (s)': '0.000'}


def test_a_slow_stream_or_a_refused_description_warns():
    level, message, _ = status(rate=89.9)
    assert level == WARN and message == 'stream rate 89.9 Hz is below 90% of rate_hz 100'
    assert status(rate=90.0)[0] == OK
    level, message, values = status(urdf_problem='robot_description on /x refused: bad')
    assert level == WARN and message == 'robot_description on /x refused: bad'
    assert dict(values)['robot_description refused'] == message
    level, _, values = status(rate=None)
    assert level == OK and dict(values)['stream rate (Hz)'] == 'not measured yet'


def test_a_joint_outside_its_range_warns_naming_it():
    outside = "joint 'joint_4' is at 0 rad, outside its range [0.194395, 2.2944] rad (…)"
    level, message, values = status(outside=outside)
    assert level == WARN
    assert message == f'{outside}: it may hold there or move toward its range'
    assert dict(values)['outside range'] == outside
    assert 'outside range' not in dict(status()[2])


def test_rate_meter_counts_publications_per_window():
    published = []
    meter = RateMeter(10.0)
    publish = meter.wrap(published.append)
    for _ in range(50):
        publish(b'x')
    assert meter.rate(10.2) is None  # too short a window
    assert meter.rate(11.0) == 50.0
    for _ in range(25):
        publish(b'x')
    assert meter.rate(11.5) == 50.0 and len(published) == 75


def test_rate_meter_counts_late_ticks_and_reports_those_since_the_last_report():
    meter = RateMeter(10.0)
    assert meter.late_report() == (0, 0, 0)
    meter.late(335_000_000, 331_000_000)
    meter.late(6_000_000, 2_000_000)
    assert (meter.late_ticks, meter.held_back_ns) == (2, 333_000_000)
    assert meter.late_report() == (2, 335_000_000, 333_000_000)
    assert meter.late_report() == (0, 0, 0)
    meter.late(5_000_000, 1_000_000)
    assert meter.late_report() == (1, 5_000_000, 1_000_000) and meter.late_ticks == 3
    values = dict(status(late=(meter.late_ticks, meter.held_back_ns))[2])
    assert values['late ticks'] == '3' and values['held back (s)'] == '0.334'
    assert status(late=(3, 334_000_000))[0] == OK  # counted and logged, not a warning


def test_counts_by_level_and_superseded_batches():
    counts = RequestCounts()
    counts.count(0, {})
    counts.count(2, {})
    counts.count(1, {'request_id': '4'})
    counts.count(1, {'superseded': '7'})
    assert (counts.accepted, counts.refused, counts.superseded) == (1, 1, 8)


def test_motion_log_says_what_runs_and_what_follows():
    log = MotionLog()
    assert log.describe(0) == 'holding'
    log.record(1_000_000_000, 'quintic', 2.0)
    assert log.describe(1_500_000_000) == 'quintic, 1.500 s left'
    assert log.describe(0) == 'holding; next: quintic in 1.000 s'
    assert log.describe(3_000_000_000) == 'holding'
    log.record(2_000_000_000, 'stop', 0.5)  # replaces the rest of the quintic
    assert log.describe(2_250_000_000) == 'stop, 0.250 s left'
    assert log.describe(2_600_000_000) == 'holding'
