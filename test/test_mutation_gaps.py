"""
Behaviour that mutation testing (doc/mutation.md) found no fast test for.

Every expected value is computed by hand from the geometry or the formula in the
docstring, not taken from the code under test.
"""

from dataclasses import replace
import math

from nfmr_dlsmc.core.gains import DlsmcConfig, InputLimits
from nfmr_dlsmc.core.metrics import (
    format_metric,
    hold_metrics,
    sample_durations,
    total_variation_rate,
    tracking_metrics,
)
from nfmr_dlsmc.core.outer_loop import position_input, reaching_term_slope
from nfmr_dlsmc.core.sliding_functions import bounded_rate, bounded_rate_slope
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.runtime.params import ControllerParams
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
import numpy as np
import pytest
import yaml

GEOMETRY = RobotGeometry()  # L = 0.89 m, track 0.53 m
A, B = 0.5 * 0.89, 0.5 * 0.53  # half wheelbase, half track [m]


# --- steer_angle_series: the vectorised steer angles of the logs and reports ---------------

def test_double_ackermann_series_points_every_wheel_at_the_turn_centre():
    # j1 = 1: P is the chassis centre; v = 1 m/s, omega = 0.5 rad/s turn about (0, R = 2 m).
    # A wheel at (x_i, y_i) is perpendicular to its radius: delta_i = atan(x_i / (R - y_i)).
    R = 2.0
    steer = steer_angle_series([1.0], [0.5], GEOMETRY, SteerMode(1.0, 0.0))
    expected = [math.atan(A / (R - B)), math.atan(A / (R + B)),
                -math.atan(A / (R - B)), -math.atan(A / (R + B))]
    assert steer.shape == (1, 4)
    np.testing.assert_allclose(steer[0], expected, rtol=1e-12)


def test_front_only_series_is_plain_ackermann_about_the_rear_axle():
    # j1 = 0: P is on the rear axle, the turn centre is (-L/2, R); rear wheels stay straight.
    R = 2.0
    steer = steer_angle_series([1.0, 1.0], [-0.5, 0.5], GEOMETRY, SteerMode(0.0, 1.0))
    left_turn = [math.atan(0.89 / (R - B)), math.atan(0.89 / (R + B)), 0.0, 0.0]
    np.testing.assert_allclose(steer[1], left_turn, rtol=1e-12, atol=1e-15)
    # The right turn mirrors it: the right wheels are now the inner ones.
    np.testing.assert_allclose(steer[0], [-left_turn[1], -left_turn[0], 0.0, 0.0],
                               rtol=1e-12, atol=1e-15)


def test_series_folds_reversing_wheels_into_the_half_plane():
    # Driving backwards the wheels keep pointing forward (angle 0, not +-pi); reversing
    # through a turn each wheel is at its forward-turn angle mirrored.
    R = 2.0
    steer = steer_angle_series([-1.0, -1.0], [0.0, -0.5], GEOMETRY, SteerMode(1.0, 0.0))
    np.testing.assert_allclose(steer[0], 0.0, atol=1e-15)
    # v = -1, omega = -0.5: the same circle, R = v / omega = 2 m, driven backwards.
    expected = [math.atan(A / (R - B)), math.atan(A / (R + B)),
                -math.atan(A / (R - B)), -math.atan(A / (R + B))]
    np.testing.assert_allclose(steer[1], expected, rtol=1e-12)


def test_series_wheels_that_stand_still_keep_their_last_angle():
    # Sample 0 stands still (nothing to keep: 0), 1 turns, 2 and 3 stand still (keep 1's
    # angles), 4 drives straight.
    R = 2.0
    v = [0.0, 1.0, 0.0, 0.0, 1.0]
    omega = [0.0, 0.5, 0.0, 0.0, 0.0]
    steer = steer_angle_series(v, omega, GEOMETRY, SteerMode(1.0, 0.0))
    turn = [math.atan(A / (R - B)), math.atan(A / (R + B)),
            -math.atan(A / (R - B)), -math.atan(A / (R + B))]
    np.testing.assert_allclose(steer[0], 0.0, atol=1e-15)
    for k in (1, 2, 3):
        np.testing.assert_allclose(steer[k], turn, rtol=1e-12)
    np.testing.assert_allclose(steer[4], 0.0, atol=1e-15)


def test_series_spinning_in_place_keeps_only_the_moving_wheels():
    # v = 0, omega = 1 in double Ackermann: P (the centre) stands, every wheel moves on a
    # circle about it: perpendicular to its position, folded into [-pi/2, pi/2].
    # FL at (A, B) moves along (-B, A): atan2(A, -B) = pi - atan(A/B), reversed to
    # -atan(A/B); FR along (B, A): atan(A/B); RL along (-B, -A): atan(A/B); RR: -atan(A/B).
    steer = steer_angle_series([0.0], [1.0], GEOMETRY, SteerMode(1.0, 0.0))
    d = math.atan(A / B)
    np.testing.assert_allclose(steer[0], [-d, d, d, -d], rtol=1e-12)


def test_series_clips_to_the_steer_limit():
    limit = 0.1
    geometry = RobotGeometry(steer_limit=limit)
    R = 2.0
    steer = steer_angle_series([1.0], [0.5], geometry, SteerMode(1.0, 0.0))
    # Every wheel of this turn asks for more than 0.1 rad (the smallest is atan(A/(R+B))).
    assert math.atan(A / (R + B)) > limit
    np.testing.assert_allclose(steer[0], [limit, limit, -limit, -limit])


def test_series_refuses_crab_mode():
    with pytest.raises(ValueError, match='crab mode'):
        steer_angle_series([1.0], [0.0], GEOMETRY, SteerMode(-1.0, 2.0))


# --- format_metric: the table cells of nfmr-eval, nfmr-analyze and the comparison report --

@pytest.mark.parametrize('value, text', [
    (None, '—'), (math.nan, '—'),
    (0.0, '0.0000'), (1.23456, '1.2346'), (-2.5, '-2.5000'), (0.01, '0.0100'),
    (0.0012345, '1.234e-03'), (-0.005, '-5.000e-03'),
])
def test_format_metric_cells(value, text):
    assert format_metric(value) == text


# --- position_input, eqs (34), (35): u = v_d - k2 |s|^r erf(h s) - C alpha ----------------------

def reaching_term(s, k2, r, h):
    """Return k2 |s|^r erf(h s) as eq. (34) subtracts it: from the law, with v_d = C = 0."""
    return -position_input(0.0, s, 0.0, 0.0, k2, r, h)


def test_the_reaching_term_is_the_odd_power_erf_product():
    # |0.25|^0.5 = 0.5; erf(2 * 0.25) = erf(0.5) = 0.5204998778130465
    assert math.isclose(reaching_term(0.25, 1.0, 0.5, 2.0), 0.5 * 0.5204998778130465,
                        rel_tol=1e-12)
    assert math.isclose(reaching_term(-0.25, 1.0, 0.5, 2.0), -0.5 * 0.5204998778130465,
                        rel_tol=1e-12)
    # |4|^0.5 = 2; erf(0.1 * 4) = erf(0.4) = 0.42839235504666845; k2 = 3 scales it.
    assert math.isclose(reaching_term(4.0, 3.0, 0.5, 0.1), 6.0 * 0.42839235504666845,
                        rel_tol=1e-12)
    assert reaching_term(0.0, 1.0, 0.5, 2.0) == 0.0


def test_position_input_subtracts_the_reaching_term_and_the_rate_term():
    # v_d = 0.4 m/s, s = 0.25 m, alpha = 0.5, C = 0.6 m/s, k2 = 2: 0.4 - 2 * 0.5 * erf(0.5) - 0.3
    u = position_input(0.4, 0.25, 0.5, 0.6, 2.0, 0.5, 2.0)
    assert math.isclose(u, 0.4 - 2.0 * 0.5 * 0.5204998778130465 - 0.6 * 0.5, rel_tol=1e-12)


# --- TrackingSession.set_params: live parameter changes reach the next tick -----------------

def test_set_params_changes_the_limits_of_the_next_tick():
    s = TrackingSession(ControllerParams(), odom_timeout=0.1)
    s.on_odometry(30.0, 40.0, 0.0, 0.0, 0.0, 0.0, 'odom')
    assert s.tick(0.0, 0.0).v < 1.0  # at t = 0 s(0) = 0: a modest speed command
    fast = InputLimits(v_min=1.0, v_max=2.0)
    s.set_params(ControllerParams(dlsmc=replace(DlsmcConfig(), limits=fast)))
    assert s.params.dlsmc.limits == fast
    s.on_odometry(30.0, 40.0, 0.0, 0.001, 0.001, 0.001, 'odom')
    assert s.tick(0.001, 0.001).v == 1.0  # now held up at the new v_min


# --- hold_metrics / tracking_metrics: the figures of holding the path ----------------------

def _hold_case():
    t = [0.0, 1.0, 2.0, 3.0, 4.0]
    dt = np.array([1.0, 1.0, 0.5, 0.25, 0.25])  # uneven sampling: each sample's duration
    distance = [9.0, 9.0, 1.0, 3.0, 2.0]
    theta_e = [9.0, 9.0, -0.5, 0.2, -0.1]
    omega = [9.0, 9.0, 1.0, -1.0, 0.5]
    saturated = [1.0, 1.0, 0.0, 1.0, 1.0]
    steer = np.array([[9.0] * 4, [9.0] * 4, [0.1, 0.0, 0.0, 0.0], [0.1, -0.5, 0.0, 0.0],
                      [0.1, -0.4, 0.0, 0.0]])
    joint = np.array([[99.0] * 4, [99.0] * 4, [0.1, -0.7, 0.0, 0.0], [0.0, 0.0, 0.0, 0.3],
                      [0.0] * 4])
    return t, distance, theta_e, omega, dt, saturated, steer, joint


def test_hold_metrics_cover_the_samples_from_hold_from_on():
    t, distance, theta_e, omega, dt, saturated, steer, joint = _hold_case()
    m = hold_metrics(t, distance, theta_e, omega, dt, 2.0, saturated, steer, joint)
    assert m['hold_from'] == 2.0
    # Window t >= 2 (the sample at t = 2 included): distance 1, 3, 2 -> sorted 1, 2, 3;
    # the 99th percentile interpolates at rank 0.99 * 2 = 1.98: 2 + 0.98 * (3 - 2).
    assert math.isclose(m['hold_distance_p99'], 2.98)
    assert m['hold_distance_max'] == 3.0
    # |theta_e| 0.5, 0.2, 0.1 -> sorted 0.1, 0.2, 0.5: 0.2 + 0.98 * 0.3.
    assert math.isclose(m['hold_theta_e_p99'], 0.494)
    assert m['hold_theta_e_max'] == 0.5
    # omega 1, -1, 0.5: total variation 2 + 1.5 over the durations of all but the last
    # sample, 0.5 + 0.25 s.
    assert math.isclose(m['hold_omega_tv'], 3.5 / 0.75)
    assert math.isclose(m['hold_omega_saturated'], 2.0 / 3.0)
    # Steer steps 0.5 rad over 0.5 s (1 rad/s) and 0.1 rad over 0.25 s (0.4 rad/s).
    assert math.isclose(m['hold_steer_rate_max'], 1.0)
    assert m['hold_steer_joint_rate_max'] == 0.7


def test_hold_metrics_are_none_outside_the_window_and_without_inputs():
    t, distance, theta_e, omega, dt, saturated, steer, joint = _hold_case()
    empty = hold_metrics(t, distance, theta_e, omega, dt, 10.0, saturated, steer, joint)
    assert empty['hold_from'] == 10.0
    assert all(v is None for k, v in empty.items() if k != 'hold_from')
    bare = hold_metrics(t, distance, [math.nan] * 5, omega, dt, 2.0)
    assert bare['hold_distance_max'] == 3.0
    for key in ('hold_theta_e_p99', 'hold_theta_e_max', 'hold_omega_saturated',
                'hold_steer_rate_max', 'hold_steer_joint_rate_max'):
        assert bare[key] is None, key
    # One sample in the window: no steer rate.
    last = hold_metrics(t, distance, theta_e, omega, dt, 4.0, saturated, steer, joint)
    assert last['hold_steer_rate_max'] is None and last['hold_distance_max'] == 2.0
    assert last['hold_omega_tv'] == 0.0


def test_tracking_metrics_of_a_hand_made_run():
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    x = np.array([1.0, 0.5, 0.005, 0.0, 0.0])
    zero = np.zeros(5)
    theta = np.array([0.1, 0.2, 0.3, -0.1, 0.05])
    theta_r = theta + 2.0 * math.pi - 0.1  # theta - theta_r wraps to 0.1 everywhere
    v = np.array([0.5, -2.0, 1.0, 1.0, 1.0])
    omega = np.array([0.1, -1.5, 1.0, -1.0, 0.5])
    m = tracking_metrics(t, x, zero, theta, zero, zero, zero, theta_r, v, omega, 1.0,
                         hold_from=3.0, omega_saturated=[0, 1, 0, 1, 0])
    assert math.isclose(m.iae, 1.505)
    assert math.isclose(m.ise, 1.0 + 0.25 + 0.005 ** 2)
    assert math.isclose(m.std, float(np.sqrt(np.mean((x - x.mean()) ** 2))))
    assert m.t_conv == 2.0 and m.t_conv_1cm == 1.0  # last above 1 mm / above 1 cm
    assert m.final_distance == 0.0
    assert m.max_v == 2.0 and m.max_abs_omega == 1.5
    assert math.isclose(m.theta_e_iae, 0.75) and math.isclose(m.theta_e_ise, 0.1525)
    assert math.isclose(m.theta_e_std, float(np.std(theta)))
    assert math.isclose(m.theta_r_iae, 0.5) and math.isclose(m.theta_r_ise, 0.05)
    assert m.theta_r_std < 1e-12
    assert math.isclose(m.max_abs_theta_e_after_conv, 0.3)  # t >= 2: 0.3, 0.1, 0.05
    assert math.isclose(m.omega_tv_after_conv, (2.0 + 1.5) / 2.0)
    assert m.hold_from == 3.0 and m.hold_distance_max == 0.0
    assert m.hold_omega_saturated == 0.5 and math.isclose(m.hold_omega_tv, 1.5)
    assert m.as_dict()['t_conv'] == 2.0 and m.as_dict()['hold_from'] == 3.0


def test_tracking_metrics_of_a_run_that_never_settles():
    t = np.array([0.0, 1.0, 2.0])
    far = np.array([1.0, 1.0, 1.0])
    zero = np.zeros(3)
    m = tracking_metrics(t, far, zero, zero, zero, zero, zero, zero, zero + 1.0, zero, 1.0)
    assert m.t_conv is None and m.t_conv_1cm is None
    assert m.max_abs_theta_e_after_conv is None and m.omega_tv_after_conv is None


def test_total_variation_rate_and_sample_durations():
    assert total_variation_rate([1.0], 0.1) == 0.0
    assert math.isclose(total_variation_rate([0.0, 1.0, -1.0], 0.5), 3.0 / 1.0)
    assert math.isclose(total_variation_rate([0.0, 1.0, -1.0], [0.5, 0.25, 9.0]), 3.0 / 0.75)
    np.testing.assert_allclose(sample_durations([0.0, 0.1, 0.3, 0.4]), [0.1, 0.2, 0.1, 0.1])
    np.testing.assert_allclose(sample_durations([0.0, 1.0, 3.0, 4.0, 4.5]),
                               [1.0, 2.0, 1.0, 0.5, 1.0])
    np.testing.assert_array_equal(sample_durations([5.0]), [0.0])


# --- the slopes of the robot profile's analytic thetadot_d ---------------------------------

@pytest.mark.parametrize('e', [0.5, -0.5, 0.05, 0.9])
def test_bounded_rate_slope_is_the_derivative_of_eq_33(e):
    xi, r = 1.0, 0.5
    a = abs(e)
    by_hand = 0.5 * math.pi * r * math.cos(0.5 * math.pi * a ** r) * a ** (r - 1.0)
    assert math.isclose(bounded_rate_slope(e, xi, r, 0.0), by_hand, rel_tol=1e-12)
    xi2 = 2.0
    by_hand2 = (0.5 * math.pi * r * math.cos(0.5 * math.pi * (a / xi2) ** r)
                * a ** (r - 1.0) / xi2 ** r)
    assert math.isclose(bounded_rate_slope(e, xi2, r, 0.0), by_hand2, rel_tol=1e-12)
    h = 1e-7
    numeric = (bounded_rate(e + h, xi2, r) - bounded_rate(e - h, xi2, r)) / (2 * h)
    assert math.isclose(bounded_rate_slope(e, xi2, r, 0.0), numeric, rel_tol=1e-5)


def test_bounded_rate_slope_zones():
    xi, r, d = 1.0, 0.5, 0.1
    chord = math.sin(0.5 * math.pi * math.sqrt(0.1)) / 0.1  # alpha(d) / d
    assert math.isclose(bounded_rate_slope(0.05, xi, r, d), chord, rel_tol=1e-12)
    assert math.isclose(bounded_rate_slope(-0.05, xi, r, d), chord, rel_tol=1e-12)
    assert math.isclose(bounded_rate_slope(0.0, xi, r, d), chord, rel_tol=1e-12)
    assert bounded_rate_slope(0.0, xi, r, 0.0) == math.inf
    assert bounded_rate_slope(1.5, xi, r, d) == 0.0 and bounded_rate_slope(-1.5, xi, r, d) == 0.0
    # At |e| = xi the curve is still inside: cos(pi / 2) = 0 up to rounding.
    assert abs(bounded_rate_slope(1.0, xi, r, d)) < 1e-15
    # Just outside the linear zone the curve's own slope applies, not the chord.
    e = 0.1
    by_hand = 0.5 * math.pi * r * math.cos(0.5 * math.pi * e ** r) * e ** (r - 1.0)
    assert math.isclose(bounded_rate_slope(e, xi, r, d), by_hand, rel_tol=1e-12)


@pytest.mark.parametrize('s', [0.3, -0.3, 2.0, -0.01])
def test_reaching_term_slope_is_the_derivative_of_the_reaching_term(s):
    k2, r, h = 1.5, 0.5, 2.0
    a = abs(s)
    by_hand = k2 * (r * a ** (r - 1.0) * abs(math.erf(h * s))
                    + a ** r * 2.0 * h / math.sqrt(math.pi) * math.exp(-(h * s) ** 2))
    assert math.isclose(reaching_term_slope(s, k2, r, h), by_hand, rel_tol=1e-12)
    step = 1e-7
    numeric = (reaching_term(s + step, k2, r, h) - reaching_term(s - step, k2, r, h)) / (2 * step)
    assert math.isclose(reaching_term_slope(s, k2, r, h), numeric, rel_tol=1e-5)
    assert reaching_term_slope(0.0, k2, r, h) == 0.0


# --- TrackingSession guards: the edges of the odometry checks --------------------------------

def _session(**kw):
    return TrackingSession(ControllerParams(), odom_timeout=0.1, **kw)


def _feed(s, x, y, stamp, wall=None):
    wall = stamp if wall is None else wall
    accepted = s.on_odometry(x, y, 0.0, wall, stamp, stamp, 'odom')
    return accepted, s.tick(stamp, wall)


@pytest.mark.parametrize('bad', [0, -1, True, 1.5, '3'])
def test_confirm_messages_must_be_an_integer_of_at_least_one(bad):
    with pytest.raises(ValueError, match='confirm_messages'):
        _session(confirm_messages=bad)


def test_one_confirming_message_takes_a_new_time_base_at_once():
    s = _session(confirm_messages=1)
    _feed(s, 1.0, 4.0, 0.0)
    accepted, out = _feed(s, 1.0, 4.0, 5.0, wall=0.001)  # a gap forward: taken at once
    assert accepted and not out.stopped


def test_restart_threshold_defaults_to_one_second_and_bounds_out_of_order():
    s = _session()
    for stamp in (2.0, 2.5, 3.0):
        _feed(s, 1.0, 4.0, stamp)
    # 0.875 s back: out of order (ignored); 1 s back (the threshold itself) and beyond: off
    # the time base, so the message is taken and stops the robot.
    assert s.on_odometry(1.0, 4.0, 0.0, 3.001, 3.001, 2.125, 'odom') is False
    assert s.on_odometry(1.0, 4.0, 0.0, 3.001, 3.001, 2.0, 'odom') is True
    assert s.tick(3.001, 3.001).stopped
    s = _session()
    _feed(s, 1.0, 4.0, 2.0)
    assert s.on_odometry(1.0, 4.0, 0.0, 2.001, 2.001, 0.5, 'odom') is True  # 1.5 s back


def test_a_repeated_stamp_is_not_out_of_order():
    s = _session()
    _feed(s, 1.0, 4.0, 0.0)
    _feed(s, 1.0, 4.0, 0.001)
    accepted, out = _feed(s, 1.0, 4.0, 0.001, wall=0.002)
    assert accepted and not out.stopped


def test_jump_limit_is_inclusive_and_counts_both_axes():
    s = _session(max_jump=1.0)
    _feed(s, 1.0, 4.0, 0.0)
    assert not _feed(s, 1.0, 5.0, 0.001)[1].stopped  # exactly 1 m along y: accepted
    out = _feed(s, 1.0, 6.5, 0.002)[1]  # 1.5 m along y only
    assert out.stopped and 'jumped 1.50 m' in out.report


def test_stale_odometry_is_reported_once_while_it_lasts():
    s = _session()
    _feed(s, 1.0, 4.0, 0.0)
    outs = [s.tick(0.2 + 0.01 * k, 0.2 + 0.01 * k) for k in range(3)]
    assert all(o.stopped for o in outs)
    assert outs[0].report is not None and outs[1].report is None and outs[2].report is None
    assert s.tick(0.3, 0.3).state[STATE_FIELDS.index('stopped')] == 1.0


def test_the_session_integrates_over_the_measured_step():
    # Ticks 2 ms apart: the controller must see dt = 2 ms, as a controller stepped by hand.
    from nfmr_dlsmc.core.dlsmc import DlsmcController
    params = ControllerParams()
    s = TrackingSession(params, odom_timeout=0.1)
    ref = DlsmcController(params.dlsmc)
    traj = params.trajectory
    for k, t in enumerate((0.0, 0.002, 0.004)):
        s.on_odometry(1.0, 4.0, 0.0, t, t, t, 'odom')
        out = s.tick(t, t)
        x_d, y_d, xdot_d, ydot_d = (float(v) for v in traj.sample(t))
        xddot_d, yddot_d = (float(v) for v in traj.acceleration(t))
        v, omega = ref.step(1.0, 4.0, 0.0, x_d, y_d, xdot_d, ydot_d, None if k == 0 else 0.002,
                            xddot_d, yddot_d)
        assert (out.v, out.omega) == (v, omega)
    # A tick 0.5 s after the previous (> 100 periods) falls back to the nominal period.
    s.on_odometry(1.0, 4.0, 0.0, 0.504, 0.504, 0.504, 'odom')
    out = s.tick(0.504, 0.504)
    x_d, y_d, xdot_d, ydot_d = (float(v) for v in traj.sample(0.504))
    xddot_d, yddot_d = (float(v) for v in traj.acceleration(0.504))
    assert (out.v, out.omega) == ref.step(1.0, 4.0, 0.0, x_d, y_d, xdot_d, ydot_d, None,
                                          xddot_d, yddot_d)


# --- BagWriter: the fields rosbag2 reads from metadata.yaml and the MCAP records ------------

def test_bag_metadata_has_the_rosbag2_version_9_layout(tmp_path):
    from mcap.reader import make_reader
    from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
    directory = tmp_path / 'nested' / 'run'  # parents are created
    with BagWriter(directory) as writer:
        writer.add_topic('/a', 'std_msgs/msg/Float64MultiArray', [QosProfile(depth=7)])
        writer.add_topic('/b', 'std_msgs/msg/Float64MultiArray',
                         [{'history': 'keep_all', 'depth': 0}])
        for k, t in enumerate((3_000, 1_000, 2_000)):
            writer.write('/a', t, b'\x00\x01\x00\x00' + bytes(8),
                         publish_time_ns=None if k else 42)
        writer.write('/b', 5_000, b'\x00\x01\x00\x00' + bytes(8))
    info = yaml.safe_load((directory / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert list(info) == ['version', 'storage_identifier', 'duration', 'starting_time',
                          'message_count', 'topics_with_message_count', 'compression_format',
                          'compression_mode', 'relative_file_paths', 'files', 'custom_data',
                          'ros_distro']  # rosbag2's own order
    assert info['compression_format'] == '' and info['compression_mode'] == ''
    assert info['custom_data'] is None and info['ros_distro'] == 'jazzy'
    assert info['starting_time'] == {'nanoseconds_since_epoch': 1_000}
    assert info['duration'] == {'nanoseconds': 4_000} and info['message_count'] == 4
    assert info['files'] == [{'path': 'run_0.mcap',
                              'starting_time': {'nanoseconds_since_epoch': 1_000},
                              'duration': {'nanoseconds': 4_000}, 'message_count': 4}]
    qos_a = info['topics_with_message_count'][0]['topic_metadata']['offered_qos_profiles'][0]
    assert list(qos_a) == ['history', 'depth', 'reliability', 'durability', 'deadline',
                           'lifespan', 'liveliness', 'liveliness_lease_duration',
                           'avoid_ros_namespace_conventions']
    assert qos_a['depth'] == 7 and qos_a['deadline'] == {'sec': 9223372036, 'nsec': 854775807}
    qos_b = info['topics_with_message_count'][1]['topic_metadata']['offered_qos_profiles']
    assert qos_b == [{'history': 'keep_all', 'depth': 0}]
    with open(directory / 'run_0.mcap', 'rb') as f:
        reader = make_reader(f)
        assert reader.get_header().library == 'nfmr'
        records = [(c.topic, m.sequence, m.log_time, m.publish_time)
                   for _, c, m in reader.iter_messages(log_time_order=False)]
        # The mcap summary carries the rosbag2 record with the same, unsorted, metadata.
        rosbag2 = {r.name: r.metadata for r in reader.iter_metadata()}['rosbag2']
    assert records == [('/a', 0, 3_000, 42), ('/a', 1, 1_000, 1_000), ('/a', 2, 2_000, 2_000),
                       ('/b', 0, 5_000, 5_000)]
    assert rosbag2['ROS_DISTRO'] == 'jazzy'
    assert list(yaml.safe_load(rosbag2['serialized_metadata']))[:3] == [
        'version', 'storage_identifier', 'duration']


def test_a_bag_of_one_message_lasts_zero_nanoseconds(tmp_path):
    from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
    with BagWriter(tmp_path / 'one') as writer:
        writer.add_topic('/a', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
        writer.write('/a', 7_000, b'\x00\x01\x00\x00' + bytes(8))
    info = yaml.safe_load((tmp_path / 'one' / 'metadata.yaml').read_text())
    assert info['rosbag2_bagfile_information']['duration'] == {'nanoseconds': 0}
    assert not (tmp_path / 'one' / 'metadata.yaml.tmp').exists()
