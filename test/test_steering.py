"""Four-wheel steering geometry: mapping, inverse, ICR property, modes and limits."""

import math

from nfmr_dlsmc.core.steering import (
    centre_twist,
    front_steer_from_yaw_rate,
    geometry_mismatch,
    RobotGeometry,
    steer_angle_series,
    SteerMode,
    unicycle_from_wheels,
    wheel_commands,
    wheel_commands_for_twist,
    yaw_rate_from_front_steer,
)
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

GEOM = RobotGeometry()  # L = 0.89 m, track 0.53 m
A, B = 0.5 * 0.89, 0.5 * 0.53  # half wheelbase, half track [m]
DOUBLE, FRONT = SteerMode(1.0, 0.0), SteerMode(0.0, 1.0)
CASES = [(1.0, 0.5), (0.2, 1.59), (2.0, -1.59), (0.5, 0.0), (1.3, -0.2), (0.2, -0.05)]


@pytest.mark.parametrize('mode', [DOUBLE, FRONT, SteerMode(0.5, 0.5), SteerMode(-0.5, 1.5)])
@pytest.mark.parametrize('v, omega', CASES)
def test_round_trip_unicycle_to_wheels_and_back(mode, v, omega):
    cmd = wheel_commands(v, omega, GEOM, mode)
    v_back, omega_back, lateral = unicycle_from_wheels(cmd.steer, cmd.wheel_speed, GEOM, mode)
    assert v_back == pytest.approx(v, abs=1e-12)
    assert omega_back == pytest.approx(omega, abs=1e-12)
    assert lateral == pytest.approx(0.0, abs=1e-12)
    assert not cmd.limited


@pytest.mark.parametrize('mode', [DOUBLE, FRONT])
@pytest.mark.parametrize('v, omega', [c for c in CASES if c[1] != 0.0])
def test_wheel_headings_are_perpendicular_to_their_icr_radius(mode, v, omega):
    cmd = wheel_commands(v, omega, GEOM, mode)
    icr = np.array([mode.zero_slip_offset(GEOM.wheelbase), v / omega])
    for (px, py), steer, speed in zip(GEOM.wheel_positions, cmd.steer, cmd.wheel_speed):
        radius = np.array([px, py]) - icr
        heading = np.array([math.cos(steer), math.sin(steer)])
        assert np.dot(heading, radius) == pytest.approx(0.0, abs=1e-12)
        # Drive speed is |omega| times that radius (signed by the direction of travel).
        assert abs(speed) * GEOM.wheel_radius == pytest.approx(abs(omega) * np.linalg.norm(radius))


def test_double_ackermann_rear_mirrors_front_and_front_only_keeps_rear_straight():
    cmd = wheel_commands(1.0, 0.5, GEOM, DOUBLE)
    np.testing.assert_allclose(cmd.steer[2:], -cmd.steer[:2], atol=1e-12)
    assert cmd.steer[0] > cmd.steer[1] > 0.0  # the inner (left) wheel turns more
    cmd = wheel_commands(1.0, 0.5, GEOM, FRONT)
    np.testing.assert_allclose(cmd.steer[2:], [0.0, 0.0], atol=1e-12)
    # Front-only turns about the rear axle: P (x_c) is the rear axle centre.
    assert FRONT.zero_slip_offset(GEOM.wheelbase) == pytest.approx(-GEOM.wheelbase / 2)
    assert DOUBLE.zero_slip_offset(GEOM.wheelbase) == 0.0


def test_crab_mode_gives_equal_angles_and_no_yaw():
    crab = SteerMode(-1.0, 2.0)
    cmd = wheel_commands(0.8, 0.0, GEOM, crab, crab_angle=0.4)
    np.testing.assert_allclose(cmd.steer, [0.4] * 4)
    np.testing.assert_allclose(cmd.wheel_speed, [0.8 / GEOM.wheel_radius] * 4)
    with pytest.raises(ValueError, match='crab mode'):
        wheel_commands(0.8, 0.1, GEOM, crab)


def test_sideways_beyond_ninety_degrees_reverses_the_wheel():
    cmd = wheel_commands_for_twist(-0.5, 0.1, 0.0, GEOM)
    assert np.all(np.abs(cmd.steer) <= math.pi / 2)
    assert np.all(cmd.wheel_speed < 0.0)


def test_steer_limit_is_honoured_and_reported():
    tight = RobotGeometry(steer_limit=0.3)
    cmd = wheel_commands(0.2, 1.59, tight, DOUBLE)
    assert cmd.limited
    assert np.all(np.abs(cmd.steer) <= 0.3 + 1e-12)
    assert not wheel_commands(1.0, 0.05, tight, DOUBLE).limited


def test_stationary_wheels_hold_their_angle():
    held = [0.1, -0.2, 0.3, -0.4]
    cmd = wheel_commands_for_twist(0.0, 0.0, 0.0, GEOM, hold_steer=held)
    np.testing.assert_allclose(cmd.steer, held)
    np.testing.assert_allclose(cmd.wheel_speed, 0.0)


@pytest.mark.parametrize('mode', [DOUBLE, FRONT, SteerMode(-0.5, 1.5)])
@pytest.mark.parametrize('geometry', [GEOM, RobotGeometry(steer_limit=0.3)])
def test_a_tick_maps_as_the_series_of_the_logs_bit_for_bit(mode, geometry):
    # A run's steer angles come from wheel_commands at each tick, the kinematic model's and
    # the logs' from steer_angle_series: the same numbers, not merely close ones.
    rng = np.random.default_rng(0)
    v, omega = rng.uniform(-2.0, 2.0, (2, 400))
    series = steer_angle_series(v, omega, geometry, mode)
    ticks = [wheel_commands(a, b, geometry, mode).steer
             for a, b in zip(v.tolist(), omega.tolist())]
    assert np.array_equal(series, ticks)


@pytest.mark.parametrize('mode', [DOUBLE, FRONT, SteerMode(0.3, 0.7)])
def test_eq2_agrees_with_rigid_body_geometry(mode):
    v, omega = 0.9, 0.7
    delta_f = front_steer_from_yaw_rate(v, omega, mode, GEOM.wheelbase)
    assert yaw_rate_from_front_steer(v, delta_f, mode, GEOM.wheelbase) == pytest.approx(omega)
    vx, vy, w = centre_twist(v, omega, mode, GEOM.wheelbase)
    # The virtual front wheel on the centre line points along its velocity.
    assert delta_f == pytest.approx(math.atan2(vy + w * GEOM.wheelbase / 2, vx))


@pytest.mark.parametrize('kwargs, name', [
    ({'j1': 1.5, 'j2': -0.5}, 'steering.j1'), ({'j1': 1.0, 'j2': 1.0}, 'steering.j2'),
    ({'j1': math.nan, 'j2': 0.0}, 'steering.j1')])
def test_invalid_steer_modes(kwargs, name):
    with pytest.raises(ParameterError) as info:
        SteerMode(**kwargs)
    assert info.value.parameter == name


@pytest.mark.parametrize('kwargs, name', [
    ({'wheelbase': 0.0}, 'geometry.wheelbase'), ({'track': -1.0}, 'geometry.track'),
    ({'wheel_radius': math.inf}, 'geometry.wheel_radius'),
    ({'steer_limit': 3.2}, 'geometry.steer_limit'),
    ({'steer_limit': 0.0}, 'geometry.steer_limit')])
def test_invalid_geometry(kwargs, name):
    with pytest.raises(ParameterError) as info:
        RobotGeometry(**kwargs)
    assert info.value.parameter == name


@pytest.mark.parametrize('j1', [-0.9999999, -0.95, -0.900001])
def test_a_mode_next_to_crab_is_refused_for_the_point_it_would_track(j1):
    # P lies (L/2)(1 - j1)/(1 + j1) behind the centre: 8900 km for the robot at -0.9999999.
    with pytest.raises(ParameterError, match=r'steering.j1 = -0.9[0-9]*: must be -1 \(crab\) '
                                             r'or >= -0.9: .* wheelbases behind'):
        SteerMode(j1, 1.0 - j1)
    near = SteerMode(-0.9, 1.9)
    assert near.zero_slip_offset(GEOM.wheelbase) == pytest.approx(-9.5 * GEOM.wheelbase)


def test_a_chassis_of_other_dimensions_is_named_by_the_first_that_differs():
    # The launcher's check before a run and the in-process plant's are this one.
    assert geometry_mismatch(GEOM, RobotGeometry()) is None
    assert geometry_mismatch(GEOM, RobotGeometry(steer_limit=1.0)) is None
    assert geometry_mismatch(GEOM, RobotGeometry(wheelbase=0.89 + 1e-10)) is None
    assert geometry_mismatch(GEOM, RobotGeometry(track=0.6, wheel_radius=0.2)) == 'track'
    assert geometry_mismatch(GEOM, RobotGeometry(wheel_radius=0.14 + 2e-9)) == 'wheel_radius'


# --- steer_angle_series: the vectorised steer angles of the logs and reports ---------------

def test_double_ackermann_series_points_every_wheel_at_the_turn_centre():
    # j1 = 1: P is the chassis centre; v = 1 m/s, omega = 0.5 rad/s turn about (0, R = 2 m).
    # A wheel at (x_i, y_i) is perpendicular to its radius: delta_i = atan(x_i / (R - y_i)).
    R = 2.0
    steer = steer_angle_series([1.0], [0.5], GEOM, SteerMode(1.0, 0.0))
    expected = [math.atan(A / (R - B)), math.atan(A / (R + B)),
                -math.atan(A / (R - B)), -math.atan(A / (R + B))]
    assert steer.shape == (1, 4)
    np.testing.assert_allclose(steer[0], expected, rtol=1e-12)


def test_front_only_series_is_plain_ackermann_about_the_rear_axle():
    # j1 = 0: P is on the rear axle, the turn centre is (-L/2, R); rear wheels stay straight.
    R = 2.0
    steer = steer_angle_series([1.0, 1.0], [-0.5, 0.5], GEOM, SteerMode(0.0, 1.0))
    left_turn = [math.atan(0.89 / (R - B)), math.atan(0.89 / (R + B)), 0.0, 0.0]
    np.testing.assert_allclose(steer[1], left_turn, rtol=1e-12, atol=1e-15)
    # The right turn mirrors it: the right wheels are now the inner ones.
    np.testing.assert_allclose(steer[0], [-left_turn[1], -left_turn[0], 0.0, 0.0],
                               rtol=1e-12, atol=1e-15)


def test_series_folds_reversing_wheels_into_the_half_plane():
    # Driving backwards the wheels keep pointing forward (angle 0, not +-pi); reversing
    # through a turn each wheel is at its forward-turn angle mirrored.
    R = 2.0
    steer = steer_angle_series([-1.0, -1.0], [0.0, -0.5], GEOM, SteerMode(1.0, 0.0))
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
    steer = steer_angle_series(v, omega, GEOM, SteerMode(1.0, 0.0))
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
    steer = steer_angle_series([0.0], [1.0], GEOM, SteerMode(1.0, 0.0))
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
        steer_angle_series([1.0], [0.0], GEOM, SteerMode(-1.0, 2.0))
