"""
Trackers a robotics engineer would otherwise reach for, on the unicycle (v, omega) interface.

Pure pursuit, Stanley and Kanayama's kinematic tracking law.
"""

import math

from nfmr_dlsmc.baselines.gains import KanayamaGains, PurePursuitGains, StanleyGains
from nfmr_dlsmc.baselines.path_frame import robot_frame_errors
from nfmr_dlsmc.baselines.single_loop import SingleLoopController
from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.saturation import saturate_speed


class PurePursuitController(SingleLoopController):
    """
    Pure pursuit (Coulter, CMU-RI-TR-92-01, 1992) on a time-parameterised reference.

    The goal point lies ``lookahead`` ahead of the reference point along theta_r,
    g = p_d + L_a (cos theta_r, sin theta_r). With alpha the bearing of g in the robot
    frame and l_d the distance to it, the arc through g has curvature 2 sin(alpha) / l_d:

        v = v_r + k_v e1,   omega = 2 sat(v) sin(alpha) / l_d,

    e1 the along-track (Kanayama) error, so the robot keeps up with the moving reference;
    sat(v) is v clipped to the speed limits (the speed actually driven).
    theta_d is the bearing of the goal point in the world frame.
    """

    name = 'pure_pursuit'

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: PurePursuitGains = self.gains
        ref = self.ref
        dx = x_d + g.lookahead * math.cos(ref.theta_r) - x
        dy = y_d + g.lookahead * math.sin(ref.theta_r) - y
        bearing = math.atan2(dy, dx)
        alpha = wrap_angle(bearing - theta)
        distance = max(math.hypot(dx, dy), 1e-9)
        e1, _, _ = robot_frame_errors(x, y, theta, x_d, y_d, ref.theta_r)
        v = ref.v_r + g.k_v * e1
        driven = saturate_speed(v, self.speed_floor(ref.v_r), self._limits)
        self.theta_d = bearing
        return v, 2.0 * driven * math.sin(alpha) / distance


class StanleyController(SingleLoopController):
    """
    Stanley steering (Thrun et al., J. Field Robot. 23(9), 2006, eq. 1) on the unicycle.

    With d the signed offset of P to the left of the reference tangent line,
    d = -sin(theta_r)(x - x_d) + cos(theta_r)(y - y_d), the Stanley steering angle is

        delta = wrap(theta_r - theta) + atan(-k d / (k_soft + v)),

    v the speed applied at the previous step. On the unicycle the desired heading is
    theta_d = theta + delta and the yaw rate follows it with a first-order law:

        omega = omega_r + k_heading delta,   v = v_r + k_v e_t,

    e_t = cos(theta_r)(x_d - x) + sin(theta_r)(y_d - y) the along-track error.
    """

    name = 'stanley'

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: StanleyGains = self.gains
        ref = self.ref
        c, s = math.cos(ref.theta_r), math.sin(ref.theta_r)
        dx, dy = x - x_d, y - y_d
        offset = -s * dx + c * dy
        along = -(c * dx + s * dy)
        delta = wrap_angle(ref.theta_r - theta) + math.atan(-g.k * offset / (g.k_soft + self.v))
        self.theta_d = theta + delta
        self.s_y = offset
        return ref.v_r + g.k_v * along, ref.omega_r + g.k_heading * delta


class KanayamaController(SingleLoopController):
    """
    Kanayama's stable tracking law (Kanayama et al., ICRA 1990, eq. 6).

        v = v_r cos e3 + k_x e1,   omega = omega_r + v_r (k_y e2 + k_theta sin e3),

    with the robot-frame errors (e1, e2, e3) of
    :func:`~nfmr_dlsmc.baselines.path_frame.robot_frame_errors`.
    """

    name = 'kanayama'

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: KanayamaGains = self.gains
        ref = self.ref
        e1, e2, e3 = robot_frame_errors(x, y, theta, x_d, y_d, ref.theta_r)
        self.s_x, self.s_y = e1, e2
        return (ref.v_r * math.cos(e3) + g.k_x * e1,
                ref.omega_r + ref.v_r * (g.k_y * e2 + g.k_theta * math.sin(e3)))
