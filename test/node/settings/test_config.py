"""The parameters checked together into one Config: broadcasting, replacements, refusals."""

import math

from planning_rig import config
import pytest


def test_config_broadcasts_and_replaces_zero_lspb_acceleration():
    cfg = config(lspb_acceleration=[0.0, 1.0, 0.0])
    assert cfg.max_acceleration.tolist() == [4.0, 4.0, 4.0]
    assert cfg.lspb_acceleration.tolist() == [4.0, 1.0, 4.0]
    assert cfg.profile_acceleration.tolist() == [4.0, 4.0, 4.0]
    assert config(profile='lspb', lspb_acceleration=2).profile_acceleration.tolist() == [2.0] * 3


@pytest.mark.parametrize('changes, reason', [
    ({'joints': []}, 'joints is empty'),
    ({'joints': ['a', 'a']}, r"joints lists \['a'\] more than once"),
    ({'rate_hz': True}, 'rate_hz must be a number'),
    ({'max_velocity': [1.0, math.nan, 1.0]},
     "max_velocity must be finite and > 0; joint 'b' has nan"),
    ({'max_acceleration': [1.0, 2.0]}, 'has 2 values but there are 3 joints'),
    ({'lspb_acceleration': -1.0}, ('lspb_acceleration must be finite and >= 0; '
                                   "joint 'a' has -1.0")),
    ({'max_jerk': 0.0}, "max_jerk must be finite and > 0; joint 'a' has 0.0"),
    ({'max_jerk': [1.0, -2.0, 1.0]}, "max_jerk must be finite and > 0; joint 'b' has -2.0"),
    ({'profile': 'septic'}, 'profile must be one of lspb, cubic, quintic, scurve'),
])
def test_config_errors_name_the_parameter(changes, reason):
    with pytest.raises(ValueError, match=reason):
        config(**changes)
