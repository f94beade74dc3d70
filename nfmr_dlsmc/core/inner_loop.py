"""Inner attitude loop: adaptive barrier-function SMC (ABFSMC)."""

import math

from nfmr_dlsmc.core.gains import InnerLoopGains
from nfmr_dlsmc.core.sliding_functions import saturated_sign, sig_pow

__all__ = ['AbfsmcInnerLoop', 'BARRIER_PHASE', 'INTEGRAL_PHASE']

#: Phases of the adaptive gain eta_hat.
INTEGRAL_PHASE = 0
BARRIER_PHASE = 1


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
    the time to step k+1, enters at step k+1.

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

    __slots__ = ('omega_max', 'gains', '_eta_integral', '_eta_rate', 'phase', 'eta_hat',
                 't_bar_reached')

    def __init__(self, gains: InnerLoopGains, omega_max: float = math.inf):
        self.omega_max = omega_max  # [rad/s], used by the anti-windup option only
        self.gains = gains
        self.reset()

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
        g = self.gains
        self._eta_integral += self._eta_rate * dt
        a = abs(s_theta)
        if self.phase == BARRIER_PHASE and a >= g.eps:
            self.phase = INTEGRAL_PHASE  # fallback: re-arm t_bar
        elif self.phase == INTEGRAL_PHASE and a <= 0.5 * g.eps:
            self.phase = BARRIER_PHASE  # t_bar reached
            self.t_bar_reached = True
        integrating = self.phase == INTEGRAL_PHASE
        eta = self._eta_integral if integrating else g.lam * a / (g.eps - a)
        capped = integrating and 0.0 < g.eta_max <= eta
        if capped:
            eta = g.eta_max
        self.eta_hat = eta
        switch = saturated_sign(s_theta, g.boundary_layer)
        omega = thetadot_d - g.k1 * sig_pow(s_theta, g.q1 / g.p1) - eta * switch
        held = capped or (g.anti_windup and abs(omega) > self.omega_max)
        self._eta_rate = g.L0 + g.L1 * a if integrating and not held else 0.0
        return omega
