"""traj_gen_ros.node.stream.transport: UDPv4 for the node unless the user chose otherwise."""

import pytest
from traj_gen_ros.node.stream.transport import choose_transport, TRANSPORTS_VARIABLE


def test_with_nothing_set_the_node_takes_udp_only(tmp_path):
    environ = {}
    line = choose_transport(environ, tmp_path)
    assert environ == {TRANSPORTS_VARIABLE: 'UDPv4'}
    assert line.startswith('DDS transport: UDPv4 only (FASTDDS_BUILTIN_TRANSPORTS=UDPv4, '
                           'set by the node')
    assert 'FASTDDS_BUILTIN_TRANSPORTS=DEFAULT keeps shared memory' in line
    for environ in ({'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'},
                    {'RMW_IMPLEMENTATION': 'rmw_fastrtps_dynamic_cpp'},
                    {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'},
                    {'ROS_LOCALHOST_ONLY': '0', 'SKIP_DEFAULT_XML_FILE': '1'}):
        choose_transport(environ, tmp_path)
        assert environ[TRANSPORTS_VARIABLE] == 'UDPv4'


@pytest.mark.parametrize('environ, says', [
    ({TRANSPORTS_VARIABLE: 'DEFAULT'},
     'DDS transport: FASTDDS_BUILTIN_TRANSPORTS=DEFAULT (yours)'),
    ({TRANSPORTS_VARIABLE: 'SHM'}, 'FASTDDS_BUILTIN_TRANSPORTS=SHM (yours)'),
    ({'FASTRTPS_DEFAULT_PROFILES_FILE': '/etc/dds.xml'},
     'your Fast DDS profile (FASTRTPS_DEFAULT_PROFILES_FILE=/etc/dds.xml)'),
    ({'FASTDDS_DEFAULT_PROFILES_FILE': 'a.xml'}, 'FASTDDS_DEFAULT_PROFILES_FILE=a.xml'),
    ({'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}, 'rmw_cyclonedds_cpp chooses it'),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}, 'set by rmw_fastrtps for '
     'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST: a process joining the graph can hold the '
     'stream back up to 1/3 s'),
    ({'ROS_LOCALHOST_ONLY': '1'}, 'shared memory and UDPv4, set by rmw_fastrtps'),
])
def test_what_the_user_set_wins_and_is_said(tmp_path, environ, says):
    before = dict(environ)
    assert says in choose_transport(environ, tmp_path)
    assert environ == before  # nothing set


def test_a_default_profile_in_the_working_directory_counts_unless_skipped(tmp_path):
    (tmp_path / 'DEFAULT_FASTRTPS_PROFILES.xml').write_text('<dds/>')
    environ = {}
    line = choose_transport(environ, tmp_path)
    assert environ == {} and line == ('DDS transport: your Fast DDS profile '
                                      f'({tmp_path / "DEFAULT_FASTRTPS_PROFILES.xml"})')
    environ = {'SKIP_DEFAULT_XML_FILE': '1'}
    choose_transport(environ, tmp_path)  # Fast DDS will not read it
    assert environ[TRANSPORTS_VARIABLE] == 'UDPv4'
