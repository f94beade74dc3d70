"""
The DLSMC's free-ICR motion mode: position and heading tracked apart (issue 38, item 1).

The paper's cascade (Fig. 2) makes the heading serve the position: the outer loop's
virtual velocity (u_x, u_y) becomes a speed along the heading and a desired heading,
v = |u|, theta_d = atan2(u_y, u_x) (eq. 40), as a unicycle needs. A 4WIS chassis can move
its centre in any direction whatever its heading (crab, turning about any point), so in the
``free_icr`` mode (u_x, u_y) is the velocity of the chassis centre C itself, turned into
the body frame, and the heading follows a reference of its own, psi_d(t). Crab is this
mode with a constant psi_d. The loops are the paper's, called, not copied:
:class:`~nfmr_dlsmc.core.outer_loop.BtintsmcOuterLoop` and
:class:`~nfmr_dlsmc.core.inner_loop.AbfsmcInnerLoop`, configured by the same
:class:`~nfmr_dlsmc.core.gains.DlsmcConfig`.

Equations
---------
With C at (x, y), heading psi, and the reference (x_d, y_d, xdot_d, ydot_d, psi_d,
psidot_d), each step:

    x_e = x - x_d,   y_e = y - y_d                                  (F1; eq. 8 at C)
    (u_x, u_y) = BTINTSMC(x_e, y_e, xdot_d, ydot_d)                 (eqs 32-35, unchanged)
    v = sat(|u|) in [0, v_max],   (u'_x, u'_y) = (v / |u|) (u_x, u_y)         (F2)
    v_x =  cos(psi) u'_x + sin(psi) u'_y,
    v_y = -sin(psi) u'_x + cos(psi) u'_y                                      (F3)
    s_psi = wrap(psi - psi_d)                                       (eq. 10, theta -> psi)
    omega = sat(psidot_d - k1 sig(s_psi)^(q1/p1) - eta_hat sign(s_psi))
                                                   (eq. 11, eta_hat by eqs 12, 13)  (F4)

(v_x, v_y, omega) is the body-frame twist of C, the input of
:func:`~nfmr_dlsmc.core.swerve_kinematics.swerve_commands`. (F2) and (F3) replace
eq. (40); on the omnidirectional model xdot = R(psi) (v_x, v_y), psidot = omega the centre
then moves at (u'_x, u'_y) whatever its heading, so the position loop sees the input it
asks for from the first step (in the paper only once theta_e = 0), and the two loops do
not interact: the position loop's Theorem 2 and the attitude loop's Theorem 1 hold each
on its own while neither input saturates.

Departures from the nonholonomic DLSMC
--------------------------------------
- No lower speed bound: v in [0, v_max], not [v_min, v_max]. The paper's v_min keeps a
  unicycle moving so that its heading can turn; here the heading turns on its own, and a
  chassis holding a point (docking, a spin on the spot) must be able to stand.
  ``limits.v_min`` does not apply, nor ``follow_slow_reference`` (it lowers that bound).
- The saturation scales the vector (|(v_x, v_y)| <= v_max, its direction kept), not one
  speed.
- The heading reference and its rate come from the caller; nothing is differentiated. So
  ``thetadot_source`` and ``thetadot_filter`` (how theta_d of eq. (40) is differentiated)
  do not apply: psidot_d is the analytic feed-forward of eq. (11).
- ``align_speed`` does not apply: it slows a unicycle whose heading is far from the
  direction it must go; here the velocity does not depend on the heading. (Wheels not yet
  at their angles are the wheel mapping's business: its stop-align-drive, D34.)
- The outer loop's ``advance`` (D27, turn first on a path) is never lowered: there is no
  heading to turn to before moving.

What applies as in the DLSMC: every gain of both loops, ``outer.adaptive_ratio``,
``outer.linear_zone`` and the declared ``steer_rate_limit`` that widens it
(``DlsmcConfig.outer_in_use``: a change of the velocity's direction is a steer change of
every wheel here too), ``inner.boundary_layer``, ``inner.eta_max``, ``inner.anti_windup``
and the declared ``steer_lag`` that widens the layer (``DlsmcConfig.inner_in_use``: the
yaw rate still comes from steered wheels), ``limits.v_max``, ``limits.omega_max`` and the
fading low-pass ``omega_filter``, ``omega_filter_band`` on the commanded omega (D14:
a step of omega steps every steer set point in this mode too).
"""

import math

from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.cascade import smoothed_yaw_rate
from nfmr_dlsmc.core.dlsmc import DlsmcController, DlsmcLoops
from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.inner_loop import AbfsmcInnerLoop
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop
from nfmr_dlsmc.core.saturation import saturate_speed, saturate_yaw_rate, SaturatedController
from nfmr_dlsmc.core.schema import one_of

__all__ = ['FreeIcrController', 'MOTION', 'MOTIONS', 'motion_controller']

#: The motion modes of the DLSMC: the paper's unicycle (heading along the motion) and the
#: 4WIS chassis's free ICR (position and heading apart).
MOTIONS = ('nonholonomic', 'free_icr')
#: The rule of the ``motion`` parameter.
MOTION = one_of(*MOTIONS)


class FreeIcrController(DlsmcLoops, SaturatedController):
    """
    The DLSMC in the free-ICR mode: BTINTSMC -> centre velocity, ABFSMC -> omega to psi_d.

    Eqs (F1)-(F4) of the module docstring, stepped once per control period ``config.dt``;
    the tracked point is the chassis centre and the output the body-frame twist of the
    centre. ``config`` holds both loops' gains and the limits, as for
    :class:`~nfmr_dlsmc.core.dlsmc.DlsmcController`; the module docstring says which of
    its options do not apply.

    Attributes (after a step)
    -------------------------
    x_e, y_e : float
        Position errors of the centre [m] (F1).
    psi_d, psidot_d : float
        The reference heading [rad] and its rate [rad/s], as given.
    s_psi : float
        Attitude sliding variable = psi_e = wrap(psi - psi_d) [rad] (eq. 10).
    u_x, u_y : float
        The outer loop's velocity of the centre in the world frame, before saturation
        [m/s] (eqs 34, 35).
    speed_raw, omega_raw : float
        |(u_x, u_y)| [m/s] and the inner loop's omega [rad/s], before saturation.
    speed_saturated, omega_saturated : bool
        The limits changed the input.
    outer, inner : BtintsmcOuterLoop, AbfsmcInnerLoop
        The two loops, with their own step attributes (s_x, s_y, eta_hat, phase, ...).

    """

    #: The motion mode of the law: its step takes a heading reference and returns a twist
    #: (v_x, v_y, omega); :func:`~nfmr_dlsmc.core.arrival.with_arrival` reads it.
    motion = 'free_icr'
    #: Names of the values :meth:`telemetry` returns, in order.
    TELEMETRY_FIELDS = ('x_e', 'y_e', 'psi_d', 'psidot_d', 'psi_e', 's_x', 's_y', 'eta_hat',
                        'inner_phase', 'u_x', 'u_y', 'speed_raw', 'omega_raw',
                        'speed_saturated', 'omega_saturated')

    __slots__ = ('outer', 'inner', '_config', '_omega_tau', '_omega_band', '_omega',
                 'x_e', 'y_e', 'psi_d', 'psidot_d', 's_psi', 'u_x', 'u_y', 'speed_raw',
                 'omega_raw', 'speed_saturated', 'omega_saturated')

    def __init__(self, config: DlsmcConfig | None = None):
        config = DlsmcConfig() if config is None else config
        if not isinstance(config, DlsmcConfig):
            raise TypeError(f'config must be a DlsmcConfig, not {type(config).__name__}')
        super().__init__(config.limits, config.dt)
        self.outer = BtintsmcOuterLoop(config.outer_in_use)
        self.inner = AbfsmcInnerLoop(config.inner_in_use)
        self.config = config
        self.reset()

    def reset(self) -> None:
        """Start over: the next step is t = 0 of a new run."""
        self.outer.reset()
        self.inner.reset()
        self.x_e = self.y_e = 0.0
        self.psi_d = self.psidot_d = self.s_psi = 0.0
        self.u_x = self.u_y = self.speed_raw = self.omega_raw = 0.0
        self.speed_saturated = self.omega_saturated = False
        self._omega = None  # [rad/s] the last commanded omega (None before the first step)

    def step(self, x: float, y: float, psi: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, psi_d: float, psidot_d: float,
             dt: float | None = None) -> tuple[float, float, float]:
        """
        Run one control period: eqs (F1)-(F4).

        Parameters
        ----------
        x, y, psi : float
            Measured pose of the chassis centre [m, m, rad].
        x_d, y_d, xdot_d, ydot_d : float
            Reference position [m] and velocity [m/s] of the centre at this instant.
        psi_d, psidot_d : float
            Reference heading [rad] (any branch: the error is wrapped) and its rate
            [rad/s], the feed-forward of eq. (11).
        dt : float, optional
            Time since the previous step [s]; default the configured period.

        Returns
        -------
        v_x, v_y, omega : float
            The saturated body-frame twist of the centre [m/s, m/s, rad/s].

        """
        if dt is None:
            dt = self._dt
        x_e = x - x_d
        y_e = y - y_d
        u_x, u_y = self.outer.step(x_e, y_e, xdot_d, ydot_d, dt)
        speed_raw = math.hypot(u_x, u_y)
        speed = saturate_speed(speed_raw, 0.0, self._limits)  # eq. (F2)
        share = speed / speed_raw if speed_raw > 0.0 else 0.0
        cos_psi, sin_psi = math.cos(psi), math.sin(psi)
        v_x = share * (cos_psi * u_x + sin_psi * u_y)  # eq. (F3)
        v_y = share * (cos_psi * u_y - sin_psi * u_x)
        s_psi = wrap_angle(psi - psi_d)  # eq. (10)
        omega_raw = self.inner.step(s_psi, psidot_d, dt)  # eqs (11)-(13)
        omega = saturate_yaw_rate(omega_raw, self._limits)
        self.omega_saturated = omega != omega_raw
        if self._omega_tau > 0.0 and self._omega is not None:  # the first step: as is
            omega = smoothed_yaw_rate(self._omega, omega, s_psi, self._omega_tau,
                                      self._omega_band, dt)
        self._omega = omega
        self.x_e, self.y_e = x_e, y_e
        self.psi_d, self.psidot_d, self.s_psi = psi_d, psidot_d, s_psi
        self.u_x, self.u_y = u_x, u_y
        self.speed_raw, self.omega_raw = speed_raw, omega_raw
        self.speed_saturated = speed != speed_raw
        return v_x, v_y, omega

    def telemetry(self) -> tuple:
        """Return the internal signals of the last step, named by ``TELEMETRY_FIELDS``."""
        return (self.x_e, self.y_e, self.psi_d, self.psidot_d, self.s_psi, self.outer.s_x,
                self.outer.s_y, self.inner.eta_hat, self.inner.phase, self.u_x, self.u_y,
                self.speed_raw, self.omega_raw, self.speed_saturated, self.omega_saturated)


def motion_controller(motion: str,
                      config: DlsmcConfig | None = None) -> DlsmcController | FreeIcrController:
    """
    Return the DLSMC for a motion mode: ``nonholonomic`` (the paper's) or ``free_icr``.

    Raises
    ------
    ParameterError
        For a ``motion`` that is neither, naming the parameter ``motion``.

    """
    MOTION.check('motion', motion, '')
    return DlsmcController(config) if motion == 'nonholonomic' else FreeIcrController(config)
