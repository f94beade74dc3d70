"""Outer position loop: bounded time-varying integral nonsingular terminal SMC (BTINTSMC)."""

import math

from nfmr_dlsmc.core.gains import adapted_rates, OuterLoopGains
from nfmr_dlsmc.core.sliding_functions import bounded_rate, bounded_rate_slope, Elementwise, FLOATS

__all__ = ['BtintsmcOuterLoop', 'position_input', 'reaching_term_slope', 'sliding_variable']

_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)


def sliding_variable(e, e0, rate, integral):
    """
    Return s = e - e(0) + C int_0^t alpha(e) dtau of eq. (32) [m], on floats or arrays.

    ``e``, ``e0``: the error on one axis now and at t = 0 [m]; ``rate``: C [m/s];
    ``integral``: the integral of alpha(e) so far [s].
    """
    return e - e0 + rate * integral


def position_input(velocity_d, s, alpha, rate, k2, r: float, h: float,
                   xp: Elementwise = FLOATS):
    """
    Return the virtual velocity input of eq. (34) or (35) on one axis [m/s].

    u_x = v_d cos(theta_r) - k2 |s_x|^(q3/p3) erf(h s_x) - C1 alpha(x_e)  (eq. 34),

    and likewise u_y with v_d sin(theta_r), s_y, C2 and alpha(y_e) (eq. 35); the second
    term is the reaching term k2 g(s), g(s) = |s|^(q3/p3) erf(h s).

    Parameters
    ----------
    velocity_d : float or ndarray
        The reference velocity on the axis, xdot_d = v_d cos(theta_r) or ydot_d [m/s].
    s : float or ndarray
        The sliding variable of eq. (32) [m].
    alpha : float or ndarray
        alpha(e) of eq. (33) [-].
    rate : float or ndarray
        C1 or C2 [m/s].
    k2 : float or ndarray
        The reaching gain [m^(1 - r)/s].
    r : float
        q3/p3.
    h : float
        The slope of erf [1/m] (doc/design.md, D4).
    xp : Elementwise
        The functions of libm for the kind of ``s``.

    """
    return velocity_d - k2 * abs(s) ** r * xp.erf(h * s) - rate * alpha


def reaching_term_slope(s: float, k2: float, r: float, h: float) -> float:
    """
    Return d(k2 g)/ds [1/s] of the reaching term k2 g(s) = k2 |s|^r erf(h s) of eq. (34).

    k2 g'(s) = k2 (r |s|^(r-1) |erf(h s)| + |s|^r (2 h / sqrt(pi)) exp(-h^2 s^2)),

    finite everywhere (erf(h s) ~ 2 h s / sqrt(pi) near 0, so g'(s) ~ |s|^r -> 0). For
    the analytic thetadot_d (doc/design.md, D5), on floats.
    """
    a = abs(s)
    if a == 0.0:
        return 0.0
    return k2 * (r * a ** (r - 1.0) * abs(math.erf(h * s))
                 + a ** r * _TWO_OVER_SQRT_PI * h * math.exp(-h * h * s * s))


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
    The equations are :func:`sliding_variable`,
    :func:`~nfmr_dlsmc.core.sliding_functions.bounded_rate` and :func:`position_input`,
    which the batch simulator applies to arrays.

    With ``gains.adaptive_ratio`` the rates C1, C2 are re-proportioned to e(0) at the
    first step (:func:`~nfmr_dlsmc.core.gains.adapted_rates`). With ``gains.linear_zone`` > 0,
    alpha has a linear segment around 0 (robot profile, see
    :func:`~nfmr_dlsmc.core.sliding_functions.bounded_rate`).

    :attr:`advance` < 1 (set by the cascade: a robot facing away from theta_d on a path,
    doc/design.md, D27) moves the sliding variables by that share of a step only,
    s' = advance (e' + C alpha(e)): e(0) takes up the rest of the error's change and the
    integral only that share of alpha, so s does not wind up while the robot, turning, cannot
    follow; 1 (the paper, and after :meth:`reset`) is eq. (32) exactly.

    Attributes (after a step)
    -------------------------
    C1, C2 : float
        The rates in use [m/s].
    s_x, s_y : float
        Sliding variables [m].
    alpha_x, alpha_y : float
        alpha(x_e), alpha(y_e) of eq. (33) [-].

    Attributes (set before a step)
    ------------------------------
    advance : float
        Share [0, 1] of the next step by which the sliding variables move (1: eq. 32).
    """

    __slots__ = ('_gains', '_r2', '_r3', '_started', '_ex0', '_ey0', '_int_ax', '_int_ay',
                 '_adaptive', '_zone', '_x_e', '_y_e', 'C1', 'C2', 's_x', 's_y', 'alpha_x',
                 'alpha_y', 'advance')

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
        self.advance = 1.0

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
        return (position_input(xdot_d, s_x, self.alpha_x, self.C1, k2, r3, h),
                position_input(ydot_d, s_y, self.alpha_y, self.C2, k2, r3, h))

    def _surfaces(self, x_e: float, y_e: float, dt: float) -> tuple[float, float]:
        """Advance the integrals of eq. (32) and return (s_x, s_y) [m]; sets alpha_x, alpha_y."""
        g = self._gains
        if self._started:
            advance = self.advance
            self._int_ax += advance * self.alpha_x * dt
            self._int_ay += advance * self.alpha_y * dt
            if advance != 1.0:  # e(0) takes up the rest of the error's change
                self._ex0 += (1.0 - advance) * (x_e - self._x_e)
                self._ey0 += (1.0 - advance) * (y_e - self._y_e)
        else:
            self._started = True
            self._ex0, self._ey0 = x_e, y_e
            if self._adaptive:
                self.C1, self.C2 = adapted_rates(g.C1, g.C2, x_e, y_e)
        self._x_e, self._y_e = x_e, y_e
        self.alpha_x = bounded_rate(x_e, g.xi, self._r2, self._zone)
        self.alpha_y = bounded_rate(y_e, g.xi, self._r2, self._zone)
        self.s_x = sliding_variable(x_e, self._ex0, self.C1, self._int_ax)
        self.s_y = sliding_variable(y_e, self._ey0, self.C2, self._int_ay)
        return self.s_x, self.s_y

    def input_rate(self, xdot_e: float, ydot_e: float, xddot_d: float,
                   yddot_d: float) -> tuple[float, float]:
        """
        Return the time derivative (u_x', u_y') [m/s^2] of the inputs of the last step.

        Eqs (34), (35) differentiated along the error rate (x_e', y_e') [m/s]:

            s_x' = x_e' + C1 alpha(x_e)                                (eq. 32)
            u_x' = x_d'' - k2 g'(s_x) s_x' - C1 alpha'(x_e) x_e',   g(s) = |s|^(q3/p3) erf(h s),

        and likewise for y, with the reference acceleration (x_d'', y_d'') [m/s^2]; s' times
        :attr:`advance`. Needs a finite slope of alpha at the current error: the paper's
        alpha (``linear_zone`` = 0) has an infinite one at e = 0, where the alpha' term is
        taken as 0.
        """
        g = self._gains
        r2, r3, h, k2 = self._r2, self._r3, g.h, g.k2
        sdot_x = self.advance * (xdot_e + self.C1 * self.alpha_x)
        sdot_y = self.advance * (ydot_e + self.C2 * self.alpha_y)
        slope_x = bounded_rate_slope(self._x_e, g.xi, r2, self._zone)
        slope_y = bounded_rate_slope(self._y_e, g.xi, r2, self._zone)
        if slope_x == math.inf:
            slope_x = 0.0
        if slope_y == math.inf:
            slope_y = 0.0
        udot_x = (xddot_d - reaching_term_slope(self.s_x, k2, r3, h) * sdot_x
                  - self.C1 * slope_x * xdot_e)
        udot_y = (yddot_d - reaching_term_slope(self.s_y, k2, r3, h) * sdot_y
                  - self.C2 * slope_y * ydot_e)
        return udot_x, udot_y
