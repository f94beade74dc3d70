"""Outer position loop: bounded time-varying integral nonsingular terminal SMC (BTINTSMC)."""

import math

from nfmr_dlsmc.core.gains import adapted_rates, OuterLoopGains
from nfmr_dlsmc.core.sliding_functions import bounded_rate, bounded_rate_slope, reaching_term_slope

__all__ = ['BtintsmcOuterLoop']


class BtintsmcOuterLoop:
    """
    BTINTSMC law of eqs (32)-(35), one instance per robot.

    Per axis e in {x_e, y_e} the sliding variable is (eq. 32)

        s = e - e(0) + C int_0^t alpha(e) dtau,

    so s(0) = 0 (Remark 4), and the virtual velocity inputs are (eqs 34, 35)

        u_x = v_d cos(theta_r) - k2 |s_x|^(q3/p3) erf(h s_x) - C1 alpha(x_e),
        u_y = v_d sin(theta_r) - k2 |s_y|^(q3/p3) erf(h s_y) - C2 alpha(y_e),

    with v_d cos(theta_r) = xdot_d and v_d sin(theta_r) = ydot_d (eqs 6, 7). The integral
    is a left Riemann sum: alpha of step k, times the time to step k+1, enters at step k+1.

    With ``gains.adaptive_ratio`` the rates C1, C2 are re-proportioned to e(0) at the
    first step (:func:`~nfmr_dlsmc.core.gains.adapted_rates`). With ``gains.linear_zone`` > 0,
    alpha has a linear segment around 0 (robot profile, see
    :func:`~nfmr_dlsmc.core.sliding_functions.bounded_rate`).

    Attributes (after a step)
    -------------------------
    C1, C2 : float
        The rates in use [m/s].
    s_x, s_y : float
        Sliding variables [m].
    alpha_x, alpha_y : float
        alpha(x_e), alpha(y_e) of eq. (33) [-].
    """

    __slots__ = ('_gains', '_r2', '_r3', '_started', '_ex0', '_ey0', '_int_ax', '_int_ay',
                 '_adaptive', '_zone', '_x_e', '_y_e', 'C1', 'C2', 's_x', 's_y', 'alpha_x',
                 'alpha_y')

    def __init__(self, gains: OuterLoopGains):
        self._started = False
        self.gains = gains
        self.reset()

    @property
    def gains(self) -> OuterLoopGains:
        """Return the gains in use; assigning new ones takes effect at the next step."""
        return self._gains

    @gains.setter
    def gains(self, gains: OuterLoopGains) -> None:
        self._gains = gains
        self._derive(gains)
        self.C1, self.C2 = gains.C1, gains.C2
        if self._adaptive and self._started:
            self.C1, self.C2 = adapted_rates(gains.C1, gains.C2, self._ex0, self._ey0)

    def _derive(self, gains: OuterLoopGains) -> None:
        """Set what the law derives from its gains: the exponents and the options."""
        self._r2 = gains.q2 / gains.p2
        self._r3 = gains.q3 / gains.p3
        self._adaptive = gains.adaptive_ratio
        self._zone = gains.linear_zone  # [m]

    def reset(self) -> None:
        """Forget e(0) and the integrals; the next step defines e(0)."""
        self._started = False
        self.C1, self.C2 = self._gains.C1, self._gains.C2
        self._ex0 = 0.0  # [m]
        self._ey0 = 0.0  # [m]
        self._int_ax = 0.0  # int alpha(x_e) dt [s]
        self._int_ay = 0.0  # int alpha(y_e) dt [s]
        self._x_e = 0.0  # [m] errors of the last step
        self._y_e = 0.0  # [m]
        self.s_x = 0.0
        self.s_y = 0.0
        self.alpha_x = 0.0
        self.alpha_y = 0.0

    def step(self, x_e: float, y_e: float, xdot_d: float, ydot_d: float,
             dt: float) -> tuple[float, float]:
        """
        Run one control period: errors [m] and reference velocity [m/s] -> (u_x, u_y) [m/s].

        ``dt`` [s] is the time since the previous step: the integral first adds the
        previous step's alpha times ``dt`` (a left Riemann sum), then s is formed.
        """
        g = self._gains
        s_x, s_y = self._surfaces(x_e, y_e, dt)
        r3, k2, h = self._r3, g.k2, g.h
        u_x = xdot_d - k2 * abs(s_x) ** r3 * math.erf(h * s_x) - self.C1 * self.alpha_x
        u_y = ydot_d - k2 * abs(s_y) ** r3 * math.erf(h * s_y) - self.C2 * self.alpha_y
        return u_x, u_y

    def _surfaces(self, x_e: float, y_e: float, dt: float) -> tuple[float, float]:
        """Advance the integrals of eq. (32) and return (s_x, s_y) [m]; sets alpha_x, alpha_y."""
        g = self._gains
        if self._started:
            self._int_ax += self.alpha_x * dt
            self._int_ay += self.alpha_y * dt
        else:
            self._started = True
            self._ex0, self._ey0 = x_e, y_e
            if self._adaptive:
                self.C1, self.C2 = adapted_rates(g.C1, g.C2, x_e, y_e)
        self._x_e, self._y_e = x_e, y_e
        self.alpha_x = bounded_rate(x_e, g.xi, self._r2, self._zone)
        self.alpha_y = bounded_rate(y_e, g.xi, self._r2, self._zone)
        self.s_x = x_e - self._ex0 + self.C1 * self._int_ax
        self.s_y = y_e - self._ey0 + self.C2 * self._int_ay
        return self.s_x, self.s_y

    def input_rate(self, xdot_e: float, ydot_e: float, xddot_d: float,
                   yddot_d: float) -> tuple[float, float]:
        """
        Return the time derivative (u_x', u_y') [m/s^2] of the inputs of the last step.

        Eqs (34), (35) differentiated along the error rate (x_e', y_e') [m/s]:

            s_x' = x_e' + C1 alpha(x_e)                                (eq. 32)
            u_x' = x_d'' - k2 g'(s_x) s_x' - C1 alpha'(x_e) x_e',   g(s) = |s|^(q3/p3) erf(h s),

        and likewise for y, with the reference acceleration (x_d'', y_d'') [m/s^2]. Needs a
        finite slope of alpha at the current error: the paper's alpha (``linear_zone`` = 0)
        has an infinite one at e = 0, where the alpha' term is taken as 0.
        """
        g = self._gains
        r2, r3, h, k2 = self._r2, self._r3, g.h, g.k2
        sdot_x = xdot_e + self.C1 * self.alpha_x
        sdot_y = ydot_e + self.C2 * self.alpha_y
        slope_x = bounded_rate_slope(self._x_e, g.xi, r2, self._zone)
        slope_y = bounded_rate_slope(self._y_e, g.xi, r2, self._zone)
        if slope_x == math.inf:
            slope_x = 0.0
        if slope_y == math.inf:
            slope_y = 0.0
        udot_x = (xddot_d - k2 * reaching_term_slope(self.s_x, r3, h) * sdot_x
                  - self.C1 * slope_x * xdot_e)
        udot_y = (yddot_d - k2 * reaching_term_slope(self.s_y, r3, h) * sdot_y
                  - self.C2 * slope_y * ydot_e)
        return udot_x, udot_y
