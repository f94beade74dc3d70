"""Inner attitude loop: adaptive barrier-function SMC (ABFSMC)."""

import math

from nfmr_dlsmc.core.gains import InnerLoopGains
from nfmr_dlsmc.core.sliding_functions import Elementwise, FLOATS, saturated_sign, sig_pow

__all__ = ['AbfsmcInnerLoop', 'BARRIER_PHASE', 'INTEGRAL_PHASE', 'adaptation_rate',
           'barrier_gain', 'in_barrier_phase', 'yaw_rate_command']

#: Phases of the adaptive gain eta_hat.
INTEGRAL_PHASE = 0
BARRIER_PHASE = 1


def in_barrier_phase(was_in_barrier, s_abs, eps):
    """
    Tell whether eta_hat is in its barrier phase this step, on bools or boolean arrays.

    The barrier phase of eq. (13) starts when |s| <= eps/2 (t_bar) and, by the fallback of
    doc/design.md, D6, ends when |s| reaches eps; the integral phase of eq. (12) holds
    otherwise.

    Parameters
    ----------
    was_in_barrier : bool or ndarray
        Whether the previous step was in the barrier phase.
    s_abs : float or ndarray
        |s_theta| of this step [rad].
    eps : float
        The barrier half-width epsilon [rad].

    """
    return (was_in_barrier & (s_abs < eps)) | (s_abs <= 0.5 * eps)


def barrier_gain(s_abs, lam: float, eps: float):
    """Return eta_hat = L_b(s) = lam |s| / (eps - |s|) of eq. (13) [rad/s], for |s| < eps."""
    return lam * s_abs / (eps - s_abs)


def adaptation_rate(s_abs, L0: float, L1: float):
    """Return d eta_hat / dt = L0 + L1 |s| of eq. (12) [rad/s^2], the integral phase's rate."""
    return L0 + L1 * s_abs


def yaw_rate_command(thetadot_d, s, eta, k1: float, r: float, layer: float = 0.0,
                     xp: Elementwise = FLOATS):
    """
    Return omega = thetadot_d - k1 sign(s)|s|^(q1/p1) - eta_hat sign(s) of eq. (11) [rad/s].

    Unsaturated; ``s`` = s_theta [rad], ``eta`` = eta_hat [rad/s], ``r`` = q1/p1.
    ``layer`` > 0 (robot profile, doc/design.md, D8) puts sat(s / layer) in place of
    sign(s) in the eta_hat term.
    """
    return thetadot_d - k1 * sig_pow(s, r, xp) - eta * saturated_sign(s, layer, xp)


class AbfsmcInnerLoop:
    """
    ABFSMC law of eqs (10)-(13) with the barrier fallback of doc/design.md, D6.

    With s_theta = theta_e (eq. 10) the yaw-rate command is (eq. 11)

        omega = thetadot_d - k1 sign(s)|s|^(q1/p1) - eta_hat sign(s),

    and the adaptive gain (eqs 12, 13) is

        eta_hat = int (L0 + L1 |s|) dtau          until t_bar, the first time |s| <= eps/2,
        eta_hat = L_b(s) = lam |s| / (eps - |s|)  after t_bar.

    Barrier fallback: the barrier is defined only on (-eps, eps). When, after t_bar, a
    disturbance or a saturated omega pushes |s| to eps or beyond, the law re-arms t_bar and
    returns to the integral phase; the integral resumes from the value it had reached when
    it last left that phase (the gain learned so far is kept). The barrier phase starts again
    at the next |s| <= eps/2. So the law never divides by zero and never flips sign.

    The integral is a left Riemann sum: eta_hat(0) = 0 and the integrand of step k, times
    the time to step k+1, enters at step k+1. The equations and the phase are
    :func:`yaw_rate_command`, :func:`adaptation_rate`, :func:`barrier_gain` and
    :func:`in_barrier_phase`, which the batch simulator applies to arrays.

    Anti-windup (``gains.anti_windup``, off by default as in the paper): the integral does
    not grow during a step whose omega exceeds ``omega_max``. Theorem 1 assumes an
    unsaturated omega; on a robot whose yaw rate lags the command (steering actuators) the
    plain integral keeps growing while |s_theta| cannot reach eps/2, and the loop ends in a
    bang-bang limit cycle at +-omega_max.

    Robot profile (both off by default, the paper's law):

    - ``gains.boundary_layer`` = phi > 0 replaces sign(s) in the eta_hat term by
      sat(s / phi), so the switching term is continuous;
    - ``gains.eta_max`` > 0 caps the integral phase: the integral of eq. (12) stops at it.
      Unbounded, it winds up while a lagging robot cannot reach eps/2 and re-locks it into
      a limit cycle after every barrier fallback. The barrier phase is not capped: its gain
      growing towards |s| = eps is what holds the band against a disturbance larger than
      the cap.

    Attributes
    ----------
    gains : InnerLoopGains
        The gains in use; assigning new ones takes effect at the next step.
    omega_max : float
        The yaw-rate limit the anti-windup option compares with [rad/s].

    After a step:

    eta_hat : float
        Adaptive gain used in this step [rad/s].
    phase : int
        ``INTEGRAL_PHASE`` or ``BARRIER_PHASE``.
    t_bar_reached : bool
        True once |s| has reached eps/2 at least once.

    """

    __slots__ = ('omega_max', '_gains', '_r1', '_eta_integral', '_eta_rate', 'phase',
                 'eta_hat', 't_bar_reached')

    def __init__(self, gains: InnerLoopGains, omega_max: float = math.inf):
        self.omega_max = omega_max  # [rad/s], used by the anti-windup option only
        self.gains = gains
        self.reset()

    @property
    def gains(self) -> InnerLoopGains:
        """Return the gains in use; assigning new ones takes effect at the next step."""
        return self._gains

    @gains.setter
    def gains(self, gains: InnerLoopGains) -> None:
        self._gains = gains
        self._r1 = gains.q1 / gains.p1

    def reset(self) -> None:
        """Back to the integral phase with eta_hat = 0."""
        self._eta_integral = 0.0  # [rad/s]
        self._eta_rate = 0.0  # integrand of the previous step [rad/s^2], 0 when not integrating
        self.phase = INTEGRAL_PHASE
        self.eta_hat = 0.0
        self.t_bar_reached = False

    def step(self, s_theta: float, thetadot_d: float, dt: float) -> float:
        """
        Run one control period: s_theta [rad], thetadot_d [rad/s] -> unsaturated omega [rad/s].

        ``dt`` [s] is the time since the previous step; the integral of eq. (12) first adds
        the previous step's integrand times ``dt``.
        """
        g = self._gains
        self._eta_integral += self._eta_rate * dt
        a = abs(s_theta)
        integrating = not in_barrier_phase(self.phase == BARRIER_PHASE, a, g.eps)
        if integrating:
            self.phase = INTEGRAL_PHASE
        else:
            self.phase = BARRIER_PHASE
            self.t_bar_reached = True
        eta = self._eta_integral if integrating else barrier_gain(a, g.lam, g.eps)
        capped = integrating and 0.0 < g.eta_max <= eta
        if capped:
            eta = g.eta_max
        self.eta_hat = eta
        omega = yaw_rate_command(thetadot_d, s_theta, eta, g.k1, self._r1, g.boundary_layer)
        held = capped or (g.anti_windup and abs(omega) > self.omega_max)
        self._eta_rate = adaptation_rate(a, g.L0, g.L1) if integrating and not held else 0.0
        return omega
