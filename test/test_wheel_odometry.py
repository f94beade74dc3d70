"""Wheel odometry of four steered wheels: the rigid fit, its slip and the pose of P."""

import math

from nfmr_dlsmc.core.steering import (
    RobotGeometry,
    SteerMode,
    twist_from_wheels,
    wheel_commands,
    wheel_commands_for_twist,
)
from nfmr_dlsmc.core.wheel_odometry import advance_pose, WheelOdometry
import numpy as np
import pytest

GEOM = RobotGeometry()  # L = 0.89 m, track 0.53 m, wheel radius 0.14 m
MODES = [SteerMode(1.0, 0.0), SteerMode(0.0, 1.0), SteerMode(0.5, 0.5), SteerMode(-0.5, 1.5)]


def _arc(v: float, omega: float, t: float) -> tuple:
    """Pose of a point that starts at the origin facing +x and moves at (v, omega) for t."""
    if omega == 0.0:
        return v * t, 0.0, 0.0
    radius = v / omega
    return radius * math.sin(omega * t), radius * (1.0 - math.cos(omega * t)), omega * t


@pytest.mark.parametrize('mode', MODES)
@pytest.mark.parametrize('v, omega', [(1.0, 0.5), (0.4, -1.2), (-0.6, 0.3), (0.8, 0.0)])
def test_wheels_that_follow_the_mode_integrate_to_the_arc_of_p(mode, v, omega):
    # Encoder samples of wheels commanded (v, omega) at P, at 100 Hz for 3 s: P runs on its
    # circle (backwards for v < 0) and the rigid fit leaves no slip.
    cmd = wheel_commands(v, omega, GEOM, mode)
    odometry = WheelOdometry(GEOM, mode.zero_slip_offset(GEOM.wheelbase))
    for k in range(301):
        assert odometry.update(0.01 * k, cmd.steer, cmd.wheel_speed) is None
    x, y, yaw = _arc(v, omega, 3.0)
    assert odometry.pose == pytest.approx((x, y, yaw), abs=1e-9)
    assert odometry.twist.vx == pytest.approx(v, abs=1e-12)
    assert odometry.twist.vy == pytest.approx(0.0, abs=1e-12)
    assert odometry.twist.slip_rms == pytest.approx(0.0, abs=1e-12)
    assert odometry.distance == pytest.approx(abs(v) * 3.0, rel=1e-9)


def test_crab_and_spin_on_the_spot_are_measured_too():
    crab = wheel_commands_for_twist(0.3, -0.4, 0.0, GEOM)
    odometry = WheelOdometry(GEOM, 0.0, pose=(1.0, 2.0, 0.5))
    odometry.update(0.0, crab.steer, crab.wheel_speed)
    odometry.update(2.0, crab.steer, crab.wheel_speed)
    # (0.3, -0.4) m/s in the body frame turned by the yaw 0.5 rad, for 2 s.
    c, s = math.cos(0.5), math.sin(0.5)
    assert odometry.pose == pytest.approx((1.0 + 2.0 * (0.3 * c + 0.4 * s),
                                           2.0 + 2.0 * (0.3 * s - 0.4 * c), 0.5), abs=1e-12)
    spin = wheel_commands_for_twist(0.0, 0.0, 0.8, GEOM)
    odometry.reset()
    odometry.update(0.0, spin.steer, spin.wheel_speed)
    odometry.update(1.0, spin.steer, spin.wheel_speed)
    assert odometry.pose == pytest.approx((0.0, 0.0, 0.8), abs=1e-12)
    assert odometry.distance == pytest.approx(0.0, abs=1e-12)


def test_standing_wheels_keep_the_pose_whatever_their_angles():
    odometry = WheelOdometry(GEOM, 0.0, pose=(0.5, -0.5, 1.0))
    for k, steer in enumerate(([0.3, -1.2, 0.7, 1.5], [0.0] * 4, [-1.5, 1.5, 0.2, -0.2])):
        assert odometry.update(0.1 * k, steer, [0.0] * 4) is None
    assert odometry.pose == (0.5, -0.5, 1.0)
    assert odometry.twist.slip_rms == 0.0


def test_a_wheel_that_slips_shows_in_the_residual_not_only_in_the_pose():
    cmd = wheel_commands(1.0, 0.5, GEOM, SteerMode())
    skidding = cmd.wheel_speed.copy()
    skidding[0] *= 1.2  # the front-left wheel spins 20 % faster than the chassis moves
    vx, vy, omega, slip = twist_from_wheels(cmd.steer, skidding, GEOM)
    assert slip > 0.01
    # The fit spreads the error: one spinning wheel moves the twist by less than its own share.
    extra = 0.2 * abs(cmd.wheel_speed[0]) * GEOM.wheel_radius
    assert 0.0 < abs(vx - 1.0) < extra and abs(omega - 0.5) < extra / GEOM.track
    # The residual is what the rigid body cannot explain: eight equations, three unknowns.
    pos = GEOM.wheel_positions
    speed = skidding * GEOM.wheel_radius
    fitted = np.concatenate([vx - omega * pos[:, 1], vy + omega * pos[:, 0]])
    measured = np.concatenate([speed * np.cos(cmd.steer), speed * np.sin(cmd.steer)])
    assert slip == pytest.approx(np.sqrt(np.mean((fitted - measured) ** 2)), rel=1e-12)


def test_bad_samples_are_refused_with_why_and_change_nothing():
    cmd = wheel_commands(1.0, 0.2, GEOM, SteerMode())
    odometry = WheelOdometry(GEOM)
    assert odometry.update(1.0, cmd.steer, cmd.wheel_speed) is None
    before = (odometry.pose, odometry.stamp, odometry.twist)
    assert odometry.update(1.0, cmd.steer, cmd.wheel_speed) == (
        'stamp 1.000000000 s is not after the last one, 1.000000000 s')
    assert odometry.update(0.5, cmd.steer, cmd.wheel_speed).startswith('stamp 0.500000000 s')
    assert odometry.update(2.0, cmd.steer[:3], cmd.wheel_speed) == (
        '3 steer angles and 4 wheel speeds (four of each needed)')
    assert odometry.update(2.0, [math.nan, 0, 0, 0], cmd.wheel_speed) == (
        'a steer angle or wheel speed is not finite')
    assert odometry.update(2.0, cmd.steer, [0, 0, math.inf, 0]) == (
        'a steer angle or wheel speed is not finite')
    assert odometry.update(math.nan, cmd.steer, cmd.wheel_speed) == 'stamp nan is not finite'
    assert (odometry.pose, odometry.stamp, odometry.twist) == before
    assert odometry.refused == 6
    assert odometry.update(1.5, cmd.steer, cmd.wheel_speed) is None  # a good one: taken


@pytest.mark.parametrize('omega', [0.0, 1e-12, 1e-8, 0.7, -2.5])
def test_advancing_twice_is_advancing_once_for_the_sum(omega):
    # The exponential of a constant twist is a one-parameter group: exp((a + b) X) =
    # exp(a X) exp(b X), on both sides of the small-turn series.
    start = (0.3, -0.2, 2.0)
    once = advance_pose(start, 0.9, -0.3, omega, 0.75)
    twice = advance_pose(advance_pose(start, 0.9, -0.3, omega, 0.25), 0.9, -0.3, omega, 0.5)
    assert twice == pytest.approx(once, abs=1e-13)


def test_a_tiny_turn_is_integrated_to_full_precision():
    # 1 - cos(1e-9) is 0 in double precision; the half-angle form keeps the 5e-10 m of
    # sideways motion that a yaw rate of 1e-9 rad/s gives in 1 s at 1 m/s.
    pose = advance_pose((0.0, 0.0, 0.0), 1.0, 0.5, 1e-9, 1.0)
    assert pose[1] == pytest.approx(0.5 + 0.5e-9, abs=1e-15)  # vy dt + vx omega dt^2 / 2
    assert pose[0] == pytest.approx(1.0 - 0.5 * 0.5e-9, abs=1e-15)  # vx dt - vy omega dt^2 / 2
    assert advance_pose((0.0, 0.0, 0.0), 1.0, 0.5, 0.0, 1.0) == (1.0, 0.5, 0.0)
