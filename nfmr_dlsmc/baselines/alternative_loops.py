"""
Position and attitude loops the paper compares against (Tables 2-4), for the cascade.

Position loops take the global-frame errors and the reference velocity and return the
virtual inputs (u_x, u_y) like :class:`~nfmr_dlsmc.core.outer_loop.BtintsmcOuterLoop`;
attitude loops take s_theta = theta_e and thetadot_d and return omega like
:class:`~nfmr_dlsmc.core.inner_loop.AbfsmcInnerLoop`. Every integral is a left Riemann sum over
the measured step ``dt``, as in the DLSMC.
"""

import math

from nfmr_dlsmc.baselines.gains import (
    BtsmcOuterGains,
    CrsmcInnerGains,
    CrsmcOuterGains,
    NtsmcInnerGains,
    NtsmcOuterGains,
)
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop
from nfmr_dlsmc.core.sliding_functions import saturated_sign, sig_pow, sign


class CrsmcOuterLoop:
    """
    Constant-rate reaching law on the global position errors (DL-CRSMC, paper ref. [19]).

    Surfaces s_x = x_e, s_y = y_e; reaching law s' = -rate sat(s / layer) (Gao & Hung 1993,
    constant-rate law, with a boundary layer), hence

        u_x = xdot_d - rate sat(x_e / layer),   u_y = ydot_d - rate sat(y_e / layer).
    """

    __slots__ = ('gains', 's_x', 's_y')

    def __init__(self, gains: CrsmcOuterGains):
        self.gains = gains
        self.reset()

    def reset(self) -> None:
        """Zero the last surfaces (the law has no other state)."""
        self.s_x = self.s_y = 0.0

    def step(self, x_e: float, y_e: float, xdot_d: float, ydot_d: float,
             dt: float) -> tuple[float, float]:
        """Map errors [m] and reference velocity [m/s] to (u_x, u_y) [m/s]."""
        g = self.gains
        self.s_x, self.s_y = x_e, y_e
        return (xdot_d - g.rate * saturated_sign(x_e, g.layer),
                ydot_d - g.rate * saturated_sign(y_e, g.layer))


class CrsmcInnerLoop:
    """
    Constant-rate reaching law on the attitude error (DL-CRSMC, paper ref. [19]).

    s = theta_e,  omega = thetadot_d - rate sat(s / layer)  (layer = 0: sign(s)).
    """

    __slots__ = ('gains',)

    def __init__(self, gains: CrsmcInnerGains):
        self.gains = gains

    def reset(self) -> None:
        """Do nothing: the law has no state."""

    def step(self, s_theta: float, thetadot_d: float, dt: float) -> float:
        """Map s_theta [rad] and thetadot_d [rad/s] to the unsaturated omega [rad/s]."""
        return thetadot_d - self.gains.rate * saturated_sign(s_theta, self.gains.layer)


class NtsmcOuterLoop:
    """
    Integral nonsingular terminal SMC on the global position errors (DNTSMC, ref. [21]).

    The integral terminal surface (the fixed-rate predecessor of eq. 32, without the
    bounded alpha and without removing e(0)), per axis with r = q/p:

        s = e + beta int_0^t sig(e)^r dtau,
        u = e_d' - beta sig(e)^r - k sig(s)^r,

    so that s' = -k sig(s)^r: a terminal reaching phase from s(0) = e(0), then e' =
    -beta sig(e)^r on the surface (finite-time, nonsingular: no negative powers).
    """

    __slots__ = ('gains', '_int_x', '_int_y', '_rate_x', '_rate_y', 's_x', 's_y')

    def __init__(self, gains: NtsmcOuterGains):
        self.gains = gains
        self.reset()

    def reset(self) -> None:
        """Zero the integrals."""
        self._int_x = self._int_y = 0.0  # [m^r s]
        self._rate_x = self._rate_y = 0.0  # sig(e)^r of the previous step
        self.s_x = self.s_y = 0.0

    def step(self, x_e: float, y_e: float, xdot_d: float, ydot_d: float,
             dt: float) -> tuple[float, float]:
        """Map errors [m] and reference velocity [m/s] to (u_x, u_y) [m/s]."""
        g = self.gains
        r = g.q / g.p
        self._int_x += self._rate_x * dt
        self._int_y += self._rate_y * dt
        self._rate_x, self._rate_y = sig_pow(x_e, r), sig_pow(y_e, r)
        self.s_x = x_e + g.beta * self._int_x
        self.s_y = y_e + g.beta * self._int_y
        return (xdot_d - g.beta * self._rate_x - g.k * sig_pow(self.s_x, r),
                ydot_d - g.beta * self._rate_y - g.k * sig_pow(self.s_y, r))


class NtsmcInnerLoop:
    """
    Integral nonsingular terminal SMC on the attitude error (DNTSMC, ref. [21]).

    With r = q/p and a fixed switching gain eta (no adaptation, no disturbance estimate):

        sigma = theta_e + beta int_0^t sig(theta_e)^r dtau,
        omega = thetadot_d - beta sig(theta_e)^r - k sig(sigma)^r - eta sign(sigma).
    """

    __slots__ = ('gains', '_integral', '_rate', 'sigma')

    def __init__(self, gains: NtsmcInnerGains):
        self.gains = gains
        self.reset()

    def reset(self) -> None:
        """Zero the integral."""
        self._integral = 0.0
        self._rate = 0.0
        self.sigma = 0.0

    def step(self, s_theta: float, thetadot_d: float, dt: float) -> float:
        """Map s_theta [rad] and thetadot_d [rad/s] to the unsaturated omega [rad/s]."""
        g = self.gains
        r = g.q / g.p
        self._integral += self._rate * dt
        self._rate = sig_pow(s_theta, r)
        sigma = s_theta + g.beta * self._integral
        self.sigma = sigma
        return thetadot_d - g.beta * self._rate - g.k * sig_pow(sigma, r) - g.eta * sign(sigma)


class BtsmcOuterLoop(BtintsmcOuterLoop):
    """
    Bounded time-varying SMC: the surface of eq. (32) with a linear reaching law.

    The BTINTSMC with its integral-terminal reaching term replaced by -k s:

        s = e - e(0) + C int_0^t alpha(e) dtau,
        u_x = xdot_d - k s_x - C1 alpha(x_e),   u_y = ydot_d - k s_y - C2 alpha(y_e).
    """

    __slots__ = ()

    def _derive(self, gains: BtsmcOuterGains) -> None:
        """Set the exponent of alpha; no terminal reaching term, no robot-profile option."""
        self._r2 = gains.q2 / gains.p2
        self._r3 = math.nan
        self._adaptive = False
        self._zone = 0.0

    def step(self, x_e: float, y_e: float, xdot_d: float, ydot_d: float,
             dt: float) -> tuple[float, float]:
        """Map errors [m] and reference velocity [m/s] to (u_x, u_y) [m/s]."""
        g = self._gains
        s_x, s_y = self._surfaces(x_e, y_e, dt)
        return (xdot_d - g.k * s_x - self.C1 * self.alpha_x,
                ydot_d - g.k * s_y - self.C2 * self.alpha_y)
