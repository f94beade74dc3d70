"""The chassis outline and wheel rectangles in the world frame (nfmr_dlsmc.core.footprint)."""

import math

from nfmr_dlsmc.core.footprint import chassis_corners, Footprint, wheel_centres, wheel_corners
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

FOOTPRINT = Footprint()
GEOMETRY = RobotGeometry()


def _rotate(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def test_defaults_are_table_1():
    assert (FOOTPRINT.length_m, FOOTPRINT.width_m, FOOTPRINT.wheel_diameter_m) == (
        0.89, 0.53, 0.28)


@pytest.mark.parametrize('field', ['length_m', 'width_m', 'wheel_diameter_m',
                                   'wheel_width_m'])
@pytest.mark.parametrize('value', [0.0, -0.1, float('nan')])
def test_dimensions_are_validated(field, value):
    with pytest.raises(ParameterError, match=f'footprint.{field}'):
        Footprint(**{field: value})


def test_chassis_at_theta_zero_is_the_table_1_rectangle_around_p():
    corners = chassis_corners(FOOTPRINT, 2.0, -1.0, 0.0)
    assert corners.shape == (4, 2)
    expected = np.array([[2.445, -0.735], [1.555, -0.735], [1.555, -1.265],
                         [2.445, -1.265]])
    np.testing.assert_allclose(corners, expected, atol=1e-12)
    np.testing.assert_allclose(np.ptp(corners, axis=0), [0.89, 0.53], atol=1e-12)


def test_chassis_corners_run_counter_clockwise():
    c = chassis_corners(FOOTPRINT, 0.0, 0.0, 0.7)
    area = 0.5 * np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])
    assert area == pytest.approx(0.89 * 0.53)


def test_p_offset_shifts_the_chassis_forward_of_p():
    # P on the rear axle (front-only steering): the chassis lies ahead of P.
    corners = chassis_corners(FOOTPRINT, 0.0, 0.0, 0.0, p_offset_m=-0.445)
    np.testing.assert_allclose(corners[:, 0].min(), 0.0, atol=1e-12)
    np.testing.assert_allclose(corners[:, 0].max(), 0.89, atol=1e-12)
    centres = wheel_centres(GEOMETRY, 0.0, 0.0, 0.0, p_offset_m=-0.445)
    np.testing.assert_allclose(centres[2:, 0], 0.0, atol=1e-12)


def test_rotation_by_theta_rotates_about_p():
    x, y, theta = 1.5, -2.0, 1.1
    p = np.array([x, y])
    base = chassis_corners(FOOTPRINT, x, y, 0.0) - p
    turned = chassis_corners(FOOTPRINT, x, y, theta) - p
    np.testing.assert_allclose(turned, _rotate(base, theta), atol=1e-12)
    steer = np.array([0.3, -0.2, 0.1, 0.4])
    wheels0 = wheel_corners(FOOTPRINT, GEOMETRY, x, y, 0.0, steer) - p
    wheels = wheel_corners(FOOTPRINT, GEOMETRY, x, y, theta, steer) - p
    np.testing.assert_allclose(wheels, _rotate(wheels0.reshape(-1, 2), theta).reshape(
        wheels.shape), atol=1e-12)


def test_wheel_centres_are_the_geometry_wheel_positions():
    centres = wheel_centres(GEOMETRY, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(centres, GEOMETRY.wheel_positions)
    wheels = wheel_corners(FOOTPRINT, GEOMETRY, 0.0, 0.0, 0.0, np.zeros(4))
    np.testing.assert_allclose(wheels.mean(axis=1), GEOMETRY.wheel_positions, atol=1e-12)


@pytest.mark.parametrize('wheel', range(4))
def test_a_wheels_long_axis_follows_its_steer_angle(wheel):
    theta = 0.4
    steer = np.array([0.5, -0.3, -0.5, 0.3])
    corners = wheel_corners(FOOTPRINT, GEOMETRY, 0.0, 0.0, theta, steer)[wheel]
    long_side = corners[0] - corners[1]  # front-left minus rear-left of the wheel
    short_side = corners[0] - corners[3]  # front-left minus front-right
    assert np.hypot(*long_side) == pytest.approx(0.28)
    assert np.hypot(*short_side) == pytest.approx(0.10)
    assert math.atan2(long_side[1], long_side[0]) == pytest.approx(theta + steer[wheel])


def test_vectorised_equals_per_sample():
    rng = np.random.default_rng(3)
    n = 7
    x, y, theta = rng.normal(size=n), rng.normal(size=n), rng.uniform(-3, 3, size=n)
    steer = rng.uniform(-1.5, 1.5, size=(n, 4))
    chassis = chassis_corners(FOOTPRINT, x, y, theta, p_offset_m=0.1)
    centres = wheel_centres(GEOMETRY, x, y, theta, p_offset_m=0.1)
    wheels = wheel_corners(FOOTPRINT, GEOMETRY, x, y, theta, steer, p_offset_m=0.1)
    assert chassis.shape == (n, 4, 2)
    assert centres.shape == (n, 4, 2)
    assert wheels.shape == (n, 4, 4, 2)
    for k in range(n):
        np.testing.assert_allclose(
            chassis[k], chassis_corners(FOOTPRINT, x[k], y[k], theta[k], p_offset_m=0.1))
        np.testing.assert_allclose(
            centres[k], wheel_centres(GEOMETRY, x[k], y[k], theta[k], p_offset_m=0.1))
        np.testing.assert_allclose(wheels[k], wheel_corners(
            FOOTPRINT, GEOMETRY, x[k], y[k], theta[k], steer[k], p_offset_m=0.1))


def test_steer_must_match_the_poses():
    with pytest.raises(ValueError, match=r'steer has shape \(4,\); the poses need \(3, 4\)'):
        wheel_corners(FOOTPRINT, GEOMETRY, np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(4))
