"""
Wheel odometry of a four-wheel independently steered chassis: the pose of P from its encoders.

Each control of a real 4WIS robot knows its four steer angles and four drive speeds (the
encoders a ``joint_states`` message carries). The chassis twist is their least-squares fit
over the rigid-body constraints (:func:`~nfmr_dlsmc.core.steering.twist_from_wheels`, the
geometry of doc/design.md, D1-D3), its residual a measure of slip; the twist of the tracked
point P, integrated exactly over each interval (the SE(2) exponential), gives P's pose. The
fit holds for any steering mode (j1, j2), crab included, and for wheels that stand still or
roll backwards: it assumes only that each wheel rolls along its heading.
"""

import math
from typing import NamedTuple

from nfmr_dlsmc.core.steering import RobotGeometry, twist_from_wheels
import numpy as np

__all__ = ['advance_pose', 'WheelOdometry', 'WheelTwist']


class WheelTwist(NamedTuple):
    """The chassis motion the wheels measure, at P in the body frame."""

    vx: float  #: forward velocity of P [m/s]
    vy: float  #: leftward velocity of P [m/s]
    omega: float  #: yaw rate [rad/s]
    slip_rms: float  #: RMS of the wheels' velocities the rigid fit leaves unexplained [m/s]


def advance_pose(pose, vx: float, vy: float, omega: float, dt: float) -> tuple:
    """
    Return the pose (x, y, yaw) [m, m, rad] after moving with a constant body twist for dt.

    The SE(2) exponential: with body velocity (vx, vy) [m/s] and yaw rate omega [rad/s] over
    dt [s] the displacement in the body frame at the start is

        dx = (sin(w dt) vx - (1 - cos(w dt)) vy) / w,
        dy = ((1 - cos(w dt)) vx + sin(w dt) vy) / w,

    (vx dt, vy dt for w = 0), turned into the world by the start yaw; the yaw advances by
    omega dt (not wrapped). 1 - cos(w dt) is computed as 2 sin^2(w dt / 2), which keeps its
    precision for small turns.
    """
    x, y, yaw = pose
    turn = omega * dt
    if omega == 0.0:
        s, c = dt, 0.0
    else:
        s, c = math.sin(turn) / omega, 2.0 * math.sin(0.5 * turn) ** 2 / omega
    dx, dy = s * vx - c * vy, c * vx + s * vy
    cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
    return x + cos_yaw * dx - sin_yaw * dy, y + sin_yaw * dx + cos_yaw * dy, yaw + turn


class WheelOdometry:
    """
    The pose of P integrated from wheel encoder samples, with the last twist and its slip.

    Parameters
    ----------
    geometry : RobotGeometry
        Wheel positions and radius.
    p_offset : float
        Body-frame x of the tracked point P from the chassis centre [m]
        (``SteerMode.zero_slip_offset``; 0, the centre, in crab mode).
    pose : tuple of 3 floats
        Pose (x, y, yaw) of P at the first sample [m, m, rad].

    Each accepted sample's twist is fitted; the motion between two samples is the mean of
    their twists (the trapezoid rule in the body frame) over the time between their stamps.
    A sample that is not newer than the last accepted one, or whose arrays are not four
    finite numbers each, is refused: :meth:`update` returns why, the state is unchanged and
    :attr:`refused` counts it.

    Attributes
    ----------
    pose : tuple of 3 floats
        Pose of P at :attr:`stamp` [m, m, rad]; the yaw is not wrapped.
    stamp : float or None
        Time of the last accepted sample [s]; None before the first.
    twist : WheelTwist or None
        The twist of the last accepted sample.
    distance : float
        Path length P has travelled [m].
    refused : int
        Samples refused so far.

    """

    __slots__ = ('_geometry', '_offset', 'pose', 'stamp', 'twist', 'distance', 'refused')

    def __init__(self, geometry: RobotGeometry, p_offset: float = 0.0, pose=(0.0, 0.0, 0.0)):
        self._geometry = geometry
        self._offset = float(p_offset)
        self.reset(pose)

    def reset(self, pose=(0.0, 0.0, 0.0)) -> None:
        """Start over at ``pose``; the next sample is the first."""
        self.pose = tuple(float(v) for v in pose)
        self.stamp = None
        self.twist = None
        self.distance = 0.0
        self.refused = 0

    def update(self, stamp: float, steer, wheel_speed) -> str | None:
        """
        Take one encoder sample; return None when taken, else why it was refused.

        Parameters
        ----------
        stamp : float
            Time of the sample [s].
        steer : array-like (4,)
            Steer angles [rad], FL FR RL RR.
        wheel_speed : array-like (4,)
            Drive speeds [rad/s] (negative: rolling backwards along the heading).

        """
        steer = np.asarray(steer, dtype=float)
        wheel_speed = np.asarray(wheel_speed, dtype=float)
        reason = None
        if not math.isfinite(stamp):
            reason = f'stamp {stamp} is not finite'
        elif steer.shape != (4,) or wheel_speed.shape != (4,):
            reason = (f'{steer.size} steer angles and {wheel_speed.size} wheel speeds '
                      '(four of each needed)')
        elif not (np.all(np.isfinite(steer)) and np.all(np.isfinite(wheel_speed))):
            reason = 'a steer angle or wheel speed is not finite'
        elif self.stamp is not None and stamp <= self.stamp:
            reason = f'stamp {stamp:.9f} s is not after the last one, {self.stamp:.9f} s'
        if reason is not None:
            self.refused += 1
            return reason
        vx, vy, omega, slip = twist_from_wheels(steer, wheel_speed, self._geometry)
        twist = WheelTwist(vx, vy + omega * self._offset, omega, slip)
        if self.stamp is not None:
            dt = stamp - self.stamp
            before = self.twist
            mean = (0.5 * (before.vx + twist.vx), 0.5 * (before.vy + twist.vy),
                    0.5 * (before.omega + twist.omega))
            self.pose = advance_pose(self.pose, *mean, dt)
            self.distance += math.hypot(mean[0], mean[1]) * dt
        self.stamp, self.twist = float(stamp), twist
        return None
