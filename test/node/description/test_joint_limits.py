"""node.description.joint_limits: URDF limits (urdfdom semantics) merged with the parameters."""

from concurrent.futures import ThreadPoolExecutor
import math
import subprocess
import sys

import numpy as np
import pytest
from traj_gen_ros.node.description import joint_limits as jl

INF = math.inf

# A three-joint arm (revolute, continuous, prismatic) with a fixed tool joint, written as
# robot_state_publisher gets it: XML declaration, and a <ros2_control> tag that the reader
# does not need (nor print anything about).
ARM = """<?xml version="1.0" encoding="utf-8"?>
<robot name="three_joint_arm">
  <link name="base_link"/>
  <link name="link_1"/>
  <link name="link_2"/>
  <link name="link_3"/>
  <link name="tool"/>
  <joint name="joint_1" type="revolute">
    <parent link="base_link"/>
    <child link="link_1"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2.9" upper="2.9" effort="50" velocity="2.5"/>
  </joint>
  <joint name="joint_2" type="continuous">
    <parent link="link_1"/>
    <child link="link_2"/>
    <limit effort="30" velocity="3.0"/>
  </joint>
  <joint name="joint_3" type="prismatic">
    <parent link="link_2"/>
    <child link="link_3"/>
    <limit lower="0.0" upper="0.5" effort="100" velocity="0.25"/>
  </joint>
  <joint name="tool_joint" type="fixed">
    <parent link="link_3"/>
    <child link="tool"/>
  </joint>
  <ros2_control name="arm" type="system"/>
</robot>
"""
JOINTS = ['joint_1', 'joint_2', 'joint_3']


def robot(joint: str) -> str:
    """Return a URDF with one joint element between two links."""
    return (f'<robot name="r"><link name="a"/><link name="b"/>{joint}</robot>')


def joint(kind: str, limit: str = '') -> str:
    """Return a joint element of ``kind`` named j, with ``limit`` inside."""
    return (f'<joint name="j" type="{kind}"><parent link="a"/><child link="b"/>{limit}'
            '</joint>')


@pytest.fixture
def arm_limits(capfd) -> jl.UrdfLimits:
    limits = jl.urdf_limits(ARM, JOINTS)
    assert capfd.readouterr() == ('', '')  # nothing printed about <ros2_control>
    return limits


# ---------------------------------------------------------------- reading the URDF


def test_arm_limits_per_joint_type(arm_limits):
    assert arm_limits.joints == ('joint_1', 'joint_2', 'joint_3')
    assert arm_limits.types == ('revolute', 'continuous', 'prismatic')
    assert arm_limits.lower.tolist() == [-2.9, -INF, 0.0]
    assert arm_limits.upper.tolist() == [2.9, INF, 0.5]
    assert arm_limits.velocity.tolist() == [2.5, 3.0, 0.25]  # continuous: velocity only


def test_caller_order_and_absent_joints():
    limits = jl.urdf_limits(ARM, ['joint_3', 'elbow', 'joint_1'])
    assert limits.types == ('prismatic', jl.ABSENT, 'revolute')
    assert limits.lower.tolist() == [0.0, -INF, -2.9]
    assert limits.upper.tolist() == [0.5, INF, 2.9]
    assert limits.velocity.tolist() == [0.25, INF, 2.5]


def test_bytes_and_a_declaration_free_string_parse_alike():
    as_bytes = jl.urdf_limits(ARM.encode(), JOINTS)
    bare = jl.urdf_limits(ARM.split('\n', 1)[1], JOINTS)
    for limits in (as_bytes, bare):
        assert limits.lower.tolist() == [-2.9, -INF, 0.0]
        assert limits.velocity.tolist() == [2.5, 3.0, 0.25]


def test_continuous_without_limit_element_is_unlimited():
    limits = jl.urdf_limits(robot(joint('continuous')), ['j'])
    assert (limits.lower[0], limits.upper[0], limits.velocity[0]) == (-INF, INF, INF)


def test_revolute_limit_without_lower_and_upper_is_zero_per_urdfdom():
    limits = jl.urdf_limits(robot(joint('revolute', '<limit effort="1" velocity="1"/>')),
                            ['j'])
    assert (limits.lower[0], limits.upper[0], limits.velocity[0]) == (0.0, 0.0, 1.0)


def test_fixed_joint_is_ignored_unless_asked_for():
    assert jl.urdf_limits(ARM, JOINTS).joints == tuple(JOINTS)  # tool_joint is in the URDF
    with pytest.raises(ValueError, match=r"^URDF joint 'tool_joint' is fixed: only revolute, "
                                         'continuous and prismatic joints can be trajectory'):
        jl.urdf_limits(ARM, ['joint_1', 'tool_joint'])


def test_arrays_are_read_only(arm_limits):
    with pytest.raises(ValueError, match='read-only'):
        arm_limits.lower[0] = 0.0


@pytest.mark.parametrize('urdf, message', [
    ('', r'^invalid URDF: the robot description is empty$'),
    ('<robot name="r"><link', r'^invalid URDF: not well-formed XML: '),
    ('<model name="m"/>', r'^invalid URDF: the root element is <model>, not <robot>$'),
    (robot(joint('revolute')),
     r"^invalid URDF: revolute joint 'j' has no <limit> element \(required for revolute "),
    (robot(joint('prismatic')), r"^invalid URDF: prismatic joint 'j' has no <limit>"),
    (robot(joint('revolute', '<limit effort="1" lower="-1" upper="1"/>')),
     r"^invalid URDF: joint 'j': <limit> has no velocity attribute \(required\)$"),
    (robot(joint('revolute', '<limit velocity="1" lower="-1" upper="1"/>')),
     r"^invalid URDF: joint 'j': <limit> has no effort attribute \(required\)$"),
    (robot(joint('revolute', '<limit effort="1" velocity="fast"/>')),
     r"^invalid URDF: joint 'j': <limit> velocity='fast' is not a number$"),
    (robot(joint('revolute', '<limit effort="1" velocity="1" upper="${pi}"/>')),
     r"^invalid URDF: joint 'j': <limit> upper='\$\{pi\}' is not a number$"),
    (robot(joint('hinge')), r"^invalid URDF: joint 'j' has type 'hinge': the type must be "
                            'one of revolute, continuous, prismatic, fixed, floating, planar$'),
    (robot('<joint name="j"><parent link="a"/><child link="b"/></joint>'),
     r"^invalid URDF: joint 'j' has no type attribute: the type must be one of "),
    (robot('<joint type="fixed"/>'), r'^invalid URDF: joint 1 \(line 1\) has no name '),
    (robot(joint('revolute', '<limit effort="1" velocity="1" lower="nan"/>')),
     r"^invalid URDF: joint 'j' has lower limit NaN$"),
    (robot(joint('revolute', '<limit effort="1" velocity="1" lower="1" upper="-1"/>')),
     r"^invalid URDF: joint 'j' has lower limit 1 and upper limit -1: lower must be <= upper$"),
    (robot(joint('prismatic', '<limit effort="1" velocity="0" lower="0" upper="1"/>')),
     r"^URDF joint 'j' has velocity limit 0: it must be > 0 for the joint to move$"),
    (robot(joint('continuous') + joint('revolute', '<limit effort="1" velocity="1"/>')),
     r"^invalid URDF: joint 'j' is defined twice$"),
    (robot(joint('continuous', '<mimic multiplier="2"/>')),
     r"^invalid URDF: joint 'j': <mimic> has no joint attribute \(the joint it follows\)$"),
    (robot(joint('continuous', '<mimic joint="k" offset="x"/>')),
     r"^invalid URDF: joint 'j': <mimic> offset='x' is not a number$"),
    (robot(joint('continuous', '<mimic joint="k"/>')),
     r"^URDF joint 'j' mimics joint 'k' \(<mimic>\): it follows that joint and is not "
     r'commanded; remove it from joints$'),
], ids=['empty', 'not xml', 'not robot', 'revolute no limit', 'prismatic no limit',
        'no velocity', 'no effort', 'bad float', 'xacro value', 'bad type', 'no type',
        'no name', 'nan', 'lower above upper', 'zero velocity', 'duplicate', 'mimic no joint',
        'mimic bad offset', 'mimic commanded'])
def test_invalid_urdf_is_one_line_value_error_and_prints_nothing(capfd, urdf, message):
    with pytest.raises(ValueError, match=message) as error:
        jl.urdf_limits(urdf, ['j'])
    assert '\n' not in str(error.value)
    assert capfd.readouterr() == ('', '')


def test_a_broken_limit_on_a_joint_not_commanded_still_refuses_the_urdf():
    # urdfdom refuses the whole document over any joint's <limit>: so does the reader.
    urdf = robot(joint('revolute', '<limit effort="1" velocity="1"/>')
                 + joint('revolute', '<limit effort="1"/>').replace('"j"', '"other"'))
    with pytest.raises(ValueError, match="joint 'other': <limit> has no velocity"):
        jl.urdf_limits(urdf, ['j'])


def test_what_the_node_does_not_read_is_not_checked():
    # Unexpanded xacro values in a transmission, an axis, a link and a <joint> element
    # nested in the transmission (not a robot joint): none of them is read.
    urdf = robot(
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/>'
        '<axis xyz="${axis}"/><dynamics damping="${d}"/>'
        '<limit effort="1" velocity="2" lower="-1" upper="1"/></joint>'
        '<transmission name="t"><joint name="j"><hardwareInterface>x</hardwareInterface>'
        '</joint><actuator name="m"><mechanicalReduction>${reduction}</mechanicalReduction>'
        '</actuator></transmission><link name="c"><inertial><mass value="${m}"/></inertial>'
        '</link>')
    limits = jl.urdf_limits(urdf, ['j'])
    assert (limits.lower[0], limits.upper[0], limits.velocity[0]) == (-1.0, 1.0, 2.0)


def test_a_continuous_joints_lower_and_upper_are_ignored():
    urdf = robot(joint('continuous', '<limit effort="1" velocity="0.5" lower="-0.38" '
                                     'upper="0"/>'))
    limits = jl.urdf_limits(urdf, ['j'])
    assert (limits.lower[0], limits.upper[0], limits.velocity[0]) == (-INF, INF, 0.5)


def test_parsing_from_several_threads_gives_each_its_own_limits():
    documents = [ARM.replace('velocity="2.5"', f'velocity="{index + 1}"') for index in range(8)]
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda text: jl.urdf_limits(text, JOINTS), documents * 4))
    for index, limits in enumerate(results):
        assert limits.velocity[0] == index % 8 + 1


# ---------------------------------------------------------------- merging


def test_tighter_bound_wins_and_its_source_is_recorded(arm_limits):
    merged = jl.merge_limits(arm_limits, min_position=[-3.0, -1.0, 0.1],
                             max_position=[2.0, INF, 0.5], max_velocity=[3.0, 2.0, 1.0])
    position = merged.position
    assert position.lower.tolist() == [-2.9, -1.0, 0.1]
    assert position.lower_source == (jl.URDF, jl.PARAMETER, jl.PARAMETER)
    assert position.upper.tolist() == [2.0, INF, 0.5]
    assert position.upper_source == (jl.PARAMETER, jl.NONE, jl.URDF)  # 0.5 tie: URDF
    assert merged.velocity.tolist() == [2.5, 2.0, 0.25]
    assert merged.velocity_source == (jl.URDF, jl.PARAMETER, jl.URDF)
    assert merged.units == ('rad', 'rad', 'm')
    assert merged.joints == tuple(JOINTS)


def test_defaults_keep_the_urdf_and_no_urdf_leaves_the_parameters(arm_limits):
    merged = jl.merge_limits(arm_limits)
    assert merged.position.lower_source == (jl.URDF, jl.NONE, jl.URDF)
    assert merged.position.upper_source == (jl.URDF, jl.NONE, jl.URDF)
    assert merged.velocity_source == (jl.URDF, jl.URDF, jl.URDF)

    alone = jl.merge_limits(jl.UrdfLimits.unlimited(['a', 'b']), max_position=1.5,
                            max_velocity=2.0)
    assert alone.position.lower.tolist() == [-INF, -INF]
    assert alone.position.upper.tolist() == [1.5, 1.5]
    assert alone.position.lower_source == (jl.NONE, jl.NONE)
    assert alone.position.upper_source == (jl.PARAMETER, jl.PARAMETER)
    assert alone.velocity_source == (jl.PARAMETER, jl.PARAMETER)
    assert alone.units == ('rad', 'rad')


@pytest.mark.parametrize('parameters, message', [
    ({'max_velocity': [1.0, 2.0]},
     r'^max_velocity has 2 values but there are 3 joints: give one value for all joints or '),
    ({'min_position': [0.0, math.nan, 0.0]},
     r"^min_position must be a number, not NaN \(\+-inf: no limit\); joint 'joint_2' has nan$"),
    ({'min_position': INF}, r'^min_position cannot be \+inf nor max_position -inf'),
    ({'max_position': -INF}, r'^min_position cannot be \+inf nor max_position -inf'),
    ({'max_velocity': [1.0, 0.0, 1.0]},
     r"^max_velocity must be > 0 \(inf: no limit\); joint 'joint_2' has 0.0$"),
    ({'min_position': [3.0, 0.0, 0.0]},
     r"^joint 'joint_1' has no valid position: the URDF allows \[-2.9, 2.9\] rad and the "
     r'parameters \[3, inf\] rad$'),
    ({'max_position': [INF, INF, -0.1]},
     r"^joint 'joint_3' has no valid position: the URDF allows \[0, 0.5\] m and the "
     r'parameters \[-inf, -0.1\] m$'),
])
def test_merge_refuses_bad_parameters(arm_limits, parameters, message):
    with pytest.raises(ValueError, match=message):
        jl.merge_limits(arm_limits, **parameters)


def test_describe_sources_is_one_line_naming_every_source(arm_limits):
    merged = jl.merge_limits(arm_limits, min_position=[-3.0, -1.0, 0.1],
                             max_position=[2.0, INF, 0.5], max_velocity=[3.0, 2.0, 1.0])
    assert jl.describe_sources(merged) == (
        'joint_1: [-2.9, 2] rad (lower URDF, upper max_position), 2.5 rad/s (URDF); '
        'joint_2: [-1, inf] rad (lower min_position, upper none), 2 rad/s (max_velocity); '
        'joint_3: [0.1, 0.5] m (lower min_position, upper URDF), 0.25 m/s (URDF)')
    plain = jl.describe_sources(jl.merge_limits(arm_limits))
    assert plain == ('joint_1: [-2.9, 2.9] rad (URDF), 2.5 rad/s (URDF); '
                     'joint_2: position unlimited, 3 rad/s (URDF); '
                     'joint_3: [0, 0.5] m (URDF), 0.25 m/s (URDF)')
    none = jl.describe_sources(jl.merge_limits(jl.UrdfLimits.unlimited(['a'])))
    assert none == 'a: position unlimited, velocity unlimited'


# ---------------------------------------------------------------- checking positions


@pytest.fixture
def merged(arm_limits) -> jl.JointLimits:
    return jl.merge_limits(arm_limits, min_position=[-INF, -INF, 0.1],
                           max_position=[INF, INF, INF], max_velocity=2.0)


def test_positions_within_range_bounds_included_pass(merged):
    assert jl.check_positions(JOINTS, [2.9, 1e6, 0.5], merged) is None
    assert jl.check_positions(['joint_3', 'joint_1'], [0.1, -2.9], merged) is None
    assert jl.check_positions([], [], merged) is None


def test_refusal_names_joint_value_range_and_source(merged):
    assert jl.check_positions(['joint_1'], [3.2], merged) == (
        "goal position 3.2 rad for joint 'joint_1' is outside its range [-2.9, 2.9] rad "
        '(lower from URDF; upper from URDF)')
    assert jl.check_positions(['joint_1', 'joint_3'], [0.0, 0.05], merged,
                              what='via point 2 position') == (
        "via point 2 position 0.05 m for joint 'joint_3' is outside its range [0.1, 0.5] m "
        '(lower from parameter min_position; upper from URDF)')
    # The first offending joint in the caller's order is named.
    assert "joint 'joint_3'" in jl.check_positions(['joint_3', 'joint_1'], [0.7, 5.0], merged)


def test_non_finite_and_unknown_joints_are_refused(merged):
    assert jl.check_positions(['joint_2'], [math.nan], merged) == (
        "goal position nan rad for joint 'joint_2' is not finite")
    assert jl.check_positions(['wrist'], [0.0], merged) == (
        "goal position names joint 'wrist', which has no limits; known joints: "
        "['joint_1', 'joint_2', 'joint_3']")
    with pytest.raises(ValueError, match='^2 names but 1 positions$'):
        jl.check_positions(JOINTS[:2], [0.0], merged)


def test_positions_given_as_numpy_array(merged):
    assert jl.check_positions(JOINTS, np.array([0.0, 0.0, 0.2]), merged) is None
    # Rows of positions (via points): the first offending point is named.
    assert jl.check_positions(['joint_1'], [[0.0], [1.0], [3.0]], merged,
                              what='via point {point} position') == (
        "via point 2 position 3 rad for joint 'joint_1' is outside its range [-2.9, 2.9] rad "
        '(lower from URDF; upper from URDF)')
    # Rounding beyond a bound passes; so does a joint already outside that stays there.
    assert jl.check_positions(['joint_1'], [2.9 + 1e-12], merged) is None
    assert jl.check_positions(['joint_1'], [3.2], merged, start=[3.2 + 1e-7]) is None
    assert jl.check_positions(['joint_1'], [3.2], merged, start=[3.1]) is not None
    assert jl.check_positions(JOINTS, np.array([-3.0, 0.0, 0.2]), merged).startswith(
        "goal position -3 rad for joint 'joint_1' is outside its range [-2.9, 2.9] rad")


def test_module_imports_no_ros():
    script = ('import sys\n'
              'import traj_gen_ros.node.description.joint_limits\n'
              "loaded = [m for m in sys.modules if m.startswith(('rclpy', 'rcl_'))]\n"
              'assert not loaded, loaded\n')
    result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 0, result.stderr
