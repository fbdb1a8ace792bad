"""
Integration: parameters keep their declared types; describe shows ranges and rules (issue 13).

A real generator subprocess is driven from this process with the parameter services that
``ros2 param set/get/describe`` use.
"""

import math

from node_harness import NodeProcess, running_node
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, SetParameters
import rclpy
from rclpy.node import Node

GENERATOR = '/trajectory_generator'
SCALARS = ('rate_hz',)
PER_JOINT = ('max_velocity', 'max_acceleration', 'lspb_acceleration', 'max_jerk',
             'min_position', 'max_position')
RULE = 'one value for all joints or one per joint'


class ParameterClient(Node):
    """What ``ros2 param`` does: the node's parameter services."""

    def __init__(self):
        super().__init__('parameter_client')
        self.set_client = self.create_client(SetParameters, f'{GENERATOR}/set_parameters')
        self.get_client = self.create_client(GetParameters, f'{GENERATOR}/get_parameters')
        self.describe_client = self.create_client(DescribeParameters,
                                                  f'{GENERATOR}/describe_parameters')
        for client in (self.set_client, self.get_client, self.describe_client):
            assert client.wait_for_service(timeout_sec=30.0), client.srv_name
            self.call(client, client.srv_type.Request(), attempts=6)

    def call(self, client, request, attempts: int = 1):
        """
        Call ``client``; with ``attempts`` > 1, send again what went unanswered for 5 s.

        A service is "ready" once its request reader has matched this client; its response
        writer may match this client's reader later, and a response sent before is lost
        (rmw_fastrtps waits only a short while for the match: ros2/rmw_fastrtps#390; seen
        here under load, a first ``get_parameters`` unanswered for 30 s). Each client's
        first call, an empty request, is repeated until answered, so the tests' own calls
        find both ways open.
        """
        for _ in range(attempts):
            future = client.call_async(request)
            rclpy.spin_until_future_complete(self, future, timeout_sec=30.0 / attempts)
            if future.done():
                return future.result()
            client.remove_pending_request(future)
        raise AssertionError(f'{client.srv_name}: no answer to {attempts} requests')

    def set_value(self, name: str, value: ParameterValue):
        request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
        return self.call(self.set_client, request).results[0]

    def get(self, name: str) -> ParameterValue:
        return self.call(self.get_client, GetParameters.Request(names=[name])).values[0]

    def describe(self, name: str):
        return self.call(self.describe_client,
                         DescribeParameters.Request(names=[name])).descriptors[0]


def integer(value: int) -> ParameterValue:
    return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)


def double(value: float) -> ParameterValue:
    return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)


def string(value: str) -> ParameterValue:
    return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)


@pytest.fixture(scope='module')
def client():
    # Integers given at start-up, as `-p rate_hz:=50` or `rate_hz: 50` in a file.
    with running_node('-p', 'rate_hz:=50', '-p', 'max_acceleration:=5'):
        node = ParameterClient()
        try:
            yield node
        finally:
            node.destroy_node()


def test_integers_given_at_start_up_are_stored_as_doubles(client):
    rate = client.get('rate_hz')
    assert rate.type == ParameterType.PARAMETER_DOUBLE and rate.double_value == 50.0
    acceleration = client.get('max_acceleration')
    assert acceleration.type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert list(acceleration.double_array_value) == [5.0]


def test_an_integer_set_at_run_time_stays_a_double(client):
    # `ros2 param set /trajectory_generator rate_hz 50` sends an integer.
    result = client.set_value('rate_hz', integer(60))
    assert result.successful, result.reason
    value = client.get('rate_hz')
    assert value.type == ParameterType.PARAMETER_DOUBLE and value.double_value == 60.0
    assert client.describe('rate_hz').type == ParameterType.PARAMETER_DOUBLE
    # Out of the declared range: refused by the range, the value stays.
    refused = client.set_value('rate_hz', integer(5000))
    assert not refused.successful
    assert 'rate_hz out of range' in refused.reason and 'Max: 1000.0' in refused.reason
    assert client.get('rate_hz').double_value == 60.0
    assert client.set_value('rate_hz', double(100.0)).successful


def test_a_wrong_type_is_refused_and_the_type_stays(client):
    refused = client.set_value('rate_hz', string('fast'))
    assert not refused.successful
    assert refused.reason == "Wrong parameter type, expected 'Type.DOUBLE' got 'Type.STRING'"
    refused = client.set_value('max_velocity', string('fast'))
    assert not refused.successful and "expected 'Type.DOUBLE_ARRAY'" in refused.reason
    assert client.get('rate_hz').type == ParameterType.PARAMETER_DOUBLE
    assert client.describe('rate_hz').type == ParameterType.PARAMETER_DOUBLE
    assert client.get('max_velocity').type == ParameterType.PARAMETER_DOUBLE_ARRAY


@pytest.mark.parametrize('value, stored', [
    (integer(3), [3.0]),
    (double(2.5), [2.5]),
    (ParameterValue(type=ParameterType.PARAMETER_INTEGER_ARRAY,
                    integer_array_value=[1, 2, 3, 4, 5, 6]), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
    (ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                    double_array_value=[2.0, 2.0, 2.0, 3.0, 3.0, 3.0]),
     [2.0, 2.0, 2.0, 3.0, 3.0, 3.0]),
])
def test_a_per_joint_parameter_is_always_a_double_array(client, value, stored):
    result = client.set_value('max_velocity', value)
    assert result.successful, result.reason
    got = client.get('max_velocity')
    assert got.type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert list(got.double_array_value) == stored
    assert client.describe('max_velocity').type == ParameterType.PARAMETER_DOUBLE_ARRAY


def test_describe_shows_every_range_and_rule(client):
    for name in SCALARS:
        descriptor = client.describe(name)
        assert descriptor.type == ParameterType.PARAMETER_DOUBLE
        assert len(descriptor.floating_point_range) == 1, name
        assert descriptor.floating_point_range[0].from_value == 1.0
        assert descriptor.floating_point_range[0].to_value == 1000.0
        assert 'Hz' in descriptor.description
    for name in PER_JOINT:
        descriptor = client.describe(name)
        assert descriptor.type == ParameterType.PARAMETER_DOUBLE_ARRAY, name
        assert RULE in descriptor.description and RULE in descriptor.additional_constraints
        assert 'rad' in descriptor.additional_constraints, name
    for name, choices in (('profile', 'lspb | cubic | quintic | scurve'),
                          ('via_velocities', 'heuristic | continuous')):
        descriptor = client.describe(name)
        assert descriptor.type == ParameterType.PARAMETER_STRING
        assert descriptor.additional_constraints == choices
    assert client.describe('joints').read_only
    assert client.describe('robot_description').type == ParameterType.PARAMETER_STRING


def test_max_jerk_is_set_at_run_time_and_refused_unless_positive(client):
    # `ros2 param set /trajectory_generator max_jerk 30` sends an integer: stored as [30.0].
    result = client.set_value('max_jerk', integer(30))
    assert result.successful, result.reason
    got = client.get('max_jerk')
    assert got.type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert list(got.double_array_value) == [30.0]
    per_joint = ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                               double_array_value=[10.0, 10.0, 10.0, 40.0, 40.0, 40.0])
    assert client.set_value('max_jerk', per_joint).successful
    refusal = "max_jerk must be finite and > 0; joint 'joint_1' has "
    for value, reason in ((double(0.0), refusal + '0.0'), (integer(-5), refusal + '-5.0'),
                          (ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                                          double_array_value=[1.0, 2.0]),
                           'max_jerk has 2 values but there are 6 joints')):
        refused = client.set_value('max_jerk', value)
        assert not refused.successful
        assert reason in refused.reason, refused.reason
        # The value stays.
        assert list(client.get('max_jerk').double_array_value) == [10.0, 10.0, 10.0, 40.0,
                                                                   40.0, 40.0]
    assert 'rad/s^3' in client.describe('max_jerk').additional_constraints
    assert client.set_value('max_jerk', double(20.0)).successful


def test_position_limits_default_to_none(client):
    lower, upper = client.get('min_position'), client.get('max_position')
    assert list(lower.double_array_value) == [-math.inf]
    assert list(upper.double_array_value) == [math.inf]


@pytest.mark.parametrize('override, reason', [
    ('rate_hz:=fast', "rate_hz must be a number (double); got 'fast' (a string)"),
    ('min_position:=[a, b]', 'min_position must be a number or a list of numbers (one value '
                             "for all joints or one per joint); got ['a', 'b'] (a list of "
                             'strings)'),
    ('profile:=3', 'profile must be a string; got 3 (an integer)'),
])
def test_a_wrong_type_at_start_up_exits_with_the_reason(override, reason):
    # Without the config file: rcl drops a `-p` whose type differs from the file's value.
    node = NodeProcess('-p', override, params_file=None)
    try:
        code = node.process.wait(30)
        output = node.output()
    finally:
        node.close()
    assert code == 1, output
    assert f'invalid parameters: {reason}' in output, output
    assert 'Traceback' not in output
