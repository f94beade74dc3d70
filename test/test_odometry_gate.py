"""The controller's odometry checks on their own (runtime/odometry_gate.py)."""

import math

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.odometry_gate import OdometryGate, OdometryRules
import pytest


@pytest.mark.parametrize('field, value, says', [
    ('timeout', 0.0, 'odom_timeout = 0.0 s: must be > 0'),
    ('max_jump', math.nan, 'max_jump = nan m'),
    ('restart_threshold', -1.0, 'restart_threshold = -1.0 s: must be > 0'),
    ('confirm_messages', 0, 'confirm_messages = 0: must be an integer >= 1'),
    ('confirm_messages', True, 'confirm_messages = True: must be an integer >= 1'),
])
def test_bad_rules_name_the_parameter(field, value, says):
    with pytest.raises(ParameterError, match=says.replace('.', r'\.')):
        OdometryRules(**({'timeout': 0.1} | {field: value}))


def test_each_message_gets_a_verdict_and_the_age_runs_from_the_last_taken():
    gate = OdometryGate(OdometryRules(timeout=0.1, restart_threshold=1.0, confirm_messages=2))
    assert gate.fault(0.0)[0] == 'stale' and gate.age(5.0) == math.inf
    first = gate.offer(1.0, 4.0, 0.0, wall_time=0.0, control_time=0.0, stamp=10.0)
    assert first.taken and first.control_time == 0.0 and not (first.restarted or first.gap)
    assert gate.offer(1.0, 4.0, 0.0, 0.01, 0.01, 9.99) is None  # out of order: nothing
    assert gate.pose == (1.0, 4.0, 0.0) and gate.stamp == 10.0
    assert gate.fault(0.1) is None and gate.fault(0.1001)[0] == 'stale'
    # A restart: two messages in a row on a base 5 s back, the first one's time its origin.
    assert not gate.offer(1.0, 4.0, 0.0, 0.02, 0.02, 5.0).taken
    assert gate.fault(0.02)[0] == 'stamp'
    again = gate.offer(1.0, 4.0, 0.0, 0.03, 0.03, 5.001)
    assert again.taken and again.restarted and again.control_time == 0.02
    assert gate.fault(0.03) is None and gate.age(0.05) == pytest.approx(0.02)
    # A gap ahead is no restart.
    gate.offer(1.0, 4.0, 0.0, 0.04, 0.04, 9.0)
    ahead = gate.offer(1.0, 4.0, 0.0, 0.05, 0.05, 9.001)
    assert ahead.taken and ahead.gap and not ahead.restarted


def test_a_jump_is_refused_but_not_on_a_restart():
    gate = OdometryGate(OdometryRules(timeout=0.1, max_jump=1.0, confirm_messages=1))
    gate.offer(0.0, 0.0, 0.0, 0.0, 0.0, 100.0)
    assert not gate.offer(2.0, 0.0, 0.0, 0.001, 0.001, 100.001).taken
    assert gate.fault(0.001) == ('jump', 'odometry jumped 2.00 m in one message (limit 1 m)')
    restart = gate.offer(2.0, 0.0, 0.0, 0.002, 0.002, 0.0)  # the source started over
    assert restart.taken and restart.restarted and gate.pose == (2.0, 0.0, 0.0)
