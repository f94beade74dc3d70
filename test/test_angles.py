"""Angle helpers: wrapping and the yaw of an odometry quaternion."""

import math

from nfmr_dlsmc.core.angles import wrap_angle, wrap_angles, yaw_from_quaternion
import numpy as np
import pytest


@pytest.mark.parametrize('yaw', [0.0, 0.3, -2.0, math.pi - 1e-9, -math.pi + 1e-9, 3.0])
def test_yaw_of_a_rotation_about_z_round_trips(yaw):
    q = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    assert yaw_from_quaternion(*q) == pytest.approx(yaw, abs=1e-12)


def test_a_non_unit_quaternion_reads_as_its_normalised_self():
    q = np.array([0.1, -0.2, 0.3, 0.9])
    for scale in (1e-6, 0.5, 3.0, 1e6):
        assert yaw_from_quaternion(*(scale * q)) == pytest.approx(
            yaw_from_quaternion(*(q / np.linalg.norm(q))), abs=1e-12)


def test_the_yaw_of_a_tilted_pose_is_the_heading_of_its_x_axis():
    # Roll 0.2, pitch 0.1, yaw 1.0 (ZYX): the yaw is atan2 of the rotated x axis.
    r, p, y = 0.2, 0.1, 1.0
    cr, sr, cp, sp, cy, sy = (math.cos(r / 2), math.sin(r / 2), math.cos(p / 2),
                              math.sin(p / 2), math.cos(y / 2), math.sin(y / 2))
    q = (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
         cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)
    assert yaw_from_quaternion(*q) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize('q', [(0.0, 0.0, 0.0, 0.0), (1e-12, 0.0, 0.0, 0.0),
                               (0.0, 0.0, math.nan, 1.0), (0.0, 0.0, 0.0, math.inf),
                               (1e308, 1e308, 1e308, 1e308)])
def test_a_quaternion_that_is_no_rotation_gives_nan(q):
    assert math.isnan(yaw_from_quaternion(*q))


def test_wrap_angle_matches_the_array_version():
    angles = np.linspace(-20.0, 20.0, 1001)
    assert np.array_equal(wrap_angles(angles), [wrap_angle(a) for a in angles])
    assert wrap_angle(-math.pi) == math.pi
