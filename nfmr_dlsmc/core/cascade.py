"""The double-loop cascade of Fig. 2 with any position loop and any attitude loop."""

import math

from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.saturation import saturate_speed, saturate_yaw_rate, SaturatedController

__all__ = ['CascadeController', 'smoothed_yaw_rate']


def smoothed_yaw_rate(previous: float, omega: float, s: float, tau: float, band: float,
                      dt: float) -> float:
    """
    Return the commanded yaw rate after the fading low-pass of ``omega_filter`` [rad/s].

    A first-order low-pass of the saturated omega whose time constant fades out with the
    heading error (robot option, doc/design.md, D14):

        tau' = tau (1 - |s| / band),
        omega_k = omega_{k-1} + dt / (tau' + dt) (omega - omega_{k-1})   if tau' > 0,
        omega_k = omega                                                    otherwise.

    Parameters
    ----------
    previous : float
        omega_{k-1}, the yaw rate commanded at the last step [rad/s].
    omega : float
        The saturated yaw rate of this step [rad/s].
    s : float
        The attitude sliding variable, the heading error [rad].
    tau : float
        ``omega_filter`` [s], > 0.
    band : float
        ``omega_filter_band`` [rad]: the |s| at which the filter has faded out.
    dt : float
        The time since the last step [s].

    """
    tau = tau * (1.0 - abs(s) / band)
    if tau > 0.0:
        return previous + dt / (tau + dt) * (omega - previous)
    return omega


class CascadeController(SaturatedController):
    """
    Position loop -> (v, theta_d) -> attitude loop -> omega, for one robot.

    Each step:

    1. errors in the global frame, x_e = x - x_d, y_e = y - y_d (eq. 8);
    2. position loop ``outer.step(x_e, y_e, xdot_d, ydot_d, dt) -> (u_x, u_y)``;
       v = sqrt(u_x^2 + u_y^2) and theta_d = atan2(u_y, u_x) (eq. 40);
    3. thetadot_d as the backward difference of the wrapped theta_d over the step
       (doc/design.md, D5; 0 at the first step), optionally low-pass filtered with time
       constant ``filter_tau`` (0: the raw difference); or, with ``analytic_rate``, the
       derivative of eq. (40)

           thetadot_d = (u_x u_y' - u_y u_x') / (u_x^2 + u_y^2),

       where (u_x', u_y') = ``outer.input_rate(x_e', y_e', x_d'', y_d'')`` along the
       kinematic model's error rate x_e' = v cos(theta) - x_d', y_e' = v sin(theta) - y_d'
       with this step's saturated v;
    4. s_theta = theta_e = wrap(theta - theta_d) (eqs 8, 10);
       attitude loop ``inner.step(s_theta, thetadot_d, dt) -> omega``;
    5. saturation v in [v_min, v_max], |omega| <= omega_max
       (:mod:`~nfmr_dlsmc.core.saturation`; v_min lowered to a slower reference's speed
       with ``follow_slow_reference``); with ``align_speed`` the speed saturated is
       v = sqrt(u_x^2 + u_y^2) max(cos(s_theta), 0) instead (robot option,
       doc/design.md, D24): the robot slows down, and so turns on a tighter circle, while
       its heading is far from theta_d. With ``follow_slow_reference`` too (a path,
       doc/design.md, D27) the robot turns first: the lower bound is scaled by
       max(cos(s_theta), 0) as well (facing away, v = 0: it turns on the spot), its speed
       across theta_d, v abs(sin(s_theta)), is at most ``limits.v_min`` (v <= v_min /
       abs(sin(s_theta))), and the outer loop's sliding variables move by the same share
       of the next step only (``outer.advance``, which the outer loop must have), so that
       they do not wind up while the robot turns;
    6. optionally (``omega_tau`` > 0) a first-order low-pass of omega from the second step
       on, time constant ``omega_tau`` (1 - abs(s_theta) / ``omega_band``) [s] (none from
       abs(s_theta) >= ``omega_band`` [rad] on; :func:`smoothed_yaw_rate`).

    The outer loop exposes ``s_x`` and ``s_y`` (its sliding variables) after a step.

    Attributes (after a step)
    -------------------------
    x_e, y_e : float
        Position errors [m].
    theta_d, thetadot_d : float
        Desired heading [rad] and its rate [rad/s].
    s_theta : float
        Attitude sliding variable = theta_e [rad].
    v_raw, omega_raw : float
        Inputs before saturation [m/s], [rad/s]; v_raw = sqrt(u_x^2 + u_y^2), before
        ``align_speed`` too.
    v_saturated, omega_saturated : bool
        Saturation flags: the limits changed the input.
    """

    #: Names of the values :meth:`telemetry` returns, in order.
    TELEMETRY_FIELDS = ('x_e', 'y_e', 'theta_d', 'thetadot_d', 'theta_e', 's_x', 's_y',
                        'v_raw', 'omega_raw', 'v_saturated', 'omega_saturated')

    __slots__ = ('name', '_filter_tau', '_omega_tau', '_omega_band', '_analytic', '_align',
                 'outer', 'inner', '_has_previous', 'x_e', 'y_e', 'theta_d', 'thetadot_d',
                 's_theta', 'v_raw', 'omega_raw', 'v_saturated', 'omega_saturated', '_omega')

    def __init__(self, outer, inner, limits: InputLimits | None = None, dt: float = 0.001,
                 filter_tau: float = 0.0, name: str = 'cascade', analytic_rate: bool = False,
                 omega_tau: float = 0.0, omega_band: float = 0.005,
                 align_speed: bool = False):
        super().__init__(limits, dt)
        self.name = name
        self._analytic = analytic_rate
        self.outer = outer
        self.inner = inner
        self._filter_tau = filter_tau  # [s]
        self._omega_tau = omega_tau  # [s] low-pass of the commanded omega (0: none)
        self._omega_band = omega_band  # [rad] abs(s_theta) at which it has faded out
        self._align = align_speed  # v scaled by max(cos(s_theta), 0)
        self.reset()

    def reset(self) -> None:
        """Start over: the next step is t = 0 of a new run."""
        self.outer.reset()
        self.inner.reset()
        self._has_previous = False
        self.x_e = self.y_e = 0.0
        self.theta_d = self.thetadot_d = self.s_theta = 0.0
        self.v_raw = self.omega_raw = 0.0
        self.v_saturated = self.omega_saturated = False
        self._omega = None  # [rad/s] the last commanded omega (None before the first step)

    def step(self, x: float, y: float, theta: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, dt: float | None = None, xddot_d: float = 0.0,
             yddot_d: float = 0.0) -> tuple[float, float]:
        """
        Run one control period.

        Parameters
        ----------
        x, y, theta : float
            Measured pose of point P [m, m, rad].
        x_d, y_d, xdot_d, ydot_d : float
            Reference position [m] and velocity [m/s] at this instant.
        dt : float, optional
            Time since the previous step [s]; default the configured period. A loop with
            jitter passes the measured interval so integrals and thetadot_d stay right.
        xddot_d, yddot_d : float
            Reference acceleration [m/s^2], used by the analytic thetadot_d only.

        Returns
        -------
        v, omega : float
            Saturated inputs [m/s], [rad/s].

        """
        x_e = x - x_d
        y_e = y - y_d
        if dt is None:
            dt = self._dt
        u_x, u_y = self.outer.step(x_e, y_e, xdot_d, ydot_d, dt)
        theta_d = math.atan2(u_y, u_x)
        v_raw = math.hypot(u_x, u_y)
        limits = self._limits
        # The reference's speed only where a slow one lowers the floor (not in the paper).
        v_floor = (self.speed_floor(math.hypot(xdot_d, ydot_d)) if self.follow_slow_reference
                   else limits.v_min)
        s_theta = wrap_angle(theta - theta_d)
        if self._align:
            share = max(math.cos(s_theta), 0.0)
            v_want = v_raw * share
            if self.follow_slow_reference:  # on a path: turn first (step 5, D27)
                v_floor *= share
                across = abs(math.sin(s_theta))  # v across theta_d at most limits.v_min
                if v_want * across > limits.v_min:
                    v_want = limits.v_min / across
                self.outer.advance = share
        else:
            v_want = v_raw
        v = saturate_speed(v_want, v_floor, limits)
        if self._analytic:
            udot_x, udot_y = self.outer.input_rate(v * math.cos(theta) - xdot_d,
                                                   v * math.sin(theta) - ydot_d,
                                                   xddot_d, yddot_d)
            # |u|^2 underflows to 0 below 1e-162 m/s: no direction there, as at 0.
            speed_squared = v_raw * v_raw
            thetadot_d = ((u_x * udot_y - u_y * udot_x) / speed_squared if speed_squared > 0.0
                          else 0.0)
        elif self._has_previous:
            raw = wrap_angle(theta_d - self.theta_d) / dt
            # First-order low-pass; with no filter (tau = 0) the gain is 1.
            thetadot_d = self.thetadot_d + dt / (self._filter_tau + dt) * (raw - self.thetadot_d)
        else:
            thetadot_d = 0.0
        self._has_previous = True
        omega_raw = self.inner.step(s_theta, thetadot_d, dt)
        omega = saturate_yaw_rate(omega_raw, limits)
        self.v_saturated = v != v_want
        self.omega_saturated = omega != omega_raw
        if self._omega_tau > 0.0 and self._omega is not None:  # the first step: as is
            omega = smoothed_yaw_rate(self._omega, omega, s_theta, self._omega_tau,
                                      self._omega_band, dt)
        self._omega = omega
        self.x_e, self.y_e = x_e, y_e
        self.theta_d, self.thetadot_d, self.s_theta = theta_d, thetadot_d, s_theta
        self.v_raw, self.omega_raw = v_raw, omega_raw
        return v, omega

    def telemetry(self) -> tuple:
        """Return the internal signals of the last step, named by ``TELEMETRY_FIELDS``."""
        return (self.x_e, self.y_e, self.theta_d, self.thetadot_d, self.s_theta,
                self.outer.s_x, self.outer.s_y, self.v_raw, self.omega_raw,
                self.v_saturated, self.omega_saturated)
