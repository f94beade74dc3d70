"""
Property tests of the ROS-free command gate: it never raises, never lets a bad value through.

Whatever floats and arrays arrive, the gate never lets a non-finite or out-of-limit value
through; every input is either accepted within the limits or rejected with a reason naming
topic, field and rule.
"""

import array
import math

from hypothesis import example, given, settings
from hypothesis import strategies as st
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_sim.command_gate import (
    check_steer,
    check_wheel_speed,
    CommandGate,
    map_twist,
    Rejection,
    STEER_TOPIC,
    TWIST_TOPIC,
    WHEEL_TOPIC,
)
import numpy as np
import pytest

# Overflow or invalid-value warnings would mean a non-finite value was computed unguarded.
pytestmark = pytest.mark.filterwarnings('error')

GEOMETRY = RobotGeometry()  # Table 1; steer limit pi/2
SUBNORMAL = 5e-324
any_float = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
float_lists = st.lists(any_float, max_size=8)
as_sent = st.sampled_from([list, np.array, lambda v: array.array('d', v)])  # ROS: array('d')
bounds = st.floats(min_value=1e-3, max_value=1e6)
offsets = st.sampled_from([0.0, -0.445, 0.445])  # P: centre, rear axle, front axle [m]


def _assert_rejection(result, topic):
    assert isinstance(result, Rejection)
    message = str(result)
    assert message.startswith(f'rejected {topic}: {result.field} = ')
    assert result.rule and message.endswith(result.rule)


def _assert_within(values, bound):
    assert isinstance(values, np.ndarray) and values.shape == (4,)
    assert np.all(np.isfinite(values)) and np.all(np.abs(values) <= bound)


@pytest.mark.parametrize('check, topic', [(check_steer, STEER_TOPIC),
                                          (check_wheel_speed, WHEEL_TOPIC)])
@given(values=float_lists, kind=as_sent, bound=bounds)
@example(values=[], kind=list, bound=1.0)
@example(values=[SUBNORMAL, -SUBNORMAL, 0.0, -0.0], kind=list, bound=1.0)
@example(values=[1e308, 0.0, 0.0, 0.0], kind=list, bound=1.0)
@example(values=[-1e308, math.nan, math.inf, -math.inf], kind=list, bound=1.0)
def test_arrays_are_accepted_exactly_when_four_finite_values_within_the_bound(
        check, topic, values, kind, bound):
    result = check(kind(values), bound)
    valid = (len(values) == 4 and all(math.isfinite(v) for v in values)
             and all(abs(v) <= bound for v in values))
    if valid:
        _assert_within(result, bound)
        assert result.tolist() == values
    else:
        _assert_rejection(result, topic)


@pytest.mark.parametrize('values, needle', [
    ([], 'len(data) = 0: must be 4 (FL, FR, RL, RR)'),
    ([1.0] * 5, 'len(data) = 5: must be 4'),
    ([0.0, math.nan, 0.0, 0.0],
     'data[1] (front_right) = nan rad/s: must be finite, not NaN or inf'),
    ([0.0, 0.0, -math.inf, 0.0], 'data[2] (rear_left) = -inf rad/s: must be finite'),
    ([0.0, 0.0, 0.0, 1e308], 'data[3] (rear_right) = 1e+308 rad/s: must be within +-50 rad/s '
                             '(motors.max_wheel_speed)'),
])
def test_a_rejected_wheel_array_names_topic_field_and_rule(values, needle):
    message = str(check_wheel_speed(values, 50.0))
    assert message.startswith(f'rejected {WHEEL_TOPIC}: ') and needle in message


def test_a_steer_beyond_the_limit_names_the_limit():
    message = str(check_steer([0.0, 1.6, 0.0, 0.0], math.pi / 2))
    assert message == (f'rejected {STEER_TOPIC}: data[1] (front_right) = 1.6 rad: '
                       f'must be within +-1.5708 rad (chassis.steer_limit)')


@given(vx=any_float, vy=any_float, wz=any_float, offset=offsets, bound=bounds,
       hold=st.none() | st.lists(st.floats(-math.pi / 2, math.pi / 2), min_size=4, max_size=4))
@example(vx=1e308, vy=0.0, wz=1e308, offset=0.0, bound=50.0, hold=None)
@example(vx=-1e308, vy=1e308, wz=-1e308, offset=-0.445, bound=50.0, hold=None)
@example(vx=SUBNORMAL, vy=-SUBNORMAL, wz=SUBNORMAL, offset=0.0, bound=50.0, hold=None)
def test_twists_map_within_limits_or_are_rejected(vx, vy, wz, offset, bound, hold):
    result = map_twist(vx, vy, wz, GEOMETRY, offset, bound, hold_steer=hold)
    if isinstance(result, Rejection):
        _assert_rejection(result, TWIST_TOPIC)
        return
    steer, wheel_speed = result
    assert all(math.isfinite(v) for v in (vx, vy, wz))
    _assert_within(steer, GEOMETRY.steer_limit)
    _assert_within(wheel_speed, bound)


@given(vx=st.floats(-1.0, 1.0), vy=st.floats(-1.0, 1.0), wz=st.floats(-1.0, 1.0),
       offset=offsets)
def test_ordinary_twists_are_accepted(vx, vy, wz, offset):
    # |wheel velocity| <= |v| + |wz| * 0.9 m < 2.9 m/s, i.e. < 21 rad/s on 0.14 m wheels.
    assert not isinstance(map_twist(vx, vy, wz, GEOMETRY, offset, 50.0), Rejection)


def test_a_huge_twist_names_the_twist_the_wheel_and_the_bound():
    message = str(map_twist(1e308, 0.0, 1e308, GEOMETRY, 0.0, 50.0))
    assert message.startswith(f'rejected {TWIST_TOPIC}: (linear.x, linear.y, angular.z) = '
                              f'(1e+308, 0, 1e+308) maps to front_left wheel speed = inf rad/s')
    assert message.endswith('must be within +-50 rad/s (motors.max_wheel_speed)')


def test_a_nan_twist_names_its_field():
    assert str(map_twist(0.0, 0.0, math.nan, GEOMETRY, 0.0, 50.0)) == (
        f'rejected {TWIST_TOPIC}: angular.z = nan rad/s: must be finite, not NaN or inf')


offers = st.one_of(
    st.tuples(st.just('steer'), float_lists),
    st.tuples(st.just('wheels'), float_lists),
    st.tuples(st.just('twist'), st.tuples(any_float, any_float, any_float)),
    st.tuples(st.just('take'), st.none()))


@settings(max_examples=200)
@given(sequence=st.lists(offers, max_size=30))
def test_the_gate_only_ever_hands_out_finite_commands_within_limits(sequence):
    gate = CommandGate(0.1, GEOMETRY, 0.0, max_wheel_speed=50.0)
    now = 0.0
    for kind, payload in sequence:
        now += 0.001
        if kind == 'steer':
            gate.offer_steer(payload, now)
        elif kind == 'wheels':
            gate.offer_wheels(payload, now)
        elif kind == 'twist':
            gate.offer_twist(*payload, now)
        command, report = gate.take(now)
        assert report is None or (isinstance(report, str) and report)
        if command is not None:
            steer, wheel_speed = command
            _assert_within(steer, GEOMETRY.steer_limit)
            _assert_within(wheel_speed, 50.0)


def test_a_run_of_rejections_of_one_kind_is_reported_once():
    gate = CommandGate(0.1, GEOMETRY, 0.0, max_wheel_speed=50.0)
    gate.offer_twist(0.5, 0.0, 0.0, 0.0)
    assert gate.take(0.0)[0] is not None
    reports = []
    for k in range(100):
        gate.offer_twist(1e308 / (k + 1), 0.0, 1e308, 0.001 * k)
        command, report = gate.take(0.001 * k)
        assert command is None
        reports.append(report)
    assert [r for r in reports if r] == [
        f'braking: {map_twist(1e308, 0.0, 1e308, GEOMETRY, 0.0, 50.0)}']
    gate.offer_wheels([1e308] * 4, 0.2)  # another kind: reported
    assert 'motors.max_wheel_speed' in gate.take(0.2)[1]


def test_live_limits_apply_to_the_next_command_and_are_validated():
    gate = CommandGate(0.1, GEOMETRY, 0.0, max_wheel_speed=50.0)
    gate.configure(0.2, 5.0)
    gate.offer_steer([0.0] * 4, 0.0)
    gate.offer_wheels([7.0] * 4, 0.0)
    command, report = gate.take(0.0)
    assert command is None and 'data[0] (front_left) = 7.0 rad/s: must be within +-5' in report
    with pytest.raises(ValueError, match='motors.max_wheel_speed = nan rad/s'):
        gate.configure(0.2, math.nan)


def test_while_per_wheel_commands_come_a_twist_neither_replaces_them_nor_releases_a_step():
    gate = CommandGate(0.1, GEOMETRY, 0.0, 50.0)
    gate.offer_twist(0.5, 0.0, 0.0, 0.0)  # twists alone drive the robot
    assert gate.wait_for_step_command(0.0)
    gate.take(0.0)
    steer, wheels = [0.1] * 4, [3.0] * 4
    gate.offer_steer(steer, 0.001)
    gate.offer_wheels(wheels, 0.001)
    gate.take(0.001)
    gate.offer_twist(0.5, 0.0, 1.0, 0.002)  # the same step's twist, first to arrive
    assert not gate.wait_for_step_command(0.0)  # the step waits for its per-wheel pair
    (held_steer, held_wheels), _ = gate.take(0.002)
    np.testing.assert_array_equal(held_steer, steer)
    np.testing.assert_array_equal(held_wheels, wheels)
    # No per-wheel command for longer than the timeout: twists count again.
    gate.offer_twist(0.5, 0.0, 0.0, 0.2)
    assert gate.wait_for_step_command(0.0)


def test_wheel_speeds_after_a_twist_do_not_pair_with_its_steering():
    # A controller before its first odometry answers each lockstep step with zero wheel speeds
    # and a zero twist (no steering yet to hold); the two arrive in either order, and every
    # step must be released.
    gate = CommandGate(0.1, GEOMETRY, 0.0, 50.0)
    gate.offer_twist(0.0, 0.0, 0.0, 0.0)
    gate.offer_wheels([0.0] * 4, 0.0)
    assert gate.wait_for_step_command(0.0)
    gate.take(0.0)
    gate.offer_wheels([0.0] * 4, 0.001)  # this step's wheels first, then its twist
    gate.offer_twist(0.0, 0.0, 0.0, 0.001)
    assert gate.wait_for_step_command(0.0)
    command, _ = gate.take(0.001)
    np.testing.assert_array_equal(command[1], np.zeros(4))


def test_a_realtime_step_waits_for_a_fresh_command_only_for_a_controller_that_commanded():
    import threading
    import time

    gate = CommandGate(0.1, GEOMETRY, 0.0, max_wheel_speed=50.0)
    # No command yet: nobody to wait for.
    assert gate.wait_for_fresh_command(5.0, 0.005, timeout=10.0)
    gate.offer_twist(0.5, 0.0, 0.0, 1.000)
    assert gate.wait_for_fresh_command(1.005, 0.005, timeout=0.0)  # 5 ms old: fresh
    start = time.monotonic()
    assert not gate.wait_for_fresh_command(1.006, 0.005, timeout=0.05)  # stale: waits
    assert time.monotonic() - start >= 0.05
    # A command taken while the sim waits (at the time it stands at) ends the wait.
    later = threading.Timer(0.05, gate.offer_twist, (0.5, 0.0, 0.0, 1.006))
    later.start()
    assert gate.wait_for_fresh_command(1.006, 0.005, timeout=30.0)
    later.join()
    # So does a rejected one: the step brakes at once instead of waiting.
    gate.offer_wheels([math.nan] * 4, 1.006)
    assert gate.wait_for_fresh_command(2.0, 0.005, timeout=30.0)
