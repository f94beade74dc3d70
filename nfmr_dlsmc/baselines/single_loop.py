"""
Single-loop trackers the paper compares against (Table 2): PID, CSMC and DSMC.

Each law maps the pose and the reference of one instant straight to (v, omega), with the
same interface and the same input saturation as the DLSMC. The errors are Kanayama's
robot-frame errors (e1 along, e2 lateral, e3 heading, :mod:`nfmr_dlsmc.baselines.path_frame`).
"""

import math

from nfmr_dlsmc.baselines.gains import CsmcGains, DsmcGains, PidGains
from nfmr_dlsmc.baselines.path_frame import (
    ReferenceRates,
    robot_frame_error_rates,
    robot_frame_errors,
)
from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.saturation import (
    saturate_speed,
    saturate_yaw_rate,
    SaturatedController,
)
from nfmr_dlsmc.core.sliding_functions import sign


class SingleLoopController(SaturatedController):
    """
    Shared frame of a single-loop law: reference rates, saturation and telemetry.

    A subclass implements ``_law(x, y, theta, x_d, y_d, dt) -> (v_raw, omega_raw)`` with
    ``self.ref`` (:class:`~nfmr_dlsmc.baselines.path_frame.ReferenceRates`) already updated, and
    may set ``theta_d`` (a desired heading, NaN when the law has none), ``s_x``, ``s_y``
    (its sliding variables, NaN when it has none) and ``_reset_law()``. ``v`` and
    ``omega`` hold the inputs applied at the previous step.
    """

    #: Names of the values :meth:`telemetry` returns, in order.
    TELEMETRY_FIELDS = ('x_e', 'y_e', 'theta_d', 'theta_e', 's_x', 's_y', 'v_raw',
                        'omega_raw', 'v_saturated', 'omega_saturated')
    name = 'single_loop'

    def __init__(self, gains, limits: InputLimits | None = None, dt: float = 0.001):
        super().__init__(limits, dt)
        self.gains = gains
        self.ref = ReferenceRates()
        self.reset()

    def reset(self) -> None:
        """Start over: the next step is t = 0 of a new run."""
        self.ref.reset()
        self.x_e = self.y_e = 0.0
        self.theta_d = self.theta_e = math.nan
        self.s_x = self.s_y = math.nan
        self.v = self.omega = 0.0
        self.v_raw = self.omega_raw = 0.0
        self.v_saturated = self.omega_saturated = False
        self._first = True
        self._reset_law()

    def _reset_law(self) -> None:
        """Reset the law's own state."""

    def _law(self, x, y, theta, x_d, y_d, dt):
        raise NotImplementedError

    def step(self, x: float, y: float, theta: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, dt: float | None = None, xddot_d: float = 0.0,
             yddot_d: float = 0.0) -> tuple[float, float]:
        """
        Run one control period: pose and reference -> saturated (v [m/s], omega [rad/s]).

        The pose of P is in [m, m, rad], the reference position in [m] and its velocity in
        [m/s]; ``dt`` [s] is the time since the previous step. The reference acceleration
        (``xddot_d``, ``yddot_d``) is accepted for the common interface; these laws use the
        backward-difference rates of ``self.ref``.
        """
        if dt is None:
            dt = self._dt
        self.ref.update(xdot_d, ydot_d, dt)
        v_raw, omega_raw = self._law(x, y, theta, x_d, y_d, dt)
        v = saturate_speed(v_raw, self.speed_floor(self.ref.v_r), self._limits)
        omega = saturate_yaw_rate(omega_raw, self._limits)
        self.v_saturated, self.omega_saturated = v != v_raw, omega != omega_raw
        self.x_e, self.y_e = x - x_d, y - y_d
        self.theta_e = (wrap_angle(theta - self.theta_d) if math.isfinite(self.theta_d)
                        else math.nan)
        self.v_raw, self.omega_raw = v_raw, omega_raw
        self.v, self.omega = v, omega
        self._first = False
        return v, omega

    def telemetry(self) -> tuple:
        """Return the internal signals of the last step, named by ``TELEMETRY_FIELDS``."""
        return (self.x_e, self.y_e, self.theta_d, self.theta_e, self.s_x, self.s_y,
                self.v_raw, self.omega_raw, self.v_saturated, self.omega_saturated)


class PidController(SingleLoopController):
    """
    Traditional PID on the yaw rate with a constant forward speed (paper §4.2, "PID").

    With Kanayama's lateral error e2 and heading error e3 (no feed-forward of the
    reference yaw rate, as a textbook PID):

        v = v_c,
        omega = kp e2 + ki int_0^t e2 dtau + kd e2' + k_theta e3,

    e2' a backward difference (0 at the first step), the integral a left Riemann sum.
    """

    name = 'pid'

    def _reset_law(self) -> None:
        self._integral = 0.0  # [m s]
        self._e2 = 0.0  # [m] previous lateral error

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: PidGains = self.gains
        _, e2, e3 = robot_frame_errors(x, y, theta, x_d, y_d, self.ref.theta_r)
        if self._first:
            e2_rate = 0.0
        else:
            self._integral += self._e2 * dt
            e2_rate = (e2 - self._e2) / dt
        self._e2 = e2
        self.s_y = e2
        return g.v_c, g.kp * e2 + g.ki * self._integral + g.kd * e2_rate + g.k_theta * e3


class CsmcController(SingleLoopController):
    """
    Coupled sliding-mode tracking of Yang & Kim (paper ref. [15], "CSMC").

    The coupled single-loop SMC with three surface gains (IEEE Trans. Robot. Autom. 15(3),
    1999).

    Surfaces on Kanayama's errors (the lateral one couples e2 and e3):

        s1 = e1' + k1 e1,   s2 = e2' + k2 e2 + k0 sign(e2) e3,

    and the exponential reaching law s' = -Q s - P sign(s) give (their eqs 27-28)

        v'    = Q1 s1 + P1 sign(s1) + k1 e1' + omega' e2 + omega e2' + v_r' cos e3
                - v_r e3' sin e3,
        omega = omega_r + (Q2 s2 + P2 sign(s2) + k2 e2' - omega' e1 - omega e1'
                + v_r' sin e3) / (v_r cos e3 + k0 sign(e2)).

    v is integrated (v starts at the reference speed); the error rates use the inputs
    applied at the previous step. The inputs are held over each control period, so
    omega' = 0 inside it and the omega' terms drop out (a backward difference of omega
    in their place closes an algebraic loop with gain |e1| / (dt |denominator|) >> 1 that
    diverges at once). The denominator passes through zero when
    v_r cos e3 = -k0 sign(e2): the raw omega is unbounded there.
    """

    name = 'csmc'

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: CsmcGains = self.gains
        ref = self.ref
        v_r, omega_r, vdot_r = ref.v_r, ref.omega_r, ref.vdot_r
        if self._first:
            self.v = v_r
        v, omega = self.v, self.omega
        e1, e2, e3 = robot_frame_errors(x, y, theta, x_d, y_d, ref.theta_r)
        e1_rate, e2_rate, e3_rate = robot_frame_error_rates(e1, e2, e3, v, omega, v_r, omega_r)
        sg2 = sign(e2)
        s1 = e1_rate + g.k1 * e1
        s2 = e2_rate + g.k2 * e2 + g.k0 * sg2 * e3
        c3, s3 = math.cos(e3), math.sin(e3)
        v_rate = (g.Q1 * s1 + g.P1 * sign(s1) + g.k1 * e1_rate + omega * e2_rate
                  + vdot_r * c3 - v_r * e3_rate * s3)
        numerator = (g.Q2 * s2 + g.P2 * sign(s2) + g.k2 * e2_rate - omega * e1_rate
                     + vdot_r * s3)
        denominator = v_r * c3 + g.k0 * sg2
        if denominator == 0.0:
            denominator = math.ulp(1.0)
        omega_raw = omega_r + numerator / denominator
        self.s_x, self.s_y = s1, s2
        return v + v_rate * dt, omega_raw


class DsmcController(SingleLoopController):
    """
    Decoupled sliding-mode tracking by pseudo-inverse (paper ref. [15], "DSMC").

    One surface per Kanayama error, s_i = e_i, each with its own exponential reaching law
    s_i' = -Q_i s_i - P_i sign(s_i). The error dynamics are e' = f + B u with

        f = (v_r cos e3, v_r sin e3, omega_r),   B = [[-1, e2], [0, -e1], [0, -1]],

    three equations for two inputs, so u = (v, omega) is their least-squares solution
    u = B^+ (s'_des - f), B^+ = (B^T B)^-1 B^T. With r = s'_des - f:

        omega = -(e1 r2 + r3) / (1 + e1^2),   v = -r1 - e2 (e1 r2 + r3) / (1 + e1^2).

    The lateral error has no input of its own (nonholonomy): it is reached only through
    e1 omega, so the compromise stalls when e1 is small.
    """

    name = 'dsmc'

    def _law(self, x, y, theta, x_d, y_d, dt):
        g: DsmcGains = self.gains
        ref = self.ref
        e1, e2, e3 = robot_frame_errors(x, y, theta, x_d, y_d, ref.theta_r)
        r1 = -g.Q1 * e1 - g.P1 * sign(e1) - ref.v_r * math.cos(e3)
        r2 = -g.Q2 * e2 - g.P2 * sign(e2) - ref.v_r * math.sin(e3)
        r3 = -g.Q3 * e3 - g.P3 * sign(e3) - ref.omega_r
        common = (e1 * r2 + r3) / (1.0 + e1 * e1)
        self.s_x, self.s_y = e1, e2
        return -r1 - e2 * common, -common
