"""
Tracking errors in the robot frame, and reference rates.

For the single-loop laws and the geometric trackers (the DLSMC works with global-frame
errors, eq. 8).
"""

import math

from nfmr_dlsmc.core.angles import wrap_angle


def robot_frame_errors(x: float, y: float, theta: float, x_d: float, y_d: float,
                       theta_r: float) -> tuple[float, float, float]:
    """
    Return Kanayama's tracking errors (Kanayama et al., ICRA 1990, eq. 4).

    e1 = cos(theta)(x_d - x) + sin(theta)(y_d - y)    reference ahead of P [m]
    e2 = -sin(theta)(x_d - x) + cos(theta)(y_d - y)   reference to the left of P [m]
    e3 = wrap(theta_r - theta)                        heading error [rad]

    Under the unicycle (3) with reference speed v_r and yaw rate omega_r they obey

    e1' = omega e2 - v + v_r cos(e3),  e2' = -omega e1 + v_r sin(e3),  e3' = omega_r - omega.
    """
    dx = x_d - x
    dy = y_d - y
    c = math.cos(theta)
    s = math.sin(theta)
    return c * dx + s * dy, -s * dx + c * dy, wrap_angle(theta_r - theta)


def robot_frame_error_rates(e1: float, e2: float, e3: float, v: float, omega: float,
                            v_r: float, omega_r: float) -> tuple[float, float, float]:
    """Return (e1', e2', e3') of :func:`robot_frame_errors` for inputs (v [m/s], omega [rad/s])."""
    return (omega * e2 - v + v_r * math.cos(e3), -omega * e1 + v_r * math.sin(e3),
            omega_r - omega)


class ReferenceRates:
    """
    Reference speed, heading and their rates from the sampled reference velocity.

    v_r = sqrt(xdot_d^2 + ydot_d^2) (eq. 6), theta_r = atan2(ydot_d, xdot_d) (eq. 7);
    omega_r and v_r' are backward differences over the step (0 at the first step), as
    theta_d' is in the DLSMC (doc/design.md, D5), so every law sees the same interface:
    the reference position and velocity at this instant.
    """

    __slots__ = ('_has_previous', 'v_r', 'theta_r', 'omega_r', 'vdot_r')

    def __init__(self):
        self.reset()

    def reset(self) -> None:
        """Forget the previous sample."""
        self._has_previous = False
        self.v_r = self.theta_r = self.omega_r = self.vdot_r = 0.0

    def update(self, xdot_d: float, ydot_d: float, dt: float) -> None:
        """Take this step's reference velocity [m/s]; ``dt`` [s] since the previous step."""
        v_r = math.hypot(xdot_d, ydot_d)
        theta_r = math.atan2(ydot_d, xdot_d)
        if self._has_previous:
            self.omega_r = wrap_angle(theta_r - self.theta_r) / dt
            self.vdot_r = (v_r - self.v_r) / dt
        else:
            self._has_previous = True
        self.v_r, self.theta_r = v_r, theta_r
