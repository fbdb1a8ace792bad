"""
The node's DDS transport: UDPv4 only, unless the user configured Fast DDS's transports.

Fast DDS 2.14 (ROS 2 Jazzy's ``rmw_fastrtps_cpp``) gives every participant a shared-memory
transport beside UDPv4. When a process joins the graph (a ``ros2 topic echo``, a probe),
the node's participant opens that process's shared-memory port the first time it sends
to it, and opening a port runs a health check that can wait a third of
``healthy_check_timeout_ms`` of the port's creator (333 ms with the default 1000) while
the node's other sends wait behind it (eProsima/Fast-DDS#6535): the stream froze for
333-337 ms in 4 to 8 of 50 joins at 500 Hz (``benchmarks/joins.py``). The check runs
in the process that opens a port with the creator's timeouts, so no setting of the node's
own shared-memory transport can shorten it; only not having one does.

So :func:`choose_transport`, called in ``main`` before ``rclpy.init``, sets
``FASTDDS_BUILTIN_TRANSPORTS=UDPv4`` in the node's own environment (the node's process
only: nothing else inherits it) when the user configured none of Fast DDS's transports:
no ``FASTDDS_BUILTIN_TRANSPORTS``, no XML profile (``FASTRTPS_DEFAULT_PROFILES_FILE``,
``FASTDDS_DEFAULT_PROFILES_FILE``, ``DEFAULT_FASTRTPS_PROFILES.xml`` in the working
directory), the RMW is Fast DDS's, and ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is not
``LOCALHOST``: with ``LOCALHOST`` (or ``ROS_LOCALHOST_ONLY=1``) ``rmw_fastrtps`` 8.4
replaces the built-in transports with its own shared-memory and UDPv4 ones, and the node
can only say so. Peers on the same host reach the node over UDP on the loopback (a
kernel copy per message: 6 joints at 500 Hz are about 125 KB/s); they still use shared memory
among themselves. Whatever the user set wins: ``FASTDDS_BUILTIN_TRANSPORTS=DEFAULT``
brings back Fast DDS's default (shared memory and UDPv4) for the node.

No ROS here: reads and writes an environment mapping.
"""

from __future__ import annotations

from collections.abc import MutableMapping
from pathlib import Path

#: Fast DDS's variable for its built-in transports (Fast DDS >= 2.13), and the node's choice.
TRANSPORTS_VARIABLE = 'FASTDDS_BUILTIN_TRANSPORTS'
NODE_TRANSPORTS = 'UDPv4'
#: Variables that point Fast DDS at an XML profile (2.x, 3.x), and the file it reads from
#: the working directory unless ``SKIP_DEFAULT_XML_FILE=1``.
PROFILE_VARIABLES = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
DEFAULT_PROFILE_FILE = 'DEFAULT_FASTRTPS_PROFILES.xml'
#: The RMW used when ``RMW_IMPLEMENTATION`` is unset (ROS 2 Jazzy), and Fast DDS's RMWs.
DEFAULT_RMW = 'rmw_fastrtps_cpp'
FAST_DDS_RMWS = ('rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')
#: Where this is documented for users.
SEE = 'docs/node.md#dds-transport'


def _localhost(environ: MutableMapping[str, str]) -> bool:
    """Whether rcl limits discovery to this host (``rmw_fastrtps`` then sets the transports)."""
    return (environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') == 'LOCALHOST'
            or environ.get('ROS_LOCALHOST_ONLY') == '1')


def choose_transport(environ: MutableMapping[str, str], cwd: Path | None = None) -> str:
    """
    Set the node's transport in ``environ`` if the user set none; say what is in force.

    ``cwd``: where Fast DDS looks for ``DEFAULT_FASTRTPS_PROFILES.xml`` (the working
    directory if None). Returns the start-up log line (``DDS transport: …``); sets
    ``FASTDDS_BUILTIN_TRANSPORTS=UDPv4`` only in the case the module doc describes.
    """
    rmw = environ.get('RMW_IMPLEMENTATION', '') or DEFAULT_RMW
    if rmw not in FAST_DDS_RMWS:
        return f'DDS transport: {rmw} chooses it (the node sets none)'
    if environ.get(TRANSPORTS_VARIABLE):
        return (f'DDS transport: {TRANSPORTS_VARIABLE}={environ[TRANSPORTS_VARIABLE]} '
                '(yours)')
    for name in PROFILE_VARIABLES:
        if environ.get(name):
            return f'DDS transport: your Fast DDS profile ({name}={environ[name]})'
    default_profile = (cwd if cwd is not None else Path.cwd()) / DEFAULT_PROFILE_FILE
    if environ.get('SKIP_DEFAULT_XML_FILE') != '1' and default_profile.is_file():
        return f'DDS transport: your Fast DDS profile ({default_profile})'
    if _localhost(environ):
        return ('DDS transport: shared memory and UDPv4, set by rmw_fastrtps for '
                'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST: a process joining the graph can '
                f'hold the stream back up to 1/3 s (see {SEE})')
    environ[TRANSPORTS_VARIABLE] = NODE_TRANSPORTS
    return (f'DDS transport: UDPv4 only ({TRANSPORTS_VARIABLE}={NODE_TRANSPORTS}, set by the '
            'node: no shared-memory stall when a process joins; '
            f'{TRANSPORTS_VARIABLE}=DEFAULT keeps shared memory)')
